"""Sparse polynomials in ``sin q``, ``cos q``, ``q``, ``qd``, ``qdd`` with float coefficients.

Two arrays (exponents, coefficients): products are outer sums of exponents, ``cos(q)**2`` is
always rewritten as ``1 - sin(q)**2`` (canonical, so identities cancel) and equal monomials
merge by one sort of integer row keys (:mod:`._monomials`): none of sympy's assumptions
and automatic simplification on the kinematic catalog's chains. Slots of the exponent rows,
for ``n`` coordinates: ``[0, n)`` ``sin q_j`` (``q_j`` for a linear coordinate), ``[n, 2n)``
``cos q_j``, ``[2n, 3n)`` ``qd_j``, ``[3n, 4n)`` ``qdd_j``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse
import sympy as sp
from mpmath import libmp as mlib

from ._monomials import ROUND_OFF, normalize_owned, normalize_terms, unique_rows

_BLOCK_VALUES = 1 << 17  # monomial values multiplied at once by evaluate_many

__all__ = ["TrigPolynomial", "euler_lagrange_many", "partial_derivatives_many",
           "evaluate_many", "state_values"]


class TrigPolynomial:
    """A polynomial of the slots described in the module docstring.

    Parameters
    ----------
    exponents : ndarray of int, shape (T, 4n)
    coefficients : ndarray of float, shape (T,)
    angles : tuple of bool, length n
        Which coordinates are angles (their ``cos`` slot reduced modulo ``s^2 + c^2 = 1``).
    normalize : bool, default True
        Reduce, merge equal monomials and drop round-off.

    Examples
    --------
    >>> c = TrigPolynomial.slot(1, 1, (True,))  # cos(q)
    >>> s = TrigPolynomial.slot(1, 0, (True,))
    >>> (c * c + s * s).coefficients
    array([1.])
    """

    __slots__ = ("exponents", "coefficients", "angles")

    def __init__(self, exponents, coefficients, angles, normalize=True):
        self.angles = tuple(angles)
        exponents = np.asarray(exponents, dtype=np.int16).reshape(-1, 4 * len(self.angles))
        coefficients = np.asarray(coefficients, dtype=float).reshape(-1)
        if normalize:
            exponents, coefficients = normalize_terms(exponents, coefficients, self.angles)
        self.exponents, self.coefficients = exponents, coefficients

    # -- construction ----------------------------------------------------------------------
    @classmethod
    def constant(cls, value: float, angles) -> TrigPolynomial:
        """The constant polynomial ``value``."""
        value = float(value)
        keep = abs(value) > ROUND_OFF * max(abs(value), 1.0)  # as normalized
        return cls(np.zeros((int(keep), 4 * len(angles)), dtype=np.int16), [value] * keep,
                   angles, normalize=False)

    @classmethod
    def slot(cls, n: int, index: int, angles) -> TrigPolynomial:
        """The monomial of one slot (see the module docstring); ``n`` coordinates."""
        exponents = np.zeros((1, 4 * n))
        exponents[0, index] = 1
        return cls(exponents, [1.0], angles)

    # -- arithmetic ------------------------------------------------------------------------
    def _lift(self, other) -> TrigPolynomial:
        if isinstance(other, TrigPolynomial):
            return other
        return TrigPolynomial.constant(float(other), self.angles)

    def __add__(self, other):
        other = self._lift(other)
        return TrigPolynomial(np.vstack([self.exponents, other.exponents]),
                              np.concatenate([self.coefficients, other.coefficients]), self.angles)

    __radd__ = __add__

    def __neg__(self):
        return TrigPolynomial(self.exponents, -self.coefficients, self.angles, normalize=False)

    def __sub__(self, other):
        return self + (-self._lift(other))

    def __rsub__(self, other):
        return self._lift(other) - self

    def __mul__(self, other):
        if not isinstance(other, TrigPolynomial):
            value = float(other)
            if value == 0.0:
                return TrigPolynomial.constant(0.0, self.angles)
            return TrigPolynomial(self.exponents, self.coefficients * value, self.angles,
                                  normalize=False)
        if self.is_zero or other.is_zero:
            return TrigPolynomial.constant(0.0, self.angles)
        exponents = (self.exponents[:, None, :] + other.exponents[None, :, :])
        coefficients = np.outer(self.coefficients, other.coefficients)
        return TrigPolynomial(exponents.reshape(-1, self.exponents.shape[1]),
                              coefficients.reshape(-1), self.angles)

    __rmul__ = __mul__

    @property
    def is_zero(self) -> bool:
        """Whether the polynomial has no term."""
        return self.coefficients.size == 0

    def _times_slot(self, index: int) -> TrigPolynomial:
        """This polynomial times one slot monomial (rows stay distinct; only a cosine can create a
        power to rewrite).
        """
        exponents = self.exponents.copy()
        exponents[:, index] += 1
        n = len(self.angles)
        cosine = n <= index < 2 * n and self.angles[index - n]
        return TrigPolynomial(exponents, self.coefficients, self.angles, normalize=cosine)

    @classmethod
    def _sum(cls, polynomials, angles) -> TrigPolynomial:
        """The sum of many polynomials, normalized once."""
        n_slots = 4 * len(angles)
        return cls(np.vstack([p.exponents for p in polynomials] + [np.zeros((0, n_slots))]),
                   np.concatenate([p.coefficients for p in polynomials] + [np.zeros(0)]), angles)

    # -- calculus --------------------------------------------------------------------------
    def diff_slot(self, index: int) -> TrigPolynomial:
        """Partial derivative with respect to one slot (a monomial variable)."""
        powers = self.exponents[:, index]
        rows = powers > 0
        exponents = self.exponents[rows].copy()
        exponents[:, index] -= 1
        # lowering one column keeps normalized rows distinct and normalized
        return TrigPolynomial(exponents, self.coefficients[rows] * powers[rows], self.angles,
                              normalize=False)

    def diff_position(self, j: int) -> TrigPolynomial:
        """Partial derivative with respect to the coordinate ``q_j``."""
        n = len(self.angles)
        if not self.angles[j]:
            return self.diff_slot(j)
        return TrigPolynomial._sum([self.diff_slot(j)._times_slot(n + j),
                                    -self.diff_slot(n + j)._times_slot(j)], self.angles)

    def diff_velocity(self, j: int) -> TrigPolynomial:
        """Partial derivative with respect to ``qd_j``."""
        return self.diff_slot(2 * len(self.angles) + j)

    def time_derivative(self) -> TrigPolynomial:
        """Total time derivative ``sum_j qd_j d/dq_j + qdd_j d/dqd_j``."""
        n = len(self.angles)
        pieces = []
        for j in range(n):
            pieces.append(self.diff_position(j)._times_slot(2 * n + j))
            pieces.append(self.diff_velocity(j)._times_slot(3 * n + j))
        return TrigPolynomial._sum(pieces, self.angles)

    def euler_lagrange(self) -> list[TrigPolynomial]:
        """``d/dt dL/dqd_i - dL/dq_i`` for every coordinate, this polynomial being ``L``."""
        return [self.diff_velocity(i).time_derivative() - self.diff_position(i)
                for i in range(len(self.angles))]

    def at_rest(self, velocities=True, accelerations=True) -> TrigPolynomial:
        """The polynomial with the velocities and / or accelerations set to zero."""
        n = len(self.angles)
        keep = np.ones(len(self.coefficients), dtype=bool)
        if velocities:
            keep &= ~self.exponents[:, 2 * n:3 * n].any(axis=1)
        if accelerations:
            keep &= ~self.exponents[:, 3 * n:].any(axis=1)
        return TrigPolynomial(self.exponents[keep], self.coefficients[keep], self.angles,
                              normalize=False)

    # -- conversion ------------------------------------------------------------------------
    @classmethod
    def from_sympy(cls, expr, coords, angles) -> TrigPolynomial:
        """Parse a sum of products of ``sin q``, ``cos q`` (angles), ``q`` (others) and ``qd``;
        ``ValueError`` if ``expr`` is not such a polynomial (after expansion).
        """
        n = coords.n
        slots = {}
        for j in range(n):
            if angles[j]:
                slots[sp.sin(coords.q[j])], slots[sp.cos(coords.q[j])] = j, n + j
            else:
                slots[coords.q[j]] = j
            slots[coords.qd[j]] = 2 * n + j
        try:
            return cls._parse(sp.Add.make_args(expr), slots, angles)
        except _NotPolynomial:
            return cls._parse(sp.Add.make_args(sp.expand(expr)), slots, angles)

    @classmethod
    def _parse(cls, terms, slots, angles):
        exponents = np.zeros((len(terms), 4 * len(angles)), dtype=np.int16)
        coefficients = np.zeros(len(terms))
        for row, term in enumerate(terms):
            coefficient, rest = term.as_coeff_Mul()
            value = float(coefficient)
            for factor in sp.Mul.make_args(rest):
                if factor.is_number:
                    value *= float(factor)
                    continue
                base, power = factor.as_base_exp()
                if base not in slots or not (power.is_Integer and power > 0):
                    raise _NotPolynomial(str(factor))
                exponents[row, slots[base]] += int(power)
            coefficients[row] = value
        return cls(exponents, coefficients, angles)

    def to_sympy(self, coords, evaluate: bool = True) -> sp.Expr:
        """The polynomial as a sympy expression in ``coords``' symbols; ``evaluate=False`` skips
        sympy's canonicalization (a flat sum of flat products, which the compiler reads as is).
        """
        n = len(self.angles)
        atoms = []
        for j in range(n):
            atoms.append(sp.sin(coords.q[j]) if self.angles[j] else coords.q[j])
        atoms += [sp.cos(q) for q in coords.q] + list(coords.qd) + list(coords.qdd)
        if evaluate:
            terms = [sp.Mul(sympy_number(value),
                            *[atoms[k] ** int(e) for k, e in enumerate(row) if e])
                     for row, value in zip(self.exponents, self.coefficients, strict=True)]
            return sp.Add(*terms)
        # flat products and sum without canonicalization (sympy's own constructors)
        rows, slots = np.nonzero(self.exponents)  # row by row, slots increasing
        base = int(self.exponents.max(initial=1)) + 1
        codes, factor = np.unique(slots * base + self.exponents[rows, slots], return_inverse=True)
        table = [atoms[k] if e == 1 else sp.Pow(atoms[k], e)  # each power built once
                 for k, e in zip((codes // base).tolist(), (codes % base).tolist(),
                                 strict=True)]
        factors = [table[f] for f in factor.ravel().tolist()]
        values, number = np.unique(self.coefficients, return_inverse=True)
        numbers = [fast_sympy_number(v) for v in values.tolist()]
        bounds = np.searchsorted(rows, np.arange(len(self.coefficients) + 1)).tolist()
        mul = sp.Mul._from_args
        terms = []
        for r, (value, k) in enumerate(zip(self.coefficients.tolist(), number.ravel().tolist(),
                                           strict=True)):
            row = factors[bounds[r]:bounds[r + 1]]
            if value != 1 or not row:
                row.insert(0, numbers[k])
            terms.append(mul(row, True) if len(row) > 1 else row[0])
        if len(terms) > 1:
            return sp.Add._from_args(terms, True)
        return terms[0] if terms else sp.S.Zero


_NUMBERS: dict = {}  # float -> sympy number, bounded


def fast_sympy_number(value: float) -> sp.Number:
    """:func:`sympy_number` without the parsing of ``sympy.Float`` (an equal object), cached."""
    found = _NUMBERS.get(value)
    if found is None:
        if len(_NUMBERS) > 100_000:
            _NUMBERS.clear()
        found = _NUMBERS[value] = (
            sp.Integer(int(value)) if value == int(value)
            else sp.Float._new(mlib.from_float(value, 53, mlib.round_nearest), 53))
    return found


def sympy_number(value: float) -> sp.Number:
    return sp.Integer(int(value)) if value == int(value) else sp.Float(float(value))


class _NotPolynomial(ValueError):
    """A factor that is not a power of ``sin q``, ``cos q``, ``q`` or ``qd``."""


def euler_lagrange_many(polynomials) -> list[list[TrigPolynomial]]:
    """:meth:`TrigPolynomial.euler_lagrange` of many polynomials (same ``angles``) at once, bit for
    bit: the polynomials are stacked with an owner index and every step runs once on the stack,
    merging within each owner exactly as for one polynomial. Returns per polynomial its column
    (one polynomial per coordinate).
    """
    polynomials = list(polynomials)
    if not polynomials:
        return []
    stack, n, count = _Stack.of(polynomials), len(polynomials[0].angles), len(polynomials)
    rows = []
    for i in range(n):
        velocity = stack.diff_slot(2 * n + i)
        pieces = []
        for j in range(n):
            pieces.append(velocity.diff_position(j).times_slot(2 * n + j))
            pieces.append(velocity.diff_slot(2 * n + j).times_slot(3 * n + j))
        derivative = _Stack.sum(pieces)
        rows.append(_Stack.sum([derivative, stack.diff_position(i).negative()]))
    parts = [row.parts() for row in rows]
    return [[part[k] for part in parts] for k in range(count)]


def partial_derivatives_many(polynomials) -> list:
    """``[[dL/dqd_c], [dL/dq_c]]`` (per coordinate ``c``, a list over the polynomials ``L``) at
    once, bit for bit as :meth:`TrigPolynomial.diff_velocity` and ``diff_position``.
    """
    stack, n = _Stack.of(polynomials), len(polynomials[0].angles)
    return [[derivative.parts()
             for derivative in (stack.diff_slot(2 * n + c) if part == 0
                                else stack.diff_position(c) for c in range(n))]
            for part in (0, 1)]


class _Stack:
    """Polynomials stacked with their owner: the steps of :meth:`TrigPolynomial.euler_lagrange`."""

    __slots__ = ("exponents", "coefficients", "owners", "angles", "count")

    @classmethod
    def of(cls, polynomials) -> _Stack:
        return cls(np.vstack([p.exponents for p in polynomials]),
                   np.concatenate([p.coefficients for p in polynomials]),
                   np.concatenate([np.full(len(p.coefficients), k, dtype=np.int16)
                                   for k, p in enumerate(polynomials)]),
                   polynomials[0].angles, len(polynomials))

    def __init__(self, exponents, coefficients, owners, angles, count, normalize=False):
        if normalize:
            exponents, coefficients, owners = normalize_owned(exponents, coefficients,
                                                               owners, angles, count)
        self.exponents, self.coefficients, self.owners = exponents, coefficients, owners
        self.angles, self.count = angles, count

    def _like(self, exponents, coefficients, owners, normalize=False):
        return _Stack(exponents, coefficients, owners, self.angles, self.count, normalize)

    def diff_slot(self, index):
        powers = self.exponents[:, index]
        rows = powers > 0
        exponents = self.exponents[rows].copy()
        exponents[:, index] -= 1
        return self._like(exponents, self.coefficients[rows] * powers[rows], self.owners[rows])

    def times_slot(self, index):
        exponents = self.exponents.copy()
        exponents[:, index] += 1
        n = len(self.angles)
        cosine = n <= index < 2 * n and self.angles[index - n]
        return self._like(exponents, self.coefficients, self.owners, normalize=cosine)

    def negative(self):
        return self._like(self.exponents, -self.coefficients, self.owners)

    def diff_position(self, j):
        n = len(self.angles)
        if not self.angles[j]:
            return self.diff_slot(j)
        return _Stack.sum([self.diff_slot(j).times_slot(n + j),
                           self.diff_slot(n + j).times_slot(j).negative()])

    @staticmethod
    def sum(stacks):
        first = stacks[0]
        return first._like(np.vstack([s.exponents for s in stacks]),
                           np.concatenate([s.coefficients for s in stacks]),
                           np.concatenate([s.owners for s in stacks]), normalize=True)

    def parts(self) -> list[TrigPolynomial]:
        """The polynomial of each owner (the rows are sorted by owner)."""
        bounds = np.searchsorted(self.owners, np.arange(self.count + 1)).tolist()
        return [TrigPolynomial(self.exponents[a:b], self.coefficients[a:b], self.angles,
                               normalize=False)
                for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def state_values(q, qd=None, qdd=None, angles=()) -> np.ndarray:
    """Slot values of the states: array (N, 4n) (see the module docstring)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    angles = np.asarray(angles, dtype=bool)
    zeros = np.zeros_like(q)
    position = np.where(angles, np.sin(q), q)
    cosine = np.where(angles, np.cos(q), 1.0)
    return np.hstack([position, cosine, zeros if qd is None else np.atleast_2d(qd),
                      zeros if qdd is None else np.atleast_2d(qdd)])


