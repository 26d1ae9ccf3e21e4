"""Candidate terms held as trigonometric polynomials, read as sympy expressions on demand."""

from __future__ import annotations

import hashlib
from collections.abc import Sequence

import numpy as np
import sympy as sp
from sympy.printing.str import StrPrinter

from .trigpoly import fast_sympy_number, sympy_number

__all__ = ["TrigTerms"]


class TrigTerms(Sequence):
    """Candidate terms held as trigonometric polynomials, read as sympy expressions on demand.

    A library that knows this class (:class:`~pysindy_xl.feature_library.PolynomialLagrangeLibrary`)
    derives its columns, names and evaluators from the polynomials; the (large) sympy expression
    of an item, exactly ``polynomial.to_sympy(coords)``, is built when read. Immutable: copies
    and clones share it.

    Parameters
    ----------
    polynomials : sequence of TrigPolynomial
        All with the same ``angles``.
    coords : Coordinates
    columns : sequence of list of TrigPolynomial, optional
        The Euler-Lagrange column of each polynomial, when already derived.
    names : sequence of str, optional
        :meth:`names`, when already formatted.

    Examples
    --------
    >>> import pysindy_xl as px
    >>> from pysindy_xl.feature_library.trigpoly import TrigPolynomial
    >>> c = px.Coordinates(["a"])
    >>> terms = TrigTerms([TrigPolynomial.slot(1, 0, (True,)) * 9.81], c)
    >>> terms
    [9.81*sin(a)]
    >>> terms.names()
    ['9.81*sin(a)']
    """

    def __init__(self, polynomials, coords, columns=None, names=None):
        self.polynomials = tuple(polynomials)
        self.coords = coords
        self.angles = self.polynomials[0].angles if self.polynomials else (False,) * coords.n
        if any(p.angles != self.angles for p in self.polynomials):
            raise ValueError("polynomials: expected the same angles for every polynomial")
        if len(self.angles) != coords.n:
            raise ValueError(f"polynomials: expected polynomials of {coords.n} coordinates, got "
                             f"{len(self.angles)}")
        self.columns = None if columns is None else tuple(tuple(c) for c in columns)
        self._exprs = [None] * len(self.polynomials)
        self._names = None if names is None else [str(name) for name in names]
        if self._names is not None and len(self._names) != len(self.polynomials):
            raise ValueError(f"names: expected {len(self.polynomials)} names, got "
                             f"{len(self._names)}")
        self._key = None

    def __len__(self):
        return len(self.polynomials)

    def __getitem__(self, index):
        if isinstance(index, slice):
            return [self[k] for k in range(*index.indices(len(self)))]
        expr = self._exprs[index]
        if expr is None:
            expr = self._exprs[index] = self.polynomials[index].to_sympy(self.coords)
        return expr

    def __eq__(self, other):
        if isinstance(other, TrigTerms):
            return self.key == other.key
        if isinstance(other, (list, tuple)):
            return list(self) == list(other)
        return NotImplemented

    __hash__ = None

    # concatenation gives a list, as it did when the terms were one
    def __add__(self, other):
        return list(self) + list(other)

    def __radd__(self, other):
        return list(other) + list(self)

    def __repr__(self):
        return repr(list(self))

    # immutable: copies and clones share it (and what it has built)
    def __copy__(self):
        return self

    def __deepcopy__(self, memo):
        return self

    def __sklearn_clone__(self):
        return self

    def __getstate__(self):
        return {"polynomials": self.polynomials, "coords": self.coords, "columns": self.columns}

    def __setstate__(self, state):
        self.__init__(state["polynomials"], state["coords"], state["columns"])

    @property
    def key(self) -> str:
        """A digest of the content (coordinates and polynomials), for caches."""
        if self._key is None:
            digest = hashlib.sha256(repr((tuple(map(str, self.coords.variables)),
                                          self.angles)).encode())
            for p in self.polynomials:
                digest.update(np.ascontiguousarray(p.exponents, dtype=np.int16).tobytes())
                digest.update(np.ascontiguousarray(p.coefficients, dtype=float).tobytes())
                digest.update(b"|")
            self._key = digest.hexdigest()
        return self._key

    def names(self) -> list[str]:
        """``str`` of every item, formatted from the polynomials (without building them)."""
        if self._names is None:
            printer = _Printer(self.coords, self.angles)
            self._names = [printer(p) for p in self.polynomials]
        return list(self._names)


