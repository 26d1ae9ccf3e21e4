"""The growth's candidate fits in worker processes: each candidate is fitted once, a worker's
result is the calling process's to the bit, and the growth's path and model do not depend on
``n_jobs``. The ground truth is a forced Duffing oscillator integrated by scipy."""

import numpy as np
import pytest
from support.catalog_setups import duffing_search
from support.growth import HARDENING, MASS, STIFFNESS, noisy_duffing

from pysindy_xl.catalog import grow_catalog
from pysindy_xl.catalog.candidates import (
    CandidateFits,
    evaluate_candidate,
    parameters_key,
)


def _path(result):
    return [(s.move, s.description, s.terms, s.active, s.time_error, s.region_error,
             s.criterion, s.chosen, s.note) for s in result.steps]


@pytest.mark.slow  # (the default run: identify --n-jobs 2 in test_cli_automatic.py)
def test_growth_in_two_processes_takes_the_same_path_to_the_same_law():
    x, t, u = noisy_duffing()
    moves = ("degree", "coulomb")
    alone = grow_catalog(x, t, u, coordinates=["x"], kinds="linear", moves=moves)
    shared = grow_catalog(x, t, u, coordinates=["x"], kinds="linear", moves=moves, n_jobs=2)
    assert _path(shared) == _path(alone)
    assert shared.catalog.describe() == alone.catalog.describe()
    np.testing.assert_array_equal(shared.model.coefficients(), alone.model.coefficients())
    # and it is the Duffing law (forces: m xdd + c xd + k x + h x^3), up to the noise
    coef = dict(zip(shared.model.get_feature_names(), shared.model.coefficients(), strict=True))
    np.testing.assert_allclose(2 * coef["L[x_dot**2]"], MASS, rtol=0.05)
    np.testing.assert_allclose(-2 * coef["L[x**2]"], STIFFNESS, rtol=0.05)
    np.testing.assert_allclose(-4 * coef["L[x**4]"], HARDENING, rtol=0.1)
    # the workers are a pool of their own: joblib's shared one still works afterwards
    import joblib
    assert joblib.Parallel(n_jobs=2)(joblib.delayed(abs)(-k) for k in range(3)) == [0, 1, 2]


def test_a_workers_candidate_is_the_callers_to_the_bit():
    search = duffing_search(kinetic="constant")
    fits = CandidateFits(search, n_jobs=2)
    fits.warm_up()
    quartic = {"degree": 4}
    coulomb = {"degree": 4, "dissipation": ("viscous", "coulomb"), "coulomb_scale": 0.01}
    first = fits.get(quartic, ahead=[quartic, coulomb])  # the Coulomb one goes to the worker
    assert fits.get(quartic) is first  # fitted once
    # the worker has it, running or done (it may finish first on idle cores)
    assert set(fits._running) | fits._workers_results == {parameters_key(coulomb)}
    from_worker = fits.get(coulomb)
    fits.close()
    here = evaluate_candidate(search, coulomb)
    for fields in (first, from_worker, here):
        assert fields["note"] == "" and np.isfinite(fields["criterion"])
    clocks = ("seconds", "cpu_seconds")
    assert {k: v for k, v in from_worker.items() if k not in clocks} == \
        {k: v for k, v in here.items() if k not in clocks}
    assert [kind for kind, _ in fits.events] == ["submit", "local", "worker"]
    # the quartic catalog states the Duffing law: a few per cent held out at 1 % noise, and
    # a Coulomb column the law does not have gains nothing
    assert first["criterion"] < 0.1 and here["terms"] == first["terms"] + 1
    # each split's support: the names of the terms its fit kept (the Duffing law's among them)
    (support,) = first["support"]
    assert {"L[x_dot**2]", "L[x**2]", "L[x**4]"} <= set(support)
    assert here["criterion"] > 0.95 * first["criterion"]


def test_the_ceiling_and_the_sample_count_are_reported_not_fitted():
    search = duffing_search(kinetic="constant")
    search.max_terms = 4
    fields = CandidateFits(search).get({"degree": 4})
    assert fields["note"].startswith("ceiling") and fields["criterion"] == np.inf
    search.max_terms = 50
    split = search.splits[0]
    split.train = {key: None if value is None else [v[:40] for v in value]
                   for key, value in split.train.items()}
    fields = evaluate_candidate(search, {"degree": 4})
    assert fields["note"] == "too few samples for this size" and fields["terms"] == 6


def test_parameters_of_a_catalog_met_before_get_its_fit_equal_to_their_own():
    search = duffing_search(kinetic="constant")
    fits = CandidateFits(search)
    quartic = {"degree": 4}
    same = {"degree": 4, "interaction": 2}  # one coordinate: no product of two
    other = {"degree": 3}
    first = fits.get(quartic)
    again = fits.get(same)
    assert fits.get(same) is again
    assert [kind for kind, _ in fits.events] == ["local", "same"]
    # the long way: the second parameters fitted on their own
    alone = evaluate_candidate(search, same)
    clocks = ("seconds", "cpu_seconds")
    assert {k: v for k, v in again.items() if k not in clocks} == \
        {k: v for k, v in alone.items() if k not in clocks}
    assert "interaction 2" in again["description"] and "interaction 1" in first["description"]
    assert {k: v for k, v in first.items() if k not in clocks + ("description",)} == \
        {k: v for k, v in again.items() if k not in clocks + ("description",)}
    # a catalog that differs is fitted
    cubic = fits.get(other)
    assert cubic["terms"] == first["terms"] - 1
    assert [kind for kind, _ in fits.events] == ["local", "same", "local"]


def test_candidate_content_tells_equal_catalogs_from_different_ones():
    from pysindy_xl.catalog.candidates import candidate_content
    search = duffing_search(kinetic="constant")
    quartic = candidate_content(search, {"degree": 4})
    assert quartic == candidate_content(search, {"degree": 4, "interaction": 2})
    assert quartic != candidate_content(search, {"degree": 4, "dissipation": ("coulomb",)})
    assert quartic != candidate_content(search, {"degree": 4, "kinetic": "configuration"})
    assert candidate_content(search, {"degree": -1}) is None  # not a catalog
