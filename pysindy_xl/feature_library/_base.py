"""What every catalog category shares: symbolic columns compiled once to one numeric function.

Every library maps the data ``Z`` (N, 4n + 1), columns ``coords.variables`` (see
:func:`stack_variables`), to the regression matrix ``Theta`` (n * N, F): rows
coordinate-major (rows ``c * N`` to ``(c + 1) * N - 1`` hold the equation of coordinate
``c``), entry ``(c * N + k, j)`` the symbolic entry ``E[c, j]`` at sample ``k``. One
coefficient vector ``xi`` is shared by every coordinate, the model being ``Theta @ xi = 0``:
one Lagrangian term explains several equations at once.
"""

from __future__ import annotations

import contextlib
import hashlib
from collections.abc import Sequence

import numpy as np
import scipy.sparse
import sympy as sp
from pysindy.feature_library.base import BaseFeatureLibrary
from sklearn.base import clone
from sklearn.utils.validation import check_is_fitted

from .._validation import InstanceOf, check_numeric_array, validate_params
from ..registry import register_type
from ..symbols import Coordinates
from ._compile import Terms, compile_entries, compile_terms, decompose
from ._structure import ColumnStructure, DeferredMatrix
from ._weak import integrate_by_parts

__all__ = ["SymbolicLibrary", "compile_entries", "LIBRARY_TYPES",
           "remembered_weak_values"]

#: Every catalog category by its ``spec_type``: what a model file may name. Subclasses
#: register themselves when defined; loading never imports anything.
LIBRARY_TYPES: dict[str, type] = {}

_WEAK_BLOCK = 8192  # samples per block of the weak evaluation
_WEAK_MEMO_BYTES = 1 << 28  # values kept by remembered_weak_values, at most

#: Derived terms by content, most recently used last: a clone of a catalog finds its
#: :class:`Terms` (and their compiled evaluators) here.
_DERIVED: dict = {}
_CACHED_DERIVED = 16


def shared_derivation(key, derive, cache=_DERIVED, size=_CACHED_DERIVED):
    """``derive()``, shared by every call with the same ``key`` in ``cache`` (at most ``size``
    entries, the least recently used dropped first)."""
    found = cache.pop(key, None)
    if found is None:
        found = derive()
    cache[key] = found
    while len(cache) > size:
        del cache[next(iter(cache))]
    return found


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


class TermChain(Sequence):
    """The terms of several libraries one after another, each read from its library's own
    sequence when asked for (a kinematic catalog's terms are built on demand).
    """

    def __init__(self, parts):
        self.parts = [p if isinstance(p, Sequence) else list(p) for p in parts]
        self._offsets = np.cumsum([0] + [len(p) for p in self.parts])

    def __len__(self):
        return int(self._offsets[-1])

    def __getitem__(self, index):
        if isinstance(index, slice):
            return [self[k] for k in range(*index.indices(len(self)))]
        index = range(len(self))[index]  # negative indices, IndexError
        part = int(np.searchsorted(self._offsets, index, side="right")) - 1
        return self.parts[part][index - int(self._offsets[part])]

    def __eq__(self, other):
        if isinstance(other, (list, tuple, Sequence)) and not isinstance(other, str):
            return len(self) == len(other) and list(self) == list(other)
        return NotImplemented

    __hash__ = None

    def __repr__(self):
        return repr(list(self))


def _clone_parameter(value):
    """``value`` for a clone: sympy expressions shared, anything else cloned (scikit-learn)."""
    if isinstance(value, sp.Basic):
        return value
    if isinstance(value, (list, tuple)) and all(isinstance(v, sp.Basic) for v in value):
        return type(value)(value)
    return clone(value, safe=False)


