"""The weak formulation's rows of a catalog: each entry split ``E = d/dt P - Q``, evaluated on
blocks of samples and contracted with the test functions.

:class:`WeakEvaluation` gives :class:`~pysindy_xl.feature_library.SymbolicLibrary` its weak
matrices, terms and rows; :func:`remembered_weak_values` keeps the evaluated entries of each
state array while a fit builds several weak problems of the same states.
"""

from __future__ import annotations

import contextlib
import hashlib

import numpy as np
import scipy.sparse
import sympy as sp
from sklearn.utils.validation import check_is_fitted

from .._memo import shared_derivation
from ._compile import Terms, compile_terms, decompose
from ._weak import integrate_by_parts

__all__ = ["WeakEvaluation", "remembered_weak_values"]

_WEAK_BLOCK = 8192  # samples per block of the weak evaluation
_WEAK_MEMO_BYTES = 1 << 28  # values kept by remembered_weak_values, at most


#: The test matrices of :meth:`WeakEvaluation._weak_tests` by content, most recently used
#: last (read, never modified).
_TESTS: dict = {}
_CACHED_TESTS = 16


def _sparse_key(phi, dphi, n_samples):
    """A key of the contents of two sparse matrices in CSR form (None for any other input)."""
    if not all(scipy.sparse.issparse(m) and m.format == "csr" for m in (phi, dphi)):
        return None
    digest = hashlib.sha1()
    for matrix in (phi, dphi):
        digest.update(repr((matrix.shape, matrix.dtype.str, matrix.data.shape,
                            matrix.indices.dtype.str, matrix.indptr.dtype.str)).encode())
        for part in (matrix.data, matrix.indices, matrix.indptr):
            digest.update(np.ascontiguousarray(part))
    return n_samples, digest.digest()


@contextlib.contextmanager
def remembered_weak_values(library):
    """Within the block, ``library.weak_transform`` evaluates each distinct state array once.

    At most ``_WEAK_MEMO_BYTES`` of values are kept; re-entrant. Weak rows of the same states
    under other test functions then cost only their contraction, bit for bit the same.

    Parameters
    ----------
    library : SymbolicLibrary
        A fitted library.

    Yields
    ------
    SymbolicLibrary
        ``library``, remembering its weak values until the block ends.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> library = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2]).fit()
    >>> z, phi = px.stack_variables(np.ones((20, 1)), np.ones((20, 1))), np.full((2, 20), 0.05)
    >>> with remembered_weak_values(library):
    ...     _, again = library.weak_transform(z, phi, phi), library.weak_transform(z, 2 * phi, phi)
    >>> bool(np.array_equal(again, library.weak_transform(z, 2 * phi, phi)))
    True
    """
    outer = "_weak_memo" in library.__dict__
    if not outer:
        library._weak_memo = {}
    try:
        yield library
    finally:
        if not outer:
            library.__dict__.pop("_weak_memo", None)
            library.__dict__.pop("_weak_memo_tests", None)


