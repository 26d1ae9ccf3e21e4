"""The growth's data-sized ceiling (``max_terms="auto"``): the rows of the search's fits counted
by hand from the bumps' placement rule and read off the fits themselves, on a forced Duffing
oscillator integrated by scipy."""

import numpy as np
import pytest
from support.growth import noisy_duffing

import pysindy_xl as px
import pysindy_xl.fit.build as build
from pysindy_xl.catalog import grow_catalog
from pysindy_xl.catalog import growth as growth_module
from pysindy_xl.catalog.candidates import SearchData, SearchSplit, search_rows

WIDTH = 0.5  # the test functions' half-width (s)


def _search(x, t, u, pieces):
    from pysindy_xl import XLSINDy
    from pysindy_xl.fit import RememberedSmoother
    from pysindy_xl.optimizers import ExplicitOptimizer
    from pysindy_xl.weak import BumpTestFunctions
    fixed = {"coordinates": ["x"], "kinds": ["linear"], "bounds": [(-2.0, 2.0)]}
    train = {"x": [x[a:b] for a, b in pieces], "t": [t[a:b] for a, b in pieces],
             "u": [u[a:b] for a, b in pieces], "x_dot": None, "x_ddot": None}
    template = XLSINDy(optimizer=ExplicitOptimizer(), formulation="weak",
                       test_functions=BumpTestFunctions(width=WIDTH),
                       smoother=RememberedSmoother())
    return SearchData([SearchSplit(fixed, train, [])], template, max_terms=50, forced=True)


def test_rows_of_the_search_are_the_test_functions_on_the_training_pieces():
    x, t, u = noisy_duffing()  # 500 Hz
    pieces = [(0, 1500), (2000, 2600), (3000, 3400)]
    search = _search(x, t, u, pieces)
    # by hand: 8 bumps cover each sample (the default overlap), so a piece of duration D holds
    # ceil(8 D / (2 h)) of them; the 0.8 s piece is shorter than a bump's support (1 s)
    durations = [t[b - 1] - t[a] for a, b in pieces]
    by_hand = sum(int(np.ceil(8 * d / (2 * WIDTH))) for d in durations if d >= 2 * WIDTH)
    assert by_hand == 24 + 10
    assert search_rows(search, weak=True) == by_hand
    assert search_rows(search, weak=False) == 1500 + 600 + 400  # one row per sample
    # and the fit itself has these rows (leaving the short piece out, with a warning)
    train = search.splits[0].train
    model = search.template.set_params(feature_library=px.AutomaticCatalog(
        **search.splits[0].fixed, degree=2))
    with pytest.warns(UserWarning, match="shorter than one test function"):
        model.fit(x=train["x"], t=train["t"], u=train["u"])
    with pytest.warns(UserWarning, match="shorter than one test function"):
        problem = model.regression(train["x"], train["t"], u=train["u"], formulation="weak",
                                   propagate_noise=False)
    assert problem.theta.shape[0] == by_hand


def _training_rows(monkeypatch):
    """Record the rows of every training fit of a growth's search, and of its final fit on all
    the data, last (their test functions have a set width; the scoring of held-out blocks does
    not propagate the noise)."""
    rows = []
    original = build.weak_regression

    def recorded(*args, **kwargs):
        out = original(*args, **kwargs)
        if kwargs.get("noise") != "none" and args[2].width != "auto":
            rows.append(out[0].shape[0])
        return out

    monkeypatch.setattr(build, "weak_regression", recorded)
    return rows


