"""Catalogs from the kinematic tree: candidate Lagrangians of any rigid-body MJCF model.

The Lagrangian of a rigid body is linear in its ten inertial parameters: mass ``m``, first
moments ``m c`` and rotational inertia ``I_o`` about the body frame origin (all in the body
frame). With ``v`` and ``w`` the linear velocity of the body origin and the angular velocity,
both in body coordinates, ``g_b = R^T g`` the gravity vector in body coordinates and ``h = g.p_o``,

    ``L_b = m (v.v / 2 + h) + m c . (v x w + g_b) + w . I_o w / 2``,

so the functions of ``(q, qd)`` that multiply the parameters come from the kinematics alone
(joint types, axes, anchors, body offsets and orientations), which an MJCF file gives before any
mass. Together with the armature of each joint (``armature_k qvel_k^2 / 2``) they form a catalog
whose span holds the true Lagrangian of *every* mass distribution of the mechanism.

Many of those functions are redundant: their Euler-Lagrange columns are zero (a body fixed to
the world, a total time derivative) or linear combinations of others (robotics calls the
independent combinations *base parameters*). :func:`kinematic_catalog` keeps a minimal set:
it evaluates every Euler-Lagrange column at random states and keeps, in a fixed order of
preference (bodies from the root, mass before first moments before inertia, armature last), each
column that is not in the span of the columns already kept. The dependent parameters fold into
the kept ones: the coefficient of a kept term is the *combination* of physical parameters that
:attr:`KinematicCatalog.parameters` records, so an identified model reports physical parameters.

Friction and springs are not Lagrangian: each joint adds classical candidates (viscous
``qvel_k``, smooth Coulomb ``tanh(qvel_k / eps)``, and ``qpos_k - springref_k`` for joints with
stiffness), entered in the equations that the joint force reaches (``B = T^-T``, see
:mod:`pysindy_xl.mujoco.systems`). Coordinates are those of the system: ``q = T @ qpos``.
"""

from __future__ import annotations

import hashlib
import os
import time
from dataclasses import dataclass, field

import mujoco
import numpy as np
import sympy as sp

from ..symbols import Coordinates
from .systems import MJCFSystem, MuJoCoSystem, get_system

__all__ = ["KinematicCatalog", "kinematic_catalog", "INERTIAL_PARAMETERS"]

#: Names of the ten inertial parameters of a body, in the order of the catalog's preference.
INERTIAL_PARAMETERS = ("m", "mcx", "mcy", "mcz", "Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")

# Coefficients below this magnitude in the kinematic expressions are round-off of quaternion
# and axis arithmetic (lengths and rotation entries are O(1e-6) or larger in any real model).
_CHOP = 1e-13
# A column whose part orthogonal to the kept columns is below this fraction of its norm is
# dependent; exact dependencies leave ~1e-14, independent columns O(1e-3) or more.
_INDEPENDENCE_TOL = 1e-8
_CACHE: dict = {}
_CACHE_SIZE = 16


# -- small symbolic helpers ----------------------------------------------------------------
def _chop(expr: sp.Expr) -> sp.Expr:
    """Expand ``expr`` and drop the round-off terms of float arithmetic."""
    expr = sp.expand(expr)
    if not isinstance(expr, sp.Add):
        coefficient, _ = expr.as_coeff_Mul()
        return sp.Integer(0) if coefficient.is_Number and abs(coefficient) < _CHOP else expr
    kept = []
    for term in expr.args:
        coefficient, _ = term.as_coeff_Mul()
        if not (coefficient.is_Number and abs(coefficient) < _CHOP):
            kept.append(term)
    return sp.Add(*kept)


def _reduce_trigonometry(expr: sp.Expr, angles) -> sp.Expr:
    """Rewrite ``cos(a)**2`` as ``1 - sin(a)**2`` for every angle: one canonical form per term.

    The kinematics produce the same function in many spellings (``sin(b) cos(a)**2 +
    sin(b) sin(a)**2`` is ``sin(b)``); the remainder modulo ``cos^2 + sin^2 - 1`` makes the
    catalog terms short and readable.
    """
    for angle in angles:
        sine, cosine = sp.sin(angle), sp.cos(angle)
        if expr.has(cosine):
            s, c = sp.Dummy("s"), sp.Dummy("c")
            polynomial = expr.xreplace({sine: s, cosine: c})
            reduced = sp.rem(polynomial, c**2 + s**2 - 1, c)
            expr = sp.expand(reduced.xreplace({s: sine, c: cosine}))
    return _chop(expr)


