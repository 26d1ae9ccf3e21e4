"""Catalogs from the kinematic tree: candidate Lagrangians of any rigid-body MJCF model.

A rigid body's Lagrangian is linear in its ten inertial parameters (mass ``m``, first moments
``m c``, inertia ``I_o`` about the body origin): with ``v``, ``w`` the origin's linear and
angular velocity in body coordinates, ``g_b = R^T g`` and ``h = g.p_o``,
``L_b = m (v.v / 2 + h) + m c . (v x w + g_b) + w . I_o w / 2``. With each joint's armature
these functions span every mass distribution; :func:`kinematic_catalog` keeps an independent
subset (base parameters, by a pivoted QR at random states), derived on sparse trigonometric
polynomials (:mod:`pysindy_xl.feature_library.trigpoly`). Friction and springs are classical
candidates per joint, or the joint models of ``friction=``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import time

import numpy as np

from ..._optional import import_mujoco
from ...feature_library import PolynomialLagrangeLibrary
from ...feature_library.trigpoly import evaluate_many, state_values
from ...feature_library.trigterms import TrigTerms
from ...physical.rigid_body import KinematicTree
from ...symbols import Coordinates
from ..systems.registry import MuJoCoSystem, get_system
from . import _derivation_cache
from ._kinematic_build import (
    COULOMB_LAWS,
    classical_candidates,
    derive_lagrangian,
    friction_models,
    with_joint_models,
)
from ._kinematic_tree import INERTIAL_PARAMETERS, kinematic_tree, physical_values

__all__ = ["KinematicCatalog", "PolynomialLagrangeLibrary", "kinematic_catalog",
           "INERTIAL_PARAMETERS"]

_CACHE: dict = {}
_CACHE_SIZE = 16


# -- the catalog ---------------------------------------------------------------------------
@dataclasses.dataclass
class KinematicCatalog:
    """Candidate terms of a rigid-body mechanism, derived from its kinematic tree.

    Built by :func:`kinematic_catalog` (the fields below are its results, stored as given);
    :meth:`library` is its feature library.

    Parameters
    ----------
    system : MuJoCoSystem
        The system the catalog describes.
    coords : pysindy_xl.Coordinates
        Its generalized coordinates.
    lagrange_terms : list of sympy.Expr
        Minimal independent candidate Lagrangian terms (one per base parameter).
    parameters : list of dict
        Per term, the combination ``{physical name: weight}`` its coefficient stands for.
    physical_names, physical_values : list of str, ndarray
        ``"<body>.<p>"`` for ``p`` in :data:`INERTIAL_PARAMETERS` (about the body frame
        origin, in the body frame) and ``"<joint>.armature"``; the MJCF model's values.
    combination : ndarray, shape (len(lagrange_terms), len(physical_names))
        ``base = combination @ physical``.
    classical_terms, classical_mask, classical_kinds, classical_values
        Newtonian candidates (viscous, smooth Coulomb, spring) per joint, the equations each
        enters (bool, (n_terms, n)), their ``(kind, joint)`` and MJCF values.
    n_candidates : int
        Lagrangian functions before the reduction.
    build_seconds : float, default=0.0
        Time the derivation took (s).
    tree : KinematicTree or None, default=None
        The numeric kinematic tree (:mod:`pysindy_xl.physical.rigid_body`).
    friction_models : tuple of str, default=()
        The joint models of ``friction=`` (empty: friction as ``classical_terms``).
    friction_scales : tuple of float, default=(0.01, 0.1)
        ``(coulomb_scale, stribeck_scale)``.
    joint_velocities : list of sympy.Expr, default=[]
        Each joint's velocity in the coordinates.

    Other Parameters
    ----------------
    _polynomials : list, default=[]
        Internal: the terms as polynomials, filled by :func:`kinematic_catalog`.
    _compiled : dict, default={}
        Internal: compiled numerical functions, filled on first use.

    Examples
    --------
    >>> catalog = kinematic_catalog("cart-pole")
    >>> catalog.lagrange_terms
    [0.5*x_dot**2, -theta_dot*x_dot*sin(theta) - 9.81*sin(theta),
     -theta_dot*x_dot*cos(theta) - 9.81*cos(theta), 0.5*theta_dot**2]
    >>> catalog.parameters[0]
    {'cart.m': 1.0, 'pole.m': 1.0, 'slider.armature': 1.0}
    """

    system: MuJoCoSystem
    coords: Coordinates
    lagrange_terms: list
    parameters: list
    physical_names: list
    combination: np.ndarray
    physical_values: np.ndarray
    classical_terms: list
    classical_mask: np.ndarray
    classical_kinds: list
    classical_values: np.ndarray
    n_candidates: int
    build_seconds: float = 0.0
    tree: KinematicTree | None = None
    friction_models: tuple = ()
    friction_scales: tuple = (0.01, 0.1)
    joint_velocities: list = dataclasses.field(default_factory=list)
    _polynomials: list = dataclasses.field(default_factory=list, repr=False, compare=False)
    _compiled: dict = dataclasses.field(default_factory=dict, repr=False, compare=False)

    @property
    def base_parameters(self) -> np.ndarray:
        """Base parameters of the MJCF model: the true coefficients of :attr:`lagrange_terms`.

        >>> kinematic_catalog("cart-pole").base_parameters.round(4)
        array([ 1.5 ,  0.  , -0.4 ,  0.32])
        """
        return self.combination @ self.physical_values

    def library(self, interlink=None, classical: bool = True):
        """The catalog as a feature library: forces, Lagrange terms, classical terms.

        ``interlink`` goes to :class:`~pysindy_xl.ExternalForces` (``system.force_matrix()``
        to fit with MuJoCo joint forces); ``classical=False`` leaves out friction and springs.

        Parameters
        ----------
        interlink : array_like of shape (n, n), default=None
            Passed to :class:`~pysindy_xl.ExternalForces`: ``system.force_matrix()`` to fit with
            MuJoCo joint forces; None: force ``i`` acts on coordinate ``i``.
        classical : bool, default=True
            Include the Newtonian candidates (friction, springs).

        Returns
        -------
        pysindy_xl.CatalogRepartition
            The library (not yet fitted).

        Examples
        --------
        >>> lib = kinematic_catalog("cart-pole").library().fit()
        >>> lib.get_feature_names()[:2]
        ['F[tau]', 'L[0.5*x_dot**2]']
        >>> lib.get_feature_names()[-2:]
        ['C_theta[theta_dot]', 'C_theta[tanh(100.0*theta_dot)]']
        """
        from ...feature_library import (
            CatalogRepartition,
            ClassicalLibrary,
            ExternalForces,
            JointFrictionLibrary,
        )
        libraries = [ExternalForces(self.coords, interlink=interlink),
                     PolynomialLagrangeLibrary(self.coords, _shared(self.lagrange_terms),
                                               parameters=[dict(p) for p in self.parameters],
                                               tree=self.tree)]
        if classical and self.classical_terms:
            libraries.append(ClassicalLibrary(self.coords, list(self.classical_terms),
                                              mask=self.classical_mask.copy()))
        if classical and self.friction_models:
            libraries.append(JointFrictionLibrary(
                self.coords, list(self.system.joint_names), list(self.joint_velocities),
                self.system.force_matrix(), self.friction_models, *self.friction_scales))
        return CatalogRepartition(libraries)

    def true_coefficients(self, forces: float = -1.0) -> np.ndarray:
        """Coefficient vector of the MJCF model in :meth:`library` (with classical terms).

        Viscous and spring terms get the MJCF damping and stiffness; smooth Coulomb terms
        MuJoCo's ``frictionloss`` (approximate: MuJoCo's dry friction is a constraint); joint
        models MJCF lacks (asymmetric, Stribeck, offset) zero. ``forces`` is the coefficient
        of the force column.

        Parameters
        ----------
        forces : float, default=-1.0
            Coefficient of the force column.

        Returns
        -------
        numpy.ndarray of shape (n_features,)
            One coefficient per feature of :meth:`library`.

        Examples
        --------
        >>> kinematic_catalog("cart-pole").true_coefficients().round(4)
        array([-1.  ,  1.5 ,  0.  , -0.4 ,  0.32,  0.5 ,  0.  ,  0.1 ,  0.  ])
        """
        model = self.system.mj_model()
        mjcf = {"viscous": model.dof_damping, "coulomb": model.dof_frictionloss}
        joint_models = [float(mjcf[kind][model.jnt_dofadr[k]]) if kind in mjcf else 0.0
                        for k in range(model.njnt) for kind in self.friction_models]
        return np.concatenate([[forces], self.base_parameters, self.classical_values,
                               joint_models])

    def lagrange_coefficients(self, model) -> np.ndarray:
        """Coefficients of :attr:`lagrange_terms` in a model fitted with :meth:`library`.

        Features are matched by name and scaled so that the force coefficient is -1.

        Parameters
        ----------
        model : pysindy_xl.XLSINDy
            A model fitted with this catalog's :meth:`library`.

        Returns
        -------
        numpy.ndarray of shape (len(lagrange_terms),)
            The identified base parameters, in the scale where the force coefficient is -1.

        Raises
        ------
        ValueError
            If the model lacks a Lagrange term of this catalog or a non-zero force coefficient.
        """
        names = list(model.get_feature_names())
        coefficients = np.asarray(model.coefficients(), dtype=float)
        force = [coefficients[k] for k, name in enumerate(names) if name.startswith("F[")]
        if not force or force[0] == 0:
            raise ValueError("model: no non-zero force coefficient to scale the model by")
        scale = -1.0 / force[0]
        out = np.zeros(len(self.lagrange_terms))
        index = {name: k for k, name in enumerate(names)}
        terms = self.lagrange_terms
        texts = terms.names() if isinstance(terms, TrigTerms) else [str(t) for t in terms]
        for j, text in enumerate(texts):
            name = f"L[{text}]"
            if name not in index:
                raise ValueError(f"model: its catalog has no feature {name!r}")
            out[j] = coefficients[index[name]] * scale
        return out

    # -- physical quantities -------------------------------------------------------------
    def _quantity(self, key) -> list:
        """Per term, the polynomials of ``key``: mass-matrix entries or bias forces."""
        if key not in self._compiled:
            n, terms = self.coords.n, self._polynomials
            if key == "mass":
                rows = [[p.diff_velocity(i).diff_velocity(k) for i in range(n) for k in range(n)]
                        for p in terms]
            else:  # the equations (derived with the terms) with qdd = 0 (and qd = 0: gravity)
                rows = [[e.at_rest(velocities=key == "gravity") for e in column]
                        for column in self.lagrange_terms.columns]
            self._compiled[key] = rows
        return self._compiled[key]

    def _evaluate(self, key, q, qd, coefficients, shape=()):
        """``key``'s quantity at the states, shaped ``shape`` per sample; one state: no axis."""
        single, c = np.ndim(q) == 1, self.coords
        q = _states(q, "q", c.n)
        qd = np.zeros_like(q) if qd is None else _states(qd, "qd", c.n)
        if qd.shape != q.shape:
            raise ValueError(f"qd: expected shape {q.shape}, got {qd.shape}")
        beta = self.base_parameters if coefficients is None else np.asarray(coefficients, float)
        if beta.shape != (len(self.lagrange_terms),):
            raise ValueError(f"coefficients: expected shape ({len(self.lagrange_terms)},), "
                             f"got {beta.shape}")
        rows = self._quantity(key)
        angles = [j in self.system.angle_coordinates for j in range(c.n)]
        values = evaluate_many([p for row in rows for p in row], state_values(q, qd, None, angles))
        values = values.reshape(q.shape[0], len(rows), -1)
        out = np.einsum("sfr,f->sr", values, beta).reshape(-1, *shape)
        return out[0] if single else out

    def mass_matrix(self, q, coefficients=None) -> np.ndarray:
        """Mass matrix ``M(q)`` in the system's coordinates, shape (N, n, n) or (n, n).

        Parameters
        ----------
        q : array_like of shape (N, n) or (n,)
            Generalized positions.
        coefficients : array_like of shape (len(lagrange_terms),), default=None
            Lagrange coefficients (e.g. :meth:`lagrange_coefficients`); None:
            :attr:`base_parameters` of the MJCF model.

        Returns
        -------
        numpy.ndarray of shape (N, n, n) or (n, n)
            The symmetric mass matrix at each configuration.

        Examples
        --------
        >>> kinematic_catalog("cart-pole").mass_matrix([0.0, 0.0]).round(4)
        array([[1.5 , 0.4 ],
               [0.4 , 0.32]])
        """
        return self._evaluate("mass", q, None, coefficients, (self.coords.n,) * 2)

    def gravity_torque(self, q, coefficients=None) -> np.ndarray:
        """Generalized gravity force ``dV/dq``, shape of ``q`` (``M qdd + c + dV/dq = tau``).

        ``coefficients`` as in :meth:`mass_matrix`.

        Parameters
        ----------
        q : array_like of shape (N, n) or (n,)
            Generalized positions.
        coefficients : array_like of shape (len(lagrange_terms),), default=None
            Lagrange coefficients (e.g. :meth:`lagrange_coefficients`); None:
            :attr:`base_parameters` of the MJCF model.

        Returns
        -------
        numpy.ndarray of shape (N, n) or (n,)
            ``dV/dq`` at each configuration.

        Examples
        --------
        >>> kinematic_catalog("cart-pole").gravity_torque([0.0, np.pi / 2]).round(4)
        array([0.   , 3.924])
        """
        return self._evaluate("gravity", q, None, coefficients, (self.coords.n,))

    def bias_forces(self, q, qd, coefficients=None) -> np.ndarray:
        """Coriolis, centrifugal and gravity forces, shape of ``q``: the equations at ``qdd = 0``.

        ``coefficients`` as in :meth:`mass_matrix`.

        Parameters
        ----------
        q : array_like of shape (N, n) or (n,)
            Generalized positions.
        qd : array_like, same shape as q
            Generalized velocities.
        coefficients : array_like of shape (len(lagrange_terms),), default=None
            Lagrange coefficients (e.g. :meth:`lagrange_coefficients`); None:
            :attr:`base_parameters` of the MJCF model.

        Returns
        -------
        numpy.ndarray, same shape as q
            ``c(q, qd) + dV/dq``.

        Examples
        --------
        >>> kinematic_catalog("cart-pole").bias_forces([0.0, 0.0], [0.0, 2.0]).round(4)
        array([0., 0.])
        """
        return self._evaluate("bias", q, qd, coefficients, (self.coords.n,))

    def report(self, coefficients=None, digits: int = 4, terms: bool = True) -> str:
        """Table of the base parameters: term, combination, MJCF value, identified value.

        ``coefficients`` are identified Lagrange coefficients (:meth:`lagrange_coefficients`);
        ``terms=False`` leaves out the column of terms (long for spatial arms).

        Parameters
        ----------
        coefficients : array_like of shape (len(lagrange_terms),), default=None
            Lagrange coefficients (e.g. :meth:`lagrange_coefficients`); None: the column of
            identified values is left out.
        digits : int, default=4
            Significant digits of the values.
        terms : bool, default=True
            Include the column of terms.

        Returns
        -------
        str
            The table, one line per base parameter.

        Examples
        --------
        >>> print(kinematic_catalog("cart-pole").report(terms=False))
        stands for  |  MJCF
        1*cart.m + 1*pole.m + 1*slider.armature  |  1.5
        1*pole.mcx  |  0
        1*pole.mcz  |  -0.4
        1*pole.Iyy + 1*hinge.armature  |  0.32
        """
        truth = self.base_parameters
        header = ["term"] if terms else []
        header += ["stands for", "MJCF"] + (["identified"] if coefficients is not None else [])
        lines = ["  |  ".join(header)]
        for j, term in enumerate(self.lagrange_terms):
            combination = " + ".join(f"{w:.{digits}g}*{name}"
                                     for name, w in self.parameters[j].items())
            cells = [str(term)] if terms else []
            cells += [combination, f"{truth[j]:.{digits}g}"]
            if coefficients is not None:
                cells.append(f"{float(coefficients[j]):.{digits}g}")
            lines.append("  |  ".join(cells))
        return "\n".join(lines)


