"""Lagrange category: candidate Lagrangian terms through the Euler-Lagrange operator."""

from __future__ import annotations

from fractions import Fraction
from functools import cmp_to_key

import numpy as np
import sympy as sp
from sklearn.utils.validation import check_is_fitted

from .._validation import Collection, InstanceOf
from ..expressions import format_expression
from ..symbols import Coordinates, as_expr_list
from ._base import SymbolicLibrary, shared_derivation

__all__ = ["LagrangeLibrary", "euler_lagrange"]


def _diff(expr: sp.Expr, symbol: sp.Symbol) -> sp.Expr:
    """Partial derivative by the chain rule on sums, products, powers, sin and cos (no
    ``Derivative`` object per node, as ``sympy.diff`` builds); anything else by ``sympy.diff``.
    """
    if symbol not in expr.free_symbols:
        return sp.Integer(0)
    if expr is symbol:
        return sp.Integer(1)
    if isinstance(expr, sp.Add):
        return sp.Add(*(_diff(a, symbol) for a in expr.args))
    if isinstance(expr, sp.Mul):
        args = expr.args
        return sp.Add(*(
            sp.Mul(*args[:i], _diff(a, symbol), *args[i + 1:])
            for i, a in enumerate(args) if symbol in a.free_symbols))
    if isinstance(expr, sp.Pow) and symbol not in expr.exp.free_symbols:
        base, exp = expr.args
        return exp * base ** (exp - 1) * _diff(base, symbol)
    if isinstance(expr, sp.sin):
        return sp.cos(expr.args[0]) * _diff(expr.args[0], symbol)
    if isinstance(expr, sp.cos):
        return -sp.sin(expr.args[0]) * _diff(expr.args[0], symbol)
    return sp.diff(expr, symbol)


def _defined_everywhere(expr: sp.Expr) -> bool:
    """Whether ``expr`` is finite at every finite value of its symbols (sums, products,
    nonnegative integer powers, ``sin``, ``cos``, ``Abs``, ``sign`` and ``tanh`` of finite
    numbers and symbols).
    """
    if expr.is_Symbol or isinstance(expr, sp.NumberSymbol):
        return True
    if expr.is_Number:
        return bool(expr.is_finite)
    if isinstance(expr, sp.Pow):
        return bool(expr.exp.is_Integer and expr.exp >= 0) and _defined_everywhere(expr.base)
    return (isinstance(expr, (sp.Add, sp.Mul, sp.sin, sp.cos, sp.Abs, sp.sign, sp.tanh))
            and all(_defined_everywhere(a) for a in expr.args))


#: ``expand(d piece / d symbol)`` as ``((monomial, coefficient), ...)`` by ``(piece, symbol)``
#: (:func:`expanded_derivative`): the pieces of splines recur in several terms.
_PIECE_DERIVATIVES: dict = {}
_CACHED_PIECES = 16384


#: The order of the terms of a sympy sum.
_CANONICAL = cmp_to_key(sp.Basic.compare)

#: ``sympy.expand(atom)`` by atom (:func:`_expanded_products`).
_ATOMS: dict = {}


def _python_number(number):
    """A sympy number as ``int``, ``Fraction`` (exact) or ``float``: the same value, the same
    rounding of products and sums of floats (IEEE double, like a 15-digit sympy ``Float``), at
    a fraction of sympy's cost."""
    if number.is_Integer:
        return int(number)
    if number.is_Rational:
        return Fraction(int(number.p), int(number.q))
    return float(number)


def _sympy_number(number) -> sp.Expr:
    """The inverse of :func:`_python_number`."""
    if isinstance(number, Fraction):
        return sp.Rational(number.numerator, number.denominator)
    return sp.Float(number) if isinstance(number, float) else sp.Integer(number)


def _scaled(number: sp.Expr, monomial: sp.Expr) -> sp.Expr:
    """``number * monomial`` for a monomial without a numeric factor, built without sympy's
    flattening (its arguments are already in canonical order: the number first)."""
    if monomial is sp.S.One or number is sp.S.One:
        return number * monomial
    args = monomial.args if isinstance(monomial, sp.Mul) else (monomial,)
    return sp.Mul._from_args((number, *args))


