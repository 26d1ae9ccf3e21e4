"""Terms held as trigonometric polynomials (TrigTerms): the same names, columns, files and
coefficients as their sympy expressions, without building those expressions."""

import pickle

import numpy as np
import pytest
import sympy as sp
from kinematic_models import CART_DOUBLE_PENDULUM, PLANAR_ARM, robot_arm
from sklearn.base import clone

import pysindy_xl as px
from pysindy_xl.feature_library import PolynomialLagrangeLibrary, stack_variables
from pysindy_xl.feature_library.trigpoly import TrigPolynomial, euler_lagrange_many
from pysindy_xl.feature_library.trigterms import TrigTerms
from pysindy_xl.mujoco import MJCFSystem


def _random_polynomials(n, angles, rng, count=200):
    out = []
    for _ in range(count):
        size = int(rng.integers(1, 4))
        exponents = rng.integers(0, 3, (size, 4 * n)) * (rng.random((size, 4 * n)) < 0.4)
        exponents[:, 3 * n:] = 0
        exponents[:, n:2 * n] *= np.asarray(angles)  # no cosine of a linear coordinate
        values = rng.choice([1.0, 0.5, 2.0, 9.81, 1e-5, 3.25e7, 0.1, 0.123456789], size)
        signs = rng.choice([1.0, -1.0], size)
        polynomial = TrigPolynomial(exponents, values * signs, angles)
        if not polynomial.is_zero:
            out.append(polynomial)
    out.append(TrigPolynomial.constant(2.5, angles))
    out.append(TrigPolynomial.constant(-1.0, angles))
    return out


@pytest.mark.parametrize("angles", [(True,), (True, False), (False, True, True)])
def test_names_are_sympys_str(angles):
    """Names are formatted from the exponent rows, exactly as sympy prints the expression."""
    n = len(angles)
    coords = px.Coordinates([f"q{k}" for k in range(n)])
    polynomials = _random_polynomials(n, angles, np.random.default_rng(n))
    terms = TrigTerms(polynomials, coords)
    assert terms.names() == [str(p.to_sympy(coords)) for p in polynomials]


@pytest.mark.parametrize("xml", [PLANAR_ARM, CART_DOUBLE_PENDULUM, robot_arm(5)],
                         ids=["planar", "cart-two-link", "robot-5"])
def test_catalog_library_matches_the_sympy_terms(xml):
    """The catalog's library (polynomial terms) and the same library given the sympy
    expressions of its terms have the same names, columns and file description; fitting the
    first builds no sympy term."""
    catalog = px.kinematic_catalog(MJCFSystem(xml))
    terms = catalog.lagrange_terms
    fresh = TrigTerms(terms.polynomials, terms.coords)  # nothing built yet
    fast = PolynomialLagrangeLibrary(catalog.coords, fresh, catalog.parameters,
                                     catalog.tree).fit()
    assert all(e is None for e in fresh._exprs)
    expressions = [p.to_sympy(catalog.coords) for p in terms.polynomials]
    slow = PolynomialLagrangeLibrary(catalog.coords, expressions, catalog.parameters,
                                     catalog.tree).fit()
    assert fast.get_feature_names() == slow.get_feature_names()
    assert fast.get_feature_names() == [f"L[{e}]" for e in expressions]
    rng = np.random.default_rng(0)
    x = stack_variables(*rng.normal(size=(4, 30, catalog.coords.n)))
    np.testing.assert_array_equal(fast.transform(x), slow.transform(x))
    assert fast.symbolic_matrix_ == slow.symbolic_matrix_
    assert fast.to_spec() == slow.to_spec()
    assert list(fresh) == expressions  # items built on demand are the expressions
    assert fresh + [sp.Integer(1)] == expressions + [1] and [] + fresh == expressions
    assert fresh[-1] == expressions[-1] and fresh[:2] == expressions[:2]


def test_trig_terms_are_shared_and_pickle():
    catalog = px.kinematic_catalog(MJCFSystem(robot_arm(4)))
    library = catalog.library()
    lagrange = library.libraries[1]
    assert clone(lagrange).terms is lagrange.terms
    again = pickle.loads(pickle.dumps(lagrange.fit()))
    assert again.terms == lagrange.terms
    assert again.get_feature_names() == lagrange.get_feature_names()


