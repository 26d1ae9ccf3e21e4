"""MuJoCo's dry friction: how the solver regularizes a dof's ``frictionloss``."""

from __future__ import annotations

import numpy as np

from ..._optional import import_mujoco

__all__ = ["dry_friction_scales", "sliding_velocities"]


def dry_friction_scales(model) -> tuple[np.ndarray, np.ndarray]:
    """How MuJoCo regularizes each dof's ``frictionloss``: velocity scale ``s`` and lead ``tau``.

    Dry friction is a soft constraint row; the solver's Huber cost gives

    .. math:: f = -F \\, \\mathrm{sat}\\!\\left(\\frac{a + b v}{R F}\\right)
              = -F \\, \\mathrm{sat}\\!\\left(\\frac{v + \\tau a}{s}\\right),
              \\qquad \\mathrm{sat}(x) = \\max(-1, \\min(1, x)),

    ``F`` the frictionloss, ``b = 2 / (d_max t_c)`` the reference damping of
    ``solreffriction`` (``t_c`` at least twice the step; a negative ``solref`` gives
    ``b = -solref[1] / d_max``), ``R = (1 - d_0) / d_0 w_0`` from ``solimpfriction``'s
    ``d_min`` and ``dof_invweight0``: ``tau = 1 / b``, ``s = R F / b`` (shape (nv,) each).
    Below saturation it acts as a damping ``b / R`` plus an inertia ``1 / R``.

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.

    Returns
    -------
    scale : numpy.ndarray of shape (nv,)
        The velocity scale ``s`` of each degree of freedom.
    lead : numpy.ndarray of shape (nv,)
        The lead time ``tau`` of each degree of freedom (s).

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
    """``qd`` (N, n) with every joint speed raised to at least ``margin`` times its sticking
    scale (:func:`dry_friction_scales` of ``model``): where every joint slides, MuJoCo's dry
    friction is ``-F sign(v)`` and its mass matrix the rigid body's.

    Parameters
    ----------
    system : MuJoCoSystem
        The system (maps generalized velocities to joint velocities).
    model : mujoco.MjModel
        The compiled model whose ``frictionloss`` acts.
    q, qd : array_like of shape (N, n)
        Generalized positions and velocities.
    margin : float, default=2.0
        Least joint speed, in multiples of the sticking scale.

    Returns
    -------
    numpy.ndarray of shape (N, n)
        The generalized velocities, each joint speed raised where it was below the margin.
    """
    qpos, qvel = system.from_generalized(q, qd)
    least = margin * dry_friction_scales(model)[0]
    qvel = np.where(qvel < 0, -1.0, 1.0) * np.maximum(np.abs(qvel), least)
    return system.to_generalized(qpos, qvel)[1]
