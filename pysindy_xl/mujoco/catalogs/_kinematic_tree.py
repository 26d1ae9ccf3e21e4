"""Kinematics of an MJCF tree as polynomials: the functions multiplying inertial parameters.

For every moving body, the velocity ``v`` of its frame origin and its angular velocity ``w``
(both in body coordinates), the gravity vector in body coordinates and the height term
``g . p`` are propagated from the world through body offsets, orientations and joints exactly
as MuJoCo's ``mj_kinematics`` places the frames (hinges turn about their axis through the anchor
``jnt_pos``, slides translate along their axis, angles are measured from ``qpos0``). Everything
is a :class:`~pysindy_xl.feature_library.trigpoly.TrigPolynomial` in the system's coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..._optional import import_mujoco
from ...feature_library.trigpoly import TrigPolynomial
from ...physical.rigid_body import KinematicTree
from ...physical.structure import INERTIAL_PARAMETERS
from ..systems.registry import MuJoCoSystem

__all__ = ["INERTIAL_PARAMETERS", "body_functions", "kinematic_tree", "physical_values"]

# Rotation entries and offsets below this magnitude are round-off of quaternion arithmetic.
_CHOP = 1e-13


# -- vector helpers on polynomials ---------------------------------------------------------
def _matvec(matrix, vector):
    return [sum((matrix[i][k] * vector[k] for k in range(3)), 0.0 * vector[0])
            for i in range(3)]


def _matTvec(matrix, vector):
    return [sum((matrix[k][i] * vector[k] for k in range(3)), 0.0 * vector[0])
            for i in range(3)]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _numeric(values) -> list[float]:
    """Floats with round-off zeros (``6e-17`` from quaternion arithmetic) made exact zeros."""
    return [0.0 if abs(v) < _CHOP else float(v) for v in values]


def _quat_matrix(quat) -> list[list[float]]:
    matrix = np.zeros(9)
    import_mujoco().mju_quat2Mat(matrix, np.asarray(quat, dtype=float))
    rows = _numeric(matrix)
    return [rows[0:3], rows[3:6], rows[6:9]]


def _axis_rotation(axis, s, c):
    """Rotation by the angle of sine ``s`` and cosine ``c`` about the unit ``axis`` (Rodrigues)."""
    a = _numeric(axis)
    skew = [[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]]
    return [[c * float(i == j) + s * skew[i][j] + (1 - c) * (a[i] * a[j]) for j in range(3)]
            for i in range(3)]


@dataclass
class _Frame:
    """A body frame during the recursion, in its own coordinates: origin velocity ``v``,
    angular velocity ``w``, gravity ``g`` and ``h = g . p`` (``p`` the origin; ``-V = m h``)."""

    v: list
    w: list
    g: list
    h: TrigPolynomial


def _joint_variables(system: MuJoCoSystem, model):
    """Each joint's sine and cosine (hinge) or displacement (slide), and velocity, as polynomials:
    ``qpos - qpos0`` is a row of ``T^-1`` applied to ``q``, expanded by the angle-sum formulas
    (integer rows: relative hinges of a chain)."""
    n = system.n
    is_angle = tuple(j in system.angle_coordinates for j in range(n))
    inverse = np.linalg.inv(system.joint_to_coordinates)

    def slot(index):
        return TrigPolynomial.slot(n, index, is_angle)

    mujoco = import_mujoco()
    hinge = int(mujoco.mjtJoint.mjJNT_HINGE)
    joints = []
    for k in range(model.njnt):
        row = inverse[k]
        used = np.flatnonzero(np.abs(row) > 1e-12)
        velocity = sum((float(row[j]) * slot(2 * n + j) for j in used), 0.0 * slot(0))
        reference = float(model.qpos0[model.jnt_qposadr[k]])
        name = system.joint_names[k]
        if int(model.jnt_type[k]) == hinge:
            if not all(is_angle[j] and float(row[j]).is_integer() for j in used):
                raise ValueError(f"system: the angle of hinge {name!r} must be an integer "
                                 "combination of angle coordinates (joint_to_coordinates)")
            sine, cosine = TrigPolynomial.constant(0.0, is_angle), TrigPolynomial.constant(
                1.0, is_angle)
            for j in used:  # angle-sum formulas, one unit of q_j at a time
                sign = np.sign(row[j])
                for _ in range(int(abs(row[j]))):
                    sine, cosine = (sine * slot(n + j) + sign * cosine * slot(j),
                                    cosine * slot(n + j) - sign * sine * slot(j))
            cr, sr = np.cos(reference), np.sin(reference)
            joints.append({"sin": sine * cr - cosine * sr, "cos": cosine * cr + sine * sr,
                           "velocity": velocity})
        else:
            if any(is_angle[j] for j in used):
                raise ValueError(f"system: slide joint {name!r} must map to linear coordinates")
            displacement = sum((float(row[j]) * slot(j) for j in used), 0.0 * slot(0))
            joints.append({"displacement": displacement - reference, "velocity": velocity})
    return joints, is_angle


def body_functions(system, model):
    """Lagrangian functions of every moving body (order of INERTIAL_PARAMETERS).

    Returns
    -------
    functions : dict body id -> list of 10 TrigPolynomial
    joints : list of dict
        Per joint: ``sin``, ``cos`` or ``displacement``, ``velocity`` polynomials.
    """
    joints, is_angle = _joint_variables(system, model)
    zero = [TrigPolynomial.constant(0.0, is_angle)] * 3
    frames = {0: _Frame(v=zero, w=zero,
                        g=[TrigPolynomial.constant(x, is_angle) for x in model.opt.gravity],
                        h=zero[0])}
    moving = {0: False}
    functions = {}
    for b in range(1, model.nbody):
        parent_id = int(model.body_parentid[b])
        parent = frames[parent_id]
        rot = _quat_matrix(model.body_quat[b])
        offset = _numeric(model.body_pos[b])
        frame = _Frame(v=_matTvec(rot, [x + y for x, y in zip(parent.v, _cross(parent.w, offset),
                                                              strict=True)]),
                       w=_matTvec(rot, parent.w),
                       g=_matTvec(rot, parent.g),
                       h=parent.h + _dot(parent.g, offset))
        moving[b] = moving[parent_id] or model.body_jntnum[b] > 0
        for k in range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b]):
            axis = _numeric(model.jnt_axis[k])
            joint = joints[k]
            rate = joint["velocity"]
            if "sin" in joint:
                # MuJoCo turns the frame about the axis through the anchor jnt_pos
                anchor = _numeric(model.jnt_pos[k])
                turn = _axis_rotation(axis, joint["sin"], joint["cos"])
                turned_anchor = _matvec(turn, anchor)
                shift = [a - t for a, t in zip(anchor, turned_anchor, strict=True)]
                relative = [rate * a for a in axis]
                shift_rate = [-x for x in _cross(relative, turned_anchor)]
            else:
                turn = None
                shift = [joint["displacement"] * a for a in axis]
                relative = zero
                shift_rate = [rate * a for a in axis]
            velocity = [v + x + d for v, x, d in
                        zip(frame.v, _cross(frame.w, shift), shift_rate, strict=True)]
            spin = [w + r for w, r in zip(frame.w, relative, strict=True)]
            height = frame.h + _dot(frame.g, shift)
            if turn is None:
                frame = _Frame(v=velocity, w=spin, g=frame.g, h=height)
            else:
                frame = _Frame(v=_matTvec(turn, velocity), w=_matTvec(turn, spin),
                               g=_matTvec(turn, frame.g), h=height)
        frames[b] = frame
        if not moving[b]:
            continue  # welded to the world: constant energy, no dynamics
        v, w = frame.v, frame.w
        first_moment = [a + g for a, g in zip(_cross(v, w), frame.g, strict=True)]
        functions[b] = [0.5 * _dot(v, v) + frame.h, *first_moment,
                        0.5 * (w[0] * w[0]), 0.5 * (w[1] * w[1]), 0.5 * (w[2] * w[2]),
                        w[0] * w[1], w[0] * w[2], w[1] * w[2]]
    return functions, joints


def physical_values(model, body: int) -> np.ndarray:
    """The ten inertial parameters of a body: m, m c, inertia about the frame origin."""
    mass = float(model.body_mass[body])
    centre = np.array(model.body_ipos[body], dtype=float)
    principal = np.zeros(9)
    import_mujoco().mju_quat2Mat(principal, np.asarray(model.body_iquat[body], dtype=float))
    principal = principal.reshape(3, 3)
    inertia = principal @ np.diag(model.body_inertia[body]) @ principal.T
    # parallel-axis theorem: from the centre of mass to the body frame origin
    inertia += mass * (centre @ centre * np.eye(3) - np.outer(centre, centre))
    return np.array([mass, *(mass * centre), inertia[0, 0], inertia[1, 1], inertia[2, 2],
                     inertia[0, 1], inertia[0, 2], inertia[1, 2]])


def kinematic_tree(system: MuJoCoSystem, model) -> KinematicTree:
    """The numeric :class:`~pysindy_xl.physical.rigid_body.KinematicTree` of an MJCF model:
    the same frames as :func:`body_functions`, for the rigid-body kernel."""
    mujoco = import_mujoco()
    bodies = range(1, model.nbody)
    rotations = np.zeros((model.nbody - 1, 9))
    for b in bodies:
        mujoco.mju_quat2Mat(rotations[b - 1], np.asarray(model.body_quat[b], dtype=float))
    return KinematicTree(
        body_names=tuple(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}"
                         for b in bodies),
        parents=np.asarray(model.body_parentid[1:], dtype=int) - 1,
        offsets=np.asarray(model.body_pos[1:], dtype=float),
        rotations=rotations.reshape(-1, 3, 3),
        joint_names=tuple(system.joint_names),
        joint_bodies=np.asarray(model.jnt_bodyid, dtype=int) - 1,
        joint_hinge=np.asarray(model.jnt_type) == int(mujoco.mjtJoint.mjJNT_HINGE),
        joint_axes=np.asarray(model.jnt_axis, dtype=float),
        joint_anchors=np.asarray(model.jnt_pos, dtype=float),
        joint_references=np.asarray(model.qpos0[model.jnt_qposadr], dtype=float),
        joint_to_coordinates=np.asarray(system.joint_to_coordinates, dtype=float),
        gravity=np.asarray(model.opt.gravity, dtype=float),
    )