def test_acceleration_in_a_term_is_refused():
    coords = px.Coordinates(["a"])
    exponents = np.zeros((1, 4))
    exponents[0, 3] = 1  # a_ddot
    terms = TrigTerms([TrigPolynomial(exponents, [1.0], (True,))], coords)
    with pytest.raises(ValueError, match="terms: .*accelerations"):
        PolynomialLagrangeLibrary(coords, terms).fit()


def test_bad_polynomials_are_refused():
    coords = px.Coordinates(["a", "b"])
    with pytest.raises(ValueError, match="polynomials"):
        TrigTerms([TrigPolynomial.constant(1.0, (True,))], coords)
    with pytest.raises(ValueError, match="polynomials"):
        TrigTerms([TrigPolynomial.constant(1.0, (True, True)),
                   TrigPolynomial.constant(1.0, (True, False))], coords)
    assert sp.sympify(TrigTerms([TrigPolynomial.constant(1.0, (True, True))], coords)[0]) == 1


@pytest.mark.parametrize("angles", [(True, True, True), (False, True, False)])
def test_euler_lagrange_many_is_each_polynomials_bit_for_bit(angles):
    """The stacked derivation gives exactly (same rows, same bits) each polynomial's own
    Euler-Lagrange column, including merged and dropped round-off terms."""
    n = len(angles)
    rng = np.random.default_rng(7)
    polynomials = _random_polynomials(n, angles, rng, count=60)
    polynomials += px.kinematic_catalog(MJCFSystem(robot_arm(3))).lagrange_terms.polynomials \
        if angles == (True, True, True) else []
    stacked = euler_lagrange_many(polynomials)
    for polynomial, column in zip(polynomials, stacked, strict=True):
        for alone, together in zip(polynomial.euler_lagrange(), column, strict=True):
            np.testing.assert_array_equal(alone.exponents, together.exponents)
            np.testing.assert_array_equal(alone.coefficients, together.coefficients)
    assert euler_lagrange_many([]) == []