def _numeric(values) -> list[sp.Expr]:
    """Floats as sympy numbers, with round-off zeros made exact zeros."""
    return [sp.Integer(0) if abs(v) < _CHOP else sp.Float(float(v)) for v in values]


def _matvec(matrix, vector):
    return [_chop(sum(matrix[i][k] * vector[k] for k in range(3))) for i in range(3)]


def _matTvec(matrix, vector):
    return [_chop(sum(matrix[k][i] * vector[k] for k in range(3))) for i in range(3)]


def _cross(a, b):
    return [
        _chop(a[1] * b[2] - a[2] * b[1]),
        _chop(a[2] * b[0] - a[0] * b[2]),
        _chop(a[0] * b[1] - a[1] * b[0]),
    ]


def _dot(a, b) -> sp.Expr:
    return _chop(sum(x * y for x, y in zip(a, b, strict=True)))


def _quat_matrix(quat) -> list[list[sp.Expr]]:
    matrix = np.zeros(9)
    mujoco.mju_quat2Mat(matrix, np.asarray(quat, dtype=float))
    rows = _numeric(matrix)
    return [rows[0:3], rows[3:6], rows[6:9]]


def _axis_rotation(axis, s, c) -> list[list[sp.Expr]]:
    """Rotation by the angle of sine ``s`` and cosine ``c`` about the unit ``axis`` (Rodrigues)."""
    a = _numeric(axis)
    skew = [[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]]
    return [
        [_chop(c * int(i == j) + s * skew[i][j] + (1 - c) * a[i] * a[j]) for j in range(3)]
        for i in range(3)
    ]


@dataclass
class _Frame:
    """A body frame during the recursion, everything in the frame's own coordinates.

    ``v``: velocity of the origin, ``w``: angular velocity, ``g``: gravity vector, ``h``:
    gravity times the world position of the origin (``g . p``, so that ``-V = m h``).
    """

    v: list
    w: list
    g: list
    h: sp.Expr


