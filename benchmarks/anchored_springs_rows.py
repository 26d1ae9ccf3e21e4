"""Every row of the five benchmark sets with the move ``"anchored_springs"``, against the rows
without it: the evidence for (or against) making it a default move.

The rows without it are each set's stitched record (its full run with the later row-level
reruns laid over it, a later file winning: :func:`stitched_sets.stitched`), as they stood on
main ``8883912`` where the move is opt-in. The rows with it are the files
``anchored_springs_all_<set>_8883912.jsonl`` (``--extra-moves anchored_springs --no-hand`` on
``8883912``; the move's position among the moves does not change what is tried, so these are
also the rows of the move made a default) and, for the three systems rerun after the grid-edge
rule of session 23, the files ``anchored_springs_v2_<set>.jsonl``; last, the rows rerun after
the near-path rule (``anchored_springs_v3_<set>_a52ae4e.jsonl``).

Usage: ``python benchmarks/anchored_springs_rows.py [--rows TEMPLATE] [SET ...]`` prints per
set the rates at 0-1 % and 5 % noise without and with the move, every verdict that changed, the
rows whose grown catalog keeps an anchored spring, and the CPU seconds. ``--rows`` takes the
rows with the move from one run instead (``TEMPLATE`` a results file name with ``{set}``, for
example ``anchored_springs_default_{set}_baa0658``: every row with the move and the resumed
search, ``baa0658``); the verdicts and catalogs that differ from the stitched rows with the move
above are then listed too.
"""

from __future__ import annotations

import os
import sys

import numpy as np
from stitched_sets import rows, stitched

RESULTS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results")

#: Each set's full run, then its reruns in the order they were laid over it.
BASELINE = {
    "grid": ["generic_systems_grid_6a7b6d6", "differences_default_grid_5836b2b",
             "degree_limit_1d_grid_f06c688", "degree_limit_grid_f06c688",
             "own_runs_grid_19e7d92", "tie_count_grid_4031549", "knots_default_grid_64e6f85"],
    "unseen": ["unseen_systems_412b492", "differences_default_unseen_5836b2b",
               "degree_limit_1d_unseen_f06c688", "degree_limit_unseen_f06c688",
               "own_runs_unseen_19e7d92", "tie_count_unseen_4031549",
               "knots_default_unseen_64e6f85"],
    "blind1": ["blind_systems_c2a50a8", "differences_default_blind1_5836b2b",
               "degree_limit_1d_blind1_f06c688", "degree_limit_blind1_f06c688",
               "own_runs_blind1_19e7d92", "tie_count_blind1_4031549",
               "knots_default_blind1_64e6f85"],
    "blind2": ["blind2_systems_c2a50a8", "differences_default_blind2_5836b2b",
               "degree_limit_1d_blind2_f06c688", "degree_limit_blind2_f06c688",
               "half_car_c0294a5", "own_runs_blind2_19e7d92", "tie_count_blind2_4031549",
               "three_link_arm_1645dc8", "knots_default_blind2_64e6f85",
               "knots_default_half_car_822725e", "knots_default_three_link_arm_822725e"],
    "blind3": ["blind3_systems_412b492", "differences_default_blind3_5836b2b",
               "degree_limit_1d_blind3_f06c688", "degree_limit_blind3_f06c688",
               "own_runs_blind3_19e7d92", "tie_count_blind3_4031549",
               "knots_default_blind3_64e6f85"],
}
#: The rows with the move: the run of every other system on ``8883912``, then the reruns after
#: the grid-edge rule (session 23), then those after the near-path rule (``a52ae4e``: every row
#: whose catalog or held-out error the move had changed, and the gains).
WITH_MOVE = {name: [f"anchored_springs_all_{name}_8883912", f"anchored_springs_v2_{name}",
                    f"anchored_springs_v3_{name}_a52ae4e"] for name in BASELINE}


def _existing(names) -> list:
    paths = [os.path.join(RESULTS, f"{n}.jsonl") for n in names]
    return [p for p in paths if os.path.exists(p)]


def without_move(name) -> dict:
    """The set's rows without the move, by ``(system, forcing, noise, seed)``."""
    paths = _existing(BASELINE[name])
    return stitched(paths[0], paths[1:])[0]