def _times(left: dict, right: dict) -> dict:
    """The product of two sums of monomials ``{((atom, power), ...): coefficient}``."""
    out: dict = {}
    for key_a, coef_a in left.items():
        for key_b, coef_b in right.items():
            powers = dict(key_a)
            for atom, power in key_b:
                powers[atom] = powers.get(atom, 0) + power
            key = frozenset(powers.items())
            out[key] = out.get(key, 0) + coef_a * coef_b
    return out


def _expanded_products(expr: sp.Expr, depth: int = 0) -> dict:
    """``expr`` multiplied out as ``{monomial: coefficient}``, a monomial being a frozenset of
    ``(atom, power)``: sums, products and positive integer powers distributed by dictionary
    arithmetic instead of :func:`sympy.expand`'s rewriting (the atoms, e.g. ``Abs(z)``, are
    expanded by sympy once each).
    """
    if expr.is_Number:
        return {frozenset(): _python_number(expr)}
    if isinstance(expr, sp.Add):
        out: dict = {}
        for arg in expr.args:
            for key, coef in _expanded_products(arg, depth).items():
                out[key] = out.get(key, 0) + coef
        return out
    if isinstance(expr, sp.Mul):
        out = {frozenset(): 1}
        for arg in expr.args:
            out = _times(out, _expanded_products(arg, depth))
        return out
    base, exp = expr.as_base_exp()
    if exp.is_Integer and exp > 0 and isinstance(base, (sp.Add, sp.Mul)):
        factor, out = _expanded_products(base, depth), {frozenset(): 1}
        for _ in range(int(exp)):
            out = _times(out, factor)
        return out
    if not (exp.is_Integer and exp > 0):
        base, exp = expr, sp.Integer(1)
    expanded = shared_derivation(base, lambda: sp.expand(base), _ATOMS, _CACHED_PIECES)
    if expanded != base and depth < 4:
        return _expanded_products(expanded ** exp, depth + 1)
    return {frozenset({(base, int(exp))}): 1}


def _monomials(expr: sp.Expr, depth: int = 0) -> dict:
    """``sympy.expand(expr)`` as ``{monomial: coefficient}`` with sympy monomials (up to the
    rounding of float coefficients): :func:`_expanded_products`, each monomial then built by
    sympy, whose automatic rewriting (``Abs(z)**2 = z**2`` for real ``z``) is expanded again.
    """
    out: dict = {}
    for key, coef in _expanded_products(expr, depth).items():
        monomial = sp.Mul(*(atom ** power for atom, power in key))
        c, rest = monomial.as_coeff_Mul()
        c = _python_number(c)
        factors = sp.Mul.make_args(rest)
        if depth < 4 and any(isinstance(f.as_base_exp()[0], (sp.Add, sp.Mul)) for f in factors):
            parts = _monomials(monomial, depth + 1)  # rewritten into a product of sums
        else:
            parts = {rest: c}
        for m, k in parts.items():
            out[m] = out.get(m, 0) + coef * k
    return out


def _piece_derivative(piece: sp.Expr, symbol: sp.Symbol) -> tuple:
    """``expand(d piece / d symbol)`` as pairs ``(monomial, coefficient)``, derived once."""
    def derive():
        return tuple((m, c) for m, c in _monomials(_diff(piece, symbol)).items() if c != 0)

    return shared_derivation((piece, symbol), derive, _PIECE_DERIVATIVES, _CACHED_PIECES)


