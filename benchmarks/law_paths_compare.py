"""Gained and lost rows of a run against a reference results file (verdict ``auto.right``).

    python benchmarks/law_paths_compare.py NEW.jsonl REFERENCE.jsonl
"""
from __future__ import annotations

import json
import sys


def key(row):
    return row["system"], row["forcing"], row["noise"], row["seed"]


def main(new_path, reference_path):
    reference = {key(r): r for r in map(json.loads, open(reference_path))}
    gained, lost, same, cpu_new, cpu_old = [], [], 0, 0.0, 0.0
    for row in map(json.loads, open(new_path)):
        old = reference.get(key(row))
        if old is None:
            print("no reference row:", key(row))
            continue
        cpu_new += row.get("cpu_seconds", 0.0)
        cpu_old += old.get("cpu_seconds", 0.0)
        new_right, old_right = row["auto"]["right"], old["auto"]["right"]
        line = (f"{key(row)}: held out {old['auto']['held_out']:.3g} -> "
                f"{row['auto']['held_out']:.3g}, kept {old['kept']} -> {row['kept']}, "
                f"terms {old['terms']} -> {row['terms']}")
        if new_right and not old_right:
            gained.append(line)
        elif old_right and not new_right:
            lost.append(line)
        else:
            same += 1
            if old["kept"] != row["kept"] or old["terms"] != row["terms"]:
                print("  same verdict, changed:", line)
    print(f"{new_path} vs {reference_path}: {same} same verdict, {len(gained)} gained, "
          f"{len(lost)} lost; CPU s {cpu_old:.0f} -> {cpu_new:.0f}")
    for line in gained:
        print("  gained", line)
    for line in lost:
        print("  lost", line)


if __name__ == "__main__":
    main(*sys.argv[1:])
