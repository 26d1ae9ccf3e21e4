"""A settled end of a growth's search whose final fit fails is refused, and the search goes on
(:func:`pysindy_xl.catalog.climb_ends.resumed_end`); the rows of the generic systems where this
happens are checked by the benchmark's ground truth in tests/benchmark/test_settled_end_resumed.py.
Here the climber's bookkeeping: a refused step is never kept again, nor judged a near tie."""

from types import SimpleNamespace

import pytest

from pysindy_xl.catalog.climb_ends import RESUMES, resumed_end
from pysindy_xl.catalog.path import GrowthStep
from pysindy_xl.catalog.ties import near_ties

PASSES = SimpleNamespace(dynamics_=object(), mass_matrix_check_={
    "positive_definite_fraction": 1.0, "median_condition": 2.0})
INDEFINITE = SimpleNamespace(dynamics_=object(), mass_matrix_check_={
    "positive_definite_fraction": 0.4, "median_condition": 2.0})


class _Climber:
    """The part of :class:`~pysindy_xl.catalog.climbs.Climber` that resumed_end reads."""

    def __init__(self, settled):
        self.first = GrowthStep("start", "", 4, 3, 0.2, 0.2, 0.2, True)
        self._settled, self._refused = settled, set()

    def settled(self, step):
        return step.move in self._settled

    def refuse(self, step, why):
        step.note = why
        self._refused.add(id(step))

    def refused(self, step):
        return id(step) in self._refused


def _search(ends):
    """search() of the growth: the next end each call, skipping the refused ones as the climbs
    do (they never keep a refused step)."""
    calls = []

    def search():
        calls.append(1)
        return next(end for end in ends if not end[1].note)
    return search, calls


def _end(move, criterion):
    return ({"move": move}, GrowthStep(move, "", 8, 5, criterion, criterion, criterion, True), [])


def test_a_settled_end_whose_final_fit_fails_is_refused_and_the_search_goes_on():
    springs, law = _end("anchored_springs", 0.025), _end("kinetic", 0.03)
    climber = _Climber(settled={"anchored_springs"})
    search, calls = _search([springs, law])
    fits = {"anchored_springs": INDEFINITE, "kinetic": PASSES}
    lines = []
    state, best, path, model = resumed_end(climber, search, lambda s, step: fits[step.move],
                                           progress=lines.append)
    assert best is law[1] and model is PASSES and len(calls) == 2
    assert climber.refused(springs[1]) and springs[1].note.startswith("final fit: its mass")
    assert "refused" in lines[0] and "anchored_springs" in lines[0]


@pytest.mark.parametrize("settled, fit", [({"kinetic"}, PASSES), (set(), INDEFINITE)],
                         ids=["settled and passing", "failing but not settled"])
def test_an_end_is_searched_once_where_it_passes_or_was_not_settled(settled, fit):
    end = _end("kinetic", 0.03)
    search, calls = _search([end, _end("other", 0.04)])
    state, best, _, model = resumed_end(_Climber(settled), search, lambda s, step: fit)
    assert best is end[1] and model is fit and len(calls) == 1 and not end[1].note


def test_the_further_checks_refuse_too_and_the_refusals_are_bounded():
    ends = [_end(f"family{k}", 0.02) for k in range(RESUMES + 2)]
    climber = _Climber(settled={end[1].move for end in ends})
    search, calls = _search(ends)
    _, best, _, model = resumed_end(climber, search, lambda s, step: PASSES,
                                    check=lambda model: "it leaves its free runs")
    assert len(calls) == RESUMES + 1 and best is ends[RESUMES][1]
    assert all(end[1].note == "final fit: it leaves its free runs" for end in ends[:RESUMES])


def test_the_first_catalog_is_never_refused():
    climber = _Climber(settled={"start"})
    search, calls = _search([({}, climber.first, [])])
    _, best, _, _ = resumed_end(climber, search, lambda s, step: INDEFINITE)
    assert best is climber.first and len(calls) == 1 and not best.note


def test_a_refused_step_is_no_near_tie():
    best = GrowthStep("kinetic", "", 8, 5, 0.030, 0.030, 0.030, True)
    refused = GrowthStep("anchored_springs", "", 9, 5, 0.031, 0.031, 0.031, False,
                         note="final fit: its mass matrix is not positive definite")
    kept = GrowthStep("trig", "", 9, 5, 0.032, 0.032, 0.032, False)
    assert [step.move for step in near_ties([best, refused, kept], best)] == ["kinetic", "trig"]
