"""What every catalog category shares: symbolic columns compiled once to one numeric function.

Every library maps the data ``Z`` (N, 4n + 1), columns ``coords.variables`` (see
:func:`stack_variables`), to the regression matrix ``Theta`` (n * N, F): rows
coordinate-major (rows ``c * N`` to ``(c + 1) * N - 1`` hold the equation of coordinate
``c``), entry ``(c * N + k, j)`` the symbolic entry ``E[c, j]`` at sample ``k``. One
coefficient vector ``xi`` is shared by every coordinate, the model being ``Theta @ xi = 0``:
one Lagrangian term explains several equations at once.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import sympy as sp
from pysindy.feature_library.base import BaseFeatureLibrary
from sklearn.base import clone
from sklearn.utils.validation import check_is_fitted

from .._memo import shared_derivation as _shared
from .._validation import InstanceOf, check_numeric_array, validate_params
from ..registry import register_type
from ..symbols import Coordinates
from ._compile import Terms, compile_entries, compile_terms, decompose
from ._structure import ColumnStructure, DeferredMatrix
from ._weak_evaluation import WeakEvaluation, remembered_weak_values

__all__ = ["SymbolicLibrary", "compile_entries", "LIBRARY_TYPES",
           "remembered_weak_values"]

#: Every catalog category by its ``spec_type``: what a model file may name. Subclasses
#: register themselves when defined; loading never imports anything.
LIBRARY_TYPES: dict[str, type] = {}

#: Derived terms by content, most recently used last: a clone of a catalog finds its
#: :class:`Terms` (and their compiled evaluators) here.
_DERIVED: dict = {}
_CACHED_DERIVED = 16


def shared_derivation(key, derive, cache=_DERIVED, size=_CACHED_DERIVED):
    """``derive()``, shared by every call with the same ``key`` in ``cache`` (at most ``size``
    entries, the least recently used dropped first; :func:`pysindy_xl._memo.shared_derivation`
    with the derived terms' cache by default)."""
    return _shared(key, derive, cache, size)


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


class SymbolicLibrary(ColumnStructure, WeakEvaluation, BaseFeatureLibrary):
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

    # -- weak formulation (:class:`~._weak_evaluation.WeakEvaluation`) ------------------------
    def _derive_weak_terms(self) -> tuple[np.ndarray, Terms]:
        if type(self)._build_weak_symbolic is not SymbolicLibrary._build_weak_symbolic:
            return self._split_weak_terms()  # a split of its own, from what it knows
        # integration by parts of the entries: a function of the entries and coordinates
        key = ("weak terms", self.coords.variables, self.symbolic_matrix_.shape,
               tuple(self.symbolic_matrix_))
        return shared_derivation(key, self._split_weak_terms)

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
