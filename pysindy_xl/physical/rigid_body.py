r"""Rigid-body dynamics of a kinematic tree from inertial parameters: ``M(q)`` and bias forces.

A kinematic catalog's Lagrangian is linear in the bodies' inertial parameters :math:`\pi`, so
its Euler-Lagrange equations are those of rigid bodies with parameters :math:`\pi`, whatever
their values; evaluated here by composite rigid bodies, at a cost that grows with the bodies,
not with the expanded equations' monomials. Spatial vectors are ``[angular; linear]`` in world
coordinates at the world origin. Every function takes a :class:`KinematicTree`, parameters
``pi`` (``tree.physical_names``) and an array module ``xp`` (NumPy or ``jax.numpy``), batched
and without in-place updates, so the same code serves the simulators and
:meth:`XLSINDy.to_jax <pysindy_xl.XLSINDy.to_jax>`.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from .structure import INERTIAL_PARAMETERS

__all__ = ["KinematicTree", "joint_screws", "physical_parameters_from_base",
           "rigid_body_dynamics", "world_inertias"]


@dataclasses.dataclass(frozen=True, eq=False)
class KinematicTree:
    """The kinematics of a mechanism of hinge and slide joints, as MuJoCo places its frames.

    Each parameter is stored as the attribute of the same name.

    Bodies are listed parents first, each placed in its parent's frame by a fixed offset and
    rotation, then moved by its joints in order (about or along the axis by
    ``qpos - reference``). The system's coordinates are ``q = joint_to_coordinates @ qpos``.

    Parameters
    ----------
    body_names : tuple of str, length B
        Body names, parents first.
    parents : ndarray of int, shape (B,)
        Each body's parent, ``-1`` for the world.
    offsets : ndarray, shape (B, 3)
        Fixed offset of each body in its parent's frame.
    rotations : ndarray, shape (B, 3, 3)
        Fixed placement in the parent's frame (``x_parent = R x_body + offset``).
    joint_names : tuple of str, length J
        Joint names.
    joint_bodies : ndarray of int, shape (J,)
        The body each joint moves.
    joint_hinge : ndarray of bool, shape (J,)
        Hinge (``True``) or slide.
    joint_axes, joint_anchors : ndarray, shape (J, 3)
        Unit axis and anchor in the body's frame.
    joint_references : ndarray, shape (J,)
        ``qpos`` at which each joint leaves its body in the placement above.
    joint_to_coordinates : ndarray, shape (J, J)
        Invertible ``T`` with ``q = T @ qpos``.
    gravity : ndarray, shape (3,)
        Gravitational acceleration in the world frame.
    """

    body_names: tuple
    parents: np.ndarray
    offsets: np.ndarray
    rotations: np.ndarray
    joint_names: tuple
    joint_bodies: np.ndarray
    joint_hinge: np.ndarray
    joint_axes: np.ndarray
    joint_anchors: np.ndarray
    joint_references: np.ndarray
    joint_to_coordinates: np.ndarray
    gravity: np.ndarray

    def __post_init__(self):
        B, J = len(self.body_names), len(self.joint_names)
        shapes = {"parents": (B,), "offsets": (B, 3), "rotations": (B, 3, 3), "joint_bodies": (J,),
                  "joint_hinge": (J,), "joint_axes": (J, 3), "joint_anchors": (J, 3),
                  "joint_references": (J,), "joint_to_coordinates": (J, J), "gravity": (3,)}
        for name, shape in shapes.items():
            dtype = {"parents": int, "joint_bodies": int, "joint_hinge": bool}.get(name, float)
            try:
                value = np.array(getattr(self, name), dtype=dtype)
            except (TypeError, ValueError):
                raise ValueError(f"KinematicTree.{name}: expected numbers of shape {shape}") \
                    from None
            if value.shape != shape or (dtype is float and not np.all(np.isfinite(value))):
                raise ValueError(f"KinematicTree.{name}: expected finite values of shape "
                                 f"{shape}, got shape {value.shape}")
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        object.__setattr__(self, "body_names", tuple(str(b) for b in self.body_names))
        object.__setattr__(self, "joint_names", tuple(str(j) for j in self.joint_names))
        if J == 0:
            raise ValueError("KinematicTree: expected at least one joint")
        if np.any(self.parents >= np.arange(B)) or np.any(self.parents < -1):
            raise ValueError("KinematicTree.parents: each body's parent must come before it "
                             "(or be -1, the world)")
        if np.any((self.joint_bodies < 0) | (self.joint_bodies >= B)) or np.any(
                np.diff(self.joint_bodies) < 0):
            raise ValueError("KinematicTree.joint_bodies: expected body indices in body order")
        if not np.allclose(np.linalg.norm(self.joint_axes, axis=1), 1.0, atol=1e-9):
            raise ValueError("KinematicTree.joint_axes: expected unit vectors")
        if abs(np.linalg.det(self.joint_to_coordinates)) < 1e-12:
            raise ValueError("KinematicTree.joint_to_coordinates: expected an invertible matrix")

    @functools.cached_property
    def joint_support(self) -> np.ndarray:
        """``(B, J)`` bool: joint ``k`` moves body ``b``."""
        support = np.zeros((len(self.body_names), len(self.joint_names)), dtype=bool)
        for b, parent in enumerate(self.parents):
            if parent >= 0:
                support[b] = support[parent]
            support[b, self.joint_bodies == b] = True
        return support

    @functools.cached_property
    def moving_bodies(self) -> np.ndarray:
        """Indices of the bodies some joint moves (whose parameters enter the dynamics)."""
        return np.flatnonzero(self.joint_support.any(axis=1))

    @functools.cached_property
    def physical_names(self) -> tuple:
        """Names of ``pi``: ``"<body>.<p>"`` per moving body and :data:`INERTIAL_PARAMETERS`, then
        ``"<joint>.armature"``.
        """
        names = [f"{self.body_names[b]}.{p}" for b in self.moving_bodies
                 for p in INERTIAL_PARAMETERS]
        return tuple(names + [f"{joint}.armature" for joint in self.joint_names])

    @functools.cached_property
    def _frame_plan(self) -> dict:
        """How :func:`joint_screws` composes frames: one per joint, one per jointless body (at
        ``J + i``), parents first.
        """
        J = len(self.joint_names)
        prefix_rotation = np.broadcast_to(np.eye(3), (J, 3, 3)).copy()
        prefix_offset = np.zeros((J, 3))
        fixed_rotation, fixed_offset, frames, joint_frames, body_frames = [], [], [], [], []
        for b, parent in enumerate(self.parents):
            frame = body_frames[parent] if parent >= 0 else -1
            joints = np.flatnonzero(self.joint_bodies == b)
            if len(joints):
                prefix_rotation[joints[0]] = self.rotations[b]
                prefix_offset[joints[0]] = self.offsets[b]
                for k in joints:
                    frames.append((k, frame))
                    frame = len(frames) - 1
                    joint_frames.append(frame)
            else:
                fixed_rotation.append(self.rotations[b])
                fixed_offset.append(self.offsets[b])
                frames.append((J + len(fixed_rotation) - 1, frame))
                frame = len(frames) - 1
            body_frames.append(frame)
        return {"prefix_rotation": prefix_rotation, "prefix_offset": prefix_offset,
                "fixed_rotation": np.array(fixed_rotation).reshape(-1, 3, 3),
                "fixed_offset": np.array(fixed_offset).reshape(-1, 3), "frames": frames,
                "joint_frames": np.array(joint_frames), "body_frames": np.array(body_frames),
                "axis_skew": _skew(np.asarray(self.joint_axes), np)}

    @functools.cached_property
    def _moving_support(self) -> np.ndarray:
        """``(J, Bm)``: 1 where joint ``k`` moves moving body ``b``."""
        return self.joint_support[self.moving_bodies].T.astype(float)

    @functools.cached_property
    def _ancestry(self) -> np.ndarray:
        """``(J, J)`` bool: joint ``k`` moves the frame of joint ``l``'s axis, or ``k == l``."""
        return (self._preceding_joints.T > 0) | np.eye(len(self.joint_names), dtype=bool)

    @functools.cached_property
    def _inverse_transform(self) -> np.ndarray:
        return np.linalg.inv(self.joint_to_coordinates)

    @functools.cached_property
    def _preceding_joints(self) -> np.ndarray:
        """``(J, J)``: 1 where joint ``k'`` moves the frame carrying joint ``k``'s axis."""
        J = len(self.joint_names)
        preceding = np.zeros((J, J), dtype=bool)
        for k, b in enumerate(self.joint_bodies):
            parent = self.parents[b]
            if parent >= 0:
                preceding[k] = self.joint_support[parent]
            preceding[k, :k] |= self.joint_bodies[:k] == b
        return preceding.astype(float)

    def to_dict(self) -> dict:
        """JSON-ready description; :meth:`from_dict` reads it back.

        Returns
        -------
        dict
            Every field as plain lists and numbers.

        Examples
        --------
        >>> tree = KinematicTree.from_dict(KinematicTree.from_dict({
        ...     "body_names": ["b"], "parents": [-1], "offsets": [[0, 0, 0]],
        ...     "rotations": [[[1, 0, 0], [0, 1, 0], [0, 0, 1]]], "joint_names": ["j"],
        ...     "joint_bodies": [0], "joint_hinge": [False], "joint_axes": [[1, 0, 0]],
        ...     "joint_anchors": [[0, 0, 0]], "joint_references": [0],
        ...     "joint_to_coordinates": [[1]], "gravity": [0, 0, -9.81]}).to_dict())
        >>> tree.physical_names[:2], tree.physical_names[-1]
        (('b.m', 'b.mcx'), 'j.armature')
        """
        return {field.name: (list(value) if isinstance(value, tuple) else value.tolist())
                for field in dataclasses.fields(self)
                for value in [getattr(self, field.name)]}

    @classmethod
    def from_dict(cls, data) -> KinematicTree:
        """The tree of :meth:`to_dict`; ``ValueError`` naming the field on anything else."""
        if not isinstance(data, dict):
            raise ValueError(f"KinematicTree: expected a dict, got {type(data).__name__}")
        names = [field.name for field in dataclasses.fields(cls)]
        if set(data) != set(names):
            raise ValueError(f"KinematicTree: expected the fields {names}, got {sorted(data)}")
        for key in ("body_names", "joint_names"):
            if not isinstance(data[key], list) or not all(isinstance(s, str) for s in data[key]):
                raise ValueError(f"KinematicTree.{key}: expected a list of strings")
        return cls(**data)


