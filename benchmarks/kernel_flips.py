"""Which benchmark rows turn on rounding: every row of the five sets run twice on one machine,
with OpenBLAS's default kernel and with ``OPENBLAS_CORETYPE=Haswell``, the code the same.

The growth compares held-out criteria, and on noise-free data many catalogs' criteria sit at the
rounding floor; a different BLAS kernel rounds differently and may settle another catalog. This
script counts, per set, the rows whose verdict, catalog or held-out error differ between two
runs of the same rows (by ``(system, forcing, noise, seed)``).

Usage: ``python benchmarks/kernel_flips.py FIRST SECOND [SET ...]``, ``FIRST`` and ``SECOND``
results file names with ``{set}`` (no ``.jsonl``), for example
``anchored_springs_default_{set}_baa0658 kernel_haswell_{set}_3013667`` (the default kernel on a
2-core AMD EPYC, then the Haswell kernel on the same machine; the package of ``3013667`` is that
of ``baa0658`` with the move ``"anchored_springs"`` among the defaults, which the first file's
``--extra-moves`` gave). Prints a markdown section per set.
"""

from __future__ import annotations

import os
import sys

import numpy as np
from stitched_sets import rows

RESULTS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results")
SETS = ("grid", "unseen", "blind1", "blind2", "blind3")


def _loaded(template, name) -> dict:
    path = os.path.join(RESULTS, template.format(set=name) + ".jsonl")
    return rows(path) if os.path.exists(path) else {}


def _right(record) -> bool:
    return bool(record["auto"].get("right"))


def report(first, second, name) -> str:
    """The markdown section of set ``name``: rows of ``first`` against those of ``second``."""
    one, two = _loaded(first, name), _loaded(second, name)
    keys = sorted(k for k in one if k in two)
    flips = [k for k in keys if _right(one[k]) != _right(two[k])]
    catalogs = sum(one[k].get("catalog") != two[k].get("catalog") for k in keys)
    apart = sum(not np.isclose(one[k]["auto"]["held_out"], two[k]["auto"]["held_out"],
                               rtol=0.01, atol=1e-8) for k in keys)
    lines = [f"### {name}: {len(keys)} rows in both", "",
             "| noise | right, first | right, second |", "| --- | --- | --- |"]
    for label, chosen in (("0-1 %", lambda k: k[2] <= 0.01), ("5 %", lambda k: k[2] > 0.01)):
        picked = [k for k in keys if chosen(k)]
        lines.append(f"| {label} | {sum(_right(one[k]) for k in picked)}/{len(picked)} | "
                     f"{sum(_right(two[k]) for k in picked)}/{len(picked)} |")
    lines += ["", f"Another catalog: {catalogs} rows; a held-out error more than 1 % apart: "
              f"{apart} rows; another verdict: {len(flips)} rows.", ""]
    if flips:
        lines += ["| system | forcing | noise | seed | right | held-out % | catalogs |",
                  "| --- | --- | --- | --- | --- | --- | --- |"]
        for key in flips:
            a, b = one[key], two[key]
            lines.append(f"| {' | '.join(map(str, key))} | {_right(a)} -> {_right(b)} | "
                         f"{100 * a['auto']['held_out']:.3g} -> {100 * b['auto']['held_out']:.3g}"
                         f" | {a.get('catalog', '')} -> {b.get('catalog', '')} |")
        lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    import argparse
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("first")
    parser.add_argument("second")
    parser.add_argument("sets", nargs="*", default=list(SETS))
    args = parser.parse_args(argv)
    print("\n".join(report(args.first, args.second, name) for name in args.sets))
    return 0


if __name__ == "__main__":
    sys.exit(main())
