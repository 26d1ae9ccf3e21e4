r"""What makes a catalog's coefficients physical: the rigid bodies behind its base parameters.

A kinematic catalog's Lagrange coefficients are *base parameters* :math:`\beta = C \pi` of the
bodies' inertial parameters :math:`\pi`; its friction columns carry friction. They are *physically
consistent* when some :math:`\pi` with :math:`C \pi = \beta` has every pseudo-inertia positive
semidefinite and every armature and friction non-negative (:mod:`pysindy_xl.physical.sdp`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .friction import dry_friction_law

__all__ = ["INERTIAL_PARAMETERS", "PhysicalStructure", "catalog_structure", "friction_kind",
           "has_parameter_map", "pseudo_inertia_matrix"]

#: The inertial parameters of one body, in this order: mass, first moments ``m c``, inertia
#: about the body frame's origin (diagonal, then products).
INERTIAL_PARAMETERS = ("m", "mcx", "mcy", "mcz", "Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
#: Joint models whose coefficient is a dissipation (non-negative in a consistent model).
DISSIPATIVE = ("viscous", "coulomb")


@dataclasses.dataclass(frozen=True, eq=False)
class PhysicalStructure:
    """The physical meaning of a problem's columns (see the module docstring).

    Attributes
    ----------
    names : tuple of str
        Physical parameters ``pi``: ``"<body>.<p>"`` for ``p`` in :data:`INERTIAL_PARAMETERS`,
        ``"<joint>.armature"``, and any other name a map uses (unconstrained).
    base_columns : ndarray of int, shape (k,)
        Columns whose coefficients are base parameters.
    combination : ndarray, shape (k, len(names))
        ``coef[base_columns] = combination @ pi``.
    bodies : tuple of str
    body_indices : ndarray of int, shape (len(bodies), 10)
        Indices into ``names`` of each body's parameters.
    armature : ndarray of int
        Indices into ``names`` of the armatures.
    friction_columns : ndarray of int
        Columns of viscous or dry friction (non-negative).
    selectable_columns : ndarray of int
        Joint friction and sensor model columns a fit may leave out
        (``ExplicitOptimizer(select="friction")``).

    Examples
    --------
    >>> s = PhysicalStructure.from_maps([{"link.m": 1.0, "j.armature": 1.0}, {"link.Iyy": 1.0}],
    ...                                 base_columns=[1, 2], friction_columns=[3])
    >>> s.bodies, len(s.names), s.combination.shape
    (('link',), 11, (2, 11))
    >>> s.select(np.array([0, 2, 3])).base_columns.tolist()
    [1]
    """

    names: tuple
    base_columns: np.ndarray
    combination: np.ndarray
    bodies: tuple
    body_indices: np.ndarray
    armature: np.ndarray
    friction_columns: np.ndarray
    selectable_columns: np.ndarray = dataclasses.field(
        default_factory=lambda: np.zeros(0, dtype=int))

    @classmethod
    def from_maps(cls, maps, base_columns, friction_columns=(),
                  selectable_columns=()) -> PhysicalStructure:
        """The structure of base parameters given as ``{physical name: weight}`` maps (a kinematic
        catalog's ``parameters``) in ``base_columns``; the other arguments are the fields.
        """
        used = list(dict.fromkeys(name for m in maps for name in m))
        bodies = list(dict.fromkeys(name.rsplit(".", 1)[0] for name in used
                                    if name.rsplit(".", 1)[-1] in INERTIAL_PARAMETERS))
        names = [f"{body}.{p}" for body in bodies for p in INERTIAL_PARAMETERS]
        names += [name for name in used if name not in names]
        index = {name: k for k, name in enumerate(names)}
        combination = np.zeros((len(maps), len(names)))
        for j, m in enumerate(maps):
            for name, weight in m.items():
                combination[j, index[name]] = float(weight)
        return cls(tuple(names), np.asarray(base_columns, dtype=int).reshape(-1), combination,
                   tuple(bodies),
                   np.arange(10 * len(bodies), dtype=int).reshape(len(bodies), 10),
                   np.array([k for k, name in enumerate(names)
                             if name.endswith(".armature")], dtype=int),
                   np.asarray(friction_columns, dtype=int).reshape(-1),
                   np.asarray(selectable_columns, dtype=int).reshape(-1))

    @classmethod
    def from_combination(cls, names, combination) -> PhysicalStructure:
        """The structure of ``beta = combination @ pi`` over ``names`` (base parameter ``j`` in
        column ``j``, no friction).
        """
        combination = np.asarray(combination, dtype=float)
        maps = [{names[p]: combination[j, p] for p in np.flatnonzero(combination[j])}
                for j in range(combination.shape[0])]
        structure = cls.from_maps(maps, np.arange(len(maps)))
        # keep the caller's order of the physical parameters
        order = [structure.names.index(name) if name in structure.names else -1 for name in names]
        if sorted(order) != list(range(len(structure.names))):
            missing = set(structure.names) - set(names)
            raise ValueError(f"names: every body's ten parameters are needed, missing "
                             f"{sorted(missing)}")
        where = {name: k for k, name in enumerate(names)}
        return dataclasses.replace(
            structure, names=tuple(names), combination=combination,
            body_indices=np.array([[where[f"{b}.{p}"] for p in INERTIAL_PARAMETERS]
                                   for b in structure.bodies], dtype=int).reshape(-1, 10),
            armature=np.array([where[n] for n in names if n.endswith(".armature")], dtype=int))

    @property
    def constrains(self) -> bool:
        """Whether there is a body, an armature or a friction to constrain."""
        return bool(len(self.bodies) or len(self.armature) or len(self.friction_columns))

    def select(self, columns) -> PhysicalStructure:
        """The structure in the indices of a problem made of ``columns``; base parameters left out
        leave ``combination`` too (the data do not decide them).
        """
        columns = np.asarray(columns, dtype=int)
        position = {int(c): k for k, c in enumerate(columns)}
        rows = [j for j, c in enumerate(self.base_columns) if int(c) in position]
        return dataclasses.replace(
            self, base_columns=np.array([position[int(self.base_columns[j])] for j in rows],
                                        dtype=int),
            combination=self.combination[rows],
            friction_columns=np.array([position[int(c)] for c in self.friction_columns
                                       if int(c) in position], dtype=int),
            selectable_columns=np.array([position[int(c)] for c in self.selectable_columns
                                         if int(c) in position], dtype=int))

    def nearest_consistent(self, pi) -> np.ndarray:
        """``pi`` with every pseudo-inertia projected onto the PSD cone and negative armatures
        zeroed: a solver's answer made exactly consistent.

        >>> s = PhysicalStructure.from_maps([{"b.m": 1.0}], base_columns=[0])
        >>> s.nearest_consistent([-1e-9, 0, 0, 0, 1, 1, 1, 0, 0, 0])[0]
        np.float64(0.0)
        """
        pi = np.array(pi, dtype=float)
        for indices in self.body_indices:
            values, vectors = np.linalg.eigh(pseudo_inertia_matrix(pi[indices]))
            pseudo = (vectors * np.clip(values, 0.0, None)) @ vectors.T
            sigma = pseudo[:3, :3]
            inertia = np.trace(sigma) * np.eye(3) - sigma
            pi[indices] = [pseudo[3, 3], *pseudo[:3, 3], inertia[0, 0], inertia[1, 1],
                           inertia[2, 2], inertia[0, 1], inertia[0, 2], inertia[1, 2]]
        pi[self.armature] = np.clip(pi[self.armature], 0.0, None)
        return pi

    def pseudo_inertias(self, pi) -> np.ndarray:
        """Every body's pseudo-inertia at ``pi``, shape (len(bodies), 4, 4)."""
        pi = np.asarray(pi, dtype=float)
        return np.array([pseudo_inertia_matrix(pi[k]) for k in self.body_indices]).reshape(-1, 4, 4)


def pseudo_inertia_matrix(parameters):
    r"""The pseudo-inertia of one body from its ten parameters (Wensing, Kim and Slotine, 2017).

    .. math:: J = \begin{pmatrix} \tfrac12 \operatorname{tr}(I) \mathbb 1 - I & h \\
              h^T & m \end{pmatrix}

    Parameters
    ----------
    parameters : sequence of 10
        :data:`INERTIAL_PARAMETERS` values (inertia about the frame origin), numbers or cvxpy
        expressions.

    Returns
    -------
    ndarray or cvxpy Expression, shape (4, 4)
        Positive semidefinite exactly when a mass distribution has these parameters.

    Examples
    --------
    A point mass of 2 at (0, 0, 1):

    >>> pseudo_inertia_matrix([2, 0, 0, 2, 2, 2, 0, 0, 0, 0]).tolist()
    [[0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 2.0, 2.0], [0.0, 0.0, 2.0, 2.0]]
    """
    m, hx, hy, hz, ixx, iyy, izz, ixy, ixz, iyz = parameters
    trace = (ixx + iyy + izz) / 2
    rows = [[trace - ixx, -ixy, -ixz, hx], [-ixy, trace - iyy, -iyz, hy],
            [-ixz, -iyz, trace - izz, hz], [hx, hy, hz, m]]
    if any(hasattr(v, "is_dcp") for v in parameters):
        import cvxpy as cp

        return cp.bmat(rows)
    return np.array(rows, dtype=float)


def friction_kind(term, velocity, acceleration=None) -> str | None:
    """``"viscous"`` for ``qd_c``, ``"dry"`` for a unit dry friction law of ``qd_c``
    (:func:`~pysindy_xl.physical.friction.dry_friction_law`), None otherwise.
    """
    if term == velocity:
        return "viscous"
    return "dry" if dry_friction_law(term, velocity, acceleration) else None


def has_parameter_map(library) -> bool:
    """Whether some library says which physical parameters its terms stand for.

    Parameters
    ----------
    library : pysindy_xl.CatalogRepartition
        The fitted catalog.

    Returns
    -------
    bool
        True when a library of the catalog has ``parameters``.
    """
    return any(getattr(lib, "parameters", None) is not None for lib in library.libraries_)


def catalog_structure(library) -> PhysicalStructure | None:
    """The physical structure of a fitted catalog's columns (base parameters from its Lagrange
    libraries' ``parameters`` maps, friction from its classical columns), or None.
    """
    maps, columns = [], []
    for lib, block in zip(library.libraries_, library.slices_, strict=True):
        parameters = getattr(lib, "parameters", None)
        if lib.category != "lagrange" or parameters is None:
            continue
        maps += [dict(p) for p in parameters]
        columns += list(range(block.start, block.start + lib.n_output_features_))
    if not maps:
        return None
    return PhysicalStructure.from_maps(maps, columns, friction_columns(library),
                                       joint_model_columns(library))


def joint_model_columns(library, models=None) -> list:
    """Columns of a fitted catalog's joint friction and sensor models, of ``models`` only if given.
    """
    out = []
    for lib, block in zip(library.libraries_, library.slices_, strict=True):
        for k, (model, _) in enumerate(getattr(lib, "kinds_", None) or ()):
            if models is None or model in models:
                out.append(block.start + k)
    return out


def friction_columns(library) -> list:
    """Columns of a fitted catalog that are viscous or dry friction, of a coordinate or a joint."""
    joint_models = joint_model_columns(library)
    out = joint_model_columns(library, DISSIPATIVE)
    coords = library.coords
    for j, category in enumerate(library.categories_):
        if category != "classical" or j in joint_models:
            continue
        entering = np.flatnonzero(library.entry_sizes()[:, j] > 0).tolist()
        if len(entering) == 1 and friction_kind(library.feature_terms_[j],
                                                coords.qd[entering[0]], coords.qdd[entering[0]]):
            out.append(j)
    return sorted(out)
