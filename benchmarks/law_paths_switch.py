"""Run a benchmark script with the unforced law search's noise balance on or off.

``on`` (``report``: and print the spread of the weights at exit):
``law_balance.install()`` swaps the balanced search into
``optimizers.homogeneous`` at run time (the package is not changed); ``off``: the package as
it is. For A/B runs on the same code:

    PYTHONPATH=$PWD python benchmarks/law_paths_switch.py off benchmarks/share_probe.py \\
        half_car:unforced:0.01:0
"""
from __future__ import annotations

import os
import runpy
import sys

import law_balance


def main():
    state, script, *arguments = sys.argv[1:]
    if state not in ("on", "off", "report"):
        raise SystemExit(f"state: expected 'on', 'off' or 'report', got {state!r}")
    if state != "off":
        law_balance.install(report=state == "report")
    sys.argv = [script, *arguments]
    sys.path.insert(0, os.path.dirname(os.path.abspath(script)))
    runpy.run_path(script, run_name="__main__")


if __name__ == "__main__":
    main()
