"""Generalized coordinates and helpers that build candidate-term catalogs."""

from __future__ import annotations

import itertools
import keyword
from collections.abc import Iterable, Sequence

import numpy as np
import sympy as sp

from .expressions import FUNCTIONS, check_real_expression, check_term

__all__ = ["Coordinates", "monomials", "products", "stack_variables"]

# names the expression grammar reads as constants or functions, and the time symbol
_RESERVED = {"t", "E", "pi", "I", "oo", "nan", "zoo", *FUNCTIONS}


class Coordinates:
    """Generalized coordinates of a mechanical system and their sympy symbols.

    For a coordinate named ``x`` the symbols are ``x`` (position), ``x_dot``
    (velocity), ``x_ddot`` (acceleration) and ``tau_x`` (generalized force).

    Parameters
    ----------
    names : sequence of str
        Names of the coordinates, unique ASCII Python identifiers.

    Attributes
    ----------
    n : int
    names : tuple of str
    q, qd, qdd, tau : tuple of sympy.Symbol
        Positions, velocities, accelerations and generalized forces, one per coordinate.
    t : sympy.Symbol

    Examples
    --------
    >>> import pysindy_xl as px
    >>> coords = px.Coordinates(["x", "theta"])
    >>> coords.n, coords.qd
    (2, (x_dot, theta_dot))
    """

    def __init__(self, names: Sequence[str]):
        if isinstance(names, str) or not isinstance(names, Iterable):
            raise TypeError(f"names: expected a sequence of str, got {type(names).__name__}")
        names = tuple(names)
        if not names:
            raise ValueError("names: expected at least one coordinate name")
        for name in names:
            if not isinstance(name, str) or not name.isidentifier() or keyword.iskeyword(name):
                raise ValueError(f"names: {name!r} is not a valid identifier")
            if not name.isascii():
                raise ValueError(f"names: {name!r} is not ASCII; coordinate names must be ASCII "
                                 "identifiers (saved models spell them in the restricted term "
                                 "grammar), e.g. 'theta'")
            if (name in _RESERVED or name.startswith("tau_")
                    or name.endswith(("_dot", "_ddot"))):
                raise ValueError(f"names: {name!r} is reserved (time 't', constants 'E', 'pi', "
                                 "'I', function names, 'tau_*', '*_dot', '*_ddot')")
        if len(set(names)) != len(names):
            raise ValueError(f"names: duplicate coordinate names in {names}")
        self.names = names
        self.n = len(names)
        self.q = tuple(sp.Symbol(n, real=True) for n in names)
        self.qd = tuple(sp.Symbol(f"{n}_dot", real=True) for n in names)
        self.qdd = tuple(sp.Symbol(f"{n}_ddot", real=True) for n in names)
        self.tau = tuple(sp.Symbol(f"tau_{n}", real=True) for n in names)
        self.t = sp.Symbol("t", real=True)

    @property
    def state(self) -> tuple[sp.Symbol, ...]:
        """Symbols of the state ``(q_1..q_n, qd_1..qd_n)``."""
        return self.q + self.qd

    @property
    def variables(self) -> tuple[sp.Symbol, ...]:
        """``(q, qd, qdd, tau, t)``: the columns of the libraries' input
        (:func:`pysindy_xl.feature_library.stack_variables`)."""
        return self.q + self.qd + self.qdd + self.tau + (self.t,)

    def symbol_table(self) -> dict[str, sp.Symbol]:
        """Map from symbol name to symbol, used to parse saved expressions."""
        return {str(s): s for s in self.variables}

    def __eq__(self, other) -> bool:
        return isinstance(other, Coordinates) and other.names == self.names

    def __hash__(self) -> int:
        return hash(self.names)

    def __repr__(self) -> str:
        return f"Coordinates({list(self.names)!r})"


