"""The near ties' keep rule measured row by row: every row whose growth judged near ties.

The rule (:func:`pysindy_xl.catalog.ties.tie_keeps`) acts only where two near ties or more
are judged again (a row's ``ties`` field lists them); every other row grows bit-identically.
``--list`` writes those rows of the five sets' current figures (the full runs with the later
reruns laid over them, as ``stitched_sets.py`` does; the half-car and three-link arm left
out: too slow), 5 % rows first; ``--run LIST OUTDIR`` grows them on the working tree's package
(``--no-baselines``), one JSON line per row in ``OUTDIR/ties_SET.jsonl`` (resumes), each with
``tie_log``: the choice of the former rule (the tolerance on the cross-validated criterion,
the search split's term counts, recomputed from the same fits) and of the current one, and
``tie_changed``; ``--compare OUTDIR`` prints the verdicts gained and lost.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import json
import os
import sys

sys.path.insert(0, os.path.dirname(__file__))

import generic_systems as gs  # noqa: E402
from stitched_sets import stitched  # noqa: E402

RESULTS = os.path.join(os.path.dirname(__file__), "results")
MODULES = {"grid": "generic_systems", "unseen": "unseen_systems", "blind1": "blind_systems",
           "blind2": "blind2_systems", "blind3": "blind3_systems"}
SETS = {  # the full run, then the reruns laid over it (final_sets_c0294a5.md)
    "grid": ["generic_systems_grid_6a7b6d6", "differences_default_grid_5836b2b",
             "degree_limit_1d_grid_f06c688", "degree_limit_grid_f06c688"],
    "unseen": ["unseen_systems_412b492", "differences_default_unseen_5836b2b",
               "degree_limit_1d_unseen_f06c688", "degree_limit_unseen_f06c688"],
    "blind1": ["blind_systems_c2a50a8", "differences_default_blind1_5836b2b",
               "degree_limit_1d_blind1_f06c688", "degree_limit_blind1_f06c688"],
    "blind2": ["blind2_systems_c2a50a8", "differences_default_blind2_5836b2b",
               "degree_limit_1d_blind2_f06c688", "degree_limit_blind2_f06c688",
               "half_car_c0294a5"],
    "blind3": ["blind3_systems_412b492", "differences_default_blind3_5836b2b",
               "degree_limit_1d_blind3_f06c688", "degree_limit_blind3_f06c688"],
}
SLOW = ("half_car", "three_link_arm")


def current(name) -> dict:
    """The set's current rows by ``(system, forcing, noise, seed)``."""
    paths = [os.path.join(RESULTS, f + ".jsonl") for f in SETS[name]]
    return stitched(paths[0], paths[1:])[0]


def tie_rows() -> list:
    """``(set, system, forcing, noise, seed)`` of every row with two near ties or more."""
    rows = [(name, *key) for name in SETS for key, record in sorted(current(name).items())
            if len(record.get("ties") or []) > 1 and key[0] not in SLOW]
    return sorted(rows, key=lambda row: -row[3])


def run(rows, outdir) -> None:
    from pysindy_xl.catalog import ties
    from pysindy_xl.catalog.keep_rules import single_keeps

    log, rule = [], ties.break_ties

    def logged(steps, parameters_of, judge, tolerance=0.05, progress=None):
        new = rule(steps, parameters_of, judge, tolerance, progress)
        old = steps[0]  # the former rule on the same cross-validated criteria
        for step in sorted(steps[1:], key=lambda s: s.tie_error):
            if single_keeps(dataclasses.replace(step, criterion=step.tie_error),
                            dataclasses.replace(old, criterion=old.tie_error), tolerance):
                old = step
        log.append([[old.move, old.terms], [new.move, new.terms], old is not new])
        return new

    ties.break_ties = logged
    tables = {}
    for k, (name, system_name, forcing, noise, seed) in enumerate(rows):
        out = os.path.join(outdir, f"ties_{name}.jsonl")
        if (system_name, forcing, noise, seed) in gs.recorded(
                out, lambda r: (r["system"], r["forcing"], r["noise"], r["seed"])):
            continue
        table = tables.setdefault(name, importlib.import_module(MODULES[name]).systems())
        system = table[system_name]
        log.clear()
        record = gs.run_case(system, gs.Truth(system), noise, seed, forcing == "forced",
                             baselines=False)
        record["tie_log"], record["tie_changed"] = list(log), any(x[2] for x in log)
        with open(out, "a", encoding="utf-8") as handle:
            handle.write(json.dumps(gs._finite(record)) + "\n")
        print(f"[{k + 1}/{len(rows)}] {name} {system_name} {forcing} {noise} {seed}: right "
              f"{record['auto']['right']}, changed {record['tie_changed']}, "
              f"cpu {record['cpu_seconds']:.1f}", flush=True)


def compare(outdir) -> None:
    for name in SETS:
        path = os.path.join(outdir, f"ties_{name}.jsonl")
        if not os.path.exists(path):
            continue
        before = current(name)
        with open(path, encoding="utf-8") as handle:
            after = [json.loads(line) for line in handle if line.strip()]
        for record in after:
            key = (record["system"], record["forcing"], record["noise"], record["seed"])
            was, now = bool(before[key]["auto"].get("right")), bool(record["auto"].get("right"))
            mark = "gained" if now and not was else "LOST" if was and not now else "same"
            if mark != "same" or record["tie_changed"]:
                print(f"{name:<7}{' '.join(map(str, key)):<52} {mark:<7} changed "
                      f"{record['tie_changed']!s:<6} {record['tie_log']}")
        changed = sum(r["tie_changed"] for r in after)
        print(f"{name}: {len(after)} rows run, choice changed in {changed}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--list", metavar="FILE")
    parser.add_argument("--run", nargs=2, metavar=("LIST", "OUTDIR"))
    parser.add_argument("--compare", metavar="OUTDIR")
    args = parser.parse_args(argv)
    if args.list:
        with open(args.list, "w", encoding="utf-8") as handle:
            handle.writelines(" ".join(map(str, row)) + "\n" for row in tie_rows())
    if args.run:
        with open(args.run[0], encoding="utf-8") as handle:
            rows = [line.split() for line in handle if line.strip()]
        run([(a, b, c, float(d), int(e)) for a, b, c, d, e in rows], args.run[1])
    if args.compare:
        compare(args.compare)
    return 0


if __name__ == "__main__":
    sys.exit(main())