class SymbolicLibrary(ColumnStructure, BaseFeatureLibrary):
    """Base class of the catalog categories: a matrix of symbolic columns, compiled once.

    Subclasses implement :meth:`_build_symbolic`, returning the feature names and the sympy
    matrix ``E`` (n, F) (``E[c, j]``: feature ``j`` in the equation of coordinate ``c``).
    ``fit`` derives ``E`` and compiles its non-zero entries into one vectorized evaluator
    (:func:`compile_entries`); ``transform`` runs it as laid out in the module docstring.

    Parameters
    ----------
    coords : Coordinates
        Generalized coordinates of the system.

    Examples
    --------
    A new category only describes its columns:

    >>> import sympy as sp, pysindy_xl as px
    >>> class Gravity(SymbolicLibrary):
    ...     def _build_symbolic(self):
    ...         return ["sin"], sp.Matrix([[sp.sin(self.coords.q[0])]])
    >>> Gravity(px.Coordinates(["theta"])).fit().transform([[0.5, 0, 0, 0, 0]]).round(3)
    array([[0.479]])
    """

    #: category label used in feature names and reports; ``"forces"`` marks the known
    #: right-hand side, ``"lagrange"`` features whose term is a candidate Lagrangian term
    category = "symbolic"
    #: preference among exactly dependent columns (lower is kept; see
    #: :meth:`CatalogRepartition.column_priority
    #: <pysindy_xl.CatalogRepartition.column_priority>`)
    column_rank = 3
    #: the name a model file gives this class (default: ``module.QualifiedName``)
    spec_type: str

    #: what each parameter accepts (:func:`~pysindy_xl._validation.validate_params`), checked
    #: at the start of ``fit``; the entries themselves (terms, shapes) by the library
    _parameter_constraints = {"coords": [InstanceOf(Coordinates, "a pysindy_xl.Coordinates")]}

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        register_type(LIBRARY_TYPES, cls)

    def __init__(self, coords: Coordinates):
        self.coords = coords

    def __sklearn_clone__(self):
        """An unfitted copy with the same parameters, sharing the (immutable) sympy expressions."""
        params = self.get_params(deep=False)
        return type(self)(**{name: _clone_parameter(value) for name, value in params.items()})

    # -- to implement --------------------------------------------------------------------
    def _build_symbolic(self) -> tuple[list[str], sp.Matrix]:
        raise NotImplementedError

    def _feature_terms(self) -> list:
        """The term each feature stands for (a Lagrangian term, an added function), None if none."""
        return [None] * self.n_output_features_

    def _check_coords(self):
        if not isinstance(self.coords, Coordinates):
            raise TypeError(
                f"coords: expected a pysindy_xl.Coordinates, got {type(self.coords).__name__}")

    # -- pysindy / scikit-learn interface ------------------------------------------------
    def fit(self, x=None, y=None):
        """Derive the symbolic columns (their evaluator is compiled on first use).

        Parameters
        ----------
        x : array, shape (N, 4n + 1), optional
            Library input; only its width is checked. Default None.
        y : None
            Ignored (scikit-learn's signature).

        Returns
        -------
        self : SymbolicLibrary
            The fitted library (``feature_names_``, ``symbolic_matrix_``, ``entry_index_``,
            ``n_output_features_``).
        """
        self._fit_symbolic()
        if x is not None:
            self._check_input(x)
        return self

    def _fit_symbolic(self):
        """Derive the symbolic columns and set the attributes that describe them."""
        validate_params(self)
        self._check_coords()
        names, matrix = self._build_symbolic()
        n = self.coords.n
        if matrix.shape != (n, len(names)):
            raise RuntimeError("internal error: symbolic matrix shape does not match names")
        if not isinstance(matrix, DeferredMatrix):
            self._check_columns(names, matrix)
        self.feature_names_ = list(names)
        self._symbolic_matrix = matrix
        self.__dict__.pop("_structure", None)
        self.n_output_features_ = len(names)
        terms = self._feature_terms()
        # a lazy sequence (terms built on demand, e.g. TrigTerms) stays one
        self.feature_terms_ = (terms if isinstance(terms, Sequence)
                               and not isinstance(terms, (list, str)) else list(terms))
        if isinstance(matrix, DeferredMatrix):
            self.entry_index_ = np.argwhere(matrix.sizes > 0).reshape(-1, 2)
        else:
            self.entry_index_ = np.array([(c, j) for c in range(n) for j in range(len(names))
                                          if matrix[c, j] != 0], dtype=int).reshape(-1, 2)
        for stale in ("weak_P_", "weak_Q_", "_weak_evaluate", "_weak_entry_index",
                      "_column_terms", "_weak_terms"):
            self.__dict__.pop(stale, None)
        self.__dict__.get("_weak_memo", {}).clear()  # values of the former entries
        self.n_features_in_ = len(self.coords.variables)

    def _check_columns(self, names, matrix) -> None:
        """Refuse derived columns that cannot be evaluated (a DiracDelta), naming the feature."""
        from ..expressions import check_term

        for j, feature in enumerate(names):
            for c in range(matrix.shape[0]):
                try:
                    check_term(matrix[c, j], "feature_library")
                except ValueError as err:
                    raise ValueError(
                        f"feature_library: the term {feature} cannot be used: its column "
                        f"{str(matrix[c, j])[:80]} is not evaluable ({str(err).split(', which')[0]}"
                        "); catalog terms must be differentiable twice"
                    ) from None

    def _compile(self):
        self._evaluate = compile_terms(self.coords.variables, self.column_terms())

    def column_terms(self) -> Terms:
        """The non-zero entries of the columns as polynomials in a few atoms, derived on first use.

        The kernel of :meth:`transform` and of :class:`~pysindy_xl.dynamics.CatalogDynamics`.

        Returns
        -------
        Terms
            One entry per row of ``entry_index_`` (``(coordinate, feature)`` pairs), decomposed
            into monomials (:class:`~pysindy_xl.feature_library.Terms`).
        """
        check_is_fitted(self, "entry_index_")
        terms = self.__dict__.get("_column_terms")
        if terms is None:
            terms = self._column_terms = self._derive_column_terms()
        return terms

    def _derive_column_terms(self) -> Terms:
        entries = tuple(self.symbolic_matrix_[c, j] for c, j in self.entry_index_)
        return shared_derivation(("column terms", entries), lambda: decompose(entries))

    def __getstate__(self):
        # compiled evaluators are closures: rebuilt on first use after unpickling
        state = self.__dict__.copy()
        for key in ("_evaluate", "_weak_evaluate", "_weak_entry_index", "_weak_memo", "_structure"):
            state.pop(key, None)
        return state

    def __setstate__(self, state):
        if "symbolic_matrix_" in state:  # the state of an earlier version
            state = {"_symbolic_matrix" if k == "symbolic_matrix_" else k: v
                     for k, v in state.items()}
        super().__setstate__(state)

    def _check_input(self, x) -> np.ndarray:
        x = check_numeric_array(x, "x", finite=False, min_samples=0)
        width = len(self.coords.variables)
        if x.ndim != 2 or x.shape[1] != width:
            raise ValueError(
                f"x: expected the stacked variables array of shape (n_samples, {width}) "
                f"(see pysindy_xl.feature_library.stack_variables), got shape {x.shape}")
        if x.shape[0] == 0:
            raise ValueError(f"x: expected at least one sample, got shape (0, {width})")
        if not np.all(np.isfinite(x)):
            raise ValueError("x: contains NaN or inf")
        return x

    def _check_finite_output(self, theta, n_rows):
        """Name the features that are NaN or inf on the data (log(x) at x <= 0, overflow)."""
        bad = ~np.isfinite(theta)
        if not bad.any():
            return
        columns = np.flatnonzero(bad.any(axis=0))
        names = [self.feature_names_[j] for j in columns[:5]]
        samples = np.unique(np.flatnonzero(bad.any(axis=1)) % n_rows)
        raise ValueError(
            f"feature_library: the term{'s' if len(columns) > 1 else ''} "
            f"{', '.join(names)}{' ...' if len(columns) > 5 else ''} "
            f"{'are' if len(columns) > 1 else 'is'} NaN or inf on {len(samples)} of {n_rows} "
            f"samples (first at sample {samples[0]}): the data leave the term's domain "
            "(log, sqrt, 1/x of values <= 0) or the values are too large (overflow)")

    def check_domain(self, x) -> None:
        """Raise ``ValueError`` when a candidate term is undefined on ``x``.

        The base class accepts every input; libraries with terms that have a domain
        (``log``, ``sqrt``...) override it.

        Parameters
        ----------
        x : array, shape (N, 4n + 1)
            Library input (:func:`stack_variables`).
        """

    def transform(self, x) -> np.ndarray:
        """The stacked regression matrix ``Theta`` of the data.

        Entry ``(c * N + k, j)`` is the symbolic entry ``E[c, j]`` (feature ``j`` in the
        equation of coordinate ``c``) at sample ``k``; the model is ``Theta @ xi = 0``.

        Parameters
        ----------
        x : array, shape (N, 4n + 1)
            Library input: positions, velocities, accelerations, forces and times
            (:func:`stack_variables`).

        Returns
        -------
        ndarray, shape (n * N, F)
            Rows coordinate-major: rows ``c * N`` to ``(c + 1) * N - 1`` hold the equation of
            coordinate ``c``.

        Raises
        ------
        ValueError
            When ``x`` has the wrong width, or a column is NaN or inf on it.

        Examples
        --------
        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2]).fit()
        >>> z = px.stack_variables(np.array([[2.0]]), np.array([[1.0]]), np.array([[3.0]]))
        >>> lib.transform(z)  # d/dt d(qd^2)/dqd = 2 qdd, -d(q^2)/dq = -2 q
        array([[ 6., -4.]])
        """
        check_is_fitted(self, "entry_index_")
        if not hasattr(self, "_evaluate"):  # compiled on first use: weak fits need none
            self._compile()
        x = self._check_input(x)
        n_samples = x.shape[0]
        # column-major: each entry written in place into a contiguous block (LAPACK's layout)
        theta = np.zeros((self.coords.n * n_samples, self.n_output_features_), order="F")
        targets = [theta[c * n_samples : (c + 1) * n_samples, j] for c, j in self.entry_index_]
        with np.errstate(all="ignore"):
            self._evaluate(x, targets)
        self._check_finite_output(theta, n_samples)
        return theta

    # -- weak formulation -------------------------------------------------------------------
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
        if type(self)._build_weak_symbolic is not SymbolicLibrary._build_weak_symbolic:
            return self._split_weak_terms()  # a split of its own, from what it knows
        # integration by parts of the entries: a function of the entries and coordinates
        key = ("weak terms", self.coords.variables, self.symbolic_matrix_.shape,
               tuple(self.symbolic_matrix_))
        return shared_derivation(key, self._split_weak_terms)

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
        # int phi E = -int phi' P - int phi Q: each non-zero entry meets its own test matrix
        tests = [scipy.sparse.csc_matrix(-dphi), scipy.sparse.csc_matrix(-phi)]
        parts = [np.flatnonzero(index[:, 0] == part) for part in (0, 1)]
        n_windows = phi.shape[0]
        contributions = np.zeros((n_windows, len(index)))
        with np.errstate(all="ignore"):  # (kept values are evaluated here)
            blocks = self._weak_values(x)
        for start in range(0, n_samples, _WEAK_BLOCK):  # blocks of samples bound the memory
            stop = min(start + _WEAK_BLOCK, n_samples)
            with np.errstate(all="ignore"):
                values = next(blocks)  # entries x samples
            for part, entries in enumerate(parts):
                if len(entries):
                    # samples x entries in C order, as the sparse product reads them
                    contributions[:, entries] += tests[part][:, start:stop] @ np.ascontiguousarray(
                        values[entries].T)
        weak = np.zeros((n, n_windows, n_features))
        np.add.at(weak, (index[:, 1], slice(None), index[:, 2]), contributions.T)
        weak = weak.reshape(n * n_windows, n_features)
        self._check_finite_output(weak, n_windows)
        return weak

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

    def get_feature_names(self, input_features=None) -> list[str]:
        """Names of the features, in column order.

        Parameters
        ----------
        input_features : list of str, optional
            pysindy's argument, ignored. Default None.

        Returns
        -------
        list of str
            ``L[term]`` for Lagrangian terms, ``C_<coordinate>[term]`` for classical ones,
            ``F[tau]`` for the forces.

        Examples
        --------
        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2]).fit()
        >>> lib.get_feature_names()
        ['L[x_dot**2]', 'L[x**2]']
        """
        check_is_fitted(self, "feature_names_")
        return list(self.feature_names_)

    def symbolic_matrix(self) -> sp.Matrix:
        """The symbolic columns, derived on first use.

        Returns
        -------
        sympy.Matrix, shape (n, F)
            Entry ``[c, j]`` is feature ``j`` in the equation of coordinate ``c``.

        Examples
        --------
        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2]).fit()
        >>> lib.symbolic_matrix()
        Matrix([[2*x_ddot, -2*x]])
        """
        if not hasattr(self, "entry_index_"):
            self.fit()
        return self.symbolic_matrix_

    def __add__(self, other):
        return LIBRARY_TYPES["CatalogRepartition"]([self, other])

    # -- persistence ----------------------------------------------------------------------
    def to_spec(self) -> dict:
        """JSON-serializable description of this library, read back by :meth:`from_spec`.

        Used by :meth:`XLSINDy.save <pysindy_xl.XLSINDy.save>` (:mod:`pysindy_xl.io`); a library
        that can be saved implements it.

        Returns
        -------
        dict
            ``{"type": spec_type, ...}``: plain JSON values, terms in the restricted grammar.
        """
        raise NotImplementedError(f"{type(self).__name__}: to_spec is not implemented; a "
                                  "library that can be saved describes itself in plain JSON")

    @classmethod
    def from_spec(cls, spec: dict, reader):
        """The library a specification describes (the inverse of :meth:`to_spec`).

        Parameters
        ----------
        spec : dict
            The description; untrusted (from a file).
        reader : SpecReader
            Parses the parts of ``spec`` within the loader's budget
            (:class:`~pysindy_xl.feature_library.SpecReader`): ``reader.coords``,
            ``reader.terms(spec)``, ``reader.matrix(spec, key, shape)``, ``reader.library(spec)``,
            ``reader.expect(condition, what)``.

        Returns
        -------
        SymbolicLibrary
            The library, not fitted.
        """
        raise NotImplementedError(f"{cls.__name__}: from_spec is not implemented")