def as_expr_list(exprs, name: str) -> list[sp.Expr]:
    if isinstance(exprs, sp.Basic):
        exprs = [exprs]
    try:
        exprs = [sp.sympify(e) if isinstance(e, (int, float)) else e for e in exprs]
    except TypeError:
        raise TypeError(f"{name}: expected a sequence of sympy expressions") from None
    for e in exprs:
        if not isinstance(e, sp.Basic):
            raise TypeError(f"{name}: expected sympy expressions, got {type(e).__name__}")
        if e in _CHECKED:  # a clone's terms, checked when the original was fitted
            continue
        check_real_expression(e, name)
        check_term(e, name)
        _CHECKED[e] = None
        while len(_CHECKED) > _CACHED_CHECKS:
            del _CHECKED[next(iter(_CHECKED))]
    return exprs


#: Terms that passed the checks of :func:`as_expr_list` (each walks the whole tree), oldest first.
_CHECKED: dict = {}
_CACHED_CHECKS = 4096


def _unique(exprs: Iterable[sp.Expr]) -> list[sp.Expr]:
    return list(dict.fromkeys(e for e in exprs if e != 0))


def monomials(exprs, degree: int) -> list[sp.Expr]:
    """All products of ``exprs`` of total degree 1..``degree``, with repetition.

    Returns the distinct products (no constant), by degree then by input order.

    >>> import sympy as sp
    >>> a, b = sp.symbols("a b")
    >>> monomials([a, b], 2)
    [a, b, a**2, a*b, b**2]
    """
    exprs = as_expr_list(exprs, "exprs")
    from ._validation import check_option
    degree = check_option("degree", degree, "int", low=1)
    return _unique(sp.Mul(*combo) for d in range(1, degree + 1)
                   for combo in itertools.combinations_with_replacement(exprs, d))


def products(terms_a, terms_b) -> list[sp.Expr]:
    """Every pairwise product ``a * b``, de-duplicated, in order of first appearance.

    Include ``1`` in either list to keep the terms of the other list alone.

    >>> import sympy as sp
    >>> a, b = sp.symbols("a b")
    >>> products([1, a], [b, a])
    [b, a, a*b, a**2]
    """
    terms_a = as_expr_list(terms_a, "terms_a")
    terms_b = as_expr_list(terms_b, "terms_b")
    return _unique(sp.Mul(x, y) for x in terms_a for y in terms_b)


def stack_variables(q, qd, qdd=None, tau=None, t=None) -> np.ndarray:
    """Stack the data into the library input ``Z`` of shape ``(N, 4n + 1)``.

    Parameters
    ----------
    q, qd : array, shape (N, n)
        Positions and velocities.
    qdd, tau : array, shape (N, n), optional
        Accelerations and generalized forces; zeros when absent.
    t : array, shape (N,), optional
        Sample times; zeros when absent.

    Returns
    -------
    Z : ndarray, shape (N, 4n + 1)
        Columns in the order of :attr:`Coordinates.variables`.

    Examples
    --------
    >>> import numpy as np
    >>> stack_variables(np.zeros((5, 2)), np.ones((5, 2))).shape
    (5, 9)
    """
    q = np.asarray(q, dtype=float)
    if q.ndim != 2:
        raise ValueError(f"q: expected a 2-D array (n_samples, n), got shape {q.shape}")
    n_samples, n = q.shape
    parts = []
    for name, a in (("q", q), ("qd", qd), ("qdd", qdd), ("tau", tau)):
        a = np.zeros((n_samples, n)) if a is None else np.asarray(a, dtype=float)
        if a.shape != (n_samples, n):
            raise ValueError(f"{name}: expected shape {(n_samples, n)}, got {a.shape}")
        parts.append(a)
    t = np.zeros(n_samples) if t is None else np.asarray(t, dtype=float).reshape(-1)
    if t.shape != (n_samples,):
        raise ValueError(f"t: expected shape {(n_samples,)}, got {t.shape}")
    return np.column_stack(parts + [t])
