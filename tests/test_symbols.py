"""Coordinates and the catalog helpers ``monomials`` / ``products``."""

import itertools
from math import comb

import numpy as np
import pytest
import sympy as sp

import pysindy_xl as px


def test_coordinates_attributes_and_symbol_names():
    coords = px.Coordinates(["x", "theta"])
    assert coords.n == 2
    assert coords.names == ("x", "theta")
    assert [str(s) for s in coords.q] == ["x", "theta"]
    assert [str(s) for s in coords.qd] == ["x_dot", "theta_dot"]
    assert [str(s) for s in coords.qdd] == ["x_ddot", "theta_ddot"]
    assert [str(s) for s in coords.tau] == ["tau_x", "tau_theta"]
    assert str(coords.t) == "t"
    for symbol in (*coords.variables,):
        assert isinstance(symbol, sp.Symbol)
        assert symbol.is_real is True
    assert coords.state == coords.q + coords.qd
    assert coords.variables == coords.q + coords.qd + coords.qdd + coords.tau + (coords.t,)
    assert len(coords.variables) == 4 * coords.n + 1
    assert len(set(coords.variables)) == len(coords.variables)


def test_symbols_are_shared_between_equal_coordinates():
    # Two Coordinates with the same names must produce the same sympy symbols, otherwise
    # expressions built from one would not be recognized by libraries built on the other.
    a, b = px.Coordinates(["x", "theta"]), px.Coordinates(("x", "theta"))
    assert a == b and hash(a) == hash(b)
    assert a.variables == b.variables
    assert a != px.Coordinates(["theta", "x"])
    assert a.q[0] == sp.Symbol("x", real=True)
    assert a.q[0] != sp.Symbol("x")  # assumptions are part of the symbol


def test_symbol_table_maps_names_to_variables():
    coords = px.Coordinates(["q1", "q2"])
    table = coords.symbol_table()
    assert set(table) == {str(s) for s in coords.variables}
    assert table["q2_ddot"] is coords.qdd[1]
    assert table["tau_q1"] is coords.tau[0]
    assert table["t"] is coords.t


def test_single_coordinate_accepts_any_iterable_of_names():
    coords = px.Coordinates(name for name in ["phi"])
    assert coords.n == 1 and coords.names == ("phi",)
    assert "phi" in repr(coords)


@pytest.mark.parametrize(
    "names",
    [
        ["x", "x"],
        ["a", "b", "a"],
    ],
)
def test_duplicate_names_rejected(names):
    with pytest.raises(ValueError, match="names.*duplicate"):
        px.Coordinates(names)


@pytest.mark.parametrize("name", ["t", "tau_x", "x_dot", "x_ddot", "tau_"])
def test_reserved_names_rejected(name):
    with pytest.raises(ValueError, match="names.*reserved"):
        px.Coordinates(["a", name])


@pytest.mark.parametrize("name", ["1x", "x y", "x-y", "", "lambda", "class", "x.y", "sin(x)"])
def test_non_identifier_names_rejected(name):
    with pytest.raises(ValueError, match="names"):
        px.Coordinates([name])


def test_non_string_name_rejected():
    with pytest.raises(ValueError, match="names"):
        px.Coordinates(["x", 3])


def test_empty_names_rejected():
    with pytest.raises(ValueError, match="names"):
        px.Coordinates([])


@pytest.mark.parametrize("names", ["theta", 3, None])
def test_names_must_be_a_sequence(names):
    with pytest.raises(TypeError, match="names"):
        px.Coordinates(names)


def test_monomials_contents_and_order():
    a, b = sp.symbols("a b")
    assert px.monomials([a, b], 2) == [a, b, a**2, a * b, b**2]
    assert px.monomials([a], 3) == [a, a**2, a**3]
    assert px.monomials(a, 1) == [a]


