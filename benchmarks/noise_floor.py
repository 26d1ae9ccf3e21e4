"""The growth's noise floor on generic systems: the chosen law's criterion against its floor,
and what the stop at the floor saves.

For each case (``benchmarks/generic_systems.py``: system, forcing, noise, seed) the growth runs
without the stop (``noise_floor=False``) with every step's floor computed (the search's
``SearchData.floor`` set to ``"now"``): the ratio of the chosen catalog's criterion to its
floor, and the smallest ratio of the steps worse than it; then without the stop and with it
(the default), as they run: the steps and CPU seconds saved, and whether the chosen catalog
is the same.

Usage::

    PYTHONPATH=$PWD python benchmarks/noise_floor.py --out F.jsonl \\
        spring_pendulum:unforced:0.05:0 duffing:unforced:0.01:0 ...
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time

import generic_systems as gs
import growth_cases as gc
import numpy as np

from pysindy_xl.catalog import candidates, growth


@dataclasses.dataclass
class _EverySearch(candidates.SearchData):
    """The growth's search data, computing every step's floor."""

    def __post_init__(self):
        self.floor = "now"


def _grow(system, xs, ts, us, noise_floor, every=False):
    """A growth and its CPU seconds (``every``: every step's floor computed)."""
    growth.SearchData = _EverySearch if every else candidates.SearchData
    started = time.process_time()
    try:
        found = gc.grow(system, xs, ts, us, noise_floor=noise_floor)
    finally:
        growth.SearchData = candidates.SearchData
    return found, time.process_time() - started


def run(case: str) -> dict:
    """One case ``system:forcing:noise:seed``: the figures of both growths."""
    system, _, _, (_, _, xs, ts, us) = gs.case_of(case)
    plain, _ = _grow(system, xs, ts, us, False, every=True)
    _, plain_cpu = _grow(system, xs, ts, us, False)
    stopped, stopped_cpu = _grow(system, xs, ts, us, True)
    final = plain.catalog.describe()
    result = max(k for k, s in enumerate(plain.steps) if s.chosen and s.description == final)
    law = plain.steps[result]
    others = [s.criterion / s.noise_floor for s in plain.steps
              if s is not law and np.isfinite(s.criterion) and s.noise_floor > 0
              and s.criterion > law.criterion * 1.05]
    return {"case": case, "criterion": law.criterion, "floor": law.noise_floor,
            "ratio": law.criterion / law.noise_floor if law.noise_floor > 0 else None,
            "worse_min_ratio": min(others) if others else None,
            "steps": [len(plain.steps), len(stopped.steps)],
            "cpu_seconds": [plain_cpu, stopped_cpu],
            "same_catalog": stopped.catalog.describe() == final}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="+", help="system:forcing:noise:seed")
    parser.add_argument("--out", default=None, help="JSONL file the records are appended to")
    args = parser.parse_args(argv)
    for case in args.cases:
        record = run(case)
        print(f"{case}: law {100 * record['criterion']:.3f} % / floor "
              f"{100 * record['floor']:.3f} % = {record['ratio']}, worse steps from "
              f"{record['worse_min_ratio']}, steps {record['steps']}, cpu "
              f"{record['cpu_seconds'][0]:.2f} -> {record['cpu_seconds'][1]:.2f} s, same "
              f"catalog {record['same_catalog']}", flush=True)
        if args.out:
            with open(args.out, "a") as handle:
                handle.write(json.dumps(record) + "\n")


if __name__ == "__main__":
    main()
