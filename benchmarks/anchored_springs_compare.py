"""Rows of ``anchored_springs_<set>.jsonl`` (the move ``"anchored_springs"`` switched on with
``--extra-moves``) against the stitched baseline of main ``822725e`` (session 23's
``/work/notes/s23/baseline.py``): right before/after, held-out error, CPU seconds.

Usage: ``python benchmarks/anchored_springs_compare.py blind2 blind1 grid unseen``; a name
``v2:blind2`` reads ``anchored_springs_v2_blind2.jsonl`` (a rerun after a change).
"""

import json
import os
import sys

sys.path.insert(0, "/work/notes/s23")
from baseline import current  # noqa: E402

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results")


def main(names):
    for label in names:
        prefix, _, name = label.rpartition(":")
        path = os.path.join(HERE, f"anchored_springs_{prefix + '_' if prefix else ''}{name}.jsonl")
        if not os.path.exists(path):
            continue
        before = current(name)
        after = {}
        for line in open(path):
            r = json.loads(line)
            after[(r["system"], r["forcing"], r["noise"], r["seed"])] = r
        print(f"\n### {name} ({len(after)} rows)\n")
        print("| system | forcing | noise | seed | right before -> after | held-out % before -> "
              "after | CPU s before -> after | catalog after |")
        print("| --- | --- | --- | --- | --- | --- | --- | --- |")
        gained = lost = 0
        cpu = [0.0, 0.0]
        for key in sorted(after):
            a, b = after[key], before.get(key)
            if b is None:
                continue
            ra, rb = bool(a["auto"].get("right")), bool(b["auto"].get("right"))
            gained += ra and not rb
            lost += rb and not ra
            cpu[0] += b.get("cpu_seconds", 0.0)
            cpu[1] += a.get("cpu_seconds", 0.0)
            mark = "" if ra == rb else (" **gained**" if ra else " **lost**")
            anchor = "anchor" if "sqrt" in a.get("catalog", "") else ""
            print(f"| {key[0]} | {key[1]} | {key[2]} | {key[3]} | {rb} -> {ra}{mark} | "
                  f"{100 * b['auto'].get('held_out', float('nan')):.3g} -> "
                  f"{100 * a['auto'].get('held_out', float('nan')):.3g} | "
                  f"{b.get('cpu_seconds', 0):.1f} -> {a.get('cpu_seconds', 0):.1f} | {anchor} |")
        right_b = sum(bool(before[k]["auto"].get("right")) for k in after if k in before)
        right_a = sum(bool(after[k]["auto"].get("right")) for k in after if k in before)
        print(f"\n{name}: right {right_b} -> {right_a} of {len(after)}; gained {gained}, lost "
              f"{lost}; CPU {cpu[0]:.0f} s -> {cpu[1]:.0f} s")


if __name__ == "__main__":
    main(sys.argv[1:] or ["blind2", "blind1", "grid", "unseen"])
