"""Mass-matrix form of a catalog's equations, built numerically (:class:`CatalogDynamics`)."""

from __future__ import annotations

import numpy as np
import sympy as sp

from ..feature_library import Terms, decompose
from ..physical.rigid_body import rigid_body_dynamics
from .mass_matrix import MassMatrixDynamics

__all__ = ["CatalogDynamics"]


class CatalogDynamics(MassMatrixDynamics):
    r"""The equations ``sum_j xi_j E[c, j] = 0`` of a catalog in mass-matrix form.

    The column entries ``E[c, j]``, decomposed once into monomials of a few atoms, are combined
    numerically with the coefficients ``coef`` (F,) into

    .. math:: M_{ck} = \sum_j \xi_j \frac{\partial E_{cj}}{\partial \ddot q_k}, \qquad
              f_c = -\sum_j \xi_j E_{cj}\big|_{\ddot q = 0}.

    Lagrange libraries with a kinematic tree go through the rigid-body kernel instead
    (:mod:`pysindy_xl.physical.rigid_body`; ``rigid_parts``: their ``(tree, pi)``), so an arm
    costs what its bodies cost. The symbolic forms are built on first use.

    Parameters
    ----------
    library : CatalogRepartition
        A fitted catalog.
    coef : array, shape (F,)
        Its coefficients ``xi``, one per feature.
    held : bool array, shape (n,), optional
        Coordinates held still (:mod:`pysindy_xl.fit.still`), whose equation becomes
        ``qdd_c = 0``; default None (none).

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> library = px.CatalogRepartition([px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])])
    >>> dyn = CatalogDynamics(library.fit(), np.array([-1.0, 1.0, -1.5]))  # x'' + 3 x = u
    >>> dyn.accelerations(np.array([[1.0]]), np.array([[0.0]]), np.array([[5.0]]))
    array([[1.]])
    >>> dyn.mass_matrix_expr, dyn.forcing_expr
    (Matrix([[2.0]]), Matrix([[1.0*tau_x - 3.0*x]]))
    """

    def __init__(self, library, coef, held=None):
        coef = np.asarray(coef, dtype=float)
        self.coords = library.coords
        self._n = self.coords.n
        held = np.zeros(self._n, dtype=bool) if held is None else np.asarray(held, dtype=bool)
        if held.shape != (self._n,):
            raise ValueError(f"held: expected {self._n} flags, got shape {held.shape}")
        self._held = held
        self.rigid_parts, rigid_features = _rigid_body_parts(library, coef)
        self._terms = _catalog_terms(library, coef, held, ~rigid_features)
        if self.rigid_parts:  # their monomials are written out only for the symbolic forms
            self._symbolic_source = (library, coef)
        self._compile()

    def _rigid_body(self, z):
        """``M`` and ``f`` of :attr:`rigid_parts` at the rows of ``z``, zero for held coordinates.
        """
        n = self._n
        q, qd = z[:, :n], z[:, n:2 * n]
        mass, bias = 0.0, 0.0
        for tree, pi in self.rigid_parts:
            part_mass, part_bias = rigid_body_dynamics(tree, pi, q, qd)
            mass, bias = mass + part_mass, bias + part_bias
        moving = ~self._held
        return mass * moving[:, None], -bias * moving

    def mass_and_forcing(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        mass, force = super().mass_and_forcing(z)
        if self.rigid_parts:
            rigid_mass, rigid_force = self._rigid_body(np.asarray(z, dtype=float))
            mass, force = mass + rigid_mass, force + rigid_force
        return mass, force

    mass_and_forcing.__doc__ = MassMatrixDynamics.mass_and_forcing.__doc__

    def _evaluate_scalar(self, *values):
        entries = super()._evaluate_scalar(*values)
        if not self.rigid_parts:
            return entries
        mass, force = self._rigid_body(np.array([values], dtype=float))
        return (np.asarray(entries, dtype=float)
                + np.concatenate([mass.reshape(-1), force.reshape(-1)])).tolist()

    @property
    def terms(self) -> Terms:
        """``M`` and ``f`` as polynomials, rigid-body parts written out (built on first use)."""
        if not self.rigid_parts:
            return self._terms
        full = self.__dict__.get("_full_terms")
        if full is None:
            library, coef = self._symbolic_source
            full = self._full_terms = _catalog_terms(library, coef, self._held)
        return full

    @property
    def mass_matrix_expr(self) -> sp.Matrix:
        """``M(q, qd)``, shape (n, n), from the monomials."""
        n = self._n
        return sp.Matrix(n, n, self._symbolic_entries()[: n * n])

    @property
    def forcing_expr(self) -> sp.Matrix:
        """``f(q, qd, tau, t)``, shape (n, 1), from the monomials."""
        return sp.Matrix(self._symbolic_entries()[self._n * self._n:])

    @property
    def equations(self) -> list:
        """``M qdd - f``, one expression per coordinate."""
        return list(self.mass_matrix_expr * sp.Matrix(self.coords.qdd) - self.forcing_expr)

    def _symbolic_entries(self) -> list:
        terms = self.terms
        atoms = terms.atoms
        return [sp.Add(*(sp.Float(coef) * sp.Mul(*(atoms[i] ** p for i, p in key))
                         for coef, key in entry)) for entry in terms.entries]


def _rigid_body_parts(library, coef) -> tuple[list, np.ndarray]:
    """``(tree, pi)`` of the Lagrange libraries of ``library`` that carry a kinematic tree, and the
    mask of their features (evaluated by the rigid-body kernel instead of their monomials)."""
    parts = getattr(library, "libraries_", [library])
    slices = getattr(library, "slices_", [slice(0, len(coef))])
    mask = np.zeros(len(coef), dtype=bool)
    rigid = []
    for part, columns in zip(parts, slices, strict=True):
        pi = part.rigid_body_parameters(coef[columns]) if hasattr(
            part, "rigid_body_parameters") else None
        if pi is not None:
            rigid.append((part.tree, pi))
            mask[columns] = True
    return rigid, mask


def _catalog_terms(library, coef, held, features=None) -> Terms:
    """:class:`Terms` of ``M`` and ``f`` from the entries with a non-zero coefficient (of the
    ``features`` mask when given), held coordinates' rows excepted."""
    index = library.entry_index_
    keep = (coef[index[:, 1]] != 0) & ~held[index[:, 0]]
    if features is not None:
        keep &= features[index[:, 1]]
    active = np.flatnonzero(keep)
    terms = library.column_terms()
    if _acceleration_in_a_factor(terms, library.coords):  # expanded, then split
        terms = decompose([sp.expand(library.symbolic_matrix_[c, j])
                           for c, j in index[active]])
    else:
        terms = terms.take(active)
    return _mass_and_forcing_terms(library.coords, terms, index[active, 0],
                                   coef[index[active, 1]], held)


def _acceleration_in_a_factor(terms: Terms, coords) -> bool:
    """Whether an atom other than an acceleration contains one (``(qdd + q)``: not splittable)."""
    accelerations = set(coords.qdd)
    return any(atom.free_symbols & accelerations for atom in terms.atoms
               if atom not in accelerations)


def _mass_and_forcing_terms(coords, terms: Terms, rows, weights, held=None) -> Terms:
    """:class:`Terms` of ``M`` (n * n, row-major) and ``f`` (n) of ``sum_k weights[k] entry_k = 0``
    (``entry_k`` in the equation of ``rows[k]``); ``held`` coordinates get ``qdd_c = 0``."""
    n = coords.n
    if _acceleration_in_a_factor(terms, coords):
        raise ValueError("equations: not linear in the accelerations")
    which = {index: k for index, atom in enumerate(terms.atoms)
             for k, symbol in enumerate(coords.qdd) if atom == symbol}
    sums = [{} for _ in range(n * n + n)]
    for entry, row, weight in zip(terms.entries, rows, weights, strict=True):
        for coef, key in entry:
            found = [(position, power) for position, (index, power) in enumerate(key)
                     if index in which]
            if not found:
                target, monomial, value = n * n + row, key, -weight * coef
            elif len(found) == 1 and found[0][1] == 1:
                position = found[0][0]
                target = row * n + which[key[position][0]]
                monomial, value = key[:position] + key[position + 1:], weight * coef
            else:
                raise ValueError("equations: not linear in the accelerations")
            sums[target][monomial] = sums[target].get(monomial, 0.0) + value
    for c in np.flatnonzero(held) if held is not None else ():
        sums[c * n + c] = {(): 1.0}
    return Terms(terms.atoms, [[(float(coef), key) for key, coef in entry.items() if coef != 0]
                               for entry in sums])
