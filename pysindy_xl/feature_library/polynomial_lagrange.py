"""Lagrangian candidate terms that are trigonometric polynomials, derived on sparse arrays
(:mod:`.trigpoly`) without sympy's general differentiation: the Lagrangians of rigid-body
chains (the kinematic catalogs of :mod:`pysindy_xl.mujoco`).
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import sympy as sp

from .._validation import Collection, InstanceOf
from ..expressions import format_expression
from ..physical.rigid_body import KinematicTree, physical_parameters_from_base
from ..symbols import as_expr_list
from ._base import shared_derivation
from ._compile import Terms
from ._structure import DeferredMatrix
from .lagrange import LagrangeLibrary
from .trigpoly import TrigPolynomial, euler_lagrange_many, partial_derivatives_many
from .trigterms import TrigTerms

__all__ = ["PolynomialLagrangeLibrary"]


class PolynomialLagrangeLibrary(LagrangeLibrary):
    """:class:`~pysindy_xl.LagrangeLibrary` with a fast derivation for trigonometric polynomials.

    Same columns and names as ``LagrangeLibrary``. When every term is a polynomial in
    ``sin q_j``, ``cos q_j`` (angles), ``q_j`` (other coordinates) and ``qd_j``, the columns are
    derived on sparse arrays (:mod:`.trigpoly`); otherwise symbolically (with a warning when an
    angle enters both bare and through its sine or cosine).

    Parameters
    ----------
    coords : Coordinates
        The generalized coordinates.
    terms : sequence of sympy.Expr or TrigTerms
        Candidate Lagrangian terms, as in :class:`~pysindy_xl.LagrangeLibrary`.
    parameters : sequence of dict, optional
        Default None.
        One per term: the physical parameters it stands for, ``{name: weight}`` (a kinematic
        catalog's base parameters); read by :meth:`XLSINDy.physical_parameters
        <pysindy_xl.XLSINDy.physical_parameters>`.
    tree : KinematicTree, optional
        The mechanism the terms come from (with ``parameters``): models then evaluate their
        Lagrangian part with the rigid-body kernel of :mod:`pysindy_xl.physical.rigid_body`.

    Examples
    --------
    >>> import numpy as np, sympy as sp, pysindy_xl as px
    >>> c = px.Coordinates(["theta", "x"])
    >>> terms = [c.qd[0] ** 2 * sp.cos(c.q[0]) ** 2, c.qd[0] * c.qd[1] * sp.sin(c.q[0]),
    ...          c.q[1] ** 2 * sp.cos(c.q[0])]
    >>> data = np.random.default_rng(0).normal(size=(50, 9))
    >>> fast = PolynomialLagrangeLibrary(c, terms).fit().transform(data)
    >>> bool(np.allclose(fast, px.LagrangeLibrary(c, terms).fit().transform(data)))
    True
    """

    spec_type = "PolynomialLagrangeLibrary"
    _parameter_constraints = {
        **LagrangeLibrary._parameter_constraints,
        "parameters": [None, Collection("a sequence of dict (one per term)")],
        "tree": [None, InstanceOf(KinematicTree, "a KinematicTree")],
    }

    def __init__(self, coords, terms, parameters=None, tree=None):
        super().__init__(coords, terms)
        self.parameters = parameters
        self.tree = tree

    def rigid_body_parameters(self, coefficients):
        """Physical parameters of :attr:`tree` for given coefficients of the terms.

        The parameters whose Lagrangian is ``sum_j coefficients[j] terms[j]``, least-norm
        (:func:`~pysindy_xl.physical.rigid_body.physical_parameters_from_base`).

        Parameters
        ----------
        coefficients : array, shape (n_terms,)
            Coefficients of this library's terms.

        Returns
        -------
        ndarray or None
            The physical parameters of the tree, in the order of ``tree.physical_names``; None
            without a tree.
        """
        if self.tree is None:
            return None
        self._check_tree()
        return physical_parameters_from_base(self.tree, self.parameters, coefficients)

    def _check_tree(self):
        if not isinstance(self.tree, KinematicTree):
            raise TypeError(f"tree: expected a KinematicTree, got {type(self.tree).__name__}")
        if self.parameters is None:
            raise ValueError("tree: needs parameters (the physical combination of each term)")
        if len(self.tree.joint_names) != self.coords.n:
            raise ValueError(f"tree: has {len(self.tree.joint_names)} joints for "
                             f"{self.coords.n} coordinates")

    @property
    def complete_catalog(self) -> bool:
        """Whether every term stands for a physical parameter (``parameters`` given), so that an
        unforced law needs no selection of terms.
        """
        return self.parameters is not None

    def _build_symbolic(self):
        trig = isinstance(self.terms, TrigTerms) and self.terms.coords == self.coords
        terms = self.terms if trig else as_expr_list(self.terms, "terms")
        if self.tree is not None:
            self._check_tree()
        self.__dict__.pop("_polynomial_columns", None)
        if not len(terms):
            return super()._build_symbolic()  # raises the ValueError of LagrangeLibrary
        coords = self.coords
        key = ("polynomials", terms.key) if trig else (tuple(coords.variables), tuple(terms))
        derivation = shared_derivation(
            key, lambda: _derive_trig(terms) if trig else _derive(coords, terms),
            _DERIVATIONS, _CACHED_DERIVATIONS)
        if derivation is _NOT_POLYNOMIAL:
            mixed = _mixed_angles(terms, coords)
            if mixed:
                warnings.warn(
                    f"terms: the angle{'s' * (len(mixed) > 1)} {', '.join(mixed)} enter"
                    f"{'s' * (len(mixed) == 1)} both through sin/cos and bare "
                    "(e.g. theta and sin(theta)); PolynomialLagrangeLibrary derives such terms "
                    "symbolically, which is slower: put the terms with the bare angles in a "
                    "LagrangeLibrary of their own (pysindy_xl.AutomaticCatalog does)",
                    stacklevel=2)
            return super()._build_symbolic()
        self.terms_ = terms
        # the exact terms and columns, for column_terms and weak_terms
        self._polynomial_columns = derivation
        self.zero_terms_ = list(derivation.zero_terms)
        return list(derivation.names), derivation.structure

    def _deferred_matrix(self) -> sp.Matrix:
        derivation = self._polynomial_columns
        if derivation.matrix is None:  # shared by clones of this library
            columns = [[e.to_sympy(self.coords, evaluate=False) for e in column]
                       for column in derivation.derived]
            derivation.matrix = sp.Matrix(self.coords.n, len(columns), lambda i, j: columns[j][i])
        return derivation.matrix

    def impulsive(self) -> bool:
        """Whether an acceleration enters a column with a switching coefficient.

        Returns
        -------
        bool
            False for columns derived as trigonometric polynomials (smooth coefficients); as
            :class:`~pysindy_xl.LagrangeLibrary` for terms derived symbolically.
        """
        if self.__dict__.get("_polynomial_columns") is not None:
            return False
        return super().impulsive()

    def check_domain(self, x) -> None:
        """Raise ``ValueError`` naming the terms undefined on ``x``.

        Only symbolically derived terms need :meth:`LagrangeLibrary.check_domain
        <pysindy_xl.LagrangeLibrary.check_domain>`: trigonometric polynomials are defined
        everywhere.

        Parameters
        ----------
        x : array, shape (N, 4n + 1)
            Library input (:func:`~pysindy_xl.feature_library.stack_variables`).
        """
        if "_polynomial_columns" not in self.__dict__:
            super().check_domain(x)

    def _check_columns(self, names, matrix) -> None:
        if "_polynomial_columns" not in self.__dict__:  # derived symbolically
            super()._check_columns(names, matrix)
        # polynomials in sin, cos, q, qd, qdd are evaluable everywhere

    def _derive_column_terms(self) -> Terms:
        """The column entries straight from the polynomials' exponent rows (no sympy)."""
        if "_polynomial_columns" not in self.__dict__:
            return super()._derive_column_terms()
        derivation = self._polynomial_columns
        if derivation.column_terms is None:  # shared by clones of this library
            derived = derivation.derived
            derivation.column_terms = self._terms_of([derived[j][c] for c, j in self.entry_index_])
        return derivation.column_terms

    def _derive_weak_terms(self):
        """``P = dL/dqd`` and ``Q = dL/dq`` of every term straight from its polynomial."""
        if "_polynomial_columns" not in self.__dict__:
            return super()._derive_weak_terms()
        derivation = self._polynomial_columns
        if derivation.weak_terms is None:
            index, entries = [], []
            parts = partial_derivatives_many(derivation.polynomials)
            for part in (0, 1):
                for c in range(self.coords.n):
                    for j, derivative in enumerate(parts[part][c]):
                        if not derivative.is_zero:
                            index.append((part, c, j))
                            entries.append(derivative)
            derivation.weak_terms = (np.array(index, dtype=int).reshape(-1, 3),
                                     self._terms_of(entries))
        return derivation.weak_terms

    def _terms_of(self, polynomials) -> Terms:
        """:class:`Terms` of polynomials over the slot atoms ``(sin q | q, cos q, qd, qdd)``."""
        angles = self._polynomial_columns.angles
        coords = self.coords
        atoms = ([sp.sin(q) if angle else q for q, angle in zip(coords.q, angles, strict=True)]
                 + [sp.cos(q) for q in coords.q] + list(coords.qd) + list(coords.qdd))
        sizes = [len(p.coefficients) for p in polynomials]
        return Terms.from_arrays(
            atoms, np.vstack([p.exponents for p in polynomials]
                             + [np.zeros((0, len(atoms)), dtype=np.int16)]),
            np.concatenate([p.coefficients for p in polynomials] + [np.zeros(0)]),
            np.repeat(np.arange(len(polynomials)), sizes), len(polynomials))

    def to_spec(self) -> dict:
        """JSON-serializable description of this library, read back by :meth:`from_spec`.

        A trigonometric polynomial term is written as its exponent rows and coefficients (exact
        and compact), any other term in the restricted grammar.

        Returns
        -------
        dict
            ``{"type": spec_type, ...}``: the parameters as plain JSON values, terms in the
            restricted grammar (:func:`~pysindy_xl.expressions.format_expression`).
        """
        coords = self.coords
        if isinstance(self.terms, TrigTerms) and self.terms.coords == coords and len(self.terms):
            polynomials = self.terms.polynomials
            n = coords.n
            # the angles the terms use, as the sympy path finds them
            used = np.zeros(n, dtype=bool)
            for p in polynomials:
                used |= (p.exponents[:, :2 * n] != 0).reshape(-1, 2, n).any(axis=(0, 1))
            angles = tuple(bool(a and u) for a, u in zip(self.terms.angles, used, strict=True))
            items = [{"exponents": p.exponents.tolist(), "coefficients": p.coefficients.tolist()}
                     for p in polynomials]
            return self._spec(angles, items)
        terms = as_expr_list(self.terms, "terms")
        angles = _angles(terms, coords)
        items = []
        for term in terms:
            try:
                polynomial = TrigPolynomial.from_sympy(term, coords, angles)
            except ValueError:
                polynomial = None
            if polynomial is not None and polynomial.to_sympy(coords) == term:
                items.append({"exponents": polynomial.exponents.tolist(),
                              "coefficients": polynomial.coefficients.tolist()})
            else:
                items.append(format_expression(term))
        return self._spec(angles, items)

    def _spec(self, angles, items) -> dict:
        spec = {"type": self.spec_type, "angles": list(angles), "terms": items}
        if self.parameters is not None:
            spec["parameters"] = [{str(k): float(v) for k, v in p.items()} for p in self.parameters]
        if self.tree is not None:
            spec["tree"] = self.tree.to_dict()
        return spec

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
        PolynomialLagrangeLibrary
            The library, not fitted.
        """
        coords = reader.coords
        angles, items = spec.get("angles"), spec.get("terms")
        reader.expect(isinstance(angles, list) and len(angles) == coords.n
                      and all(isinstance(a, bool) for a in angles),
                      f"{cls.spec_type}.angles must be one true or false per coordinate")
        reader.expect(isinstance(items, list) and items,
                      f"{cls.spec_type}.terms must be a non-empty list")
        reader.count_terms(len(items))
        terms = []
        for k, item in enumerate(items):
            if isinstance(item, str):
                terms.append(reader.term(item))
                continue
            exponents, coefficients = reader.polynomial(item, 4 * coords.n,
                                                        f"{cls.spec_type}.terms[{k}]")
            terms.append(TrigPolynomial(exponents, coefficients, angles))
        if all(isinstance(t, TrigPolynomial) for t in terms):
            terms = TrigTerms(terms, coords)  # sympy expressions built only when read
        else:
            terms = [t.to_sympy(coords) if isinstance(t, TrigPolynomial) else t for t in terms]
        parameters = spec.get("parameters")
        reader.expect(parameters is None or (
            isinstance(parameters, list) and len(parameters) == len(terms)
            and all(isinstance(p, dict) and all(
                isinstance(k, str) and isinstance(v, (int, float)) and not isinstance(v, bool)
                and np.isfinite(v) for k, v in p.items()) for p in parameters)),
            f"{cls.spec_type}.parameters must be one object of finite weights per term")
        tree = spec.get("tree")
        if tree is not None:
            reader.expect(parameters is not None, f"{cls.spec_type}.tree needs parameters")
            reader.expect(isinstance(tree, dict) and len(tree.get("body_names", ())) <= 1000,
                          f"{cls.spec_type}.tree must be an object of at most 1000 bodies")
            try:
                tree = KinematicTree.from_dict(tree)
            except (TypeError, ValueError) as err:
                reader.expect(False, f"{cls.spec_type}.tree: {err}")
            reader.expect(len(tree.joint_names) == coords.n,
                          f"{cls.spec_type}.tree must have one joint per coordinate")
            known = set(tree.physical_names)
            reader.expect(all(name in known for p in parameters for name in p),
                          f"{cls.spec_type}.parameters must name parameters of the tree")
        return cls(coords, terms, parameters, tree)


@dataclasses.dataclass
class _Derivation:
    """The Euler-Lagrange columns of a list of polynomial terms, and what derives from them;
    shared by every library with the same coordinates and terms (clones, loaded models).
    """

    angles: tuple
    polynomials: list
    derived: list  # per term, its Euler-Lagrange column (one polynomial per coordinate)
    names: list
    structure: DeferredMatrix  # of the columns; their sympy matrix built on first use
    zero_terms: list
    matrix: sp.Matrix | None = None
    column_terms: Terms | None = None
    weak_terms: tuple | None = None


_NOT_POLYNOMIAL = object()  # cached verdict: some term is not a trigonometric polynomial
_CACHED_DERIVATIONS = 4
_DERIVATIONS: dict = {}  # (variables, terms) -> _Derivation, least recently used first


def _derive(coords, terms):
    angles = _angles(terms, coords)
    try:
        polynomials = [TrigPolynomial.from_sympy(t, coords, angles) for t in terms]
    except ValueError:
        return _NOT_POLYNOMIAL
    return _derivation(coords, polynomials, euler_lagrange_many(polynomials),
                       [_feature_name(t) for t in terms])


def _derive_trig(terms: TrigTerms):
    """The derivation of terms given as polynomials, with the columns they carry when derived."""
    n = terms.coords.n
    for p in terms.polynomials:
        if p.exponents[:, 3 * n:].any():
            raise ValueError(f"terms: Lagrangian term {TrigTerms([p], terms.coords)[0]} uses "
                             "accelerations; only positions, velocities and t are allowed")
    derived = terms.columns
    if derived is None:
        derived = euler_lagrange_many(terms.polynomials)
    return _derivation(terms.coords, list(terms.polynomials), [list(c) for c in derived],
                       [f"L[{name}]" for name in terms.names()])


def _derivation(coords, polynomials, derived, names):
    angles = polynomials[0].angles
    n = coords.n
    # each slot's variable: sin q | q, cos q, qd, qdd (coords.variables: q, qd, qdd, tau, t)
    slots = np.zeros((4 * n, len(coords.variables)), dtype=bool)
    slots[np.arange(4 * n), np.r_[np.arange(n), np.arange(n), np.arange(n, 3 * n)]] = True
    used = np.array([[e.exponents.any(axis=0) for e in column] for column in derived],
                    dtype=bool).reshape(len(derived), n, 4 * n)
    structure = DeferredMatrix(
        np.swapaxes(used @ slots, 0, 1),
        np.array([[len(e.coefficients) for e in column] for column in derived],
                 dtype=int).reshape(len(derived), n).T)
    zero_terms = [j for j, column in enumerate(derived) if all(e.is_zero for e in column)]
    return _Derivation(angles, polynomials, derived, names, structure, zero_terms)


def _angles(terms, coords) -> tuple:
    """Which coordinates the terms use as angles (through their sine or cosine)."""
    return tuple(any(t.has(sp.sin(q)) or t.has(sp.cos(q)) for t in terms) for q in coords.q)


def _mixed_angles(terms, coords) -> list[str]:
    """The angles (coordinates in some sin/cos) that some term also uses bare."""
    out = []
    for q, angle in zip(coords.q, _angles(terms, coords), strict=True):
        if angle:
            bare = sp.Dummy()
            hidden = {sp.sin(q): bare, sp.cos(q): bare}
            if any(t.xreplace(hidden).has(q) for t in terms):
                out.append(str(q))
    return out


def _feature_name(term: sp.Expr) -> str:
    # the names of LagrangeLibrary: saved models are checked against them when loaded
    return f"L[{term}]"