def expanded_derivative(expr: sp.Expr, symbol: sp.Symbol, scale=1) -> sp.Expr:
    r"""``scale * expand(d expr / d symbol)``, derived term by term of ``expr``.

    With ``expr = sum_k c_k f_k`` (numbers ``c_k``, the terms' pieces ``f_k``),

    .. math:: \text{scale} \cdot \frac{\partial\, \text{expr}}{\partial\, \text{symbol}}
              = \sum_k (\text{scale}\, c_k)\, \operatorname{expand}
              \Big(\frac{\partial f_k}{\partial\, \text{symbol}}\Big),

    each piece's expanded derivative computed once (and kept for every expression that shares
    the piece: the cubic pieces of splines on the same knots) and the sum collected by
    monomial. The result equals ``sympy.expand(scale * sympy.diff(expr, symbol))``: exactly
    where the coefficients are exact (rationals), up to rounding where they are floats (the
    sums are added in another order).

    Parameters
    ----------
    expr : sympy.Expr
        The expression to differentiate.
    symbol : sympy.Symbol
        The variable.
    scale : number, default 1
        A factor of the result (``-1``: the Euler-Lagrange part ``-dL/dq`` of a potential).

    Returns
    -------
    sympy.Expr
        An expanded sum of products.

    Examples
    --------
    >>> import sympy as sp
    >>> x = sp.Symbol("x")
    >>> expanded_derivative(3 * (x + 1) ** 2 + (x + 1) ** 2 / 2 - sp.sin(x), x, -1)
    -7*x + cos(x) - 7
    """
    scale = _python_number(sp.sympify(scale))
    collected: dict = {}
    for term in sp.Add.make_args(expr):
        coefficient, piece = term.as_coeff_Mul()
        if symbol not in piece.free_symbols:
            continue
        factor = scale * _python_number(coefficient)
        for monomial, weight in _piece_derivative(piece, symbol):
            collected[monomial] = collected.get(monomial, 0) + factor * weight
    terms = [_scaled(_sympy_number(c), m) for m, c in collected.items() if c != 0]
    if len(terms) < 2:
        return sp.Add(*terms)
    # the canonical sum of distinct monomials without sympy's collection: the number first,
    # the other terms in sympy's order
    numbers = [t for t in terms if t.is_Number]
    others = sorted((t for t in terms if not t.is_Number), key=_CANONICAL)
    return sp.Add._from_args(numbers + others)


def euler_lagrange(lagrangian: sp.Expr, coords: Coordinates) -> list[sp.Expr]:
    r"""Euler-Lagrange expressions ``d/dt dL/dqd_i - dL/dq_i`` for every coordinate.

    .. math:: E_i = \frac{d}{dt}\frac{\partial L}{\partial \dot q_i}
              - \frac{\partial L}{\partial q_i}, \qquad
              \frac{d}{dt} = \sum_k \Big(\dot q_k \frac{\partial}{\partial q_k}
              + \ddot q_k \frac{\partial}{\partial \dot q_k}\Big) + \frac{\partial}{\partial t}.

    Parameters
    ----------
    lagrangian : sympy.Expr
        A Lagrangian in ``coords.q``, ``coords.qd`` and ``coords.t``.
    coords : Coordinates
        The generalized coordinates.

    Returns
    -------
    list of sympy.Expr
        One expanded expression per coordinate, linear in the accelerations (the equation of
        motion of an unforced system is ``E_i = 0``).

    Examples
    --------
    >>> import pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> euler_lagrange(c.qd[0] ** 2 / 2 - c.q[0] ** 2 / 2, c)
    [x + x_ddot]
    """
    used = lagrangian.free_symbols
    if not used & set(coords.qd + (coords.t,)):  # a potential V(q): E_i = -dV/dq_i
        return [expanded_derivative(lagrangian, qi, -1) if qi in used else sp.Integer(0)
                for qi in coords.q]
    out = []
    for qi, qdi in zip(coords.q, coords.qd, strict=True):
        # differentiate only with respect to symbols that occur: most catalog terms use few
        momentum = _diff(lagrangian, qdi) if qdi in used else sp.Integer(0)
        present = momentum.free_symbols
        d_dt = _diff(momentum, coords.t) if coords.t in present else sp.Integer(0)
        for qk, qdk, qddk in zip(coords.q, coords.qd, coords.qdd, strict=True):
            if qk in present:
                d_dt += _diff(momentum, qk) * qdk
            if qdk in present:
                d_dt += _diff(momentum, qdk) * qddk
        potential = _diff(lagrangian, qi) if qi in used else sp.Integer(0)
        out.append(sp.expand(d_dt - potential))
    return out


