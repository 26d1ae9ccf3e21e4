"""One row's near ties, block by block, beside the law's (hand-built) catalog.

Runs ``grow_catalog`` on a case of a set (``python benchmarks/tie_trace.py blind2_systems
cart_stiffening_pendulum:unforced:0.05:2``) and prints the growth's table, the found and true
Lagrangians, the scores, and for each near tie and for the hand-built catalog (the system's
``hand`` parameters) the cross-validated fits' criterion, fitted terms and the error of each
held-out block (every block held out in turn, as the near ties are judged: :mod:`.ties`).
The traces of ``results/noise_floor_choices.md`` were made with it.
"""

from __future__ import annotations

import importlib
import os
import sys
import time
import warnings

import numpy as np
import sympy as sp

sys.path.insert(0, os.path.dirname(__file__))

import generic_systems as gs  # noqa: E402

import pysindy_xl as px  # noqa: E402
from pysindy_xl.catalog import growth, ties  # noqa: E402


def trace(module: str, case: str) -> dict:
    """Grow the case ``system:forcing:noise:seed`` of the set ``module``; print its trace."""
    table = importlib.import_module(module).systems()
    system, truth, forced, (runs, test, xs, ts, us) = gs.case_of(case, table)
    hand, rows, original = dict(system["hand"]), [], ties.judge_near_ties

    def judged(steps, best, parameters_of, judge, **options):
        fits = judge()  # (one judge more: the hand-built catalog's folds too)
        try:
            for step in ties.near_ties(steps, best, options.get("physical", False)) + [None]:
                fields = fits.get(hand if step is None else parameters_of(step))
                rows.append(("HAND" if step is None else step.move, fields["terms"],
                             np.nan if step is None else step.criterion, fields["active"],
                             fields["criterion"], fields["block_errors"]))
        finally:
            fits.close()
        return original(steps, best, parameters_of, judge, **options)

    growth.judge_near_ties = judged
    started = time.process_time()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            found = px.grow_catalog(xs, ts, us, coordinates=list(system["coords"].names),
                                    kinds=system["kinds"])
    finally:
        growth.judge_near_ties = original
    print(found.table())
    print("catalog:", found.catalog.describe())
    print("found L:", found.model.lagrangian())
    print("true  L:", sp.expand(system["L"]))
    scores = gs.score(*gs._xlsindy_functions(found.model), system, truth, test, runs, forced)
    print("scores:", scores)
    for move, terms, criterion, active, cv, blocks in rows:
        print(f"  {move:<30}{terms:>5} terms, {active:>3} fitted, search {100 * criterion:6.2f} %,"
              f" cross-validated {100 * cv:6.3f} %, blocks "
              + " ".join(f"{100 * b:.3f}" for b in blocks))
    print(f"CPU {time.process_time() - started:.1f} s")
    return {"scores": scores, "ties": rows}


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit("usage: tie_trace.py SET_MODULE SYSTEM:FORCING:NOISE:SEED")
    trace(*sys.argv[1:])