# -- the catalog ---------------------------------------------------------------------------
@dataclass
class KinematicCatalog:
    """Candidate terms of a rigid-body mechanism, derived from its kinematic tree.

    Built by :func:`kinematic_catalog`; use :meth:`library` for the feature library.

    Attributes
    ----------
    system : MuJoCoSystem
        The system whose coordinates the terms use.
    coords : Coordinates
        ``system.coords``.
    lagrange_terms : list of sympy.Expr
        Minimal independent set of candidate Lagrangian terms (one per base parameter).
    parameters : list of dict
        For each Lagrange term, the physical-parameter combination its coefficient stands for,
        ``{physical parameter name: weight}``.
    physical_names : list of str
        All physical parameters: ``"<body>.<p>"`` for ``p`` in :data:`INERTIAL_PARAMETERS`
        (inertia about the body frame origin, in the body frame) and ``"<joint>.armature"``.
    combination : ndarray, shape (len(lagrange_terms), len(physical_names))
        ``base = combination @ physical``: base parameters from physical parameters.
    physical_values : ndarray, shape (len(physical_names),)
        The physical parameters of the MJCF model.
    classical_terms : list of sympy.Expr
        Newtonian candidates (viscous, smooth Coulomb, spring), one per joint and kind.
    classical_mask : ndarray of bool, shape (len(classical_terms), n)
        Equations each classical term enters.
    classical_kinds : list of tuple
        ``(kind, joint name)`` of each classical term, ``kind`` in ``"viscous"``,
        ``"coulomb"``, ``"spring"``.
    n_candidates : int
        Lagrangian functions before the reduction (ten per moving body plus one per joint).
    build_seconds : float
        Time of the symbolic derivation and reduction.

    Examples
    --------
    >>> catalog = kinematic_catalog("cart-pole")
    >>> catalog.lagrange_terms
    [x_dot**2, theta_dot*x_dot*cos(theta), cos(theta), theta_dot**2]
    >>> catalog.parameters[3]
    {'pole.mcy': 0.0, 'pole.Iyy': 0.5, 'hinge.armature': 0.5}
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
    _compiled: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def base_parameters(self) -> np.ndarray:
        """Base parameters of the MJCF model: the true coefficients of :attr:`lagrange_terms`.

        Returns
        -------
        ndarray, shape (len(lagrange_terms),)

        Examples
        --------
        >>> kinematic_catalog("cart-pole").base_parameters.round(4)
        array([0.75  , 0.4   , 3.924 , 0.1600005])
        """
        return self.combination @ self.physical_values

    def library(self, interlink=None, classical: bool = True):
        """The catalog as a feature library: forces, Lagrange terms, classical terms.

        Parameters
        ----------
        interlink : array (n, n), optional
            Passed to :class:`~pysindy_xl.ExternalForces` (``system.force_matrix()`` to fit
            with MuJoCo joint forces ``u``).
        classical : bool, default True
            Include the Newtonian candidates (friction, springs).

        Returns
        -------
        CatalogRepartition

        Examples
        --------
        >>> lib = kinematic_catalog("cart-pole").library().fit()
        >>> lib.get_feature_names()[:3]
        ['F[tau]', 'L[x_dot**2]', 'L[theta_dot*x_dot*cos(theta)]']
        """
        from ..feature_library import (
            CatalogRepartition,
            ClassicalLibrary,
            ExternalForces,
            LagrangeLibrary,
        )

        libraries = [ExternalForces(self.coords, interlink=interlink),
                     LagrangeLibrary(self.coords, list(self.lagrange_terms))]
        if classical and self.classical_terms:
            libraries.append(ClassicalLibrary(self.coords, list(self.classical_terms),
                                              mask=self.classical_mask.copy()))
        return CatalogRepartition(libraries)

    def true_coefficients(self, forces: float = -1.0) -> np.ndarray:
        """Coefficient vector of the MJCF model in :meth:`library` (with classical terms).

        Viscous and spring terms get the MJCF damping and stiffness (mapped to the
        coordinates with ``B``); smooth Coulomb terms get MuJoCo's ``frictionloss`` (an
        approximation: MuJoCo's dry friction is a constraint, not a smooth law).

        Parameters
        ----------
        forces : float, default -1.0
            Coefficient of the force column.

        Returns
        -------
        ndarray, shape (1 + len(lagrange_terms) + n_classical_features,)

        Examples
        --------
        >>> kinematic_catalog("cart-pole").true_coefficients().round(4)
        array([-1.    ,  0.75  ,  0.4   ,  3.924 ,  0.16  ,  0.5   ,  0.    ,  0.1   ,  0.    ])
        """
        return np.concatenate([[forces], self.base_parameters, self.classical_values])

    def lagrange_coefficients(self, model) -> np.ndarray:
        """Coefficients of :attr:`lagrange_terms` in a fitted model, force coefficient -1.

        Parameters
        ----------
        model : XLSINDy
            Fitted with :meth:`library` (features matched by name; an implicit model is
            rescaled so that its force coefficient is -1).

        Returns
        -------
        ndarray, shape (len(lagrange_terms),)

        Raises
        ------
        ValueError
            If the model's catalog lacks a Lagrange term of this catalog, or has no force
            coefficient to scale by.
        """
        names = list(model.get_feature_names())
        coefficients = np.asarray(model.coefficients(), dtype=float)
        force = [coefficients[k] for k, name in enumerate(names) if name.startswith("F[")]
        if not force or force[0] == 0:
            raise ValueError("model: no non-zero force coefficient to scale the model by")
        scale = -1.0 / force[0]
        out = np.zeros(len(self.lagrange_terms))
        index = {name: k for k, name in enumerate(names)}
        for j, term in enumerate(self.lagrange_terms):
            name = f"L[{term}]"
            if name not in index:
                raise ValueError(f"model: its catalog has no feature {name!r}")
            out[j] = coefficients[index[name]] * scale
        return out

    # -- physical quantities -------------------------------------------------------------
    def _evaluator(self, key):
        if key not in self._compiled:
            c = self.coords
            if key == "mass":
                exprs = [[sp.diff(term, c.qd[i], c.qd[k]) for term in self.lagrange_terms]
                         for i in range(c.n) for k in range(c.n)]
            else:  # gravity: -dL/dq at rest; bias: Euler-Lagrange with qdd = 0
                from ..feature_library.lagrange import euler_lagrange

                rest = {qd: 0 for qd in c.qd} if key == "gravity" else {}
                exprs = []
                for i in range(c.n):
                    exprs.append([])
                for term in self.lagrange_terms:
                    column = euler_lagrange(term, c)
                    for i in range(c.n):
                        value = column[i].subs({qdd: 0 for qdd in c.qdd})
                        exprs[i].append(value.subs(rest))
            flat = [e for row in exprs for e in row]
            function = sp.lambdify([c.q, c.qd], flat, modules="numpy", cse=True)
            self._compiled[key] = (function, len(exprs))
        return self._compiled[key]

    def _evaluate(self, key, q, qd, coefficients):
        c = self.coords
        q = _states(q, "q", c.n)
        qd = np.zeros_like(q) if qd is None else _states(qd, "qd", c.n)
        if qd.shape != q.shape:
            raise ValueError(f"qd: expected shape {q.shape}, got {qd.shape}")
        beta = self.base_parameters if coefficients is None else np.asarray(coefficients, float)
        if beta.shape != (len(self.lagrange_terms),):
            raise ValueError(f"coefficients: expected shape ({len(self.lagrange_terms)},), "
                             f"got {beta.shape}")
        function, n_rows = self._evaluator(key)
        values = function(tuple(q.T), tuple(qd.T))
        n_samples, n_terms = q.shape[0], len(self.lagrange_terms)
        table = np.empty((len(values), n_samples))
        for k, v in enumerate(values):  # constant entries come back as scalars
            table[k] = np.broadcast_to(v, (n_samples,))
        return np.einsum("rfs,f->sr", table.reshape(n_rows, n_terms, n_samples), beta)

    def mass_matrix(self, q, coefficients=None) -> np.ndarray:
        """Mass matrix ``M(q)`` in the system's coordinates.

        Parameters
        ----------
        q : array, shape (N, n) or (n,)
            Positions.
        coefficients : array, shape (len(lagrange_terms),), optional
            Lagrange coefficients (e.g. from :meth:`lagrange_coefficients`); default the
            MJCF model's base parameters.

        Returns
        -------
        ndarray, shape (N, n, n) or (n, n)

        Examples
        --------
        >>> kinematic_catalog("cart-pole").mass_matrix([0.0, 0.0]).round(4)
        array([[1.5, 0.4],
               [0.4, 0.32 ]])
        """
        single = np.ndim(q) == 1
        n = self.coords.n
        out = self._evaluate("mass", q, None, coefficients).reshape(-1, n, n)
        return out[0] if single else out

    def gravity_torque(self, q, coefficients=None) -> np.ndarray:
        """Generalized gravity force ``dV/dq`` (the equations read ``M qdd + c + dV/dq = tau``).

        Parameters
        ----------
        q : array, shape (N, n) or (n,)
        coefficients : array, optional
            See :meth:`mass_matrix`.

        Returns
        -------
        ndarray, shape (N, n) or (n,)

        Examples
        --------
        >>> kinematic_catalog("cart-pole").gravity_torque([0.0, np.pi / 2]).round(4)
        array([0.   , 3.924])
        """
        single = np.ndim(q) == 1
        out = self._evaluate("gravity", q, None, coefficients)
        return out[0] if single else out

    def bias_forces(self, q, qd, coefficients=None) -> np.ndarray:
        """Coriolis, centrifugal and gravity forces: the equations with ``qdd = 0``.

        Parameters
        ----------
        q, qd : array, shape (N, n) or (n,)
        coefficients : array, optional
            See :meth:`mass_matrix`.

        Returns
        -------
        ndarray, shape (N, n) or (n,)

        Examples
        --------
        >>> kinematic_catalog("cart-pole").bias_forces([0.0, 0.0], [0.0, 2.0]).round(4)
        array([0., 0.])
        """
        single = np.ndim(q) == 1
        out = self._evaluate("bias", q, qd, coefficients)
        return out[0] if single else out

    def report(self, coefficients=None, digits: int = 4) -> str:
        """Table of the base parameters: combination, MJCF value, identified value.

        Parameters
        ----------
        coefficients : array, optional
            Identified Lagrange coefficients (see :meth:`lagrange_coefficients`).
        digits : int, default 4
            Significant digits.

        Returns
        -------
        str

        Examples
        --------
        >>> print(kinematic_catalog("cart-pole").report().splitlines()[1])
        x_dot**2  |  0.5*cart.m + 0.5*pole.m  |  0.75
        """
        truth = self.base_parameters
        lines = ["term  |  stands for  |  MJCF" + ("  |  identified" if coefficients is not None
                                                 else "")]
        for j, term in enumerate(self.lagrange_terms):
            combo = " + ".join(f"{w:.{digits}g}*{name}" for name, w in self.parameters[j].items()
                               if abs(w) > 1e-12)
            line = f"{term}  |  {combo}  |  {truth[j]:.{digits}g}"
            if coefficients is not None:
                line += f"  |  {float(coefficients[j]):.{digits}g}"
            lines.append(line)
        return "\n".join(lines)


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
def _resolve_system(system) -> MuJoCoSystem:
    if isinstance(system, MuJoCoSystem):
        return system
    if isinstance(system, str) and system.lstrip().startswith("<"):
        return MJCFSystem(system)
    if isinstance(system, (str, os.PathLike)):
        if isinstance(system, str) and not system.endswith(".xml") and os.path.isfile(system):
            return MJCFSystem(system)
        return get_system(system)
    raise TypeError(
        f"system: expected a MuJoCoSystem, an MJCF path or MJCF text, got {type(system).__name__}"
    )


def _joint_substitutions(system: MuJoCoSystem, model, joint_symbols):
    """Express each joint's sine, cosine, displacement and velocity in the coordinates."""
    coords = system.coords
    inverse = np.linalg.inv(system.joint_to_coordinates)
    integer_map = np.allclose(inverse, np.round(inverse))
    subs = {}
    for k in range(model.njnt):
        row = np.round(inverse[k]) if integer_map else inverse[k]
        position = sum((sp.Integer(int(a)) if integer_map else sp.Float(a)) * qj
                       for a, qj in zip(row, coords.q, strict=True) if a != 0)
        velocity = sum((sp.Integer(int(a)) if integer_map else sp.Float(a)) * qdj
                       for a, qdj in zip(row, coords.qd, strict=True) if a != 0)
        reference = float(model.qpos0[model.jnt_qposadr[k]])
        kind = joint_symbols[k]
        subs[kind["velocity"]] = velocity
        if "sin" in kind:
            s, c = sp.expand_trig(sp.sin(position)), sp.expand_trig(sp.cos(position))
            if reference != 0.0:  # MuJoCo measures the angle from the joint's ref
                cr, sr = np.cos(reference), np.sin(reference)
                s, c = s * cr - c * sr, c * cr + s * sr
            subs[kind["sin"]], subs[kind["cos"]] = sp.expand(s), sp.expand(c)
        else:
            subs[kind["displacement"]] = position - reference
    return subs


