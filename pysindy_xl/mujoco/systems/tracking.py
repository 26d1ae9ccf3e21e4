"""Tracking control of plain torque motors: a PD loop that makes them follow a position
reference, as the controller of a real arm does.

Random torques excite an arm only if its motors can hold it against gravity; otherwise it
falls onto its joint stops. :func:`tracking_controller` designs a PD controller per motor and
:func:`tracked_model` writes it into a copy of the model as ``position`` servos, so MuJoCo's
actuator law (:mod:`~pysindy_xl.mujoco.systems.actuation`) is the controller everywhere.
"""

from __future__ import annotations

import numpy as np

from ..._optional import import_mujoco
from .actuation import supported_actuator

__all__ = ["tracking_controller", "tracked_model", "TRACKING_BANDWIDTH", "TRACKING_ERROR"]

#: Closed-loop bandwidth (rad/s) of the tracking controller of plain torque motors
#: (:func:`tracking_controller`): twice the top of the random references' band (1.5 Hz by
#: default) over ``SERVO_BANDWIDTH_FRACTION``, so that the references are followed.
TRACKING_BANDWIDTH = 2 * np.pi * 5.0
#: Tracking error, as a fraction of the joint's range, at which the tracking controller's
#: stiffness balances the joint's largest static load (gravity over the range, dry friction).
TRACKING_ERROR = 0.02


def _plain_motor(model, a: int) -> bool:
    """Whether actuator ``a`` is a plain torque motor (fixed gain, no bias) on a limited
    hinge or slide joint."""
    mujoco = import_mujoco()
    joint = model.actuator_trnid[a, 0]
    return (supported_actuator(model, a)
            and int(model.actuator_gaintype[a]) == int(mujoco.mjtGain.mjGAIN_FIXED)
            and int(model.actuator_biastype[a]) == int(mujoco.mjtBias.mjBIAS_NONE)
            and bool(model.jnt_limited[joint])
            and int(model.jnt_type[joint]) in (int(mujoco.mjtJoint.mjJNT_HINGE),
                                               int(mujoco.mjtJoint.mjJNT_SLIDE)))


def _torque_range(model, a: int) -> tuple[float, float]:
    """The force range of motor ``a`` (``gain * ctrlrange`` within ``forcerange``)."""
    low, high = -np.inf, np.inf
    if model.actuator_ctrllimited[a]:
        bounds = model.actuator_gainprm[a, 0] * model.actuator_ctrlrange[a]
        low, high = float(bounds.min()), float(bounds.max())
    if model.actuator_forcelimited[a]:
        low = max(low, float(model.actuator_forcerange[a, 0]))
        high = min(high, float(model.actuator_forcerange[a, 1]))
    return low, high


def plain_motors(model) -> np.ndarray:
    """Boolean (nu,): the actuators :func:`tracking_controller` can make track a reference
    (plain torque motors on limited hinge or slide joints).

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.

    Returns
    -------
    numpy.ndarray of bool, shape (nu,)
        True for the actuators that can be made to track.
    """
    return np.array([_plain_motor(model, a) for a in range(model.nu)], dtype=bool)


def gravity_torques(model, poses) -> np.ndarray:
    """Gravity's generalized forces (``qfrc_bias`` at rest), shape (P, nv), at poses (P, nq).

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.
    poses : array_like of shape (P, nq)
        Joint positions.

    Returns
    -------
    numpy.ndarray of shape (P, nv)
        Gravity's generalized force at each pose.
    """
    mujoco = import_mujoco()
    data = mujoco.MjData(model)
    out = np.empty((len(poses), model.nv))
    for k, pose in enumerate(poses):  # a handful of poses: one forward pass each
        data.qpos[:], data.qvel[:] = pose, 0.0
        mujoco.mj_forward(model, data)
        out[k] = data.qfrc_bias
    return out


