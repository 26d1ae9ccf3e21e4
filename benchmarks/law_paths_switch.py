"""Run a benchmark script with the unforced law search's noise balance on or off.

``optimizers.homogeneous.select_law(..., balance=...)`` swapped at run time (the package is
not changed), for A/B runs on the same code:

    PYTHONPATH=$PWD python benchmarks/law_paths_switch.py off benchmarks/share_probe.py \\
        half_car:unforced:0.01:0
"""
from __future__ import annotations

import functools
import os
import runpy
import sys

from pysindy_xl.optimizers import homogeneous


def main():
    state, script, *arguments = sys.argv[1:]
    if state not in ("on", "off"):
        raise SystemExit(f"state: expected 'on' or 'off', got {state!r}")
    homogeneous.select_law = functools.partial(homogeneous.select_law, balance=state == "on")
    sys.argv = [script, *arguments]
    sys.path.insert(0, os.path.dirname(os.path.abspath(script)))
    runpy.run_path(script, run_name="__main__")


if __name__ == "__main__":
    main()
