"""Unforced weak form: test functions of several widths, and h-block cross-validation of the
noise ratio (issue 34)."""


import numpy as np
import pytest

import pysindy_xl as px
from pysindy_xl.fit import UNFORCED_WIDTH_MULTIPLES, build_problem, trajectory_data
from pysindy_xl.optimizers import homogeneous
from pysindy_xl.weak import BumpTestFunctions


def test_width_multiples_stack_the_rows_of_every_width_by_centre():
    t = np.linspace(0.0, 10.0, 1001)
    single = BumpTestFunctions(width=1.0)
    phi_1, dphi_1, h = single.matrices(t)
    phi, dphi, h_multi = BumpTestFunctions(width=1.0, width_multiples=(1.0, 2.0)).matrices(t)
    phi_2, _, _ = BumpTestFunctions(width=2.0).matrices(t)
    assert h == h_multi == 1.0
    assert phi.shape[0] == phi_1.shape[0] + phi_2.shape[0]
    # every row is a bump of one of the widths, and the rows advance in time
    support = np.count_nonzero(phi.toarray(), axis=1)  # samples inside (-h, h) or (-2h, 2h)
    assert np.all(np.isin(support, [199, 200, 399, 400]))
    assert np.count_nonzero(support < 300) == phi_1.shape[0]
    centres = (phi.toarray() @ t) / phi.toarray().sum(axis=1)
    assert np.all(np.diff(centres) >= -1e-9)
    # integration by parts holds for each row: int phi q' = -int phi' q
    assert float(abs(phi @ np.cos(t) + dphi @ np.sin(t)).max()) < 1e-8
    # one multiple is the single width
    phi_same, dphi_same, _ = BumpTestFunctions(width=1.0, width_multiples=(1.0,)).matrices(t)
    assert (phi_same != phi_1).nnz == 0 and (dphi_same != dphi_1).nnz == 0


def test_a_width_that_does_not_fit_is_left_out():
    t = np.linspace(0.0, 3.0, 301)
    phi, _, _ = BumpTestFunctions(width=1.0, width_multiples=(1.0, 2.0)).matrices(t)
    assert phi.shape[0] == BumpTestFunctions(width=1.0).matrices(t)[0].shape[0]


@pytest.mark.parametrize("multiples", [(), (1.0, -1.0), (np.nan,)])
def test_bad_width_multiples_are_refused(multiples):
    with pytest.raises(ValueError, match="width_multiples"):
        BumpTestFunctions(width=1.0, width_multiples=multiples).matrices(np.linspace(0, 5, 101))


def test_unforced_data_get_rows_of_several_widths(cart_pole_system):
    t = np.arange(0.0, 10.0, 0.01)
    run = cart_pole_system.simulate(np.array([0.0, 0.5, 0.0, 0.0]), t, None)
    library = px.CatalogRepartition([px.ExternalForces(cart_pole_system.coords),
                                     px.LagrangeLibrary(cart_pole_system.coords, [
                                         cart_pole_system.coords.qd[0] ** 2])]).fit()
    unforced = build_problem(library, trajectory_data(run["q"], t, None, None, None, 2),
                             "weak").catalog_map
    forced = build_problem(library, trajectory_data(run["q"], t, None, None,
                                                    np.zeros_like(run["q"]), 2), "weak").catalog_map
    assert unforced.weak_info["half_width"] == forced.weak_info["half_width"]
    single = forced.weak_info["test_functions"][0]
    h, duration = forced.weak_info["half_width"], t[-1] - t[0]
    expected = sum(int(np.ceil(8.0 * duration / (2 * m * h))) for m in UNFORCED_WIDTH_MULTIPLES
                   if 2 * m * h <= duration)
    assert unforced.weak_info["test_functions"][0] == expected > single


def test_held_out_rows_are_kept_apart_from_the_training_rows(monkeypatch):
    """h-block cross-validation: each fold trains on the rows at least FOLD_GAP of a fold away
    from its held-out rows (and all the others when the gap is zero)."""
    rng = np.random.default_rng(0)
    theta = rng.normal(size=(1000, 3))
    moments = 1000 * np.eye(3)[None]
    seen = []
    factor = homogeneous.triangular_factor
    monkeypatch.setattr(homogeneous, "triangular_factor",
                        lambda rows: seen.append(len(rows)) or factor(rows))
    homogeneous._held_out_ratios(theta, moments, [np.arange(3)], 1, 5)
    gap = int(homogeneous.FOLD_GAP * 1000 / 5)
    # training then test factor per fold; the end folds lose one gap, the others two
    assert seen[0::2] == [800 - gap, 800 - 2 * gap, 800 - 2 * gap, 800 - 2 * gap, 800 - gap]
    assert seen[1::2] == [200] * 5
    seen.clear()
    monkeypatch.setattr(homogeneous, "FOLD_GAP", 0.0)
    homogeneous._held_out_ratios(theta, moments, [np.arange(3)], 1, 5)
    assert seen[0::2] == [800] * 5


def test_held_out_ratio_of_a_law_that_holds_stays_near_one():
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=(2, 4000))
    theta = np.column_stack([a, b, a - 2 * b]) + 0.05 * rng.normal(size=(4000, 3))
    ratios, _ = homogeneous._held_out_ratios(theta, 0.05**2 * 4000 * np.eye(3)[None],
                                             [np.arange(3)], 1, 5)
    assert 0.8 < ratios.mean() < 1.25


@pytest.mark.slow
def test_cart_double_pendulum_unforced_at_5_percent():
    """Paper catalog, three unforced 10 s runs, 5 % position noise, seed 0: the exact law
    (with one test-function width and no gap the selection returned an 11-term law missing
    the pendulums' friction and an inertia term)."""
    from support.unforced_cells import fit_unforced_cell

    model, true = fit_unforced_cell("cart_double_pendulum", 0.05, seed=0)
    coef = model.coefficients()
    np.testing.assert_array_equal(coef != 0, true != 0)
    scaled = coef * (coef @ true) / (coef @ coef)
    support = true != 0
    assert np.median(np.abs(scaled[support] - true[support]) / np.abs(true[support])) < 0.05
