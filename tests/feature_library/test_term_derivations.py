"""Lagrange terms derived once per term: catalogs that share terms get the columns and weak
parts that sympy's own differentiation gives, whatever was derived before."""

import numpy as np
import pytest
import sympy as sp

import pysindy_xl as px
from pysindy_xl.catalog.bases import bspline
from pysindy_xl.feature_library.lagrange import euler_lagrange


def _truth(term, coords):
    """Euler-Lagrange columns and (P, Q) by sympy.diff, independently of the package."""
    columns, momenta, forces = [], [], []
    for q, qd in zip(coords.q, coords.qd, strict=True):
        momentum = sp.diff(term, qd)
        d_dt = sum(sp.diff(momentum, a) * b for a, b in
                   zip((*coords.q, *coords.qd), (*coords.qd, *coords.qdd), strict=True))
        columns.append(sp.expand(d_dt + sp.diff(momentum, coords.t) - sp.diff(term, q)))
        momenta.append(sp.expand(momentum))
        forces.append(sp.expand(sp.diff(term, q)))
    return columns, momenta, forces


def _same(a, b):
    return sp.expand(a - b) == 0


def test_overlapping_catalogs_get_the_true_columns():
    coords = px.Coordinates(["r", "theta"])
    (r, th), (rd, thd) = coords.q, coords.qd
    shared = [rd**2, r**2 * thd**2, r * sp.cos(th), sp.Rational(3, 2) * rd * thd * sp.sin(th)]
    first = px.LagrangeLibrary(coords, [*shared, r**3, coords.t * r]).fit()
    second = px.LagrangeLibrary(coords, [r**4, *shared[::-1], th**2]).fit()
    for library in (first, second):
        matrix = library.symbolic_matrix()
        momenta, forces = library.weak_matrices()
        for k, term in enumerate(library.terms):
            columns, p_true, q_true = _truth(term, coords)
            for i in range(coords.n):
                assert _same(matrix[i, k], columns[i]), (term, i)
                assert _same(momenta[i, k], p_true[i]), (term, i)
                assert _same(forces[i, k], q_true[i]), (term, i)


def test_a_repeated_term_is_the_same_expression_as_a_fresh_derivation():
    # bit for bit: a term with float coefficients (a B-spline) gives the expressions that
    # deriving it alone gives, before and after other catalogs were derived
    coords = px.Coordinates(["x"])
    spline = bspline(coords.q[0], 0.3, 0.2)
    alone = px.LagrangeLibrary(coords, [spline]).fit()
    px.LagrangeLibrary(coords, [coords.q[0] ** 2, spline, coords.qd[0] ** 2]).fit()
    again = px.LagrangeLibrary(coords, [spline, coords.q[0] ** 3]).fit()
    assert again.symbolic_matrix()[0, 0] == alone.symbolic_matrix()[0, 0]
    assert again.weak_matrices()[1][0, 0] == alone.weak_matrices()[1][0, 0]
    assert euler_lagrange(spline, coords)[0] == alone.symbolic_matrix()[0, 0]
    assert _same(alone.symbolic_matrix()[0, 0], -sp.diff(spline, coords.q[0]))


def test_terms_finite_everywhere_skip_the_domain_check():
    coords = px.Coordinates(["x"])
    x = coords.q[0]
    spline, log = bspline(x, 0.0, 0.5), sp.log(x)
    library = px.LagrangeLibrary(coords, [spline, sp.tanh(x) * coords.qd[0] ** 2, log]).fit()
    checked, _ = library._domain_check()
    assert checked == [log]  # only the term with a domain is evaluated
    z = np.zeros((3, 5))
    z[:, 0] = [-1.0, 0.5, 2.0]
    with pytest.raises(ValueError, match="log"):
        library.check_domain(z)


def test_a_potential_with_float_coefficients_gets_its_gradient():
    # Q = -E for a potential: a B-spline's Q equals its derivative up to rounding
    coords = px.Coordinates(["x"])
    x = coords.q[0]
    spline = bspline(x, 0.3, 0.2)
    library = px.LagrangeLibrary(coords, [spline, x**2 * coords.qd[0] ** 2]).fit()
    momenta, forces = library.weak_matrices()
    assert momenta[0, 0] == 0
    z = np.linspace(-0.2, 0.8, 41)
    expected = sp.lambdify(x, sp.diff(spline, x))(z)
    found = sp.lambdify(x, forces[0, 0])(z)
    np.testing.assert_allclose(found, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
    np.testing.assert_allclose(sp.lambdify(x, -library.symbolic_matrix()[0, 0])(z), found,
                               rtol=0, atol=0)
