"""Whether a benchmark row's verdict turns on rounding: the row run again with its positions
multiplied by ``1 + scale N(0, 1)`` (default scale 1e-14, a few units in the last place).

A machine-free stand-in for running the rows under another BLAS kernel (``kernel_flips.py``):
on noise-free data many catalogs' held-out criteria sit at the rounding floor, and a row whose
verdict changes with a perturbation this small is decided by rounding, not by the data.

Usage: ``python benchmarks/rounding_perturbation.py SET:SYSTEM:FORCING:NOISE:SEED [...]
[--draws 2] [--scale 1e-14] [--out FILE.jsonl]``, ``SET`` one of grid, unseen, blind1, blind2,
blind3. Prints one line per draw (verdict, held-out error, terms, the end's notes) and, with
``--out``, appends the rows.
"""

from __future__ import annotations

import argparse
import json
import sys

import blind2_systems
import blind3_systems
import blind_systems
import generic_systems as gs
import numpy as np
import unseen_systems

TABLES = {"grid": gs.systems, "unseen": unseen_systems.systems, "blind1": blind_systems.systems,
          "blind2": blind2_systems.systems, "blind3": blind3_systems.systems}


def perturbed_row(key: str, draw: int, scale: float) -> dict:
    """The row ``SET:SYSTEM:FORCING:NOISE:SEED`` with its positions perturbed (draw ``draw``)."""
    name, system, forcing, noise, seed = key.split(":")
    table = TABLES[name]()
    noisy = gs._noisy

    def rounded_differently(runs, level, case_seed):  # the case's positions, then the draw
        rng = np.random.default_rng(1000 + draw)
        return [x * (1 + scale * rng.standard_normal(x.shape))
                for x in noisy(runs, level, case_seed)]

    gs._noisy = rounded_differently  # (run_case draws its positions through it)
    try:
        record = gs.run_case(table[system], gs.Truth(table[system]), float(noise), int(seed),
                             forcing == "forced", baselines=False, hand=False)
    finally:
        gs._noisy = noisy
    record.update({"set": name, "draw": draw, "scale": scale})
    return record


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("keys", nargs="+", metavar="SET:SYSTEM:FORCING:NOISE:SEED")
    parser.add_argument("--draws", type=int, default=2)
    parser.add_argument("--scale", type=float, default=1e-14)
    parser.add_argument("--out", default=None, metavar="FILE.jsonl")
    args = parser.parse_args(argv)
    for key in args.keys:
        for draw in range(args.draws):
            record = perturbed_row(key, draw, args.scale)
            auto = record.get("auto") or {}
            print(f"{key} draw {draw}: right {auto.get('right')}, held-out "
                  f"{auto.get('held_out')}, {record.get('terms')} terms, {record.get('kept')} "
                  f"kept, {record.get('steps')} steps, {record.get('end_notes')}", flush=True)
            if args.out:
                with open(args.out, "a", encoding="utf-8") as handle:
                    handle.write(json.dumps(gs._finite(record)) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
