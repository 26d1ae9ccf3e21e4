"""A coordinate's natural splines enter a model whole: the catalog's groups and the grouped fit."""

import pickle

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from sklearn.base import clone

import pysindy_xl as px
from pysindy_xl.catalog.bases import natural_splines
from pysindy_xl.optimizers import GroupedOptimizer, close_groups, optimizer_from_spec


def test_spline_columns_are_each_coordinates_splines_in_the_fitted_catalog():
    catalog = px.AutomaticCatalog(["x", "theta"], kinds=["linear", "angle"],
                                  bounds=[(-1.0, 2.0), (-0.5, 0.5)], splines={"x": 6, "theta": 5},
                                  interaction=2)
    groups = catalog.spline_columns()
    fitted = clone(catalog).fit()
    x, theta = fitted.coords.q
    for group, (q, low, high, k) in zip(groups, [(x, -1.0, 2.0, 6), (theta, -0.5, 0.5, 5)],
                                        strict=True):
        # the basis less its last function (they sum to 1: a constant potential)
        expected = natural_splines(q, low, high, k)[:-1]
        found = [fitted.feature_terms_[j] for j in group]
        assert len(found) == k - 1
        assert all(sp.simplify(a - b) == 0 for a, b in zip(found, expected, strict=True))
    assert not set(groups[0]) & set(groups[1])
    assert px.AutomaticCatalog(["x"]).spline_columns() == []


def test_close_groups_completes_touched_groups_only():
    support = np.array([True, False, True, False, False, False])
    closed = close_groups(support, [[1, 2], [3, 4], [5, 9]])
    assert closed.tolist() == [True, True, True, False, False, False]


def _log_cosh_runs(noise, seed=3):
    """x'' = u - 4 tanh(2 x) - 0.1 x' (V = 2 log cosh 2x, unit mass), by scipy at 1e-10,
    positions with Gaussian noise of ``noise`` times their spread."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 10.0, 0.002)
    xs, us = [], []
    for _ in range(2):
        frequencies, phases = rng.uniform(0.1, 1.0, 5), rng.uniform(0, 2 * np.pi, 5)

        def force(time, f=frequencies, p=phases):
            return 3.0 * np.sin(2 * np.pi * f * np.atleast_1d(time)[:, None] + p).sum(-1) / 2.5

        def rhs(time, y, force=force):
            return [y[1], force(time)[0] - 4 * np.tanh(2 * y[0]) - 0.1 * y[1]]

        y = solve_ivp(rhs, (0, t[-1]), rng.uniform(-1, 1, 2), t_eval=t, rtol=1e-10,
                      atol=1e-10, method="DOP853").y
        xs.append((y[0] + noise * y[0].std() * rng.normal(size=len(t)))[:, None])
        us.append(force(t)[:, None])
    return xs, [t, t], us


def test_grouped_fit_keeps_the_spline_potential_whole_and_right():
    xs, ts, us = _log_cosh_runs(noise=0.01)
    low, high = np.percentile(np.vstack(xs), [1, 99])
    catalog = px.AutomaticCatalog(["x"], bounds=[(low, high)], splines=12, kinetic="constant")
    group = catalog.spline_columns()[0]
    grouped = GroupedOptimizer(px.EnsembleOptimizer(px.ExplicitOptimizer()), groups=[group])
    model = px.XLSINDy(catalog, optimizer=grouped).fit(xs, ts, u=us)
    kept = model.coef_[group] != 0
    assert kept.all() or not kept.any()
    assert kept.all()
    # the potential's force against the truth 4 tanh(2 x) over the data's range
    grid = np.linspace(low, high, 41)[:, None]
    zero = np.zeros_like(grid)
    force = model.predict_forces(grid, zero, zero)[:, 0]
    truth = 4 * np.tanh(2 * grid[:, 0])
    # (the bagged selection of single splines keeps 7 of 11 here: 57 % off)
    assert np.linalg.norm(force - truth) / np.linalg.norm(truth) < 0.06
    # pickles; a model file names it (its groups, not plain values, are left out)
    assert pickle.loads(pickle.dumps(model)).coef_.tolist() == model.coef_.tolist()
    assert isinstance(optimizer_from_spec(model.optimizer_.to_spec()), GroupedOptimizer)


def test_grouped_optimizer_refuses_bad_groups():
    theta = np.random.default_rng(0).normal(size=(50, 3))
    with pytest.raises(ValueError, match="groups"):
        GroupedOptimizer(px.ExplicitOptimizer(), groups=[[0.5, 1]]).fit_catalog(theta, 1, [0])
