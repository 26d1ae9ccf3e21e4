"""The growth's work budget (``work_budget``, :mod:`pysindy_xl.catalog.budget`): the catalogs the
search fits, counted at the fits themselves, on a forced Duffing oscillator integrated by scipy."""

import numpy as np
import pytest
from support.growth import noisy_duffing

from pysindy_xl.catalog import candidates, grow_catalog
from pysindy_xl.catalog.budget import WORK_BUDGET, work_cost


def _fitted(monkeypatch):
    """Record the terms of every catalog the search fits (each call of the candidate fit)."""
    terms = []
    original = candidates.evaluate_candidate

    def recorded(search, parameters):
        out = original(search, parameters)
        terms.append(out["terms"])
        return out

    monkeypatch.setattr(candidates, "evaluate_candidate", recorded)
    return terms


def test_work_is_the_cost_of_the_catalogs_fitted_and_stays_within_the_budget(monkeypatch):
    x, t, u = noisy_duffing()
    terms = _fitted(monkeypatch)
    free = grow_catalog(x, t, u, coordinates=["x"], kinds="linear", moves=("degree",),
                        tie_break=False, work_budget=None)
    unbounded = list(terms)
    assert free.work == pytest.approx(sum(work_cost(k) for k in unbounded))
    # a budget that the first catalog and the first degree move fill: the rest is refused
    budget = work_cost(unbounded[0]) + work_cost(unbounded[1])
    assert budget < free.work
    terms.clear()
    found = grow_catalog(x, t, u, coordinates=["x"], kinds="linear", moves=("degree",),
                         tie_break=False, work_budget=budget)
    assert terms == unbounded[:2]  # nothing over the budget was fitted
    assert found.work == pytest.approx(budget) and found.work <= budget * (1 + 1e-12)
    refused = [s for s in found.steps if s.note.startswith("budget")]
    assert refused and all(not np.isfinite(s.criterion) and not s.chosen for s in refused)
    assert all(s.terms > 0 for s in refused)
    # the steps that were fitted are those of the unbounded growth
    fitted = [s for s in found.steps if not s.note.startswith("budget")]
    assert [(s.move, s.terms, s.criterion) for s in fitted] == \
        [(s.move, s.terms, s.criterion) for s in free.steps[:len(fitted)]]


def test_the_default_budget_leaves_an_ordinary_growth_as_it_was(monkeypatch):
    x, t, u = noisy_duffing()
    terms = _fitted(monkeypatch)
    found = grow_catalog(x, t, u, coordinates=["x"], kinds="linear", moves=("degree",))
    by_default = list(terms)
    terms.clear()
    free = grow_catalog(x, t, u, coordinates=["x"], kinds="linear", moves=("degree",),
                        work_budget=None)
    assert terms == by_default and found.work < WORK_BUDGET
    assert [(s.move, s.terms, s.criterion, s.chosen) for s in found.steps] == \
        [(s.move, s.terms, s.criterion, s.chosen) for s in free.steps]
    assert np.array_equal(found.model.coefficients(), free.model.coefficients())


@pytest.mark.parametrize("bad", [-1.0, "many", float("nan")])
def test_a_bad_budget_is_refused_by_name(bad):
    x, t, u = noisy_duffing()
    with pytest.raises((ValueError, TypeError), match="work_budget: expected a real number"):
        grow_catalog(x, t, u, coordinates=["x"], moves=("degree",), work_budget=bad)
