"""A set's rates from row-level reruns laid over an earlier full run.

A change that can act only on some systems (a move that needs two coordinates of one kind, a
degree limit of the linear coordinates) is measured by rerunning those systems' rows; every
other row grows bit-identically. This script lays the reruns over the full run, row by row
(rows keyed by system, forcing, noise and seed; a later file wins), and prints the rates at
0-1 % and 5 % noise, the CPU figures, and the systems whose rows come from the full run alone.
Usage::

    python benchmarks/stitched_sets.py results/unseen_systems_412b492.jsonl \\
        results/differences_default_unseen_5836b2b.jsonl results/degree_limit_unseen_f06c688.jsonl
"""

from __future__ import annotations

import json
import sys

import numpy as np


def rows(path) -> dict:
    """The JSON lines of ``path`` by ``(system, forcing, noise, seed)``."""
    with open(path, encoding="utf-8") as handle:
        records = [json.loads(line) for line in handle if line.strip()]
    return {(r["system"], r["forcing"], r["noise"], r["seed"]): r for r in records}


def stitched(base, overlays) -> tuple:
    """The rows of ``base`` with those of each overlay laid over them in turn, and for each
    row the index of the file it comes from (0: ``base``)."""
    final = rows(base)
    source = dict.fromkeys(final, 0)
    for index, path in enumerate(overlays, start=1):
        for key, record in rows(path).items():
            final[key], source[key] = record, index
    return final, source


def summary(final, source) -> str:
    """Rates at 0-1 % and 5 % noise, CPU median and rows within 10 CPU s, stale systems."""
    lines = []
    for label, chosen in (("0-1 %", lambda k: k[2] <= 0.01), ("5 %", lambda k: k[2] > 0.01)):
        keys = [k for k in final if chosen(k)]
        right = sum(bool(final[k]["auto"].get("right")) for k in keys)
        share = 100 * right / max(len(keys), 1)
        lines.append(f"right at {label}: {right}/{len(keys)} ({share:.0f} %)")
    cpu = np.array([final[k]["cpu_seconds"] for k in final if "cpu_seconds" in final[k]])
    lines.append(f"CPU s: median {np.median(cpu):.1f}, max {cpu.max():.0f}, "
                 f"{int(np.sum(cpu <= 10))}/{cpu.size} within 10 s")
    stale = sorted({k[0] for k, index in source.items() if index == 0})
    lines.append(f"systems from the full run alone: {', '.join(stale) or 'none'}")
    return "\n".join(lines)


def main(argv=None) -> int:
    paths = list(sys.argv[1:] if argv is None else argv)
    if not paths:
        raise SystemExit("usage: stitched_sets.py FULL_RUN.jsonl [RERUN.jsonl ...]")
    print(summary(*stitched(paths[0], paths[1:])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
