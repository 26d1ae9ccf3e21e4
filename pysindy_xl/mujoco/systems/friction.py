"""MuJoCo's dry friction: how the solver regularizes a dof's ``frictionloss``."""

from __future__ import annotations

import numpy as np

from .. import import_mujoco

__all__ = ["dry_friction_scales"]


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