def _shared(terms):
    """The catalog's terms for a library: a :class:`TrigTerms` as is (immutable), else a copy."""
    return terms if isinstance(terms, TrigTerms) else list(terms)


def _states(a, name: str, n: int) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != n:
        raise ValueError(f"{name}: expected shape (N, {n}) or ({n},), got {np.shape(a)}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or inf")
    return a


# -- derivation ----------------------------------------------------------------------------
def kinematic_catalog(system, coulomb: bool = True, coulomb_scale: float = 0.01,
                      seed: int = 0, friction=None, stribeck_scale: float = 0.1,
                      coulomb_law: str = "smooth") -> KinematicCatalog:
    """Candidate Lagrangian and Newtonian terms derived from the kinematic tree of a model.

    Every moving body contributes the ten functions multiplying its inertial parameters,
    every joint its armature ``qvel^2 / 2``, reduced to independent Euler-Lagrange columns
    (base parameters). Cached in memory by model text, coordinates and options, and on disk
    by kinematic content (``PYSINDY_XL_CACHE=off`` turns that off).

    Parameters
    ----------
    system : MuJoCoSystem, str or os.PathLike
        A system (coordinates ``q = T @ qpos``), a registry name, an MJCF path or MJCF text
        (MuJoCo's joint coordinates). Hinge and slide joints only.
    coulomb : bool, default=True
        Add a smooth Coulomb candidate ``tanh(qvel / coulomb_scale)`` per joint.
    coulomb_scale : float, default=0.01
        Velocity scale of the smooth Coulomb candidate.
    seed : int, default=0
        Seed of the random states of the numerical reduction.
    friction : sequence of str or "all", default=None
        Models of real joints offered for every joint (``"viscous"``, ``"coulomb"``,
        ``"asymmetric"``, ``"stribeck"``, ``"offset"``;
        :class:`~pysindy_xl.feature_library.JointFrictionLibrary`), replacing the viscous and
        Coulomb candidates; None: viscous (and, with ``coulomb``, smooth Coulomb) candidates.
    stribeck_scale : float, default=0.1
        The Stribeck model's velocity scale ``v_s`` (with ``friction``).
    coulomb_law : {"smooth", "mujoco"}, default="smooth"
        ``"mujoco"``: MuJoCo's regularized ``frictionloss``
        (:func:`~pysindy_xl.physical.friction.regularized_dry_friction`), for data MuJoCo
        simulated from this model. Not with ``friction``.

    Returns
    -------
    KinematicCatalog
        The catalog; :meth:`KinematicCatalog.library` is its feature library.

    Raises
    ------
    ValueError
        When the model has a joint other than hinge or slide, or an option is invalid.

    Examples
    --------
    A pendulum whose centre of mass is off its link axis and whose inertia is full:

    >>> xml = '''<mujoco><option gravity="0 0 -9.81"/><worldbody><body>
    ...   <joint name="a" type="hinge" axis="0 1 0"/>
    ...   <inertial pos="0.1 0.02 -0.5" mass="2" fullinertia="0.3 0.2 0.15 0.01 0.02 0.03"/>
    ... </body></worldbody></mujoco>'''
    >>> catalog = kinematic_catalog(xml)
    >>> catalog.lagrange_terms
    [9.81*sin(a), -9.81*cos(a), 0.5*a_dot**2]
    >>> catalog.parameters
    [{'body1.mcx': 1.0}, {'body1.mcz': 1.0}, {'body1.Iyy': 1.0, 'a.armature': 1.0}]
    >>> catalog.base_parameters.round(4)  # m c_x, m c_z, Iyy about the hinge axis
    array([ 0.2  , -1.   ,  0.72])
    """
    system = get_system(system)
    for name, value in (("coulomb_scale", coulomb_scale), ("stribeck_scale", stribeck_scale)):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
                np.isfinite(value) and value > 0):
            raise ValueError(f"{name}: expected a positive number, got {value!r}")
    if coulomb_law not in COULOMB_LAWS:
        raise ValueError(f"coulomb_law: expected one of {COULOMB_LAWS}, got {coulomb_law!r}")
    friction = friction_models(friction)
    if friction and coulomb_law != "smooth":
        raise ValueError(f"coulomb_law: {coulomb_law!r} is a law of the Coulomb candidate, which "
                         "the joint models of friction= replace (laws of real joints)")
    model = system.mj_model()
    if model.nq != system.n or model.nv != system.n:
        raise ValueError(f"system: MJCF has nq={model.nq}, nv={model.nv}; expected one hinge or "
                         f"slide joint per coordinate ({system.n})")
    mujoco = import_mujoco()
    for k in range(model.njnt):
        if int(model.jnt_type[k]) not in (int(mujoco.mjtJoint.mjJNT_HINGE),
                                          int(mujoco.mjtJoint.mjJNT_SLIDE)):
            raise ValueError(f"system: joint {system.joint_names[k]!r} is not a hinge or slide "
                             "joint; only those are supported")
    key = (hashlib.sha256(system.xml().encode()).hexdigest(), system.coordinate_names,
           system.joint_to_coordinates.tobytes(), bool(coulomb), float(coulomb_scale), seed,
           friction, float(stribeck_scale), coulomb_law)
    if key in _CACHE:
        # same model text and coordinates: same catalog, but bound to the system given (its
        # other settings, e.g. force amplitudes, matter to whoever uses catalog.system)
        return dataclasses.replace(_CACHE[key], system=system)
    start = time.perf_counter()
    catalog = _build(system, model, bool(coulomb), float(coulomb_scale), seed, coulomb_law)
    if friction:
        catalog = with_joint_models(catalog, system, model, friction,
                                     (float(coulomb_scale), float(stribeck_scale)))
    catalog.build_seconds = time.perf_counter() - start
    if len(_CACHE) >= _CACHE_SIZE:
        _CACHE.pop(next(iter(_CACHE)))
    _CACHE[key] = catalog
    return catalog