def _body_functions(model):
    """Lagrangian functions of every moving body, in joint symbols.

    Returns
    -------
    functions : dict body id -> list of 10 sympy.Expr (order of INERTIAL_PARAMETERS)
    joint_symbols : list of dict, one per joint
    """
    hinge, slide = int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)
    joint_symbols = []
    for k in range(model.njnt):
        symbols = {"velocity": sp.Symbol(f"_w{k}")}
        if int(model.jnt_type[k]) == hinge:
            symbols["sin"], symbols["cos"] = sp.Symbol(f"_s{k}"), sp.Symbol(f"_c{k}")
        elif int(model.jnt_type[k]) == slide:
            symbols["displacement"] = sp.Symbol(f"_x{k}")
        else:
            raise ValueError(f"system: joint #{k} is not a hinge or slide joint")
        joint_symbols.append(symbols)
    zero = [sp.Integer(0)] * 3
    frames = {0: _Frame(v=zero, w=zero, g=_numeric(model.opt.gravity), h=sp.Integer(0))}
    moving = {0: False}
    functions = {}
    for b in range(1, model.nbody):
        parent = frames[int(model.body_parentid[b])]
        rot = _quat_matrix(model.body_quat[b])
        offset = _numeric(model.body_pos[b])
        frame = _Frame(
            v=_matTvec(rot, [_chop(x + y) for x, y in
                             zip(parent.v, _cross(parent.w, offset), strict=True)]),
            w=_matTvec(rot, parent.w),
            g=_matTvec(rot, parent.g),
            h=_chop(parent.h + _dot(parent.g, offset)),
        )
        moving[b] = moving[int(model.body_parentid[b])] or model.body_jntnum[b] > 0
        for k in range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b]):
            axis = _numeric(model.jnt_axis[k])
            symbols = joint_symbols[k]
            rate = symbols["velocity"]
            if "sin" in symbols:
                anchor = _numeric(model.jnt_pos[k])
                turn = _axis_rotation(model.jnt_axis[k], symbols["sin"], symbols["cos"])
                turned_anchor = _matvec(turn, anchor)
                shift = [_chop(a - b) for a, b in zip(anchor, turned_anchor, strict=True)]
                relative = [a * rate for a in axis]
                shift_rate = [-x for x in _cross(relative, turned_anchor)]
            else:
                turn = None
                shift = [a * symbols["displacement"] for a in axis]
                relative = zero
                shift_rate = [a * rate for a in axis]
            velocity = [_chop(v + x + d) for v, x, d in
                        zip(frame.v, _cross(frame.w, shift), shift_rate, strict=True)]
            spin = [_chop(w + r) for w, r in zip(frame.w, relative, strict=True)]
            height = _chop(frame.h + _dot(frame.g, shift))
            if turn is None:
                frame = _Frame(v=velocity, w=spin, g=frame.g, h=height)
            else:
                frame = _Frame(v=_matTvec(turn, velocity), w=_matTvec(turn, spin),
                               g=_matTvec(turn, frame.g), h=height)
        frames[b] = frame
        if not moving[b]:
            continue  # welded to the world: constant energy, no dynamics
        v, w = frame.v, frame.w
        first_moment = [_chop(a + b) for a, b in zip(_cross(v, w), frame.g, strict=True)]
        half = sp.Rational(1, 2)
        functions[b] = [
            _chop(half * _dot(v, v) + frame.h), *first_moment,
            _chop(half * w[0] ** 2), _chop(half * w[1] ** 2), _chop(half * w[2] ** 2),
            _chop(w[0] * w[1]), _chop(w[0] * w[2]), _chop(w[1] * w[2]),
        ]
    return functions, joint_symbols


