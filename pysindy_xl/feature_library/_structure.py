"""The structure of a library's symbolic columns, known without their sympy matrix.

A fit needs only which entries are non-zero, which variables each involves and how many
terms each has; a library that derives its columns another way (trigonometric polynomials
on exponent arrays) gives that as a :class:`DeferredMatrix` and builds the sympy matrix on
the first read of ``symbolic_matrix_``.
"""

from __future__ import annotations

import numpy as np
import sympy as sp
from sklearn.utils.validation import check_is_fitted

__all__ = ["DeferredMatrix", "ColumnStructure"]

# Functions that switch: a coefficient of an acceleration made of them is an impulse
_SWITCHES = (sp.sign, sp.Abs, sp.Piecewise, sp.Heaviside, sp.DiracDelta, sp.floor,
             sp.ceiling, sp.Max, sp.Min)


class DeferredMatrix:
    """A symbolic matrix known by its structure: ``variables`` (n, F, V), whether entry ``(c, j)``
    involves variable ``v`` of ``coords.variables``, and ``sizes`` (n, F), its terms (0: zero).
    """

    def __init__(self, variables, sizes):
        self.variables = np.asarray(variables, dtype=bool)
        self.sizes = np.asarray(sizes, dtype=int)
        self.shape = self.sizes.shape


class ColumnStructure:
    """``symbolic_matrix_`` (built on first read when deferred) and the structure of the columns,
    for :class:`~pysindy_xl.feature_library.SymbolicLibrary`.
    """

    @property
    def symbolic_matrix_(self) -> sp.Matrix:
        """The sympy matrix of the columns (built on first read for a :class:`DeferredMatrix`)."""
        matrix = self.__dict__.get("_symbolic_matrix")
        if matrix is None:
            raise AttributeError(f"{type(self).__name__} is not fitted: no symbolic_matrix_")
        if isinstance(matrix, DeferredMatrix):
            self.__dict__.setdefault("_structure", (matrix.variables, matrix.sizes))
            matrix = self._symbolic_matrix = self._deferred_matrix()
        return matrix

    def _deferred_matrix(self) -> sp.Matrix:
        """The sympy matrix of a library that derived a :class:`DeferredMatrix`."""
        raise NotImplementedError

    def _entry_structure(self) -> tuple[np.ndarray, np.ndarray]:
        """``(variables, sizes)`` as in :class:`DeferredMatrix` (from sympy if needed)."""
        check_is_fitted(self, "entry_index_")
        found = self.__dict__.get("_structure")
        if found is None:
            matrix = self._symbolic_matrix
            if isinstance(matrix, DeferredMatrix):
                found = (matrix.variables, matrix.sizes)
            else:
                position = {v: k for k, v in enumerate(self.coords.variables)}
                variables = np.zeros(matrix.shape + (len(position),), dtype=bool)
                sizes = np.zeros(matrix.shape, dtype=int)
                for c, j in self.entry_index_:
                    entry = matrix[c, j]
                    sizes[c, j] = len(sp.Add.make_args(entry))
                    variables[c, j, [position[v] for v in entry.free_symbols
                                     if v in position]] = True
                found = (variables, sizes)
            self._structure = found
        return found

    def involves(self, symbols) -> np.ndarray:
        """Which entries involve any of ``symbols``.

        Parameters
        ----------
        symbols : sequence of sympy.Symbol
            Variables of ``coords`` (e.g. ``coords.qdd``).

        Returns
        -------
        ndarray of bool, shape (n, F)
            True where entry ``[c, j]`` depends on one of them.

        Examples
        --------
        >>> import pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2]).fit().involves(c.qdd).tolist()
        [[True, False]]
        """
        variables = list(self.coords.variables)
        wanted = [variables.index(s) for s in symbols if s in variables]
        return self._entry_structure()[0][:, :, wanted].any(axis=2)

    def entry_sizes(self) -> np.ndarray:
        """Number of terms of each entry of the columns.

        Returns
        -------
        ndarray of int, shape (n, F)
            Terms of entry ``[c, j]`` once expanded, 0 where the entry is zero.
        """
        return self._entry_structure()[1]

    def impulsive(self) -> bool:
        """Whether an acceleration enters an entry with a coefficient that switches with the state
        (``sign``, ``Abs``, ``Piecewise``, ...; the lead of MuJoCo's dry friction).

        Such an entry is an impulse at each switch, which samples catch or miss by chance while
        integration by parts states it exactly: ``formulation="auto"`` then fits in the weak form.

        Returns
        -------
        bool
            True when some acceleration's coefficient switches with the state.

        Examples
        --------
        >>> import sympy as sp, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> px.ClassicalLibrary(c, [c.qd[0], sp.Abs(c.qd[0]) * c.qdd[0]]).fit().impulsive()
        True
        >>> px.ClassicalLibrary(c, [sp.sign(c.qd[0]), c.qd[0] ** 2 * c.qdd[0]]).fit().impulsive()
        False
        """
        check_is_fitted(self, "entry_index_")
        matrix = self.symbolic_matrix_
        for c, j in self.entry_index_:
            entry = matrix[c, j]
            if entry.has(*_SWITCHES) and any(
                    sp.diff(entry, qdd).has(*_SWITCHES) for qdd in self.coords.qdd
                    if qdd in entry.free_symbols):
                return True
        return False
