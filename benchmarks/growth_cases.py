"""The growth on chosen cases of ``generic_systems.py``: its path, catalog and scores, and two
runs compared case by case.

A case is ``system:forcing:noise:seed`` (``forcing`` ``forced`` or ``unforced``; the data are
those of ``generic_systems.py``: two 10 s runs at 1 kHz, positions with Gaussian noise). Each
case appends one JSON line (its catalog, path, criterion, CPU seconds, fitted Lagrangian and
the benchmark's scores); cases already in the file are skipped. ``--compare A B`` prints a
markdown table of the cases two files share (catalog, held-out, 2 s simulation and off-box
errors, right, criterion, CPU seconds, whether the path is the same). Usage::

    PYTHONPATH=$PWD python benchmarks/growth_cases.py out.jsonl spring_pendulum:unforced:0.05:2
    python benchmarks/growth_cases.py --compare before.jsonl after.jsonl
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

import generic_systems as gs  # noqa: E402

import pysindy_xl as px  # noqa: E402


def grow(system, xs, ts, us, **options):
    """``grow_catalog(**options)`` on a case's data (:func:`generic_systems.case_of`): the
    system's coordinates and kinds, warnings silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return px.grow_catalog(xs, ts, us, coordinates=list(system["coords"].names),
                               kinds=system["kinds"], **options)


def iter_cases(cases, run, out=None, done=None):
    """Yield ``(case, run(case))`` for each case key of ``cases`` not yet recorded, each record
    (a dict with its ``"case"``) appended to the JSONL file ``out`` (None: not written) before
    it is yielded: a rerun skips the cases of ``done`` (a JSONL file; default ``out``), so a
    run killed and restarted resumes."""
    recorded = gs.recorded(out if done is None else done, lambda record: record["case"])
    for case in cases:
        if case in recorded:
            continue
        record = run(case)
        if out:
            with open(out, "a", encoding="utf-8") as handle:
                handle.write(json.dumps(record) + "\n")
        yield case, record


def run_case(case: str) -> dict:
    """The growth on one case: its record (see the module docstring)."""
    system, truth, forced, (runs, test, xs, ts, us) = gs.case_of(case)
    record = {"case": case}
    cpu = time.process_time()
    try:
        found = grow(system, xs, ts, us)
        record["cpu"] = time.process_time() - cpu
        record["catalog"] = found.catalog.describe()
        record["path"] = [[s.move, s.terms, s.active, s.criterion, s.chosen]
                          for s in found.steps]
        record["criterion"] = found.held_out_error
        record["L"] = str(found.model.lagrangian())[:300]
        record["score"] = gs.score(*gs._xlsindy_functions(found.model), system, truth, test,
                                   runs, forced)
    except Exception as error:  # noqa: BLE001 - a failed case is recorded
        record["cpu"] = time.process_time() - cpu
        record["error"] = repr(error)[:300]
    return record


def _percent(value) -> str:
    return "inf" if value is None or not np.isfinite(value) else f"{100 * value:.2f}"


def _short(catalog: str) -> str:
    for long, short in (("dissipation viscous", "visc"), ("natural splines", "spl"),
                        ("cubic splines, quadratic ends", "qspl"),
                        ("interaction", "int"), ("kinetic ", "kin ")):
        catalog = catalog.replace(long, short)
    return catalog


def compare(before: str, after: str) -> str:
    """The markdown table of the cases both files hold (see the module docstring)."""
    def load(path):
        with open(path) as f:
            return {r["case"]: r for r in map(json.loads, f)}
    old, new = load(before), load(after)
    lines = ["| case | catalog before -> after | held-out % | 2 s sim % | off-box % | right | "
             "criterion % | CPU s | path |", "|---|---|---|---|---|---|---|---|---|"]
    shared = [case for case in old if case in new]
    for case in shared:
        a, b = old[case], new[case]
        sa, sb = a.get("score", {}), b.get("score", {})
        ca, cb = a.get("catalog", a.get("error", "-")), b.get("catalog", b.get("error", "-"))
        catalog = f"same: {_short(ca)}" if ca == cb else f"{_short(ca)} -> {_short(cb)}"
        row = [case, catalog]
        row += [f"{_percent(sa.get(k))} -> {_percent(sb.get(k))}"
                for k in ("held_out", "simulation", "off_box")]
        row.append(f"{'Y' if sa.get('right') else 'n'} -> {'Y' if sb.get('right') else 'n'}")
        row.append(f"{_percent(a.get('criterion'))} -> {_percent(b.get('criterion'))}")
        row.append(f"{a['cpu']:.1f} -> {b['cpu']:.1f}")
        same = ([p[:3] + p[4:] for p in a.get("path", [])]
                == [p[:3] + p[4:] for p in b.get("path", [])])
        row.append("same" if same else f"{len(a.get('path', []))} -> "
                   f"{len(b.get('path', []))} steps")
        lines.append("| " + " | ".join(row) + " |")
    right = [sum(bool(r[c].get("score", {}).get("right")) for c in shared) for r in (old, new)]
    lines += ["", f"right: {right[0]} -> {right[1]} of {len(shared)}"]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", help="JSONL file the records are appended to")
    parser.add_argument("cases", nargs="*", help="system:forcing:noise:seed")
    parser.add_argument("--compare", nargs=2, metavar=("BEFORE", "AFTER"))
    args = parser.parse_args(argv)
    if args.compare:
        print(compare(*args.compare))
        return
    for case, record in iter_cases(args.cases, run_case, args.out):
        score = record.get("score", {})
        print(case, record.get("catalog", record.get("error")),
              {k: round(v, 4) for k, v in score.items() if isinstance(v, float)},
              score.get("right"), round(record["cpu"], 1), flush=True)


if __name__ == "__main__":
    main()