def test_unique_rows_is_numpys_unique_of_the_row_bytes():
    """One int64 key per row sorts and groups rows as their bytes do, including entries a
    key cannot hold (negative or past one byte, compared as bytes)."""
    from pysindy_xl.feature_library._monomials import unique_rows

    rng = np.random.default_rng(3)
    for high in (1, 3, 300, 40_000):
        for _ in range(20):
            rows = rng.integers(-high if high > 300 else 0, high, (int(rng.integers(1, 60)), 9))
            rows = np.vstack([rows, rows[: len(rows) // 2]]).astype(np.int16)
            keys = rows.view(np.dtype((np.void, rows.shape[1] * 2))).ravel()
            _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
            found = unique_rows(rows)
            np.testing.assert_array_equal(found[0], first)
            np.testing.assert_array_equal(found[1], inverse.ravel())


def test_evaluate_many_matches_the_sympy_expressions():
    """Monomials evaluated factor by factor equal the polynomials' sympy expressions."""
    from pysindy_xl.feature_library.trigpoly import evaluate_many, state_values

    angles = (True, False, True)
    coords = px.Coordinates(["a", "b", "c"])
    polynomials = _random_polynomials(3, angles, np.random.default_rng(5), count=40)
    rng = np.random.default_rng(6)
    q, qd = rng.uniform(-2, 2, (2, 25, 3))
    states = state_values(q, qd, angles=angles)
    values = evaluate_many(polynomials, states)
    # round-off bound: the sum of the terms' magnitudes
    scale = evaluate_many([TrigPolynomial(p.exponents, np.abs(p.coefficients), angles,
                                          normalize=False) for p in polynomials],
                          np.abs(states))
    for k, polynomial in enumerate(polynomials):
        expected = sp.lambdify(list(coords.q) + list(coords.qd),
                               polynomial.to_sympy(coords), "numpy")(*q.T, *qd.T)
        assert np.all(np.abs(values[:, k] - expected) <= 1e-13 * scale[:, k] + 1e-300)


def test_terms_as_arrays_evaluate_bit_for_bit_as_tuples():
    """Terms given as arrays (a polynomial library's columns) hold the same entries as their
    tuples, reorder as they do, and compile to an evaluator with the same bits; both agree
    with the sympy columns."""
    from pysindy_xl.feature_library._compile import Terms, compile_terms

    library = px.kinematic_catalog(MJCFSystem(robot_arm(3))).library().fit()
    part = next(lib for lib in library.libraries_ if isinstance(lib, PolynomialLagrangeLibrary))
    arrays = part.column_terms()
    assert arrays._entries is None  # derived as arrays
    tuples = Terms(arrays.atoms, [list(entry) for entry in arrays.entries])
    assert tuples == arrays
    for made, given in zip(tuples.arrays(), arrays.arrays(), strict=True):  # both ways
        np.testing.assert_array_equal(made, given)
    order = np.random.default_rng(0).permutation(len(tuples))[:40]
    assert Terms.from_arrays(arrays.atoms, *arrays.arrays()).take(order) == tuples.take(order)
    variables = part.coords.variables
    z = np.random.default_rng(1).normal(size=(64, len(variables)))
    fast = compile_terms(variables, arrays)(z, stacked=True)
    slow = compile_terms(variables, tuples)(z, stacked=True)
    np.testing.assert_array_equal(fast, slow)
    matrix = part.symbolic_matrix_
    for k, (c, j) in enumerate(part.entry_index_[:30]):
        expected = sp.lambdify(variables, matrix[c, j], "numpy")(*z.T)
        np.testing.assert_allclose(fast[k], expected, rtol=1e-10, atol=1e-10)
    assert pickle.loads(pickle.dumps(arrays)) == arrays


def _cosine_squares_pass_by_pass(exponents, coefficients, owners, angles):
    """The rewriting one pass at a time: in each row, the first angle whose cosine power is
    >= 2; unchanged rows, then ``cos^(k-2)`` rows, then ``-sin^2 cos^(k-2)`` rows."""
    n, angle = len(angles), np.asarray(angles)
    while True:
        high = (exponents[:, n:2 * n] >= 2) & angle
        rows = np.flatnonzero(high.any(axis=1))
        if not len(rows):
            return exponents, coefficients, owners
        slot = n + np.argmax(high[rows], axis=1)
        keep = ~high.any(axis=1)
        base = exponents[rows]
        base[np.arange(len(rows)), slot] -= 2
        sine = base.copy()
        sine[np.arange(len(rows)), slot - n] += 2
        exponents = np.vstack([exponents[keep], base, sine])
        coefficients = np.concatenate([coefficients[keep], coefficients[rows],
                                       -coefficients[rows]])
        owners = np.concatenate([owners[keep], owners[rows], owners[rows]])


def test_cosine_squares_rewrite_row_for_row_and_keep_the_values():
    """High cosine powers of several angles become the rows (same order, same bits) of the
    pass-by-pass rewriting, and the polynomial keeps its values (cos^2 + sin^2 = 1)."""
    from pysindy_xl.feature_library._monomials import _reduce_cosine_squares
    from pysindy_xl.feature_library.trigpoly import evaluate_many, state_values

    angles = (True, False, True, True)
    rng = np.random.default_rng(11)
    exponents = rng.integers(0, 6, (40, 16)).astype(np.int16)
    exponents[:, 5] = 0  # no cosine of the linear coordinate
    coefficients, owners = rng.normal(size=40), rng.integers(0, 5, 40)
    found = _reduce_cosine_squares(exponents, coefficients, owners, angles)
    expected = _cosine_squares_pass_by_pass(exponents, coefficients, owners, angles)
    for a, b in zip(found, expected, strict=True):
        np.testing.assert_array_equal(a, b)
    assert found[0][:, [4, 6, 7]].max() < 2 and len(found[0]) > 10 * len(exponents)
    q, qd, qdd = rng.uniform(-2, 2, (3, 10, 4))
    states = state_values(q, qd, qdd, angles=angles)
    before = evaluate_many([TrigPolynomial(exponents, coefficients, angles, normalize=False)],
                           states)
    after = evaluate_many([TrigPolynomial(found[0], found[1], angles, normalize=False)], states)
    np.testing.assert_allclose(after, before, rtol=1e-9)
