"""The MuJoCo runs of a validation: the fresh reference trajectory, and the identified model
stepped by MuJoCo in closed loop (:mod:`~pysindy_xl.evaluation.validation`)."""

from __future__ import annotations

import numpy as np

from ..data.dataset import Trajectory
from ..mujoco.systems.actuation import start_on_reference
from ..mujoco.systems.registry import get_system
from ..mujoco.systems.tracking import tracked_model
from ..simulation.forcing import FORCING_MODES, SumOfSinusoids
from ..simulation.generate import actuator_signals, simulate_trajectory
from ..simulation.integration import UnstableSimulationError, choose_integration
from ..simulation.signals import motor_tracking

__all__ = ["validation_trajectory"]


def validation_trajectory(system, duration: float = 10.0, forcing: str = "explicit",
                          actuators=None, seed=None, sample_every: int = 10,
                          initial_scale: float = 1.0, substeps: int = 4,
                          backoff: bool = True, integrator: str = "auto",
                          control: str = "auto", **signal_options) -> Trajectory:
    """A fresh noise-free MuJoCo trajectory with random initial state and forcing.

    Parameters
    ----------
    system : MuJoCoSystem or str
    duration : float, default 10.0
        Simulated time (s).
    forcing, actuators, seed, sample_every, initial_scale, integrator, control
        As in :func:`generate_dataset`.
    substeps : int, default 4
        MuJoCo internal steps per model step (with ``integrator="auto"`` at least this many).
    backoff : bool, default True
        When a constraint acts, draw again with half the forcing amplitude and initial
        spread (at most three times); keep the draw whose first constraint comes latest.
    **signal_options
        ``n_components``, ``max_frequency``, ``amplitude_scale``, ``amplitude``.

    Returns
    -------
    Trajectory
        Clean, with the constraint data; ``info["signals"]`` holds the controls (None when no
        actuator is driven: zero controls).

    Examples
    --------
    >>> trajectory = validation_trajectory("double-pendulum", duration=0.5, forcing="implicit",
    ...                                    seed=0)
    >>> trajectory.t[:3], trajectory.q.shape, bool((trajectory.tau == 0).all())
    (array([0.  , 0.01, 0.02]), (51, 2), True)
    """
    system = get_system(system)
    if forcing not in FORCING_MODES:
        raise ValueError(f"forcing: expected one of {FORCING_MODES}, got {forcing!r}")
    rng = np.random.default_rng(seed)
    model = system.mj_model()
    controller = motor_tracking(system, model, forcing, actuators,
                                signal_options.get("amplitude_scale", 1.0),
                                signal_options.get("amplitude"), control)
    if controller is not None:
        model = tracked_model(model, controller)
    integration = choose_integration(model, integrator, substeps)
    best, best_start, factor = None, -1, 1.0
    for _ in range(4 if backoff else 1):
        q0, qd0 = system.random_initial_state(rng, scale=initial_scale * factor)
        signals = actuator_signals(system, model, forcing, rng, actuators, backoff=factor,
                                   tracking=controller, **signal_options)
        q0, qd0 = start_on_reference(system, signals, q0, qd0, model)
        trajectory = simulate_trajectory(system, duration, signals, q0, qd0, sample_every,
                                         control_at="midpoint", integrator=integration,
                                         mj_model=model)
        trajectory.info.setdefault("signals", None)  # the controls are known: zero
        if controller is not None:
            trajectory.info["tracking"] = controller
        active = trajectory.constraint_active
        start = int(np.argmax(active)) if active.any() else len(active)
        if factor < 1:
            trajectory.info["backoff"] = factor
        if start > best_start:
            best, best_start = trajectory, start
        if start == len(active):
            break
        factor /= 2
    return best


def mujoco_closed_loop(model, system, trajectory, substeps, required):
    """``(states, failure)`` of the identified model stepped by MuJoCo under the MJCF's
    actuators (and the reference's tracking controller) and the reference's controls (the
    ``mujoco`` simulator of :mod:`~pysindy_xl.evaluation.validation`), or None where
    MuJoCo cannot state the model (a ValueError when ``required``).

    Parameters
    ----------
    model : pysindy_xl.XLSINDy
        The identified model.
    system : MuJoCoSystem
        The system whose MJCF actuators drive the model.
    trajectory : Trajectory
        The reference, with its controls in ``info["signals"]``.
    substeps : int
        MuJoCo steps per sample.
    required : bool
        Raise a ValueError where MuJoCo cannot state the model, instead of returning None.

    Returns
    -------
    tuple or None
        ``(states, failure)``: states (k, 2n) and why the run stopped early (or None); None
        where MuJoCo cannot state the model.
    """
    from .._optional import import_mujoco
    from ..export.mjcf import identified_mj_model
    mujoco = import_mujoco()
    mj, reason = identified_mj_model(model, system)
    if mj is not None and trajectory.info.get("tracking") is not None:
        mj = tracked_model(mj, trajectory.info["tracking"])  # the reference's controller
    t = trajectory.t
    timestep = float(mj.opt.timestep) if mj is not None else 0.0
    every = int(round((t[1] - t[0]) / timestep)) if mj is not None else 0
    if mj is not None and not (t[0] == 0 and every >= 1 and np.allclose(
            np.diff(t), every * timestep)):
        mj, reason = None, "the reference is not sampled on the model's time steps from t = 0"
    if mj is None:
        if required:
            raise ValueError(f"simulator: MuJoCo cannot step this model: {reason}")
        return None
    signals = trajectory.info["signals"]
    signals = None if signals is None else SumOfSinusoids.from_dict(signals)
    mj.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_LIMIT) | int(
        mujoco.mjtDisableBit.mjDSBL_CONTACT)
    integration = choose_integration(mj, "auto", substeps)
    try:
        run = simulate_trajectory(system, t[-1], signals, trajectory.q[0], trajectory.qd[0], every,
                                  control_at="midpoint", integrator=integration, mj_model=mj)
    except UnstableSimulationError as error:
        return trajectory.state[:0], f"diverged ({error})"
    return run.state[:len(t)], None
