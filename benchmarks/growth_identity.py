"""Catalog growths before and after a change meant to keep them: bit for bit identical?

Runs :func:`pysindy_xl.grow_catalog` on generic_systems cases (1 to 4 coordinates, forced and
unforced, 0 to 5 % noise, a spline catalog) and writes (``--write PATH``) or compares with
(``--compare PATH``) a JSON file of every step's move, terms, active terms, criterion, block errors
and cross-validated tie error, and the final model's coefficients. The comparison is exact
(``==``, NaN equal to NaN; JSON writes floats exactly): a change of the arithmetic's order
shows. Prints each growth's CPU
seconds (``time.process_time``).

Usage (the package imported is the first on ``PYTHONPATH``)::

    PYTHONPATH=/path/to/before python benchmarks/growth_identity.py --write before.json
    PYTHONPATH=$PWD python benchmarks/growth_identity.py --compare before.json
"""

import argparse
import json
import os
import sys
import time
import warnings

import numpy as np

import pysindy_xl as px

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import generic_systems as gs  # noqa: E402

# (system, forcing, position noise, seed)
CASES = [("spring_pendulum", "forced", 0.01, 0), ("rotating_frame", "unforced", 0.05, 0),
         ("three_masses", "forced", 0.01, 0), ("four_chain", "forced", 0.01, 0),
         ("log_cosh_well", "forced", 0.01, 0), ("duffing", "unforced", 0.0, 0),
         ("double_pendulum", "forced", 0.05, 1)]


def grow(name, forcing, noise, seed):
    """The recorded numbers of one growth and its CPU seconds."""
    system = gs.systems()[name]
    forced = forcing == "forced"
    runs = gs.make_runs(system, gs.Truth(system), seed, forced)
    xs = gs._noisy(runs, noise, seed)
    ts = [r["t"] for r in runs]
    us = [r["u"] for r in runs] if forced else None
    start = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = px.grow_catalog(xs, ts, us, coordinates=list(system["coords"].names),
                                 kinds=system["kinds"])
    cpu = time.process_time() - start
    steps = [(s.move, s.terms, s.active, s.criterion, s.block_errors, s.tie_error)
             for s in result.steps]
    return (steps, result.model.coefficients().tolist()), cpu


def same(a, b) -> bool:
    """Exact equality of two recorded values (NaN equal to NaN)."""
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape:
        return False
    if a.dtype.kind == "f" or b.dtype.kind == "f":
        return bool(np.all((a == b) | (np.isnan(a) & np.isnan(b))))
    return bool(np.all(a == b))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", help="write the growths' numbers to this JSON file")
    parser.add_argument("--compare", help="compare the growths with this JSON file")
    parser.add_argument("--cases", default=None,
                        help="comma-separated indices into CASES (default: all)")
    args = parser.parse_args()
    picked = (range(len(CASES)) if args.cases is None
              else [int(k) for k in args.cases.split(",")])
    print(f"package: {px.__file__}")
    found = {}
    for k in picked:
        key = " ".join(map(str, CASES[k]))
        found[key], cpu = grow(*CASES[k])
        print(f"{key:38s} {len(found[key][0]):3d} steps  CPU {cpu:6.2f} s", flush=True)
    # through JSON both ways, so that the two sides hold the same types (lists, floats)
    found = json.loads(json.dumps(found))
    if args.write:
        with open(args.write, "w", encoding="utf-8") as handle:
            json.dump(found, handle)
    if args.compare:
        with open(args.compare, encoding="utf-8") as handle:
            before = json.load(handle)
        identical = True
        for case, (steps, coefficients) in found.items():
            old_steps, old_coefficients = before[case]
            steps_same = len(steps) == len(old_steps) and all(
                same(a, b) for new, old in zip(steps, old_steps, strict=True)
                for a, b in zip(new, old, strict=True))
            coefficients_same = same(coefficients, old_coefficients)
            identical &= steps_same and coefficients_same
            print(f"{case:38s} steps "
                  f"{'identical' if steps_same else 'DIFFERENT'}, coefficients "
                  f"{'identical' if coefficients_same else 'DIFFERENT'}")
        print("all growths bit-identical" if identical else "SOME GROWTHS DIFFER")
        sys.exit(0 if identical else 1)


if __name__ == "__main__":
    main()