def physical_parameters_from_base(tree: KinematicTree, maps, beta) -> np.ndarray:
    r"""Least-norm physical parameters :math:`\pi` with :math:`C \pi = \beta`.

    Any solution gives the same equations of motion; ``C`` is read from a kinematic catalog's
    ``parameters`` maps (``{physical name: weight}`` per base parameter).

    Parameters
    ----------
    tree : KinematicTree
        The mechanism (its ``physical_names``).
    maps : sequence of dict
        Per base parameter, ``{physical name: weight}``.
    beta : array, shape (len(maps),)
        The base parameters.

    Returns
    -------
    ndarray, shape (len(tree.physical_names),)
        :math:`\pi = C^+ \beta`.

    Raises
    ------
    ValueError
        On a name that is not a parameter of the tree.
    """
    index = {name: p for p, name in enumerate(tree.physical_names)}
    combination = np.zeros((len(maps), len(index)))
    for j, weights in enumerate(maps):
        for name, weight in weights.items():
            if name not in index:
                raise ValueError(f"parameters: {name!r} is not a parameter of the kinematic "
                                 f"tree (bodies {list(tree.body_names)})")
            combination[j, index[name]] = weight
    beta = np.asarray(beta, dtype=float)
    return np.linalg.lstsq(combination, beta, rcond=None)[0]


