"""Fitting the same data in micrometres and in metres gives the same model in the
corresponding units (issue 13), for the explicit strong form with measured derivatives and
the weak form.

Positions in micrometres scale the generalized force of that coordinate by 1e-6 (N -> J/um,
the force conjugate to a coordinate in um) and the Lagrangian coefficients by the matching
powers of 1e-6.
"""

import warnings

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from sklearn.base import clone

import pysindy_xl as px
from pysindy_xl.optimizers import balance_coordinates, coordinate_weights, independent_columns

UM = 1e6  # micrometres per metre


def _oscillator(scale):
    """x'' + 3 x + 0.5 x^3 = u with x in metres, returned with positions times ``scale``."""
    t = np.linspace(0, 10, 2001)

    def u(s):
        return 0.4 * np.sin(1.1 * s) + 0.3 * np.cos(2.3 * s)

    def rhs(s, y):
        return [y[1], u(s) - 3 * y[0] - 0.5 * y[0] ** 3]

    y = solve_ivp(rhs, (0, 10), [0.2, 0.0], t_eval=t, rtol=1e-11, atol=1e-12).y.T
    acc = np.array([rhs(s, state)[1] for s, state in zip(t, y, strict=True)])
    force = np.array([u(s) for s in t])
    return t, y[:, :1] * scale, y[:, 1:] * scale, acc[:, None] * scale, force[:, None] / scale


def _cart_pole(scale):
    """Cart (x, metres) and pendulum; positions of the cart times ``scale``."""
    big_m, m, length, g = 1.0, 0.1, 0.5, 9.81
    t = np.linspace(0, 10, 2001)

    def u(s):
        return np.array([0.3 * np.sin(1.1 * s) + 0.2 * np.cos(2.3 * s), 0.05 * np.sin(0.7 * s)])

    def rhs(s, y):
        _, th, _, thd = y
        mass = np.array([[big_m + m, m * length * np.cos(th)],
                         [m * length * np.cos(th), m * length**2]])
        force = np.array([m * length * thd**2 * np.sin(th), -m * g * length * np.sin(th)])
        return np.concatenate([[y[2], thd], np.linalg.solve(mass, force + u(s))])

    y = solve_ivp(rhs, (0, 10), [0, 0.3, 0, 0], t_eval=t, rtol=1e-11, atol=1e-12).y.T
    acc = np.array([rhs(s, state)[2:] for s, state in zip(t, y, strict=True)])
    forces = np.array([u(s) for s in t])
    s = np.array([scale, 1.0])
    return t, y[:, :2] * s, y[:, 2:] * s, acc * s, forces / s


def _fit(library, formulation, t, x, xd, xdd, u):
    model = px.XLSINDy(library, px.ExplicitOptimizer(), formulation=formulation)
    kwargs = {"x_dot": xd, "x_ddot": xdd} if formulation == "strong" else {}
    with warnings.catch_warnings():
        warnings.simplefilter("error", px.IdentificationWarning)
        return model.fit(x, t, u=u, **kwargs).coefficients()


ONE = px.Coordinates(["x"])
X, XD = ONE.q[0], ONE.qd[0]


def _linear_oscillator(scale):
    """x'' + 3 x = u in metres; positions times ``scale``, forces divided by it."""
    t, x, xd, xdd, u = _oscillator(1.0)
    u = xdd + 3 * x  # the linear law on the same trajectory
    return t, x * scale, xd * scale, xdd * scale, u / scale


@pytest.mark.parametrize("formulation", ["strong", "weak"])
def test_linear_oscillator_in_micrometres(formulation):
    # L = xd^2/2 - 3/2 x^2: both coefficients scale by 1e-12 in um
    terms = [XD**2, X**2]
    metres = _fit(px.LagrangeLibrary(ONE, terms), formulation, *_linear_oscillator(1.0))
    micro = _fit(px.LagrangeLibrary(ONE, terms), formulation, *_linear_oscillator(UM))
    tolerance = 1e-8 if formulation == "strong" else 1e-4
    np.testing.assert_allclose(metres, [-1.0, 0.5, -1.5], rtol=tolerance)
    np.testing.assert_allclose(micro / [1.0, UM**-2, UM**-2], metres, rtol=tolerance)


# L = xd^2/2 - 3/2 x^2 - x^4/8; in um: xd^2 and x^2 scale by 1e-12, x^4 by 1e-24
ONE_TERMS = [XD**2, X**2, X**4, X**3]
ONE_TRUE = np.array([-1.0, 0.5, -1.5, -0.125, 0.0])
ONE_UNITS = np.array([1.0, UM**-2, UM**-2, UM**-4, UM**-3])


@pytest.mark.parametrize("formulation", ["strong", "weak"])
def test_cubic_oscillator_in_micrometres(formulation):
    metres = _fit(px.LagrangeLibrary(ONE, ONE_TERMS), formulation, *_oscillator(1.0))
    np.testing.assert_allclose(metres, ONE_TRUE, atol=1e-3)
    micro = _fit(px.LagrangeLibrary(ONE, ONE_TERMS), formulation, *_oscillator(UM))
    np.testing.assert_allclose(micro / ONE_UNITS, metres, rtol=1e-3, atol=1e-3)