def _physical_values(model, body: int) -> np.ndarray:
    """The ten inertial parameters of a body: m, m c, inertia about the frame origin."""
    mass = float(model.body_mass[body])
    centre = np.array(model.body_ipos[body], dtype=float)
    principal = np.zeros(9)
    mujoco.mju_quat2Mat(principal, np.asarray(model.body_iquat[body], dtype=float))
    principal = principal.reshape(3, 3)
    inertia = principal @ np.diag(model.body_inertia[body]) @ principal.T
    # parallel-axis theorem: from the centre of mass to the body frame origin
    inertia += mass * (centre @ centre * np.eye(3) - np.outer(centre, centre))
    return np.array([mass, *(mass * centre), inertia[0, 0], inertia[1, 1], inertia[2, 2],
                     inertia[0, 1], inertia[0, 2], inertia[1, 2]])


def _independent_columns(matrix: np.ndarray) -> list[int]:
    """Columns kept in order when not in the span of those kept before (Gram-Schmidt)."""
    norms = np.linalg.norm(matrix, axis=0)
    basis = np.zeros((matrix.shape[0], 0))
    kept = []
    for j in range(matrix.shape[1]):
        if norms[j] == 0:
            continue
        residual = matrix[:, j] / norms[j]
        for _ in range(2):  # re-orthogonalize: one pass loses digits on near-parallel columns
            residual = residual - basis @ (basis.T @ residual)
        size = np.linalg.norm(residual)
        if size > _INDEPENDENCE_TOL:
            basis = np.column_stack([basis, residual / size])
            kept.append(j)
    return kept


