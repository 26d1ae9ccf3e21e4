"""MuJoCo's dry friction: how the solver regularizes a dof's ``frictionloss``."""

from __future__ import annotations

import numpy as np

from .. import import_mujoco

__all__ = ["dry_friction_scales", "sliding_velocities"]


def dry_friction_scales(model) -> tuple[np.ndarray, np.ndarray]:
    """How MuJoCo regularizes each degree of freedom's ``frictionloss``: a velocity scale
    ``s`` and a lead time ``tau``.

    MuJoCo applies dry friction as a soft constraint row on the dof (its force ``f``, its
    acceleration ``a``, velocity ``v``); the solver minimizes a Huber cost, so that

    .. math:: f = -F \\, \\mathrm{sat}\\!\\left(\\frac{a + b v}{R F}\\right)
              = -F \\, \\mathrm{sat}\\!\\left(\\frac{v + \\tau a}{s}\\right),
              \\qquad \\mathrm{sat}(x) = \\max(-1, \\min(1, x)),

    with ``F`` the frictionloss, ``b = 2 / (d_max t_c)`` the reference damping of
    ``solreffriction = (t_c, zeta)`` (``t_c`` at least twice the time step; a negative
    ``solref`` gives ``b = -solref[1] / d_max`` directly), ``R = (1 - d_0) / d_0 w_0`` the
    regularizer from the impedance ``d_0`` of ``solimpfriction`` at zero violation (its
    ``d_min``) and the dof's inverse inertia at ``qpos0`` (``dof_invweight0``). Hence
    ``tau = 1 / b`` and ``s = R F / b``. The friction saturates at ``+-F`` only once the velocity
    predicted ``tau`` ahead exceeds ``s``; below it acts as a damping ``b / R`` plus an inertia
    ``1 / R``, which on a light link (large ``w_0``) may exceed the link's own.

    Parameters
    ----------
    model : mujoco.MjModel

    Returns
    -------
    scale, lead : ndarray, shape (nv,)
        ``s`` (velocity units of the dof; zero where ``frictionloss`` is zero) and ``tau`` (s).

    Examples
    --------
    >>> import mujoco
    >>> model = mujoco.MjModel.from_xml_string(
    ...     '<mujoco><worldbody><body><joint frictionloss="2"/><geom size=".1" mass="1"/>'
    ...     '</body></worldbody></mujoco>')
    >>> scale, lead = dry_friction_scales(model)
    >>> round(float(lead[0]), 6)  # d_max t_c / 2: default solref (0.02, 1), d_max 0.95
    0.0095
    """
    solref, solimp = model.dof_solref, model.dof_solimp
    d_min = np.clip(solimp[:, 0], 1e-4, 0.9999)  # MuJoCo's mjMINIMP, mjMAXIMP
    d_max = np.clip(solimp[:, 1], 1e-4, 0.9999)
    timeconst = solref[:, 0]
    if not model.opt.disableflags & int(import_mujoco().mjtDisableBit.mjDSBL_REFSAFE):
        timeconst = np.maximum(timeconst, 2 * model.opt.timestep)
    damping = np.where(solref[:, 0] > 0, 2 / (d_max * np.maximum(timeconst, 1e-300)),
                       -solref[:, 1] / d_max)
    regularizer = (1 - d_min) / d_min * model.dof_invweight0
    return regularizer * model.dof_frictionloss / damping, 1 / damping


def sliding_velocities(system, model, q, qd, margin: float = 2.0) -> np.ndarray:
    """``qd`` with every joint speed raised to at least ``margin`` times its sticking scale.

    Where every joint slides, MuJoCo's dry friction is ``-F sign(v)`` and its mass matrix the
    rigid body's (``mj_fullM``): a model with MuJoCo's regularized dry friction matches both
    only there.

    Parameters
    ----------
    system : MuJoCoSystem
    model : mujoco.MjModel
        Whose scales (:func:`dry_friction_scales`) apply; one dof per joint.
    q, qd : ndarray, shape (N, n)
        States in the system's coordinates.
    margin : float, default 2.0

    Returns
    -------
    ndarray, shape (N, n)
        The velocities in the coordinates (unchanged without ``frictionloss``).
    """
    qpos, qvel = system.from_generalized(q, qd)
    least = margin * dry_friction_scales(model)[0]
    qvel = np.where(qvel < 0, -1.0, 1.0) * np.maximum(np.abs(qvel), least)
    return system.to_generalized(qpos, qvel)[1]
