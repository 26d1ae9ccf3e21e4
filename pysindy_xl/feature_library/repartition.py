"""CatalogRepartition: the concatenation of catalog categories into one regression problem."""

from __future__ import annotations

import numpy as np
import sympy as sp
from sklearn.utils.validation import check_is_fitted

from .._validation import Collection
from ._base import SymbolicLibrary, TermChain, shared_derivation
from ._compile import Terms
from ._structure import DeferredMatrix
from .external_forces import ExternalForces

__all__ = ["CatalogRepartition"]


_MERGED: dict = {}  # (identities of the parts' terms, column offsets) -> (parts, merged)
_CACHED_MERGES = 8


def _merged(slices, parts) -> tuple[np.ndarray, Terms]:
    """Concatenate the ``(index, terms)`` of several libraries: atoms merged, each index's last
    column (the feature) shifted to the library's columns; the merge of the same (cached) parts
    is reused across clones.
    """
    key = (tuple(id(terms) for _, terms in parts), tuple(c.start for c in slices),
           tuple(np.asarray(index).tobytes() for index, _ in parts))
    # the parts, kept with their merge, keep the ids valid
    found = shared_derivation(key, lambda: (parts, _merge(slices, parts)), _MERGED, _CACHED_MERGES)
    index, terms = found[1]
    return index.copy(), terms


def _as_slice(columns: list):
    """``columns`` as a slice where they are a run: a fancy index costs some 40 times as much
    on an arm's catalog."""
    if columns and columns == list(range(columns[0], columns[0] + len(columns))):
        return slice(columns[0], columns[0] + len(columns))
    return columns


def _merge(slices, parts) -> tuple[np.ndarray, Terms]:
    atoms: dict = {}
    indices, blocks = [], []
    for columns, (index, terms) in zip(slices, parts, strict=True):
        remap = [atoms.setdefault(atom, len(atoms)) for atom in terms.atoms]
        shifted = np.array(index, dtype=int).reshape(len(terms), -1)
        shifted[:, -1] += columns.start
        indices.append(shifted)
        blocks.append((remap, terms.arrays()))
    width = max((i.shape[1] for i in indices), default=2)
    powers = np.zeros((sum(len(b[1][1]) for b in blocks), len(atoms)), dtype=np.int16)
    start, entries = 0, 0
    coefficients, owners = [], []
    for remap, (block_powers, block_coefficients, block_owners, n_entries) in blocks:
        powers[start:start + len(block_coefficients), _as_slice(remap)] = block_powers
        start += len(block_coefficients)
        coefficients.append(block_coefficients)
        owners.append(block_owners + entries)
        entries += n_entries
    return (np.vstack(indices) if indices else np.zeros((0, width), dtype=int),
            Terms.from_arrays(sorted(atoms, key=atoms.get), powers,
                              np.concatenate(coefficients + [np.zeros(0)]),
                              np.concatenate(owners + [np.zeros(0, dtype=np.intp)]), entries))


def _monomial_coefficients(expr: sp.Expr) -> dict:
    """``expr`` as {monomial: coefficient} after expanding products of trigonometric sums."""
    expanded = sp.expand(sp.expand_trig(sp.expand(expr)))
    return {m: float(c) for m, c in expanded.as_coefficients_dict().items() if m != 1}


