"""A settling catalog whose final fit fails does not end the growth: on the generic systems'
rotating frame, unforced at 5 % position noise (seed 1), the anchored springs beside the
gyroscopic law reach their noise floor on the search's pieces and settle the climbs, but their
fit on all the data fails the final checks. Answering with the best physical catalog found
before them (a constant kinetic part, 2.3 % off held out) missed the law; refused, the climbs
go on and find the configuration-dependent kinetic part (0.36 %). Ground truth: the benchmark's
sympy Lagrangian integrated by scipy at 1e-10, scored by the benchmark (held-out
accelerations, a 2 s simulation, a widened box of states)."""

import pathlib
import sys
import warnings

import pytest

import pysindy_xl as px
from pysindy_xl.catalog import MOVES

BENCHMARKS = pathlib.Path(__file__).resolve().parents[2] / "benchmarks"


@pytest.mark.slow
def test_the_rotating_frame_grows_past_springs_whose_final_fit_fails():
    sys.path.insert(0, str(BENCHMARKS))
    import generic_systems as gs

    system = gs.systems()["rotating_frame"]
    truth = gs.Truth(system)
    runs, test, xs, ts, us = gs.case_data(system, truth, 0.05, 1, False)
    moves = tuple(MOVES) + tuple({"anchored_springs"} - set(MOVES))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = px.grow_catalog(xs, ts, us, coordinates=list(system["coords"].names),
                                kinds=system["kinds"], moves=moves)
    refused = [step for step in found.steps if step.note.startswith("final fit")]
    assert refused and not any(step.chosen for step in refused)
    scores = gs.score(*gs._xlsindy_functions(found.model), system, truth, test, runs, False)
    assert scores["right"], scores
    assert scores["held_out"] < 0.01, scores