def evaluate_many(polynomials, values: np.ndarray) -> np.ndarray:
    """Evaluate ``polynomials`` on all states ``values`` (N, 4n) (:func:`state_values`) at once:
    (N, len(polynomials)).
    """
    width = values.shape[1]
    exponents = np.vstack([p.exponents for p in polynomials]  # int16, not upcast
                          + [np.zeros((0, width), dtype=np.int16)])
    owner = np.repeat(np.arange(len(polynomials)), [len(p.coefficients) for p in polynomials])
    coefficients = np.concatenate([p.coefficients for p in polynomials] + [np.zeros(0)])
    first, inverse = unique_rows(exponents)
    distinct = exponents[first]
    # each monomial: its factors' powers (each computed once) multiplied in slot order, all
    # monomials of the same number of factors at once
    rows, slots = np.nonzero(distinct)  # row by row, slots increasing
    base = int(distinct.max(initial=0)) + 1
    codes = slots * base + distinct[rows, slots]
    present = np.zeros(width * base, dtype=bool)
    present[codes] = True
    factors = (np.cumsum(present) - 1)[codes]
    codes = np.flatnonzero(present)
    table = values.T[codes // base] ** (codes % base)[:, None]
    counts = np.bincount(rows, minlength=len(distinct))
    starts = np.cumsum(counts) - counts
    monomials = np.empty((len(distinct), values.shape[0]))  # a row per monomial
    monomials[counts == 0] = 1.0
    step = max(1, _BLOCK_VALUES // values.shape[0])  # blocks of rows: memory reused
    for count in np.unique(counts[counts > 0]).tolist():
        rows_of_count = np.flatnonzero(counts == count)
        for start in range(0, len(rows_of_count), step):
            members = rows_of_count[start:start + step]
            where = starts[members]
            product = table[factors[where]]
            for k in range(1, count):
                product *= table[factors[where + k]]
            monomials[members] = product
    mapping = scipy.sparse.csr_matrix((coefficients, (inverse.ravel(), owner)),
                                      shape=(len(distinct), len(polynomials)))
    return np.asarray((mapping.T @ monomials).T)