def _random_states(system: MuJoCoSystem, n_samples: int, rng) -> np.ndarray:
    from ..feature_library import stack_variables

    n = system.n
    q = rng.uniform(-1.0, 1.0, (n_samples, n))
    q[:, list(system.angle_coordinates)] *= np.pi
    qd, qdd = rng.normal(size=(2, n_samples, n))
    return stack_variables(q, qd, qdd)


def _classical_candidates(system, model, coulomb, coulomb_scale):
    """Friction and spring candidates per joint, in the coordinates, with their MJCF values."""
    coords = system.coords
    inverse = np.linalg.inv(system.joint_to_coordinates)
    force_map = system.force_matrix()
    qpos = [sp.expand(sum(sp.Float(a) * qj for a, qj in zip(inverse[k], coords.q, strict=True)
                          if a != 0)) for k in range(model.njnt)]
    qvel = [sp.expand(sum(sp.Float(a) * qdj for a, qdj in zip(inverse[k], coords.qd, strict=True)
                          if a != 0)) for k in range(model.njnt)]
    if np.allclose(inverse, np.round(inverse)):  # keep integer maps readable: theta2 - theta1
        qpos = [sp.nsimplify(e, rational=True) for e in qpos]
        qvel = [sp.nsimplify(e, rational=True) for e in qvel]
    terms, mask, kinds, values = [], [], [], []
    for k in range(model.njnt):
        name = system.joint_names[k]
        dof = model.jnt_dofadr[k]
        reaches = np.abs(force_map[:, k]) > 1e-12
        candidates = [("viscous", qvel[k], model.dof_damping[dof])]
        if coulomb:
            candidates.append(("coulomb", sp.tanh(qvel[k] / coulomb_scale),
                               model.dof_frictionloss[dof]))
        if model.jnt_stiffness[k] > 0:
            rest = float(model.qpos_spring[model.jnt_qposadr[k]])
            candidates.append(("spring", qpos[k] - rest, model.jnt_stiffness[k]))
        for kind, term, value in candidates:
            terms.append(term)
            mask.append(reaches)
            kinds.append((kind, name))
            # the joint force -value * term reaches equation i as B[i, k] times it
            values.extend(float(value) * force_map[reaches, k])
    mask = np.array(mask, dtype=bool).reshape(-1, coords.n)
    return terms, mask, kinds, np.array(values)