def _build(system, model, coulomb, coulomb_scale, seed, coulomb_law) -> KinematicCatalog:
    mujoco, coords = import_mujoco(), system.coords
    bodies = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}"
              for b in range(model.nbody)]
    digest = _derivation_cache.key(system, model, bodies, seed)
    derived = _derivation_cache.load(digest, tuple(j in system.angle_coordinates
                                                    for j in range(coords.n)))
    if derived is None:
        derived = derive_lagrangian(system, model, bodies, seed)
        if _derivation_cache.directory() is not None:  # names formatted once, stored with it
            derived["term_names"] = TrigTerms(derived["terms"], coords).names()
        _derivation_cache.save(digest, derived)
    names, combination, kept = derived["names"], derived["combination"], derived["terms"]
    values = [x for b in derived["bodies"] for x in physical_values(model, b)]
    values += [float(model.dof_armature[model.jnt_dofadr[k]]) for k in range(model.njnt)]
    parameters = [{names[p]: float(combination[j, p]) for p in np.flatnonzero(combination[j])}
                  for j in range(len(kept))]
    classical_terms, mask, kinds, classical_values = classical_candidates(
        system, model, coulomb, coulomb_scale, coulomb_law=coulomb_law)
    return KinematicCatalog(
        system=system, coords=coords,
        # sympy expressions built only when read: the library derives from the polynomials
        lagrange_terms=TrigTerms(kept, coords, columns=derived["columns"],
                                 names=derived.get("term_names")),
        parameters=parameters, physical_names=names, combination=combination,
        physical_values=np.array(values), classical_terms=classical_terms,
        classical_mask=mask, classical_kinds=kinds, classical_values=classical_values,
        n_candidates=derived["n_candidates"], tree=kinematic_tree(system, model),
        _polynomials=list(kept),
    )