def test_the_default_ceiling_is_two_thirds_of_the_rows_of_the_fits(monkeypatch):
    x, t, u = noisy_duffing()
    rows = _training_rows(monkeypatch)
    # (without the noise floor: its held-out regressions propagate noise too)
    found = grow_catalog(x, t, u, coordinates=["x"], kinds="linear", moves=("degree",),
                         noise_floor=False)
    searched, final = rows[:-1], rows[-1]  # the final fit: the search's test functions
    assert len(searched) == len(found.steps) and len(set(searched)) == 1
    assert final > searched[0]  # on all the data
    assert found.max_terms == min(400, int(searched[0] // growth_module.ROWS_PER_TERM))
    assert found.max_terms == int(searched[0] // 1.5)  # two thirds of the rows
    assert found.to_dict()["max_terms"] == found.max_terms
    # the Duffing law is found under it: m xdd + c xd + k x + h x^3 = u
    assert found.catalog.n_terms <= found.max_terms
    coef = dict(zip(found.model.get_feature_names(), found.model.coefficients(), strict=True))
    np.testing.assert_allclose(2 * coef["L[x_dot**2]"], 1.5, rtol=0.05)
    # an explicit ceiling is kept as given
    fixed = grow_catalog(x, t, u, coordinates=["x"], kinds="linear", moves=("degree",),
                         max_terms=30)
    assert fixed.max_terms == 30


def test_the_path_reports_the_data_sized_ceiling(monkeypatch):
    x, t, u = noisy_duffing()
    rows = _training_rows(monkeypatch)
    lines = []
    monkeypatch.setattr(growth_module, "ROWS_PER_TERM", 8)  # a ceiling at the first catalog
    found = grow_catalog(x, t, u, coordinates=["x"], kinds="linear", moves=("degree",),
                         progress=lines.append)
    ceiling = rows[0] // 8
    assert found.max_terms == ceiling == found.steps[0].terms == 4
    assert lines[0].startswith("ceiling") and f"({rows[0]} rows per fit)" in lines[0]
    over = [step for step in found.steps if step.terms > ceiling]
    assert over and all(step.note == f"ceiling: {step.terms} > max_terms {ceiling}"
                        and step.criterion == np.inf for step in over)
    assert found.catalog.n_terms == ceiling
    monkeypatch.setattr(growth_module, "ROWS_PER_TERM", 20)  # below the first catalog
    with pytest.raises(ValueError, match=r"max_terms: the smallest catalog has 4 terms, more "
                       r"than max_terms=\d \('auto': \d+ rows of the search's fits / 20"):
        grow_catalog(x, t, u, coordinates=["x"], kinds="linear", moves=("degree",))


@pytest.mark.parametrize(("value", "error", "message"), [
    ("big", ValueError, "max_terms: expected a positive int or 'auto', got 'big'"),
    (0, ValueError, "max_terms: expected an integer >= 1"),
    (2.5, ValueError, "max_terms: expected an integer"),
    (True, TypeError, "max_terms: expected an integer"),
])
def test_bad_ceilings_are_refused(value, error, message):
    x, t, u = noisy_duffing()
    with pytest.raises(error, match=message):
        grow_catalog(x, t, u, coordinates=["x"], max_terms=value)


def test_unforced_exact_data_stop_the_growth_at_the_law():
    """Noise-free, unforced Duffing oscillator: once the quartic catalog states the law to
    round-off (criterion below EXACT), no larger catalog is tried."""
    from scipy.integrate import solve_ivp
    from support.growth import DAMPING, HARDENING, MASS, STIFFNESS
    t = np.arange(0.0, 8.0, 2e-3)

    def rhs(_, y):
        return [y[1], -(DAMPING * y[1] + STIFFNESS * y[0] + HARDENING * y[0] ** 3) / MASS]

    x = solve_ivp(rhs, (0, t[-1]), [1.5, 0.0], t_eval=t, rtol=1e-11, atol=1e-11).y[0][:, None]
    found = grow_catalog(x, t, coordinates=["x"], kinds="linear", moves=("degree", "coulomb"))
    assert found.held_out_error < growth_module.EXACT
    assert found.catalog.describe().startswith("x: x..x^4")
    # the moves alone from the first catalog, and nothing on top of the law
    assert [(s.move, s.terms) for s in found.steps] == [
        ("start", 4), ("degree", 5), ("degree", 6), ("coulomb", 5)]
    coef = dict(zip(found.model.get_feature_names(), found.model.coefficients(), strict=True))
    scale = 2 * coef["L[x_dot**2]"] / MASS  # an implicit law is fixed up to a factor
    np.testing.assert_allclose(-2 * coef["L[x**2]"] / scale, STIFFNESS, rtol=1e-4)
    np.testing.assert_allclose(-4 * coef["L[x**4]"] / scale, HARDENING, rtol=1e-4)