def tracking_controller(model, actuators=None, n_poses: int = 16, seed=0) -> dict | None:
    """A PD controller with which plain torque motors track a position reference.

    Each motor on joint ``j`` (gear ``g``) becomes MuJoCo's ``position`` servo
    ``F = kp (ctrl - g q_j) - kv g qd_j`` within its force range, ``kp = K / g^2``,
    ``kv = D / g^2``,

    .. math::

        K = \\max\\Big(m\\,\\omega^2,\\;
            \\frac{\\max_q |g_j(q)| + f_j}{e\\,(q_j^{\\max} - q_j^{\\min})}\\Big),
        \\qquad D = 2\\sqrt{K m}

    (``m``: the joint's diagonal of ``mj_fullM``; ``g_j(q)``: gravity's torque at ``n_poses``
    random poses; ``f_j``: dry friction; ``omega = TRACKING_BANDWIDTH``,
    ``e = TRACKING_ERROR``). Returns the JSON description :func:`tracked_model` reads, or
    None when none of ``actuators`` (default all) is a plain motor on a limited joint.

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.
    actuators : sequence of int, default=None
        Indices of the actuators to make track; None: every actuator.
    n_poses : int, default=16
        Random poses at which gravity's torque is sampled.
    seed : int, default=0
        Seed of the random poses.

    Returns
    -------
    dict or None
        ``{"actuators", "kp", "kv", "ctrlrange", "forcerange"}`` (JSON-serializable), or None
        when no selected actuator is a plain motor on a limited joint.

    Examples
    --------
    >>> import mujoco
    >>> model = mujoco.MjModel.from_xml_string('''<mujoco><worldbody><body>
    ...   <joint name="j" axis="0 1 0" range="-2 2"/>
    ...   <inertial pos="0 0 -0.5" mass="1" diaginertia="1e-6 1e-6 1e-6"/></body></worldbody>
    ...   <actuator><motor joint="j"/></actuator></mujoco>''')
    >>> controller = tracking_controller(model)  # m omega^2 outweighs gravity's need
    >>> round(controller["kp"][0], 1), round(controller["kv"][0], 2)
    (246.7, 15.71)
    """
    mujoco = import_mujoco()
    candidates = range(model.nu) if actuators is None else np.atleast_1d(actuators)
    tracked = [int(a) for a in candidates if _plain_motor(model, int(a))]
    if not tracked:
        return None
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    mass = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, mass)
    rng = np.random.default_rng(seed)
    poses = np.tile(model.qpos0, (n_poses, 1))
    for j in np.flatnonzero(model.jnt_limited):
        if int(model.jnt_type[j]) in (int(mujoco.mjtJoint.mjJNT_HINGE),
                                      int(mujoco.mjtJoint.mjJNT_SLIDE)):
            poses[:, model.jnt_qposadr[j]] = rng.uniform(*model.jnt_range[j], n_poses)
    gravity = np.abs(gravity_torques(model, np.vstack([model.qpos0, poses]))).max(axis=0)
    out = {"actuators": tracked, "kp": [], "kv": [], "ctrlrange": [], "forcerange": []}
    for a in tracked:
        joint = model.actuator_trnid[a, 0]
        dof, gear = model.jnt_dofadr[joint], float(model.actuator_gear[a, 0])
        m = mass[dof, dof]
        load = gravity[dof] + model.dof_frictionloss[dof]
        width = float(np.ptp(model.jnt_range[joint]))
        stiffness = max(m * TRACKING_BANDWIDTH**2, load / (TRACKING_ERROR * width))
        out["kp"].append(float(stiffness / gear**2))
        out["kv"].append(float(2 * np.sqrt(stiffness * m) / gear**2))
        out["ctrlrange"].append(sorted(float(gear * r) for r in model.jnt_range[joint]))
        out["forcerange"].append([v if np.isfinite(v) else None for v in _torque_range(model, a)])
    return out


def tracked_model(model, controller: dict):
    """A copy of ``model`` whose motors follow ``controller`` (:func:`tracking_controller`).

    ``model`` is the one the controller was made for, or one with the same actuators (e.g.
    :func:`~pysindy_xl.export.mjcf.identified_mj_model`); its tracked actuators become
    ``position`` servos (gain ``kp``, bias ``(0, -kp, -kv)``), controls limited to
    ``ctrlrange``, forces to ``forcerange``.

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.
    controller : dict
        The description returned by :func:`tracking_controller`.

    Returns
    -------
    mujoco.MjModel
        A copy of ``model`` with the tracked motors turned into position servos.

    Examples
    --------
    >>> import mujoco
    >>> model = mujoco.MjModel.from_xml_string('''<mujoco><worldbody><body>
    ...   <joint name="j" axis="0 1 0" range="-2 2"/>
    ...   <inertial pos="0 0 -0.5" mass="1" diaginertia="1e-6 1e-6 1e-6"/></body></worldbody>
    ...   <actuator><motor joint="j"/></actuator></mujoco>''')
    >>> servo = tracked_model(model, {"actuators": [0], "kp": [100.0], "kv": [10.0],
    ...                               "ctrlrange": [[-2.0, 2.0]], "forcerange": [[-5, 5]]})
    >>> servo.actuator_biasprm[0, :3], servo.actuator_forcerange[0]
    (array([   0., -100.,  -10.]), array([-5.,  5.]))
    """
    import copy
    mujoco = import_mujoco()
    out = copy.deepcopy(model)
    for i, a in enumerate(controller["actuators"]):
        if not 0 <= int(a) < model.nu:
            raise ValueError(f"controller: actuator {a} is not one of the model's {model.nu}")
        kp, kv = float(controller["kp"][i]), float(controller["kv"][i])
        out.actuator_gaintype[a] = int(mujoco.mjtGain.mjGAIN_FIXED)
        out.actuator_biastype[a] = int(mujoco.mjtBias.mjBIAS_AFFINE)
        out.actuator_gainprm[a, :3] = (kp, 0.0, 0.0)
        out.actuator_biasprm[a, :3] = (0.0, -kp, -kv)
        out.actuator_ctrllimited[a] = 1
        out.actuator_ctrlrange[a] = controller["ctrlrange"][i]
        low, high = (np.inf * sign if v is None else float(v)
                     for v, sign in zip(controller["forcerange"][i], (-1, 1), strict=True))
        out.actuator_forcelimited[a] = int(np.isfinite(low) or np.isfinite(high))
        out.actuator_forcerange[a] = (low if np.isfinite(low) else -1e30,
                                      high if np.isfinite(high) else 1e30)
    return out