@pytest.mark.parametrize("n_base, degree", [(1, 4), (2, 3), (3, 2), (4, 3)])
def test_monomials_count_matches_combinatorics(n_base, degree):
    base = sp.symbols(f"s0:{n_base}")
    out = px.monomials(base, degree)
    # multisets of size d from n_base items, d = 1..degree
    expected = sum(comb(n_base + d - 1, d) for d in range(1, degree + 1))
    assert len(out) == expected
    assert len(set(out)) == len(out)
    assert all(sp.Poly(m, *base).total_degree() <= degree for m in out)
    assert sp.Integer(1) not in out


def test_monomials_of_trigonometric_functions_keep_distinct_products():
    theta = px.Coordinates(["theta"]).q[0]
    out = px.monomials([sp.sin(theta), sp.cos(theta)], 2)
    assert out == [sp.sin(theta), sp.cos(theta), sp.sin(theta) ** 2,
                   sp.sin(theta) * sp.cos(theta), sp.cos(theta) ** 2]


def test_monomials_drop_duplicates_and_zero():
    a = sp.Symbol("a")
    # a and a**1 are the same expression; the zero base function contributes nothing
    out = px.monomials([a, a**1, sp.Integer(0)], 2)
    assert out == [a, a**2]


@pytest.mark.parametrize("degree, error", [(0, ValueError), (-1, ValueError), (1.5, ValueError),
                                           (2.0, ValueError), (True, TypeError),
                                           ("2", TypeError), (None, TypeError)])
def test_monomials_bad_degree(degree, error):
    a = sp.Symbol("a")
    with pytest.raises(error, match="degree: expected an integer >= 1"):
        px.monomials([a], degree)


@pytest.mark.parametrize("degree", [np.int64(2), np.int32(2)])
def test_monomials_numpy_integer_degree(degree):
    a, b = sp.symbols("a b")
    assert px.monomials([a, b], degree) == [a, b, a**2, a * b, b**2]


def test_monomials_bad_exprs():
    with pytest.raises(TypeError, match="exprs"):
        px.monomials(["a", "b"], 2)
    with pytest.raises(TypeError, match="exprs"):
        px.monomials(3, 2)


def test_products_contents_order_and_dedup():
    a, b = sp.symbols("a b")
    assert px.products([1, a], [b, a]) == [b, a, a * b, a**2]
    # commutative duplicates (a*b == b*a) appear once
    assert px.products([a, b], [a, b]) == [a**2, a * b, b**2]


def test_products_count_and_membership():
    coords = px.Coordinates(["x", "theta"])
    trig = [sp.sin(coords.q[1]), sp.cos(coords.q[1])]
    velocities = px.monomials(coords.qd, 2)
    terms = px.products([1, *trig], [1, *velocities])
    assert len(velocities) == 5
    # (1 + 2) * (1 + 5) products, all distinct except nothing: constant 1 included once
    assert len(terms) == 3 * 6
    assert sp.Integer(1) in terms
    expected = {sp.Mul(u, v) for u, v in itertools.product([1, *trig], [1, *velocities])}
    assert set(terms) == expected


def test_products_with_zero_and_bad_input():
    a = sp.Symbol("a")
    assert px.products([0, a], [a]) == [a**2]
    with pytest.raises(TypeError, match="terms_a"):
        px.products([object()], [a])
    with pytest.raises(TypeError, match="terms_b"):
        px.products([a], ["a"])


def test_products_are_usable_by_numpy_lambdify():
    # the catalog terms are plain sympy expressions in the coordinate symbols
    coords = px.Coordinates(["x"])
    terms = px.products([1, sp.cos(coords.q[0])], [coords.qd[0]])
    f = sp.lambdify(coords.state, terms, "numpy")
    values = f(np.array([0.0, np.pi]), np.array([2.0, 3.0]))
    np.testing.assert_allclose(values[0], [2.0, 3.0])
    np.testing.assert_allclose(values[1], [2.0, -3.0])