def kinematic_catalog(system, coulomb: bool = True, coulomb_scale: float = 0.01,
                      seed: int = 0) -> KinematicCatalog:
    """Candidate Lagrangian and Newtonian terms derived from the kinematic tree of a model.

    Every moving body contributes the ten functions of ``(q, qd)`` that multiply its inertial
    parameters, every joint its armature ``qvel^2 / 2``; the set is reduced to independent
    Euler-Lagrange columns (base parameters, see the module docstring). Results are cached by
    model text, coordinates and options.

    Parameters
    ----------
    system : MuJoCoSystem, str or os.PathLike
        A system (its coordinates ``q = T @ qpos`` are used), a registry name, a path to an
        MJCF file or the MJCF text (coordinates: MuJoCo's joint coordinates). Hinge and slide
        joints only.
    coulomb : bool, default True
        Add a smooth Coulomb candidate ``tanh(qvel / coulomb_scale)`` per joint.
    coulomb_scale : float, default 0.01
        Velocity scale of the smooth Coulomb law.
    seed : int, default 0
        Seed of the random states of the numerical reduction.

    Returns
    -------
    KinematicCatalog
        Use ``.library()`` as the feature library of :class:`~pysindy_xl.XLSINDy`.

    Raises
    ------
    TypeError
        If ``system`` is not a system, path or MJCF text.
    ValueError
        If the model has a joint other than hinge or slide, or ``coulomb_scale`` is not
        positive.

    Examples
    --------
    A pendulum whose centre of mass is off its link axis and whose inertia is full:

    >>> xml = '''<mujoco><option gravity="0 0 -9.81"/><worldbody><body>
    ...   <joint name="a" type="hinge" axis="0 1 0"/>
    ...   <inertial pos="0.1 0.02 -0.5" mass="2" fullinertia="0.1 0.2 0.3 0.01 0.02 0.03"/>
    ... </body></worldbody></mujoco>'''
    >>> catalog = kinematic_catalog(xml)
    >>> catalog.lagrange_terms
    [cos(a), sin(a), a_dot**2]
    >>> len(catalog.library().fit().get_feature_names())  # force, 3 Lagrange, 2 friction
    6
    """
    system = _resolve_system(system)
    if isinstance(coulomb_scale, bool) or not isinstance(coulomb_scale, (int, float)) or not (
        np.isfinite(coulomb_scale) and coulomb_scale > 0
    ):
        raise ValueError(f"coulomb_scale: expected a positive number, got {coulomb_scale!r}")
    model = system.mj_model()
    if model.nq != system.n or model.nv != system.n:
        raise ValueError(f"system: MJCF has nq={model.nq}, nv={model.nv}; expected one hinge or "
                         f"slide joint per coordinate ({system.n})")
    for k in range(model.njnt):
        if int(model.jnt_type[k]) not in (int(mujoco.mjtJoint.mjJNT_HINGE),
                                          int(mujoco.mjtJoint.mjJNT_SLIDE)):
            raise ValueError(f"system: joint {system.joint_names[k]!r} is not a hinge or slide "
                             "joint; only those are supported")
    key = (hashlib.sha256(system.xml().encode()).hexdigest(), system.coordinate_names,
           system.joint_to_coordinates.tobytes(), bool(coulomb), float(coulomb_scale), seed)
    if key in _CACHE:
        return _CACHE[key]
    start = time.perf_counter()
    catalog = _build(system, model, bool(coulomb), float(coulomb_scale), seed)
    catalog.build_seconds = time.perf_counter() - start
    if len(_CACHE) >= _CACHE_SIZE:
        _CACHE.pop(next(iter(_CACHE)))
    _CACHE[key] = catalog
    return catalog