# -- the kernel ------------------------------------------------------------------------------
# index arrays: NumPy gathers with them several times faster than with lists
_NEXT, _AFTER = np.array([1, 2, 0]), np.array([2, 0, 1])


def _cross(a, b):
    """Cross product along the last axis, by index (``np.cross`` is slow on small arrays)."""
    return a[..., _NEXT] * b[..., _AFTER] - a[..., _AFTER] * b[..., _NEXT]


#: ``[v]x`` as a gather of ``[0, v]`` (flattened row-major) times signs.
_SKEW_GATHER = np.array([0, 3, 2, 3, 0, 1, 2, 1, 0])
_SKEW_SIGN = np.array([0.0, -1, 1, 1, 0, -1, -1, 1, 0])
#: The symmetric inertia matrix (flattened) from ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` at 4..9.
_INERTIA_GATHER = np.array([4, 7, 8, 7, 5, 9, 8, 9, 6])


def _skew(v, xp):
    """``[v]x`` of shape (..., 3, 3)."""
    padded = xp.concatenate([xp.zeros_like(v[..., :1]), v], axis=-1)
    return xp.reshape(padded[..., _SKEW_GATHER] * _SKEW_SIGN, v.shape[:-1] + (3, 3))


def _apply(matrix, vector):
    """``matrix @ vector`` over a batch of vectors (``vector`` of shape (..., 3))."""
    return (matrix @ vector[..., None])[..., 0]