class CatalogRepartition(SymbolicLibrary):
    """Concatenation of catalog categories into one stacked regression matrix.

    The libraries' columns are placed side by side, all compiled into one NumPy function; an
    :class:`ExternalForces` column is prepended when none is given (explicit and mixed
    regression need it). All libraries share one :class:`Coordinates`.

    Parameters
    ----------
    libraries : list of SymbolicLibrary
        The categories (:class:`~pysindy_xl.LagrangeLibrary`,
        :class:`~pysindy_xl.ClassicalLibrary`, :class:`~pysindy_xl.ExternalForces`...); nested
        ``CatalogRepartition`` are flattened. ``lag + cls`` builds the same catalog.

    Attributes
    ----------
    libraries_ : list of SymbolicLibrary
        The flattened libraries, force library included.
    slices_ : list of slice
        Columns of each library.
    categories_ : list of str
        Category of each feature (``"forces"``, ``"lagrange"``, ``"classical"``, ...).
    feature_terms_ : list
        The term each feature stands for.
    force_columns_ : list of int
        Indices of the force columns.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2]) + px.ClassicalLibrary(c, [c.qd[0]])
    >>> lib.fit().get_feature_names()
    ['F[tau]', 'L[x_dot**2]', 'L[x**2]', 'C_x[x_dot]']
    >>> lib.ideal_coefficients(lagrangian=c.qd[0] ** 2 / 2 - 2 * c.q[0] ** 2,
    ...                        classical={(c.qd[0], 0): 0.1})
    array([-1. ,  0.5, -2. ,  0.1])
    """

    category = "repartition"
    spec_type = "CatalogRepartition"
    _parameter_constraints = {
        "libraries": [Collection("a list of pysindy_xl feature libraries")],
    }

    def __init__(self, libraries):
        self.libraries = libraries

    @property
    def coords(self):
        """The coordinates shared by all the libraries (those of the first)."""
        return self.flat_libraries()[0].coords

    @property
    def complete_catalog(self) -> bool:
        """Whether every Lagrangian library is complete (its terms are the law's physical
        parameters, ``PolynomialLagrangeLibrary.complete_catalog``).
        """
        lagrange = [lib for lib in self.flat_libraries() if lib.category == "lagrange"]
        return bool(lagrange) and all(getattr(lib, "complete_catalog", False) for lib in lagrange)

    def flat_libraries(self, _parents=()) -> list[SymbolicLibrary]:
        """The libraries, nested catalogs flattened, a force library first when none is given.

        Parameters
        ----------
        _parents : tuple of int, default ()
            Internal: ids of the enclosing catalogs, to refuse a catalog nested in itself.

        Returns
        -------
        list of SymbolicLibrary
            The flattened libraries, an :class:`~pysindy_xl.ExternalForces` first when none is
            given.

        Raises
        ------
        TypeError
            For an entry that is not a catalog library.
        ValueError
            For a catalog nested in itself, no library, or libraries of different coordinates.

        Examples
        --------
        >>> import pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> catalog = px.CatalogRepartition([px.LagrangeLibrary(c, [c.qd[0] ** 2])])
        >>> [type(lib).__name__ for lib in catalog.flat_libraries()]
        ['ExternalForces', 'LagrangeLibrary']
        """
        libraries = self.libraries  # (read once: a subclass may derive it on each read)
        if isinstance(libraries, SymbolicLibrary) or not hasattr(libraries, "__iter__"):
            raise TypeError("libraries: expected a list of pysindy_xl feature libraries")
        parents = (*_parents, id(self))
        flat = []
        for lib in libraries:
            if isinstance(lib, CatalogRepartition):
                if id(lib) in parents:
                    raise ValueError("libraries: the catalog contains itself (a "
                                     "CatalogRepartition nested in its own libraries)")
                flat.extend(lib.flat_libraries(parents))
            elif isinstance(lib, SymbolicLibrary):
                flat.append(lib)
            else:
                raise TypeError(
                    "libraries: expected pysindy_xl feature libraries (SymbolicLibrary "
                    "subclasses such as LagrangeLibrary, ClassicalLibrary, ExternalForces), got "
                    f"{type(lib).__name__}; wrap pysindy libraries in "
                    "ClassicalLibrary(coords, library)")
        if not flat:
            raise ValueError("libraries: expected at least one library")
        coords = flat[0].coords
        for lib in flat[1:]:
            if lib.coords != coords:
                raise ValueError("libraries: all libraries must share the same coordinates, got "
                                 f"{coords} and {lib.coords}")
        if not any(lib.category == "forces" for lib in flat):
            flat.insert(0, ExternalForces(coords))
        return flat

    def _check_coords(self):
        self.flat_libraries()[0]._check_coords()

    def _build_symbolic(self):
        libraries = self.flat_libraries()
        names, blocks, slices = [], [], []
        for lib in libraries:
            lib._fit_symbolic()
            start = len(names)
            names.extend(lib.feature_names_)
            blocks.append(lib._entry_structure())
            slices.append(slice(start, len(names)))
        self.libraries_ = libraries
        self.slices_ = slices
        self.categories_ = [lib.category for lib in libraries
                            for _ in range(lib.n_output_features_)]
        self.force_columns_ = [j for j, cat in enumerate(self.categories_) if cat == "forces"]
        return names, DeferredMatrix(np.concatenate([v for v, _ in blocks], axis=1),
                                     np.concatenate([z for _, z in blocks], axis=1))

    def _deferred_matrix(self) -> sp.Matrix:
        return sp.Matrix.hstack(*(lib.symbolic_matrix_ for lib in self.libraries_))

    def impulsive(self) -> bool:
        """Whether an acceleration enters some library's column with a switching coefficient.

        Returns
        -------
        bool
            True when one of the libraries is impulsive
            (:meth:`SymbolicLibrary.impulsive
            <pysindy_xl.feature_library.SymbolicLibrary.impulsive>`).
        """
        return any(lib.impulsive() for lib in self.libraries_)

    def _feature_terms(self):
        return TermChain([lib.feature_terms_ for lib in self.libraries_])

    def _check_columns(self, names, matrix) -> None:
        """Each library checked its own columns when it derived them."""

    def _derive_column_terms(self) -> Terms:
        """The libraries' column terms, atoms merged, entries in ``entry_index_`` order."""
        index, terms = _merged(self.slices_,
                               [(lib.entry_index_, lib.column_terms()) for lib in self.libraries_])
        key = ("in the order of", self.entry_index_.tobytes())
        ordered = terms._memo.get(key)  # shared by clones, with its compiled evaluator
        if ordered is None:
            position = {(int(c), int(j)): k for k, (c, j) in enumerate(index)}
            ordered = terms._memo[key] = terms.take(
                [position[(int(c), int(j))] for c, j in self.entry_index_])
        return ordered

    def _derive_weak_terms(self):
        """The libraries' weak terms, atoms merged (entries in library order)."""
        return _merged(self.slices_, [lib.weak_terms() for lib in self.libraries_])

    def _build_weak_symbolic(self):
        parts = [lib.weak_matrices() for lib in self.libraries_]
        return sp.Matrix.hstack(*(p for p, _ in parts)), sp.Matrix.hstack(*(q for _, q in parts))

    def check_domain(self, x) -> None:
        """Raise ``ValueError`` naming a candidate term undefined on ``x`` (by each library).

        Parameters
        ----------
        x : array, shape (N, 4n + 1)
            Library input (:func:`~pysindy_xl.feature_library.stack_variables`).
        """
        check_is_fitted(self, "libraries_")
        for lib in self.libraries_:
            lib.check_domain(x)

    def __add__(self, other):
        return CatalogRepartition([self, other])

    def __radd__(self, other):
        return CatalogRepartition([other, self])

    # -- helpers on the coefficient vector ----------------------------------------------------
    def physical_structure(self):
        """What the columns stand for physically, in column indices.

        Rigid-body base parameters from the Lagrange libraries' ``parameters`` maps, and friction
        (:mod:`pysindy_xl.physical`).

        Returns
        -------
        PhysicalStructure or None
            None when no library maps its terms to physical parameters.
        """
        from ..physical.structure import catalog_structure

        check_is_fitted(self, "entry_index_")
        return catalog_structure(self)

    def column_priority(self) -> np.ndarray:
        """Feature indices from most to least preferred among linearly dependent columns.

        By the libraries' ``column_rank`` (forces, Lagrange, classical, others), then fewer terms in
        the column's entries, then catalog order.

        Returns
        -------
        ndarray of int, shape (F,)
            A permutation of the feature indices.

        Examples
        --------
        >>> import pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = (px.ClassicalLibrary(c, [c.q[0]]) + px.LagrangeLibrary(c, [c.q[0] ** 2])).fit()
        >>> lib.get_feature_names(), lib.column_priority().tolist()
        (['F[tau]', 'C_x[x]', 'L[x**2]'], [0, 2, 1])
        """
        check_is_fitted(self, "entry_index_")
        complexity = self.entry_sizes().sum(axis=0).tolist()
        ranks = [lib.column_rank for lib in self.libraries_ for _ in range(lib.n_output_features_)]
        keys = [(ranks[j], complexity[j], j) for j in range(self.n_output_features_)]
        return np.array([k[-1] for k in sorted(keys)], dtype=int)

    def ideal_coefficients(self, lagrangian=None, classical=None, forces: float = -1.0):
        """Coefficient vector (F,) of a known model in this catalog.

        Parameters
        ----------
        lagrangian : sympy.Expr, optional
            True Lagrangian, expanded (trigonometric sums included) and matched against the
            Lagrange terms; constant parts are ignored.
        classical : dict, optional
            ``{(term, coordinate): value}`` (coordinate an index or a name) or
            ``{feature_name: value}``.
        forces : float, default -1.0
            Coefficient of the force column.

        Returns
        -------
        ndarray, shape (F,)
            The coefficients, in feature order (zero for the terms the model does not contain).

        Raises
        ------
        ValueError
            If a part of the model is not representable in the catalog.

        Examples
        --------
        >>> import pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.CatalogRepartition([px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])]).fit()
        >>> lib.ideal_coefficients(lagrangian=c.qd[0] ** 2 / 2 - c.q[0] ** 2)
        array([-1. ,  0.5, -1. ])
        """
        if not hasattr(self, "entry_index_"):
            self.fit()
        xi = np.zeros(self.n_output_features_)
        xi[self.force_columns_] = forces
        if lagrangian is not None:
            from ..expressions import as_expression

            self._match_lagrangian(
                as_expression(lagrangian, self.coords.symbol_table(), "lagrangian"), xi)
        for key, value in (classical or {}).items():
            xi[self._classical_index(key)] += float(value)
        return xi

    def _match_lagrangian(self, lagrangian: sp.Expr, xi: np.ndarray):
        columns = [j for j, cat in enumerate(self.categories_) if cat == "lagrange"]
        expansions = [_monomial_coefficients(self.feature_terms_[j]) for j in columns]
        target = _monomial_coefficients(lagrangian)
        monomials = sorted(set(target).union(*expansions), key=sp.default_sort_key)
        row = {m: i for i, m in enumerate(monomials)}
        basis = np.zeros((len(monomials), len(columns)))
        for j, expansion in enumerate(expansions):
            for m, c in expansion.items():
                basis[row[m], j] = c
        rhs = np.zeros(len(monomials))
        for m, c in target.items():
            rhs[row[m]] = c
        solution = np.linalg.lstsq(basis, rhs, rcond=None)[0] if columns else np.zeros(0)
        residual = basis @ solution - rhs if columns else -rhs
        missing = [str(m) for m, r in zip(monomials, residual, strict=True) if abs(r) > 1e-9]
        if missing:
            raise ValueError(
                f"lagrangian: terms {missing} are not representable by the Lagrange catalog")
        solution[np.abs(solution) < 1e-12] = 0.0
        xi[columns] += solution

    def _classical_index(self, key) -> int:
        names = self.feature_names_
        if isinstance(key, str):
            if key not in names:
                raise ValueError(f"classical: unknown feature name {key!r}")
            return names.index(key)
        try:
            term, coord = key
        except (TypeError, ValueError):
            raise ValueError(f"classical: expected keys (term, coordinate) or feature names, got "
                             f"{key!r}") from None
        if isinstance(coord, str):
            if coord not in self.coords.names:
                raise ValueError(f"classical: unknown coordinate {coord!r}")
            coord = self.coords.names.index(coord)
        from ..expressions import as_expression

        term = as_expression(term, self.coords.symbol_table(), "classical")
        for j, category in enumerate(self.categories_):
            # a classical feature enters one equation: the row where its column is not zero
            if (category == "classical" and self.symbolic_matrix_[coord, j] != 0
                    and sp.simplify(self.feature_terms_[j] - term) == 0):
                return j
        raise ValueError(f"classical: term {term} in the equation of {self.coords.names[coord]} is "
                         "not in the catalog")

    def to_spec(self) -> dict:
        """JSON-serializable description of this library, read back by :meth:`from_spec`.

        The libraries are described one after the other, nested catalogs flattened.

        Returns
        -------
        dict
            ``{"type": spec_type, ...}``: the parameters as plain JSON values, terms in the
            restricted grammar (:func:`~pysindy_xl.expressions.format_expression`).
        """
        return {"type": self.spec_type,
                "libraries": [lib.to_spec() for lib in self.flat_libraries()]}

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
        CatalogRepartition
            The library, not fitted.
        """
        libraries = spec.get("libraries")
        reader.expect(isinstance(libraries, list) and libraries,
                      "libraries must be a non-empty list")
        return cls([reader.library(item) for item in libraries])