def with_move(name, template=None) -> dict:
    """The set's rows with the move (those run so far), by ``(system, forcing, noise, seed)``:
    the stitched files of :data:`WITH_MOVE`, or the one file ``template`` names."""
    found = {}
    for path in _existing([template.format(set=name)] if template else WITH_MOVE[name]):
        found.update(rows(path))
    return found


def _rate(records, keys) -> str:
    right = sum(bool(records[k]["auto"].get("right")) for k in keys)
    return f"{right}/{len(keys)} ({100 * right / max(len(keys), 1):.0f} %)"


def report(name, template=None) -> str:
    """The markdown section of one set (``template``: :func:`with_move`'s)."""
    before, after = without_move(name), with_move(name, template)
    keys = sorted(k for k in before if k in after)
    merged = {k: after.get(k, before[k]) for k in before}
    lines = [f"### {name}: {len(keys)} of {len(before)} rows run with the move", ""]
    lines.append("| noise | right without the move | right with it (every row) |")
    lines.append("| --- | --- | --- |")
    for label, chosen in (("0-1 %", lambda k: k[2] <= 0.01), ("5 %", lambda k: k[2] > 0.01)):
        picked = [k for k in before if chosen(k)]
        lines.append(f"| {label} | {_rate(before, picked)} | {_rate(merged, picked)} |")
    changed, kept = [], []
    for key in keys:
        old, new = before[key], after[key]
        was, now = bool(old["auto"].get("right")), bool(new["auto"].get("right"))
        row = (f"| {' | '.join(map(str, key))} | {was} -> {now} | "
               f"{100 * old['auto']['held_out']:.3g} -> {100 * new['auto']['held_out']:.3g} | "
               f"{new.get('catalog', '')} |")
        if was != now:
            changed.append(row)
        if "sqrt" in new.get("catalog", ""):
            kept.append(row)
    header = ["| system | forcing | noise | seed | right | held-out % | catalog with the move |",
              "| --- | --- | --- | --- | --- | --- | --- |"]
    lines += ["", f"Verdicts changed: {len(changed)}", ""] + (header + changed if changed else [])
    lines += ["", f"Grown catalogs that keep an anchored spring: {len(kept)}", ""]
    lines += header + kept if kept else []
    cpu_before = np.array([before[k].get("cpu_seconds", np.nan) for k in keys])
    cpu_after = np.array([after[k].get("cpu_seconds", np.nan) for k in keys])
    identical = sum(before[k].get("catalog") == after[k].get("catalog")
                    and before[k]["auto"]["held_out"] == after[k]["auto"]["held_out"]
                    for k in keys)
    lines += ["", f"Same catalog and held-out error to the bit: {identical} of {len(keys)} rows. "
              f"CPU s of these rows: {np.nansum(cpu_before):.0f} -> {np.nansum(cpu_after):.0f} "
              f"({100 * (np.nansum(cpu_after) / np.nansum(cpu_before) - 1):+.0f} %); rows within "
              f"10 CPU s: {int(np.sum(cpu_before <= 10))} -> {int(np.sum(cpu_after <= 10))}.", ""]
    if template:
        earlier = with_move(name)
        moved = [key for key in keys if key in earlier and (
            bool(earlier[key]["auto"].get("right")) != bool(after[key]["auto"].get("right"))
            or not np.isclose(earlier[key]["auto"]["held_out"], after[key]["auto"]["held_out"],
                              rtol=0.01, atol=1e-8))]
        lines += [f"Against the earlier rows with the move: {len(moved)} of {len(keys)} rows "
                  "with another verdict or a held-out error more than 1 % apart", ""]
        lines += ["| system | forcing | noise | seed | right | held-out % | catalog now |",
                  "| --- | --- | --- | --- | --- | --- | --- |"] if moved else []
        for key in moved:
            old, new = earlier[key]["auto"], after[key]["auto"]
            lines.append(f"| {' | '.join(map(str, key))} | {bool(old.get('right'))} -> "
                         f"{bool(new.get('right'))} | {100 * old['held_out']:.3g} -> "
                         f"{100 * new['held_out']:.3g} | {after[key].get('catalog', '')} |")
        lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    import argparse
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sets", nargs="*", default=list(BASELINE))
    parser.add_argument("--rows", default=None, metavar="TEMPLATE",
                        help="the rows with the move from one results file per set "
                             "(its name with {set}, no .jsonl)")
    args = parser.parse_args(argv)
    print("\n".join(report(name, args.rows) for name in args.sets))
    return 0


if __name__ == "__main__":
    sys.exit(main())
