"""What drives a generated run's actuators: random signals (:func:`actuator_signals`: forces
for motors, references for servos) and, when torque motors cannot hold the arm, a controller
that tracks them as references (:func:`motor_tracking`).
"""

from __future__ import annotations

import numpy as np

from .._optional import import_mujoco
from ..mujoco.systems.registry import MuJoCoSystem
from ..mujoco.systems.tracking import gravity_torques, plain_motors, tracking_controller
from .forcing import FORCING_MODES, SumOfSinusoids, within_servo_reach

__all__ = ["actuator_signals", "motor_tracking", "CONTROLS"]

#: How plain torque motors are driven (see :func:`motor_tracking`).
CONTROLS = ("auto", "open-loop", "tracking")
#: Default peak of a tracked motor's reference, as a fraction of its joint's half range (the
#: controller keeps the joint near it, so it may span most of the range).
TRACKED_AMPLITUDE = 0.9


def _actuators(model) -> list[tuple[str, str | None]]:
    """(actuator name, driven joint name or None) for each actuator of the model."""
    mujoco = import_mujoco()
    on_joint = int(mujoco.mjtTrn.mjTRN_JOINT)
    return [(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) or f"actuator{a}",
             mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, model.actuator_trnid[a, 0])
             if int(model.actuator_trntype[a]) == on_joint else None) for a in range(model.nu)]


def _driven_mask(system: MuJoCoSystem, model, forcing: str, actuators) -> np.ndarray:
    pairs = _actuators(model)
    if forcing == "implicit":
        if actuators:
            raise ValueError("actuators: not used with forcing='implicit' (no force applied)")
        return np.zeros(len(pairs), dtype=bool)
    if forcing == "explicit":
        if actuators:
            raise ValueError("actuators: not used with forcing='explicit' (every actuator driven)")
        if not pairs:
            raise ValueError("forcing: the model has no actuator; add <motor> elements to the MJCF "
                             "or use forcing='implicit'")
        return np.ones(len(pairs), dtype=bool)
    chosen = system.mixed_actuators if actuators is None else actuators
    chosen = [chosen] if isinstance(chosen, str) else list(chosen)
    known = {name for pair in pairs for name in pair if name}
    unknown = [c for c in chosen if c not in known]
    if unknown or not chosen:
        raise ValueError(f"actuators: expected a non-empty list of actuator or joint names among "
                         f"{sorted(known)}, got {chosen!r}")
    return np.array([name in chosen or joint in chosen for name, joint in pairs])


def checked_fraction(value, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name}: expected a number in (0, 1], got {value!r}")
    value = float(value)
    if not (np.isfinite(value) and 0 < value <= 1):
        raise ValueError(f"{name}: expected a number in (0, 1], got {value!r}")
    return value


def actuator_signals(system: MuJoCoSystem, model, forcing: str, rng: np.random.Generator,
                     actuators=None, n_components: int = 6, max_frequency: float = 1.5,
                     amplitude_scale: float = 1.0, amplitude=None,
                     backoff: float = 1.0, tracking=None) -> SumOfSinusoids | None:
    """Random control signals (one per actuator of ``model``) for a forcing mode.

    Undriven actuators get zero; an actuator with a ``ctrlrange`` oscillates around its
    middle, the others with ``system.force_amplitudes`` (by joint) times ``amplitude_scale``;
    a position servo's reference is kept within its reach
    (:func:`~pysindy_xl.simulation.forcing.within_servo_reach`). None with implicit
    forcing.

    Parameters
    ----------
    system : MuJoCoSystem
        Gives the force amplitudes and the default actuators of the ``mixed`` mode.
    model : mujoco.MjModel
        The compiled model, whose actuators get the signals.
    forcing : {"implicit", "explicit", "mixed"}
        As in :func:`~pysindy_xl.mujoco.generate_dataset`.
    rng : numpy.random.Generator
        The random generator.
    actuators : sequence of str, default=None
        As in :func:`~pysindy_xl.mujoco.generate_dataset`.
    n_components : int, default=6
        Sinusoids per signal.
    max_frequency : float, default=1.5
        The highest frequency (Hz).
    amplitude_scale : float, default=1.0
        Multiplies ``system.force_amplitudes`` for actuators without ``ctrlrange``.
    amplitude : float, optional
        Peak as a fraction of the ``ctrlrange`` half-width, in (0, 1]; also multiplies the
        others. Default: 0.5 of the range (``TRACKED_AMPLITUDE`` for tracked motors), 1 else.
    backoff : float, default=1.0
        Multiplies every amplitude.
    tracking : dict, optional
        The controller of :func:`motor_tracking` when ``model`` is the tracked model.

    Returns
    -------
    SumOfSinusoids or None
        One signal per actuator, or None with implicit forcing.

    Examples
    --------
    >>> from pysindy_xl.mujoco import get_system
    >>> system = get_system("cart-pole")
    >>> signals = actuator_signals(system, system.mj_model(), "mixed", np.random.default_rng(0))
    >>> signals.n_signals, signals.amplitudes.sum(axis=1)  # slider driven, hinge free
    (2, array([3., 0.]))
    """
    if forcing not in FORCING_MODES:
        raise ValueError(f"forcing: expected one of {FORCING_MODES}, got {forcing!r}")
    driven = _driven_mask(system, model, forcing, actuators)
    if not driven.any():
        return None
    scales, offsets = _scales(system, model, amplitude_scale, amplitude, tracking)
    scales = np.where(driven, scales * float(backoff), 0.0)
    offsets = np.where(driven, offsets, 0.0)
    signals = SumOfSinusoids.random(scales, rng, n_components=n_components,
                                    max_frequency=max_frequency, offsets=offsets)
    return within_servo_reach(signals, model)