#: Derived parts of single terms by content (:func:`_term_parts`): catalogs tried one after
#: another (a growing automatic catalog) share most of their terms.
_PARTS: dict = {}
_CACHED_PARTS = 8192
#: Feature names by term (printing a spline costs about a millisecond).
_NAMES: dict = {}


def _term_parts(term: sp.Expr, coords: Coordinates, weak: bool = False) -> tuple:
    """The Euler-Lagrange expressions ``E_i`` of one Lagrangian term (:func:`euler_lagrange`),
    or with ``weak`` its ``(P, Q)``: ``P_i = dL/dqd_i`` and ``Q_i = dL/dq_i`` expanded, one
    expression per coordinate; derived once per term and coordinates.

    A potential ``V(q)`` (no velocity) has ``P = 0`` and ``Q_i = dV/dq_i = -E_i``, both
    from the pieces' derivatives that :func:`expanded_derivative` keeps.
    """
    if not weak:
        return shared_derivation(("E", coords.variables, term),
                                 lambda: tuple(euler_lagrange(term, coords)),
                                 _PARTS, _CACHED_PARTS)

    def derive():
        used = term.free_symbols
        if not used & set(coords.qd + (coords.t,)):  # a potential: P = 0 and Q = -E
            return (tuple(sp.Integer(0) for _ in coords.qd),
                    tuple(expanded_derivative(term, q) if q in used else sp.Integer(0)
                          for q in coords.q))
        return tuple(tuple(sp.expand(_diff(term, v)) if v in used else sp.Integer(0)
                           for v in variables) for variables in (coords.qd, coords.q))

    return shared_derivation(("PQ", coords.variables, term), derive, _PARTS, _CACHED_PARTS)