def joint_screws(tree: KinematicTree, qpos, xp=np):
    """Forward kinematics: world placements of the body frames and the joints' unit screws.

    All local placements at once, then composed down the tree.

    Parameters
    ----------
    tree : KinematicTree
        The mechanism.
    qpos : array, shape (N, J)
        Joint positions.
    xp : module, default numpy
        Array namespace (``numpy`` or ``jax.numpy``).

    Returns
    -------
    rotations : array, shape (N, B, 3, 3)
        World rotation of every body frame.
    positions : array, shape (N, B, 3)
        World position of every body frame.
    screws : array, shape (N, J, 6)
        Each joint's unit screw, ``[axis; anchor x axis]`` (hinge) or ``[0; axis]`` (slide).
    """
    plan = tree._frame_plan
    hinge = tree.joint_hinge[:, None, None]
    angle = (qpos - tree.joint_references)[..., None, None]              # (N, J, 1, 1)
    skew = plan["axis_skew"]
    turn = xp.where(hinge, np.eye(3) + xp.sin(angle) * skew
                    + (1.0 - xp.cos(angle)) * (skew @ skew), np.eye(3))  # Rodrigues
    anchors = tree.joint_anchors
    shift = xp.where(hinge[..., 0], anchors - _apply(turn, anchors),
                     tree.joint_axes * angle[..., 0])                    # (N, J, 3)
    local_rotation = plan["prefix_rotation"] @ turn
    local_position = plan["prefix_offset"] + _apply(plan["prefix_rotation"], shift)
    N = qpos.shape[0]
    if plan["fixed_rotation"].shape[0]:  # jointless bodies: constant placements
        local_rotation = xp.concatenate([local_rotation, xp.broadcast_to(
            plan["fixed_rotation"], (N,) + plan["fixed_rotation"].shape)], axis=1)
        local_position = xp.concatenate([local_position, xp.broadcast_to(
            plan["fixed_offset"], (N,) + plan["fixed_offset"].shape)], axis=1)
    rotations, positions = [], []
    for local, parent in plan["frames"]:
        if parent < 0:
            rotations.append(local_rotation[:, local])
            positions.append(local_position[:, local])
        else:
            rotations.append(rotations[parent] @ local_rotation[:, local])
            positions.append(positions[parent]
                             + _apply(rotations[parent], local_position[:, local]))
    rotation, position = xp.stack(rotations, axis=1), xp.stack(positions, axis=1)
    joint_rotation = rotation[:, plan["joint_frames"]]                   # (N, J, 3, 3)
    axis = _apply(joint_rotation, tree.joint_axes)
    anchor = position[:, plan["joint_frames"]] + _apply(joint_rotation, anchors)
    screws = xp.concatenate([axis * hinge[..., 0],
                             xp.where(hinge[..., 0], _cross(anchor, axis), axis)], axis=-1)
    return rotation[:, plan["body_frames"]], position[:, plan["body_frames"]], screws