def _build(system, model, coulomb, coulomb_scale, seed) -> KinematicCatalog:
    from ..feature_library import LagrangeLibrary

    coords = system.coords
    functions, joint_symbols = _body_functions(model)
    subs = _joint_substitutions(system, model, joint_symbols)
    candidates, names, values = [], [], []
    for b, body_functions in functions.items():
        body = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}"
        candidates.extend(body_functions)
        names.extend(f"{body}.{p}" for p in INERTIAL_PARAMETERS)
        values.extend(_physical_values(model, b))
    for k in range(model.njnt):
        candidates.append(joint_symbols[k]["velocity"] ** 2 / 2)
        names.append(f"{system.joint_names[k]}.armature")
        values.append(float(model.dof_armature[model.jnt_dofadr[k]]))
    angles = [coords.q[i] for i in system.angle_coordinates]
    terms = [_reduce_trigonometry(_chop(f.xreplace(subs)), angles) if f != 0 else sp.Integer(0)
             for f in candidates]
    nonzero = [j for j, term in enumerate(terms) if term.free_symbols]
    regressor_library = LagrangeLibrary(coords, [terms[j] for j in nonzero]).fit()
    rng = np.random.default_rng(seed)
    n_samples = 2 * len(nonzero) // coords.n + 20
    regressor = np.zeros((coords.n * n_samples, len(terms)))
    regressor[:, nonzero] = regressor_library.transform(_random_states(system, n_samples, rng))
    kept = _independent_columns(regressor)
    # every column is a combination of the kept ones: base = combination @ physical
    combination, *_ = np.linalg.lstsq(regressor[:, kept], regressor, rcond=None)
    # exact combinations come out within ~1e-14: round the noise away (0.9999999999999999)
    combination = np.round(combination, 12)
    combination[np.abs(combination) < 1e-10] = 0.0
    parameters = [
        {names[p]: float(combination[j, p]) for p in np.flatnonzero(combination[j])}
        for j in range(len(kept))
    ]
    classical_terms, mask, kinds, classical_values = _classical_candidates(
        system, model, coulomb, coulomb_scale)
    return KinematicCatalog(
        system=system, coords=coords, lagrange_terms=[terms[j] for j in kept],
        parameters=parameters, physical_names=names, combination=combination,
        physical_values=np.array(values), classical_terms=classical_terms,
        classical_mask=mask, classical_kinds=kinds, classical_values=classical_values,
        n_candidates=len(candidates),
    )
