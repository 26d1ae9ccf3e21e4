"""Cubic splines with quadratic ends: the basis against scipy's splines, a Morse wall beyond
the data, and the growth choosing between the two continuations."""

import numpy as np
import pytest
import sympy as sp
from scipy.interpolate import CubicSpline
from support.growth import damped_forced_runs

import pysindy_xl as px
from pysindy_xl.catalog.bases import quadratic_end_splines


def _values(basis, x, points):
    f = sp.lambdify(x, basis, "numpy")
    return np.array([np.broadcast_to(v, np.shape(points)) for v in f(points)], dtype=float)


def test_the_basis_spans_scipys_cubic_splines_and_continues_them_by_their_taylor_quadratic():
    x = sp.Symbol("x", real=True)
    low, high, k = -1.0, 2.0, 7
    basis = quadratic_end_splines(x, low, high, k)
    assert len(basis) == k + 2
    knots = np.linspace(low, high, k)
    rng = np.random.default_rng(0)
    # a clamped cubic spline through random values: end slopes free, end curvatures nonzero
    spline = CubicSpline(knots, rng.normal(size=k), bc_type=((1, 2.0), (1, -3.0)))
    inside = np.linspace(low, high, 301)
    columns = _values(basis, x, inside)
    weights = np.linalg.lstsq(columns.T, spline(inside), rcond=None)[0]
    assert np.abs(columns.T @ weights - spline(inside)).max() < 1e-10
    # beyond the end knots: value, slope and curvature of the end knot, no third derivative
    for end, outside in ((low, np.linspace(low - 2.0, low, 21)),
                         (high, np.linspace(high, high + 2.0, 21))):
        taylor = (spline(end) + spline(end, 1) * (outside - end)
                  + spline(end, 2) * (outside - end) ** 2 / 2)
        assert np.abs(_values(basis, x, outside).T @ weights - taylor).max() < 1e-9
    # a partition of unity everywhere
    everywhere = np.linspace(-4.0, 5.0, 91)
    assert np.allclose(_values(basis, x, everywhere).sum(axis=0), 1.0, atol=1e-12)


def test_bad_knots_and_ends_are_refused_by_name():
    x = sp.Symbol("x", real=True)
    with pytest.raises(ValueError, match="splines: expected at least 4 knots"):
        quadratic_end_splines(x, 0.0, 1.0, 3)
    with pytest.raises(ValueError, match="spline_ends"):
        px.AutomaticCatalog(["x"], splines=6, bounds=[(0.0, 1.0)], spline_ends="cubic").fit()


def test_a_catalog_with_quadratic_ends_has_two_more_columns_and_describes_them():
    natural = px.AutomaticCatalog(["x"], splines=8, bounds=[(0.0, 1.0)], kinetic="constant")
    quadratic = px.AutomaticCatalog(["x"], splines=8, bounds=[(0.0, 1.0)], kinetic="constant",
                                    spline_ends="quadratic")
    assert quadratic.n_terms == natural.n_terms + 2
    assert "8 cubic splines, quadratic ends" in quadratic.describe()
    assert [len(group) for group in quadratic.spline_columns()] == [9]


def _morse(q):
    """Force -dV/dx of the Morse well V = 2 (1 - exp(-1.5 x))^2."""
    e = np.exp(-1.5 * q)
    return -6.0 * e * (1.0 - e)


def _morse_runs():
    """x'' = u + F_morse(x) - 0.1 x' (unit mass), two forced runs by scipy at 1e-10."""
    return damped_forced_runs(_morse, 1.5, lambda rng, seed: 0.3 * (seed - 0.5))


def test_quadratic_ends_continue_a_morse_wall_where_natural_splines_go_flat(tmp_path):
    t, xs, dxs, ddxs, us = _morse_runs()
    stacked = np.vstack(xs)[:, 0]
    bounds = [tuple(np.percentile(stacked, [1, 99]))]
    # the repulsive wall, up to 0.1 below the lowest sample (there the wall's force is
    # 60 % above its value at the lowest sample)
    wall = np.linspace(stacked.min() - 0.1, stacked.min(), 20)[:, None]
    zero = np.zeros_like(wall)
    truth = -_morse(wall)  # the force the potential's Euler-Lagrange column predicts
    errors = {}
    for ends in ("linear", "quadratic"):
        catalog = px.AutomaticCatalog(["x"], bounds=bounds, splines=12, kinetic="constant",
                                      spline_ends=ends)
        model = px.XLSINDy(catalog, optimizer=px.ExplicitOptimizer(threshold=0.0)).fit(
            xs, [t, t], x_dot=dxs, x_ddot=ddxs, u=us)
        inside = np.linspace(*bounds[0], 50)[:, None]
        fitted = {"inside": model.predict_forces(inside, 0 * inside, 0 * inside),
                  "wall": model.predict_forces(wall, zero, zero)}
        errors[ends] = {part: np.abs(fitted[part] - truth_part).max() / np.abs(truth_part).max()
                        for part, truth_part in (("inside", -_morse(inside)), ("wall", truth))}
        if ends == "quadratic":  # simulate, save and load go through the restricted grammar
            start = np.array([stacked.min() - 0.05, 0.0])
            assert np.all(np.isfinite(model.simulate(start, t[:200], u=lambda _: np.zeros(1))))
            model.save(tmp_path / "quadratic_ends.json")
            loaded = px.XLSINDy.load(tmp_path / "quadratic_ends.json")
            assert np.allclose(loaded.predict_forces(wall, zero, zero), fitted["wall"],
                               rtol=1e-10, atol=1e-12)
            # the JAX export (single precision) beyond the knots too
            rhs = model.to_jax()
            derivative = np.asarray(rhs(np.hstack([wall, zero]), np.zeros_like(wall)))
            assert np.allclose(derivative[:, 1:], model.predict(wall, zero), rtol=1e-4,
                               atol=1e-4)
    # inside the knots every cubic spline fits the well; natural splines, whose curvature
    # vanishes at the end knots, cannot bend with the wall there
    assert errors["quadratic"]["inside"] < 0.02 < errors["linear"]["inside"]
    # the wall's stiffness keeps rising; a constant stiffness follows it far closer than a
    # constant force (12 % against 72 %)
    assert errors["quadratic"]["wall"] < 0.2 and errors["linear"]["wall"] > 0.5


def test_the_growth_gives_a_morse_wall_quadratic_ends():
    t, xs, dxs, ddxs, us = _morse_runs()
    noisy = [x + np.random.default_rng(3 + k).normal(0.0, 0.01 * x.std(), x.shape)
             for k, x in enumerate(xs)]
    # without the exponentials, which state the Morse well itself (test_exponentials.py), and
    # the anchored springs: a spring's length stands in for the wall on the held-out blocks
    # (criterion 0.26 against the quadratic ends' 0.43) but is 6 % off inside the data
    moves = tuple(m for m in px.catalog.MOVES if m not in ("exponentials", "anchored_springs"))
    found = px.grow_catalog(noisy, [t, t], us, coordinates=["x"], kinds=["linear"],
                            moves=moves)
    assert "quadratic ends" in found.catalog.describe()
    stacked = np.vstack(xs)[:, 0]
    q = np.linspace(stacked.min(), stacked.max(), 200)[:, None]
    zero = np.zeros_like(q)
    # the mass is identified up to the force columns' scale: compare accelerations
    predicted = found.model.predict(q, zero)
    truth = _morse(q)
    assert np.sqrt(np.mean((predicted - truth) ** 2)) < 0.02 * np.sqrt(np.mean(truth ** 2))