class WeakEvaluation:
    """The weak matrices (:meth:`weak_matrices`), terms (:meth:`weak_terms`) and rows
    (:meth:`weak_transform`) of :class:`~pysindy_xl.feature_library.SymbolicLibrary`.

    The library gives ``coords``, ``symbolic_matrix_``, ``entry_index_``,
    ``n_output_features_``, ``_check_input`` and ``_check_finite_output``; it may derive the
    terms its own way (``_derive_weak_terms``, by default :meth:`_split_weak_terms`). The
    derived ``weak_P_``, ``weak_Q_``, ``_weak_terms``, ``_weak_evaluate`` and
    ``_weak_entry_index`` are kept on the library until it is fitted again.
    """

    def _build_weak_symbolic(self) -> tuple[sp.Matrix, sp.Matrix]:
        """``(P, Q)`` of shape ``(n, F)`` with ``E = d/dt P - Q`` entrywise (see ``_weak``)."""
        matrix = self.symbolic_matrix_
        split = [[integrate_by_parts(matrix[c, j], self.coords) if matrix[c, j] != 0
                  else (sp.Integer(0), sp.Integer(0)) for j in range(matrix.shape[1])]
                 for c in range(matrix.shape[0])]
        shape = matrix.shape
        return (sp.Matrix(*shape, lambda c, j: split[c][j][0]),
                sp.Matrix(*shape, lambda c, j: split[c][j][1]))

    def weak_matrices(self) -> tuple[sp.Matrix, sp.Matrix]:
        r"""Symbolic split ``E = d/dt P - Q`` of every entry, derived on first use.

        ``P`` and ``Q`` (n, F) are free of accelerations
        (:func:`~pysindy_xl.feature_library.integrate_by_parts`); for a Lagrange term ``L_k``:
        ``P[i, k] = dL_k/dqd_i`` and ``Q[i, k] = dL_k/dq_i``. Integrated against a test function
        ``phi`` that vanishes at both ends,

        .. math:: \int \phi E \, dt = -\int \dot\phi P \, dt - \int \phi Q \, dt.

        Returns
        -------
        P, Q : sympy.Matrix, shape (n, F)
            The two parts.

        Examples
        --------
        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2]).fit()
        >>> lib.weak_matrices()
        (Matrix([[2*x_dot, 0]]), Matrix([[0, 2*x]]))
        """
        check_is_fitted(self, "entry_index_")
        if not hasattr(self, "weak_P_"):
            self.weak_P_, self.weak_Q_ = self._build_weak_symbolic()
        return self.weak_P_, self.weak_Q_

    def weak_terms(self) -> tuple[np.ndarray, Terms]:
        """The non-zero entries of ``P`` and ``Q`` (:meth:`weak_matrices`) as polynomial terms.

        Derived on first use.

        Returns
        -------
        index : ndarray of int, shape (E, 3)
            ``(part, coordinate, feature)`` of each entry, part 0 for ``P`` and 1 for ``Q``.
        terms : Terms
            The entries, one per row of ``index``.
        """
        check_is_fitted(self, "entry_index_")
        found = self.__dict__.get("_weak_terms")
        if found is None:
            found = self._weak_terms = self._derive_weak_terms()
        return found

    def _derive_weak_terms(self) -> tuple[np.ndarray, Terms]:
        return self._split_weak_terms()

    def _split_weak_terms(self) -> tuple[np.ndarray, Terms]:
        matrices = self.weak_matrices()
        n, n_features = self.coords.n, self.n_output_features_
        entries = [(part, c, j) for part, matrix in enumerate(matrices)
                   for c in range(n) for j in range(n_features) if matrix[c, j] != 0]
        index = np.array(entries, dtype=int).reshape(-1, 3)
        return index, decompose([matrices[part][c, j] for part, c, j in entries])

    def weak_transform(self, x, phi, dphi) -> np.ndarray:
        """Weak regression matrix of one trajectory.

        Row ``(c, k)`` of column ``j`` is ``int phi_k E[c, j] dt = -int phi_k' P[c, j] dt -
        int phi_k Q[c, j] dt`` (:meth:`weak_matrices`): two products with the test matrices.

        Parameters
        ----------
        x : array, shape (N, 4n + 1)
            Library input of one trajectory; the accelerations are not used.
        phi, dphi : array or sparse matrix, shape (K, N)
            Quadrature-weighted test functions and their derivatives
            (:class:`~pysindy_xl.weak.BumpTestFunctions`).

        Returns
        -------
        theta : ndarray, shape (n * K, F)
            Rows coordinate-major, as :meth:`transform`.
        """
        x = self._check_input(x)
        if phi.shape != dphi.shape or phi.shape[1] != x.shape[0]:
            raise ValueError(f"phi, dphi: expected two matrices of shape (K, {x.shape[0]}), got "
                             f"{phi.shape} and {dphi.shape}")
        n, n_features, n_samples = self.coords.n, self.n_output_features_, x.shape[0]
        if not hasattr(self, "_weak_evaluate"):
            index, terms = self.weak_terms()
            self._weak_entry_index = index
            self._weak_evaluate = compile_terms(self.coords.variables, terms)
        index = self._weak_entry_index
        parts = [np.flatnonzero(index[:, 0] == part) for part in (0, 1)]
        n_windows = phi.shape[0]
        contributions = np.zeros((n_windows, len(index)))
        with np.errstate(all="ignore"):  # (kept values are evaluated here)
            blocks = self._weak_values(x)
        # blocks of samples bound the memory
        for tests in self._weak_tests(phi, dphi, n_samples):
            with np.errstate(all="ignore"):
                values = next(blocks)  # entries x samples
            for part, entries in enumerate(parts):
                if len(entries):
                    # samples x entries in C order, as the sparse product reads them
                    contributions[:, entries] += tests[part] @ np.ascontiguousarray(
                        values[entries].T)
        weak = np.zeros((n, n_windows, n_features))
        np.add.at(weak, (index[:, 1], slice(None), index[:, 2]), contributions.T)
        weak = weak.reshape(n * n_windows, n_features)
        self._check_finite_output(weak, n_windows)
        return weak

    def _weak_tests(self, phi, dphi, n_samples):
        """``[(-dphi, -phi)]`` (CSC) on each block of ``_WEAK_BLOCK`` samples, the test matrix
        that each part of the entries meets (``int phi E = -int phi' P - int phi Q``).

        Within :func:`remembered_weak_values`, the blocks of the last ``(phi, dphi)`` (the same
        objects) are kept: the noise propagation transforms many draws with the same ones.
        """
        kept = self.__dict__.get("_weak_memo_tests")
        if kept is not None and kept[0] is phi and kept[1] is dphi and kept[2] == n_samples:
            return kept[3]
        # sparse test matrices by content: the noise propagation transforms many draws with
        # the same ones, and a growth fits many catalogs on the same pieces
        def derive():
            tests = [scipy.sparse.csc_matrix(-dphi), scipy.sparse.csc_matrix(-phi)]
            return [[test[:, start:start + _WEAK_BLOCK] for test in tests]
                    for start in range(0, n_samples, _WEAK_BLOCK)]

        key = _sparse_key(phi, dphi, n_samples)
        blocks = derive() if key is None else shared_derivation(key, derive, _TESTS,
                                                                 _CACHED_TESTS)
        if "_weak_memo" in self.__dict__:  # (holding phi and dphi, their ids stay theirs)
            self._weak_memo_tests = (phi, dphi, n_samples, blocks)
        return blocks

    def _weak_values(self, x):
        """:meth:`weak_terms` on blocks of ``_WEAK_BLOCK`` samples of ``x`` (entries, samples),
        evaluated when read; all at once and kept within :func:`remembered_weak_values`.
        """
        blocks = (self._weak_evaluate(x[start:start + _WEAK_BLOCK], stacked=True)
                  for start in range(0, x.shape[0], _WEAK_BLOCK))
        memo = self.__dict__.get("_weak_memo")
        if memo is None:
            return blocks
        key = hashlib.sha1(np.ascontiguousarray(x)).digest()
        if key not in memo:
            values = list(blocks)
            if sum(v.nbytes for kept in [values, *memo.values()] for v in kept) > _WEAK_MEMO_BYTES:
                return iter(values)
            memo[key] = values
        return iter(memo[key])