def world_inertias(tree: KinematicTree, pi, rotations, positions, xp=np):
    """Moving bodies' inertial parameters in world coordinates, about the world origin.

    From :func:`joint_screws`'s placements; all linear in ``pi``.

    Parameters
    ----------
    tree : KinematicTree
        The mechanism.
    pi : array, shape (len(tree.physical_names),)
        Physical parameters.
    rotations : array, shape (N, B, 3, 3)
        World rotations of the body frames.
    positions : array, shape (N, B, 3)
        World positions of the body frames.
    xp : module, default numpy
        Array namespace.

    Returns
    -------
    mass : array, shape (Bm,)
        Mass of each moving body.
    moment : array, shape (N, Bm, 3)
        First moments ``m c``.
    inertia : array, shape (N, Bm, 3, 3)
        Inertia matrices about the world origin.
    """
    moving = tree.moving_bodies
    body = xp.reshape(pi[: 10 * len(moving)], (len(moving), 10))
    mass, first = body[:, 0], body[:, 1:4]
    inertia_body = xp.reshape(body[:, _INERTIA_GATHER], (len(moving), 3, 3))
    rotation, position = rotations[:, moving], positions[:, moving]      # (N, Bm, 3[, 3])
    turned = _apply(rotation, first)                                     # R h
    eye = np.eye(3)
    # parallel axes for any pi: -m [p]x^2 - [p]x[Rh]x - [Rh]x[p]x, with [a]x[b]x = b a^T - a.b
    outer = position[..., :, None] * turned[..., None, :]
    inertia = (rotation @ inertia_body @ xp.swapaxes(rotation, -1, -2)
               + mass[:, None, None] * (xp.sum(position * position, axis=-1)[..., None, None]
                                        * eye - position[..., :, None] * position[..., None, :])
               + 2.0 * xp.sum(position * turned, axis=-1)[..., None, None] * eye
               - outer - xp.swapaxes(outer, -1, -2))
    return mass, turned + mass[:, None] * position, inertia


def _momentum(mass, moment, inertia, motion, xp):
    """Spatial inertia times spatial motion ``[w; v]``: ``[I w + h x v; w x h + m v]``."""
    w, v = motion[..., :3], motion[..., 3:]
    return xp.concatenate([_apply(inertia, w) + _cross(moment, v),
                           _cross(w, moment) + mass[..., None] * v], axis=-1)


def _motion_cross(a, b, xp):
    """``a x b`` of spatial motions."""
    return xp.concatenate([_cross(a[..., :3], b[..., :3]),
                           _cross(a[..., :3], b[..., 3:]) + _cross(a[..., 3:], b[..., :3])],
                          axis=-1)


def _force_cross(a, f, xp):
    """``a x* f`` of a spatial motion and a spatial force."""
    return xp.concatenate([_cross(a[..., :3], f[..., :3]) + _cross(a[..., 3:], f[..., 3:]),
                           _cross(a[..., :3], f[..., 3:])], axis=-1)


