"""Lagrange terms derived once per term: catalogs that share terms get the columns and weak
parts that sympy's own differentiation gives, whatever was derived before."""

import numpy as np
import pytest
import sympy as sp

import pysindy_xl as px
from pysindy_xl.catalog.bases import bspline, natural_splines
from pysindy_xl.feature_library.lagrange import euler_lagrange, expanded_derivative


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


def _coefficients(expr):
    """``expr`` (an expanded sum) as ``{monomial: float coefficient}``."""
    out = {}
    for term in sp.Add.make_args(expr):
        coefficient, monomial = term.as_coeff_Mul()
        out[monomial] = out.get(monomial, 0.0) + float(coefficient)
    return out


@pytest.mark.parametrize("n_splines", [4, 8, 16])
def test_spline_potentials_get_sympys_euler_lagrange_expressions(n_splines):
    # the potentials' fast path (pieces derived once, products multiplied out by dictionary)
    # against sympy.diff and sympy.expand: the same monomials, the same coefficients up to
    # rounding (terms of rounding size may appear on one side only)
    coords = px.Coordinates(["x", "y"])
    x, y = coords.q
    basis = natural_splines(x, -1.3, 1.7, n_splines) + natural_splines(y, -0.4, 0.9, 5)
    library = px.LagrangeLibrary(coords, [*basis, x * y, y**2 * coords.qd[0] ** 2]).fit()
    matrix = library.symbolic_matrix()
    momenta, forces = library.weak_matrices()
    for k, term in enumerate(library.terms):
        columns, p_true, q_true = _truth(term, coords)
        for i in range(coords.n):
            for found, truth in ((matrix[i, k], columns[i]), (forces[i, k], q_true[i])):
                a, b = _coefficients(found), _coefficients(truth)
                scale = max([abs(v) for v in b.values()] + [1.0])
                for monomial in set(a) | set(b):
                    assert abs(a.get(monomial, 0.0) - b.get(monomial, 0.0)) <= 1e-13 * scale, \
                        (term, i, monomial)
            assert _same(momenta[i, k], p_true[i])
    z = np.linspace(-2.0, 2.5, 37)
    for k, term in enumerate(basis[:n_splines]):  # the values too, inside and beyond the knots
        expected = sp.lambdify(x, -sp.diff(term, x))(z)
        found = sp.lambdify(x, matrix[0, k])(z)
        # an expanded spline cancels terms of size ~ coefficient * |x|^2: rounding of ~1e-12
        np.testing.assert_allclose(found, expected, rtol=1e-10, atol=1e-10)


def test_exact_potentials_get_sympys_expressions_exactly():
    # exact coefficients: the fast path is sympy's expansion, expression for expression
    coords = px.Coordinates(["a", "b", "r"])
    a, b, r = coords.q
    potentials = [sp.cos(a), sp.cos(a) * sp.cos(b) - sp.sin(a) * sp.sin(b), r**4 / 4,
                  (r + 1) ** 3 * sp.sin(a) ** 2, sp.Rational(3, 7) * r**2 * sp.cos(b),
                  a**2 * b - 2 * r * sp.sin(a) * sp.cos(a), (sp.cos(a) + r) ** 2 / 3]
    for term in potentials:
        columns, _, forces = _truth(term, coords)
        assert euler_lagrange(term, coords) == columns, term
        assert [expanded_derivative(term, q) for q in coords.q] == forces, term


def test_expanded_derivative_is_sympys_expansion():
    x, y = sp.symbols("x y", real=True)
    z = 0.7 * x - 0.2
    expr = 2 * (x + sp.Abs(z) / 2) ** 3 - 0.5 * (x + sp.Abs(z) / 2) ** 3 * y + sp.sin(x) * y
    for symbol, scale in ((x, 1), (y, -1), (x, sp.Rational(-1, 3))):
        found = _coefficients(expanded_derivative(expr, symbol, scale))
        truth = _coefficients(sp.expand(scale * sp.diff(expr, symbol)))
        assert set(found) == set(truth)
        for monomial, value in truth.items():
            assert found[monomial] == pytest.approx(value, rel=1e-14, abs=1e-15)
    assert expanded_derivative(expr, sp.Symbol("w")) == 0


def test_potential_columns_are_canonical_sympy_sums():
    # built without sympy's flattening: the same objects (arguments in the same order) as
    # sympy.Add of the same terms, so they compare, hash and print as sympy's own
    coords = px.Coordinates(["x", "y"])
    x, y = coords.q
    for term in [*natural_splines(x, -1.0, 2.0, 6), x**3 * y - 2 * sp.cos(y) + y / 3]:
        for column in euler_lagrange(term, coords) + [expanded_derivative(term, y)]:
            rebuilt = sp.Add(*reversed(sp.Add.make_args(column)))
            assert column == rebuilt and column.args == rebuilt.args
            assert hash(column) == hash(rebuilt)
