"""Compare rows of ``generic_systems.py`` (run on other code) with the committed grid, case by
case: verdicts, the held-out ratio to the hand-built catalog, CPU seconds and the catalogs that
changed.

Run::

    python benchmarks/extreme_folds.py NEW.jsonl [NEW2.jsonl ...] --report OUT.md
"""

from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

GRID = os.path.join(os.path.dirname(__file__), "results", "generic_systems_grid.jsonl")


def _rows(paths):
    out = {}
    for path in paths:
        with open(path, encoding="utf-8") as handle:
            for line in handle:
                if line.strip():
                    r = json.loads(line)
                    out[(r["system"], r["forcing"], r["noise"], r["seed"])] = r
    return out


def _within(record, limit=1.5):
    return record.get("ratio") is not None and record["ratio"] <= limit


def compare(new, old):
    """Markdown lines comparing the rows ``new`` with the same cases of ``old``."""
    keys = sorted(k for k in new if k in old)
    lines = ["| | before (grid) | after |", "|---|---|---|"]
    right = [sum(bool(rows[k]["auto"]["right"]) for k in keys) for rows in (old, new)]
    within = [sum(_within(rows[k]) for k in keys) for rows in (old, new)]
    lines += [f"| right | {right[0]}/{len(keys)} | {right[1]}/{len(keys)} |",
              f"| held-out within 1.5x of the hand-built catalog | {within[0]}/{len(keys)} | "
              f"{within[1]}/{len(keys)} |"]
    cells = []
    for rows in (old, new):
        cpu = {}
        for k in keys:
            cpu.setdefault(rows[k]["n"], []).append(rows[k]["cpu_seconds"])
        cells.append("; ".join(f"{n}: {np.median(v):.1f} / {max(v):.1f}"
                               for n, v in sorted(cpu.items())))
    lines.append(f"| CPU s per case by coordinates (median / max) | {cells[0]} | {cells[1]} |")
    total = [sum(rows[k]["cpu_seconds"] for k in keys) for rows in (old, new)]
    lines.append(f"| CPU s in all | {total[0]:.0f} | {total[1]:.0f} |")
    lines += ["", "Cases whose verdict, ratio or catalog changed:", "",
              "| case | right | ratio to hand-built | CPU s | catalog before -> after |",
              "|---|---|---|---|---|"]
    for k in keys:
        a, b = old[k], new[k]
        if (a["auto"]["right"], _within(a), a.get("catalog")) == (b["auto"]["right"],
                                                                   _within(b), b.get("catalog")):
            continue
        ratio = " -> ".join("-" if r.get("ratio") is None else f"{r['ratio']:.2f}" for r in (a, b))
        lines.append(f"| {k[0]} {k[1]} {100 * k[2]:g} % seed {k[3]} | {a['auto']['right']} -> "
                     f"{b['auto']['right']} | {ratio} | {a['cpu_seconds']:.1f} -> "
                     f"{b['cpu_seconds']:.1f} | {a.get('catalog')} -> {b.get('catalog')} |")
    return lines


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("rows", nargs="+")
    parser.add_argument("--grid", default=GRID)
    parser.add_argument("--report", default=None)
    args = parser.parse_args(argv)
    text = "\n".join(compare(_rows(args.rows), _rows([args.grid])))
    print(text)
    if args.report:
        with open(args.report, "w", encoding="utf-8") as handle:
            handle.write(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