def rigid_body_dynamics(tree: KinematicTree, pi, q, qd, xp=np):
    r"""Mass matrix and bias forces of the tree with physical parameters ``pi``.

    In the system's coordinates (:math:`M = T^{-T} M_{qpos} T^{-1}`, :math:`b = T^{-T}
    b_{qpos}`), from composite inertias: :math:`M_{kl} = s_k^T I^c_l s_l` where ``k`` moves
    ``l``'s axis, :math:`b_k = s_k^T \sum_b (I_b a_b + v_b \times^* I_b v_b - g_b)` over the
    bodies ``k`` moves.

    Parameters
    ----------
    tree : KinematicTree
        The mechanism.
    pi : array, shape (len(tree.physical_names),)
        Physical parameters (:attr:`KinematicTree.physical_names`).
    q, qd : array, shape (N, J)
        Positions and velocities, in the system's coordinates.
    xp : module, default numpy
        Array namespace (``numpy`` or ``jax.numpy``).

    Returns
    -------
    mass : array, shape (N, J, J)
        Mass matrices.
    bias : array, shape (N, J)
        Coriolis, centrifugal and gravity forces (the equations at ``qdd = 0``).

    Examples
    --------
    A point mass ``m = 2`` at distance 0.5 on a hinge about ``y``, gravity along ``-z``:

    >>> import numpy as np
    >>> tree = KinematicTree(body_names=("link",), parents=np.array([-1]),
    ...                      offsets=np.zeros((1, 3)), rotations=np.eye(3)[None],
    ...                      joint_names=("hinge",), joint_bodies=np.array([0]),
    ...                      joint_hinge=np.array([True]), joint_axes=np.array([[0.0, 1, 0]]),
    ...                      joint_anchors=np.zeros((1, 3)), joint_references=np.zeros(1),
    ...                      joint_to_coordinates=np.eye(1), gravity=np.array([0.0, 0, -9.81]))
    >>> pi = np.zeros(11); pi[0], pi[3], pi[4], pi[5] = 2.0, -1.0, 0.5, 0.5  # m, m cz, Ixx, Iyy
    >>> mass, bias = rigid_body_dynamics(tree, pi, np.array([[0.0]]), np.array([[0.0]]))
    >>> mass.round(4), bias.round(4)  # m l^2, and no torque hanging straight down
    (array([[[0.5]]]), array([[0.]]))
    >>> rigid_body_dynamics(tree, pi, np.array([[np.pi / 2]]), np.array([[0.0]]))[1].round(4)
    array([[9.81]])
    """
    inverse = tree._inverse_transform
    qpos, qvel = q @ inverse.T, qd @ inverse.T
    rotations, positions, screws = joint_screws(tree, qpos, xp)
    mass, moment, inertia = world_inertias(tree, pi, rotations, positions, xp)
    support = tree._moving_support                                      # (J, Bm)
    composite_moment = support @ moment
    # composite inertia of the bodies each joint moves, then M from the ancestry
    composite_inertia = xp.reshape(support @ xp.reshape(inertia, inertia.shape[:2] + (9,)),
                                   screws.shape[:2] + (3, 3))
    composite = _momentum(support @ mass, composite_moment, composite_inertia, screws, xp)
    gram = screws @ xp.swapaxes(composite, -1, -2)                       # s_k . I^c_l s_l
    ancestry = tree._ancestry                                           # k moves l's axis
    armature = pi[10 * len(tree.moving_bodies):]
    mass_matrix = (xp.where(ancestry, gram, 0.0) + xp.where(ancestry.T, xp.swapaxes(
        gram, -1, -2), 0.0) * (1.0 - np.eye(len(armature))) + xp.diag(armature))
    # bias: the bodies' momentum rates at qdd = 0, less their weights
    rates = screws * qvel[..., None]                                    # (N, J, 6)
    body_support = support.T                                            # (Bm, J)
    velocity = body_support @ rates                                     # (N, Bm, 6)
    carrier = tree._preceding_joints @ rates                            # frame of each axis
    acceleration = body_support @ (_motion_cross(carrier, screws, xp) * qvel[..., None])
    force = (_momentum(mass, moment, inertia, acceleration, xp)
             + _force_cross(velocity, _momentum(mass, moment, inertia, velocity, xp), xp))
    gravity = xp.concatenate([_cross(composite_moment, tree.gravity), xp.broadcast_to(
        (support @ mass)[:, None] * tree.gravity, composite_moment.shape)], axis=-1)
    bias = xp.sum(screws * (support @ force - gravity), axis=-1)
    return inverse.T @ mass_matrix @ inverse, bias @ inverse