def _scales(system, model, amplitude_scale, amplitude, tracking=None):
    """Peak and offset of each actuator's random signal (see :func:`actuator_signals`)."""
    if amplitude is not None:
        amplitude = checked_fraction(amplitude, "amplitude")
    amplitudes = system.force_amplitudes
    tracked = set() if tracking is None else set(tracking["actuators"])
    scales, offsets = np.zeros(model.nu), np.zeros(model.nu)
    for a, (_, joint) in enumerate(_actuators(model)):
        if model.actuator_ctrllimited[a]:
            low, high = model.actuator_ctrlrange[a]
            default = TRACKED_AMPLITUDE if a in tracked else 0.5
            fraction = default if amplitude is None else amplitude
            scales[a], offsets[a] = fraction * (high - low) / 2, (high + low) / 2
        else:
            scales[a] = amplitudes.get(joint, 1.0) * amplitude_scale * (
                1.0 if amplitude is None else amplitude)
    return scales, offsets


def motor_tracking(system, model, forcing: str = "explicit", actuators=None,
                   amplitude_scale: float = 1.0, amplitude=None,
                   control: str = "auto") -> dict | None:
    """The controller with which a run's plain torque motors track their signals, or None.

    Where gravity outweighs a motor's random torque the arm falls onto its stops; tracked,
    each driven plain motor on a limited joint follows its signal as a position reference
    (:func:`~pysindy_xl.mujoco.systems.tracking.tracking_controller`), the recorded input
    being the torque it applies. ``forcing``, ``actuators``, ``amplitude_scale`` and
    ``amplitude`` as in :func:`actuator_signals`.

    ``control``: ``"open-loop"``, the signals are torques; ``"tracking"``, every driven plain
    motor on a limited joint tracks (ValueError where there is none); ``"auto"``, tracking
    when some of them has a random peak below gravity's torque at the reference pose.

    The paper's pendulums have no joint limits: their motors are driven open loop.

    Parameters
    ----------
    system : MuJoCoSystem
        The system.
    model : mujoco.MjModel
        The compiled model.
    forcing : str, default="explicit"
        As in :func:`~pysindy_xl.mujoco.generate_dataset`.
    actuators : sequence of str, default=None
        As in :func:`~pysindy_xl.mujoco.generate_dataset`.
    amplitude_scale : float, default=1.0
        As in :func:`actuator_signals`.
    amplitude : float, default=None
        As in :func:`actuator_signals`.
    control : {"auto", "open-loop", "tracking"}, default="auto"
        How plain torque motors are driven (see above).

    Returns
    -------
    dict or None
        The controller of :func:`~pysindy_xl.mujoco.systems.tracking.tracking_controller`, or
        None when the motors are driven open loop.

    Examples
    --------
    >>> from pysindy_xl.mujoco import get_system
    >>> system = get_system("double-pendulum")
    >>> print(motor_tracking(system, system.mj_model()))
    None
    """
    if control not in CONTROLS:
        raise ValueError(f"control: expected one of {CONTROLS}, got {control!r}")
    if control == "open-loop" or forcing == "implicit":
        return None
    candidates = np.flatnonzero(_driven_mask(system, model, forcing, actuators)
                                & plain_motors(model))
    if control == "auto":
        if not len(candidates):
            return None
        scales, _ = _scales(system, model, amplitude_scale, amplitude)
        gravity = gravity_torques(model, [model.qpos0])[0]
        dof = model.jnt_dofadr[model.actuator_trnid[candidates, 0]]
        torque = scales[candidates] * np.abs(model.actuator_gainprm[candidates, 0]
                                             * model.actuator_gear[candidates, 0])
        if not np.any(torque < np.abs(gravity[dof])):
            return None
    controller = tracking_controller(model, candidates)
    if controller is None and control == "tracking":
        raise ValueError("control: 'tracking' needs a driven plain torque motor on a limited "
                         "hinge or slide joint; the model has none")
    return controller
