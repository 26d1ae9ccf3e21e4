"""Tracking control of plain torque motors: a PD loop that makes them follow a position
reference, as the controller of a real arm does.

Random torques excite an arm only if its motors can hold it against gravity; otherwise it
falls onto its joint stops. :func:`tracking_controller` designs a PD controller per motor from
the MJCF's own model and :func:`tracked_model` writes it into a copy of the compiled model as
``position`` servos (the motors' torque limits kept), so that MuJoCo's actuator law
(:mod:`~pysindy_xl.mujoco.systems.actuation`) is the controller: generation, the actuator law
of closed-loop validation and the identified model stepped by MuJoCo all use it unchanged.
"""

from __future__ import annotations

import numpy as np

from .. import import_mujoco
from .actuation import _supported

__all__ = ["tracking_controller", "tracked_model", "plain_motors", "gravity_torques",
           "TRACKING_BANDWIDTH", "TRACKING_ERROR"]

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
    return (_supported(model, a)
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
    """Which actuators are plain torque motors (fixed gain, no bias) on a limited hinge or
    slide joint: those :func:`tracking_controller` can make track a reference.

    Parameters
    ----------
    model : mujoco.MjModel

    Returns
    -------
    ndarray of bool, shape (nu,)
    """
    return np.array([_plain_motor(model, a) for a in range(model.nu)], dtype=bool)


def gravity_torques(model, poses) -> np.ndarray:
    """Gravity's generalized forces (MuJoCo's ``qfrc_bias`` at rest) at each pose.

    Parameters
    ----------
    model : mujoco.MjModel
    poses : array, shape (P, nq)

    Returns
    -------
    ndarray, shape (P, nv)
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

    Random torques cannot excite an arm whose motors carry its weight: open loop it falls
    onto its joint stops, and every sample is constrained. A controller that tracks a
    reference inside the joint ranges keeps it there, as on a real robot; the recorded input
    is still the motor torque. Each motor ``a`` on joint ``j`` (gear ``g``) becomes the servo
    ``F = kp (ctrl - g q_j) - kv g qd_j`` (MuJoCo's ``position`` actuator: the reference
    ``ctrl / g`` is a control signal like any other, the controller a state-dependent
    actuator law), within the motor's own force range, with the joint stiffness ``K`` and
    damping ``D`` (``kp = K / g^2``, ``kv = D / g^2``)

    .. math::

        K = \\max\\Big(m\\,\\omega^2,\\;
            \\frac{\\max_q |g_j(q)| + f_j}{e\\,(q_j^{\\max} - q_j^{\\min})}\\Big),
        \\qquad D = 2\\sqrt{K m}

    (``m``: the joint's diagonal of ``mj_fullM`` at the reference pose, armature included;
    ``g_j(q)``: gravity's torque at ``n_poses`` random poses in the ranges; ``f_j``: dry
    friction; ``omega = TRACKING_BANDWIDTH``, ``e = TRACKING_ERROR``): critically damped, as
    fast as ``omega`` and stiff enough that the largest static load moves the joint by at
    most ``e`` of its range. The joint's own damping slows the loop; the references are kept
    within the loop's actual bandwidth
    (:func:`~pysindy_xl.mujoco.systems.actuation.servo_bandwidths`, with that damping) by
    :func:`~pysindy_xl.mujoco.simulation.forcing.within_servo_reach`.

    Parameters
    ----------
    model : mujoco.MjModel
    actuators : array of int, optional
        Candidate actuators (default all); those that are plain motors on limited hinge or
        slide joints are tracked.
    n_poses : int, default 16
        Random poses at which gravity is evaluated.
    seed : int, default 0

    Returns
    -------
    dict or None
        ``actuators`` (indices), ``kp``, ``kv``, ``ctrlrange`` (the joint ranges in actuator
        length units) and ``forcerange`` (the motors' force ranges, None where unbounded): a JSON
        description for :func:`tracked_model`; None when no actuator qualifies.

    Examples
    --------
    A 1 kg pendulum of 0.5 m on a motor, range +-2 rad: gravity's 4.9 N m over 2 % of
    the 4 rad range asks a stiffness of 61 N m / rad, above ``m omega^2`` (0.25 kg m^2
    at 10 pi rad/s: 247):

    >>> import mujoco
    >>> model = mujoco.MjModel.from_xml_string('''<mujoco><worldbody><body>
    ...   <joint name="j" axis="0 1 0" range="-2 2"/>
    ...   <inertial pos="0 0 -0.5" mass="1" diaginertia="1e-6 1e-6 1e-6"/></body></worldbody>
    ...   <actuator><motor joint="j"/></actuator></mujoco>''')
    >>> controller = tracking_controller(model)
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

    Parameters
    ----------
    model : mujoco.MjModel
        The model the controller was made for, or one with the same actuators (e.g. the
        identified model of :func:`~pysindy_xl.export.mjcf.identified_mj_model`).
    controller : dict
        As returned by :func:`tracking_controller` (or read back from JSON).

    Returns
    -------
    mujoco.MjModel
        Its tracked actuators are ``position`` servos (gain ``kp``, bias ``(0, -kp, -kv)``),
        controls limited to ``ctrlrange``, forces to ``forcerange``.

    Raises
    ------
    ValueError
        If ``controller`` names an actuator the model does not have.

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
