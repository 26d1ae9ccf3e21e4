"""Lagrange category: candidate Lagrangian terms through the Euler-Lagrange operator."""

from __future__ import annotations

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
    out = []
    used = lagrangian.free_symbols
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


def _term_parts(term: sp.Expr, coords: Coordinates, weak: bool = False) -> tuple:
    """The Euler-Lagrange expressions ``E_i`` of one Lagrangian term (:func:`euler_lagrange`),
    or with ``weak`` its ``(P, Q)``: ``P_i = dL/dqd_i`` and ``Q_i = dL/dq_i`` expanded, one
    expression per coordinate; derived once per term and coordinates.

    A potential ``V(q)`` (no velocity) has ``P = 0`` and ``Q_i = -E_i``: the same expression
    as expanding ``dV/dq_i`` where the coefficients are exact (rationals), and equal to it up
    to rounding of float coefficients (a B-spline's), at half the cost of its derivation.
    """
    if not weak:
        return shared_derivation(("E", coords.variables, term),
                                 lambda: tuple(euler_lagrange(term, coords)),
                                 _PARTS, _CACHED_PARTS)

    def derive():
        used = term.free_symbols
        if not used & set(coords.qd):  # a potential: P = 0 and Q = -E, no second expansion
            columns = _term_parts(term, coords)
            return tuple(sp.Integer(0) for _ in coords.qd), tuple(-e for e in columns)
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
            lambda: (tuple(f"L[{term}]" for term in terms),
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