class LagrangeLibrary(SymbolicLibrary):
    r"""Candidate Lagrangian terms, each turned into its Euler-Lagrange column.

    Term ``L_k`` contributes its Euler-Lagrange expression to the equation of every coordinate
    ``i``, one coefficient ``xi_k`` per term shared by all equations:

    .. math:: E_{ik} = \frac{d}{dt}\frac{\partial L_k}{\partial \dot q_i}
              - \frac{\partial L_k}{\partial q_i}, \qquad
              \sum_k \xi_k E_{ik} = \tau_i \;\text{ for } L = \sum_k \xi_k L_k

    (:func:`euler_lagrange`; with the force column's coefficient -1).

    Parameters
    ----------
    coords : Coordinates
        The generalized coordinates.
    terms : sequence of sympy.Expr
        Candidate terms in ``coords.q``, ``coords.qd`` and ``coords.t`` (e.g. from
        :func:`pysindy_xl.products`).

    Attributes
    ----------
    terms_ : list of sympy.Expr
        The candidate terms, checked.
    zero_terms_ : list of int
        Terms whose column is identically zero (constants, total time derivatives): never
        identifiable.

    Examples
    --------
    >>> import sympy as sp, pysindy_xl as px
    >>> c = px.Coordinates(["theta"])
    >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, sp.cos(c.q[0])])
    >>> lib.fit().get_feature_names()
    ['L[theta_dot**2]', 'L[cos(theta)]']
    >>> lib.symbolic_matrix()
    Matrix([[2*theta_ddot, sin(theta)]])
    """

    category = "lagrange"
    column_rank = 1
    spec_type = "LagrangeLibrary"
    _parameter_constraints = {
        "coords": [InstanceOf(Coordinates, "a pysindy_xl.Coordinates")],
        "terms": [InstanceOf(sp.Basic, "a sympy expression"),
                  Collection("a sequence of sympy expressions")],
    }

    def __init__(self, coords: Coordinates, terms):
        self.coords = coords
        self.terms = terms

    def _build_symbolic(self):
        terms = as_expr_list(self.terms, "terms")
        if not terms:
            raise ValueError("terms: expected at least one candidate Lagrangian term")
        allowed = set(self.coords.q + self.coords.qd + (self.coords.t,))
        for term in terms:
            extra = term.free_symbols - allowed
            if extra:
                raise ValueError(f"terms: Lagrangian term {term} uses {sorted(map(str, extra))}; "
                                 "only positions, velocities and t are allowed")
        self.terms_ = terms
        # equal catalogs (refits, resampled fits) derive their columns once
        names, columns = shared_derivation(
            ("euler-lagrange", self.coords.variables, tuple(terms)),
            lambda: (tuple(shared_derivation(term, lambda t=term: f"L[{t}]", _NAMES,
                                             _CACHED_PARTS) for term in terms),
                     tuple(_term_parts(term, self.coords) for term in terms)))
        matrix = sp.Matrix(self.coords.n, len(terms), lambda i, j: columns[j][i])
        self.zero_terms_ = [j for j, col in enumerate(columns) if all(e == 0 for e in col)]
        return list(names), matrix

    def _feature_terms(self):
        return self.terms_

    def check_domain(self, x) -> None:
        """Raise ``ValueError`` naming the candidate terms that are NaN or inf on ``x``.

        A term outside its domain (``log(x)`` at ``x <= 0``) has no meaning there, even where its
        column is finite; terms defined everywhere are not evaluated.

        Parameters
        ----------
        x : array, shape (N, 4n + 1)
            Library input (:func:`~pysindy_xl.feature_library.stack_variables`).

        Raises
        ------
        ValueError
            Naming the terms that are NaN or inf on ``x`` and on how many samples.

        Examples
        --------
        >>> import numpy as np, sympy as sp, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, sp.log(c.q[0])]).fit()
        >>> lib.check_domain(np.array([[-1.0, 0, 0, 0, 0]]))
        Traceback (most recent call last):
        ...
        ValueError: feature_library: the Lagrangian term log(x) is NaN or inf on 1 of 1 samples...
        """
        check_is_fitted(self, "terms_")
        x = self._check_input(x)
        terms, evaluate = shared_derivation(
            ("domain check", self.coords.variables, tuple(self.terms_)),
            lambda: self._domain_check())
        if not terms:
            return
        with np.errstate(all="ignore"):
            values = evaluate(x)
        for term, value in zip(terms, values, strict=True):
            bad = ~np.isfinite(value)
            if bad.any():
                raise ValueError(f"feature_library: the Lagrangian term {term} is NaN or inf on "
                                 f"{int(bad.sum())} of {len(value)} samples (first at sample "
                                 f"{int(np.flatnonzero(bad)[0])}): the data leave its domain (log, "
                                 "sqrt, 1/x of values <= 0) or overflow it")

    def _domain_check(self):
        """The terms that may be undefined somewhere, and their compiled evaluation."""
        from ._compile import compile_entries

        terms = [term for term in self.terms_ if not _defined_everywhere(term)]
        return terms, (compile_entries(self.coords.variables, terms) if terms else None)

    def _build_weak_symbolic(self):
        # P = dL/dqd and Q = dL/dq: the Euler-Lagrange column before its time derivative
        terms, coords = self.terms_, self.coords
        parts = [_term_parts(term, coords, weak=True) for term in terms]
        return (sp.Matrix(coords.n, len(terms), lambda i, k: parts[k][0][i]),
                sp.Matrix(coords.n, len(terms), lambda i, k: parts[k][1][i]))

    def to_spec(self) -> dict:
        """JSON-serializable description of this library, read back by :meth:`from_spec`.

        Returns
        -------
        dict
            ``{"type": spec_type, ...}``: the parameters as plain JSON values, terms in the
            restricted grammar (:func:`~pysindy_xl.expressions.format_expression`).
        """
        terms = as_expr_list(self.terms, "terms")
        return {"type": self.spec_type, "terms": [format_expression(t) for t in terms]}

    @classmethod
    def from_spec(cls, spec, reader):
        """The library a specification describes (the inverse of :meth:`to_spec`).

        Parameters
        ----------
        spec : dict
            The description; untrusted (from a file).
        reader : SpecReader
            Parses its parts within the loader's budget
            (:class:`~pysindy_xl.feature_library.SpecReader`).

        Returns
        -------
        LagrangeLibrary
            The library, not fitted.
        """
        return cls(reader.coords, reader.terms(spec))