TWO = px.Coordinates(["x", "theta"])
(XC, TH), (XCD, THD) = TWO.q, TWO.qd
TWO_TERMS = [XCD**2, THD**2, XCD * THD * sp.cos(TH), sp.cos(TH), XC**2]
TWO_TRUE = np.array([-1.0, 0.55, 0.0125, 0.05, 0.4905, 0.0])
TWO_UNITS = np.array([1.0, UM**-2, 1.0, UM**-1, 1.0, UM**-2])


@pytest.mark.parametrize("formulation", ["strong", "weak"])
def test_cart_pole_in_metres(formulation):
    # guards the next test: in metres the model is found
    metres = _fit(px.LagrangeLibrary(TWO, TWO_TERMS), formulation, *_cart_pole(1.0))
    np.testing.assert_allclose(metres, TWO_TRUE, atol=1e-3)


@pytest.mark.parametrize("formulation", ["strong", "weak"])
def test_cart_pole_with_the_cart_in_micrometres(formulation):
    micro = _fit(px.LagrangeLibrary(TWO, TWO_TERMS), formulation, *_cart_pole(UM))
    np.testing.assert_allclose(micro / TWO_UNITS, TWO_TRUE, rtol=1e-3, atol=1e-3)


def test_cubic_oscillator_in_micrometres_keeps_the_forces():
    # the x^4 column is ~1e24 times the forces in um: once a "zero column" (then a units error),
    # now the same catalog reduction as in metres
    fits = [px.XLSINDy(px.LagrangeLibrary(ONE, ONE_TERMS), px.ExplicitOptimizer(),
                       formulation="strong")
            for _ in range(2)]
    for model, scale in zip(fits, (1.0, UM), strict=True):
        t, x, xd, xdd, u = _oscillator(scale)
        model.fit(x, t, x_dot=xd, x_ddot=xdd, u=u)
    assert fits[1].dropped_features_ == fits[0].dropped_features_
    assert fits[1].coefficients()[0] == -1.0  # the force column (first) is kept


# ----------------------------------------------------------------- the optimizers alone
def _two_block_problem(seed=0, n=400, noise=1e-3):
    """theta = [a (block 0), b (block 1), coupling (both), spurious (both), force (both)]."""
    rng = np.random.default_rng(seed)
    zeros = np.zeros(n)
    a, b, c0, c1, s0, s1 = rng.normal(size=(6, n))
    columns = np.column_stack([np.concatenate(pair) for pair in
                               ((a, zeros), (zeros, b), (c0, c1), (s0, s1))])
    true = np.array([1.0, 2.0, 0.5, 0.0])
    force = columns @ true + noise * rng.normal(size=2 * n)
    return np.column_stack([columns, force]), np.append(true, -1.0)


@pytest.mark.parametrize("optimizer", [
    px.ExplicitOptimizer(),
    px.ExplicitOptimizer(method="lasso", alpha=1e-5),
    px.MixedOptimizer(),
    px.EnsembleOptimizer(n_models=5, random_state=0),
])
def test_optimizer_is_equivariant_under_units(optimizer):
    # block 0 in other units (x 1e6, its force included) and the coupling column x 1e-12: the
    # same coefficients up to the unit factor of that column
    theta, true = _two_block_problem()
    reference = clone(optimizer).fit_catalog(theta, 2, [4]).coef_
    np.testing.assert_allclose(reference, true, atol=1e-2)
    scaled = theta.copy()
    scaled[:400] *= 1e6
    scaled[:, 2] *= 1e-12
    coef = clone(optimizer).fit_catalog(scaled, 2, [4]).coef_
    factor = np.array([1.0, 1.0, 1e12, 1.0, 1.0])
    np.testing.assert_array_equal(coef != 0, reference != 0)
    np.testing.assert_allclose(coef / factor, reference, rtol=1e-6, atol=1e-12)


def test_coordinate_weights_are_unit_free():
    theta, _ = _two_block_problem()
    scaled = theta.copy()
    scaled[:400] *= 1e6
    scaled[:, 2] *= 1e-12
    w, w_scaled = (coordinate_weights(m, 2, [4]) for m in (theta, scaled))
    np.testing.assert_allclose(w_scaled[0] / w_scaled[1] * 1e6, w[0] / w[1], rtol=1e-12)
    # balanced twice: the second balancing is a no-op
    np.testing.assert_allclose(
        coordinate_weights(balance_coordinates(scaled, 2, [4]), 2, [4]), 1.0, rtol=1e-12)


def test_independent_columns_keeps_a_coupling_column_across_units():
    # coordinate 0 in um: the coupling column is 1e-12 in block 0 and O(1) in block 1, where it
    # equals column b; it is still independent (its block-0 part is not in the span of a)
    rng = np.random.default_rng(1)
    n = 300
    zeros = np.zeros(n)
    a, b, g, f0, f1 = rng.normal(size=(5, n))
    theta = np.column_stack([
        np.concatenate([a, zeros]),          # 0: block 0 only
        np.concatenate([zeros, b]),          # 1: block 1 only
        np.concatenate([1e-12 * g, b]),      # 2: coupling, blocks 1e12 apart
        np.concatenate([a, b]),              # 3: = col 0 + col 1
        np.concatenate([1e-6 * f0, f1]),     # 4: forces
    ])
    keep, dropped = independent_columns(theta, n_blocks=2, force_columns=[4])
    assert keep.tolist() == [0, 1, 2, 4]
    assert dropped == {3: "linear combination"}
    # without the block structure the coupling column is indistinguishable from column 1
    assert 2 in independent_columns(theta)[1]