_NESTED = StrPrinter({"full_prec": False})


class _Printer:
    """sympy's ``str`` of ``TrigPolynomial.to_sympy(coords)`` from the exponent rows: monomials in
    decreasing lexicographic order of their exponents over the generators sorted by
    ``default_sort_key`` (the constant last); a product as its sign, its coefficient unless one,
    then its factors by ``sort_key``.
    """

    def __init__(self, coords, angles):
        n = len(angles)
        atoms = [sp.sin(q) if angle else q for q, angle in zip(coords.q, angles, strict=True)]
        self.atoms = atoms + [sp.cos(q) for q in coords.q] + list(coords.qd) + list(coords.qdd)
        keys = [sp.default_sort_key(a) for a in self.atoms]
        # generators' order; an unused cosine slot (linear coordinate) never has an exponent
        self.order = np.array(sorted(range(4 * n), key=lambda k: keys[k]), dtype=int)
        self.factors: dict = {}
        self.numbers: dict = {}

    def _factor(self, slot: int, power: int) -> str:
        found = self.factors.get((slot, power))
        if found is None:
            expr = self.atoms[slot] if power == 1 else sp.Pow(self.atoms[slot], power)
            found = self.factors[(slot, power)] = str(expr)
        return found

    def number(self, value: float) -> str:
        found = self.numbers.get(value)
        if found is None:
            # inside a sum or product sympy strips a float's trailing zeros
            found = self.numbers[value] = (str(int(value)) if value == int(value)
                                           else _NESTED._print_Float(fast_sympy_number(value)))
        return found

    def __call__(self, polynomial) -> str:
        exponents, coefficients = polynomial.exponents, polynomial.coefficients
        if len(coefficients) == 0:
            return "0"
        if len(coefficients) == 1 and not exponents.any():
            return str(sympy_number(float(coefficients[0])))
        # a product's factors sort by their bases (distinct in a monomial): columns in the
        # generators' order give each row's factors in printing order
        ordered = exponents[:, self.order]
        rows = np.lexsort((-ordered).T[::-1])  # decreasing lexicographic order
        ordered = ordered[rows]
        nonzero_rows, columns = np.nonzero(ordered)
        base = int(ordered.max()) + 1
        codes, factor = np.unique(self.order[columns] * base + ordered[nonzero_rows, columns],
                                  return_inverse=True)
        table = np.array([self._factor(c // base, c % base) for c in codes.tolist()], dtype=object)
        texts = table[factor.ravel()].tolist()  # each factor's text, row by row
        bounds = np.searchsorted(nonzero_rows, np.arange(len(rows) + 1)).tolist()
        pieces = []
        for r, value in enumerate(coefficients[rows].tolist()):
            parts = texts[bounds[r]:bounds[r + 1]]
            magnitude = abs(value)
            if not parts or magnitude != 1.0:  # sympy's number 1 is the float 1.0 alone
                parts.insert(0, self.number(magnitude))
            pieces.append(("-" if value < 0 else "", "*".join(parts)))
        if (len(pieces) == 2 and not exponents[rows[1]].any() and coefficients[rows[1]] > 0
                and coefficients[rows[0]] < 0 and np.count_nonzero(exponents[rows[0]]) == 1):
            # sympy's special case: a positive constant before a negative number times one
            # factor (1 - x, not -x + 1)
            pieces = pieces[::-1]
        text = pieces[0][0] + pieces[0][1]
        for sign, body in pieces[1:]:
            text += f" {sign or '+'} {body}"
        return text
