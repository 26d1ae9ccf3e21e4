"""Validation of an identified model against a fresh MuJoCo trajectory.

The model is simulated from the initial state of a new, noise-free MuJoCo trajectory, driven
the way MuJoCo was (``ValidationResult.drive``): ``open-loop``, the forces MuJoCo applied as a
function of time (the exact signal of joint motors, else a cubic spline of the recorded
forces); ``closed-loop``, for servos, the MJCF's actuator law
(:func:`~pysindy_xl.mujoco.actuation.actuator_law`) under the run's reference controls, acting
on the model's own state, stepped (``ValidationResult.simulator``) by MuJoCo on a copy of the
model carrying the identified parameters (``mujoco``, where that reproduces ``M`` and ``f``
exactly) or by ``model.simulate`` (``model``). :doc:`/robot_arms` explains why.

Metrics: ``position_rmse``, the RMS position error over the whole horizon (inf when the model
stopped early); ``simulated_rmse``, the same over the simulated part; ``divergence_time``,
the first time some coordinate's error exceeds ``divergence_bound * max(1, ptp_i)`` (``ptp_i``
its range in the reference) or the simulation failed; ``force_error`` (closed loop), the RMS
of the actuator forces along the model's run minus MuJoCo's, relative to MuJoCo's; ``valid``,
simulated to the end, never diverged and, in closed loop, ``force_error <= force_bound``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline

from ..data.dataset import Trajectory
from ..mujoco.systems.actuation import actuator_law
from ..mujoco.systems.registry import get_system
from ..mujoco.systems.tracking import tracked_model
from ..simulation.forcing import SumOfSinusoids
from .physics import compare_physics
from .runs import mujoco_closed_loop, validation_trajectory

__all__ = ["ValidationResult", "validate_model", "compare_trajectories",
           "validation_trajectory", "DEFAULT_DIVERGENCE_BOUND", "DEFAULT_FORCE_BOUND", "DRIVES",
           "SIMULATORS", "compare_physics"]

DEFAULT_DIVERGENCE_BOUND = 0.2

#: How :func:`validate_model` drives the identified model (see the module docstring).
DRIVES = ("auto", "closed-loop", "open-loop")

#: What steps the identified model in closed loop (see the module docstring).
SIMULATORS = ("auto", "mujoco", "model")

DEFAULT_FORCE_BOUND = 0.05


@dataclass
class ValidationResult:
    """Comparison of a model's simulation with a MuJoCo trajectory.

    Made by :func:`compare_trajectories` or :func:`validate_model`; the metrics are those of
    the module docstring.

    Parameters
    ----------
    t : numpy.ndarray of shape (T,)
        Sample times (s).
    reference : numpy.ndarray of shape (T, 2n)
        MuJoCo's states ``[q, qd]``.
    prediction : numpy.ndarray of shape (k, 2n)
        The model's states at ``t[:k]`` (``k < T`` when its simulation failed).
    forces : numpy.ndarray of shape (T, n)
        The forces given to the model (closed loop: MuJoCo's actuator forces).
    position_rmse : float
        RMS position error over the whole horizon (inf when the model stopped early).
    position_rmse_per_coordinate : numpy.ndarray of shape (n,)
        The same per coordinate.
    divergence_time : float or None
        The first time some coordinate's error exceeds ``divergence_bound * max(1, ptp_i)``
        (``ptp_i`` its range in the reference) or the simulation failed (s); None if never.
    valid : bool
        The verdict: simulated to the end, never diverged and, in closed loop,
        ``force_error <= force_bound``.
    failure : str or None
        Why the simulation stopped early, or None.
    divergence_bound : float
        The bound of the divergence test.
    coordinate_names : tuple of str, default=()
        Names of the coordinates.
    simulated_rmse : float, default=nan
        Position RMSE over the part the model simulated.
    constrained_at : float or None, default=None
        When a constraint started to act in the reference, where the comparison stopped.
    drive : {"open-loop", "closed-loop"}, default="open-loop"
        How the model was driven.
    force_error : float or None, default=None
        Closed loop: relative RMS difference of the actuator forces along the two runs.
    simulator : {"model", "mujoco"}, default="model"
        What stepped the model.

    Examples
    --------
    A prediction that stops half-way:

    >>> t = np.linspace(0.0, 0.9, 10)
    >>> reference = np.column_stack([np.sin(t), np.cos(t)])
    >>> result = compare_trajectories(t, reference, reference[:5], failure="diverged")
    >>> result.n, result.simulated_fraction, result.valid, result.divergence_time
    (1, 0.5, False, 0.5)
    """

    t: np.ndarray
    reference: np.ndarray
    prediction: np.ndarray
    forces: np.ndarray
    position_rmse: float
    position_rmse_per_coordinate: np.ndarray
    divergence_time: float | None
    valid: bool
    failure: str | None
    divergence_bound: float
    coordinate_names: tuple = field(default_factory=tuple)
    simulated_rmse: float = float("nan")
    constrained_at: float | None = None
    drive: str = "open-loop"
    force_error: float | None = None
    simulator: str = "model"

    @property
    def n(self) -> int:
        """Number of coordinates."""
        return self.reference.shape[1] // 2

    @property
    def simulated_fraction(self) -> float:
        """Fraction of the horizon the model could simulate."""
        return len(self.prediction) / len(self.t)

    def to_dict(self) -> dict:
        """JSON-serializable summary: the metrics and fields, ``horizon`` (s), no arrays.

        Returns
        -------
        dict
            The metrics and scalar fields, ``horizon`` (s) and ``simulated_fraction``.

        Examples
        --------
        >>> import json
        >>> t = np.linspace(0.0, 1.0, 11)
        >>> reference = np.column_stack([t, np.ones_like(t)])
        >>> result = compare_trajectories(t, reference, reference, coordinate_names=["x"])
        >>> print(json.dumps(result.to_dict()))
        {"position_rmse": 0.0, "position_rmse_per_coordinate": {"x": 0.0},
         "divergence_time": null, "valid": true, "failure": null, "divergence_bound": 0.2,
         "horizon": 1.0, "simulated_fraction": 1.0, "simulated_rmse": 0.0,
         "constrained_at": null, "drive": "open-loop", "force_error": null,
         "simulator": "model"}
        """
        return {"position_rmse": float(self.position_rmse),
                "position_rmse_per_coordinate": dict(zip(
                    self.coordinate_names, map(float, self.position_rmse_per_coordinate),
                    strict=True)),
                "divergence_time": self.divergence_time,
                "valid": bool(self.valid),
                "failure": self.failure,
                "divergence_bound": self.divergence_bound,
                "horizon": float(self.t[-1] - self.t[0]),
                "simulated_fraction": float(self.simulated_fraction),
                "simulated_rmse": float(self.simulated_rmse),
                "constrained_at": self.constrained_at,
                "drive": self.drive,
                "force_error": self.force_error,
                "simulator": self.simulator}


def compare_trajectories(t, reference, prediction, divergence_bound=DEFAULT_DIVERGENCE_BOUND,
                         failure=None, coordinate_names=None, forces=None) -> ValidationResult:
    """Metrics of a predicted trajectory against a reference (see the module docstring).

    Parameters
    ----------
    t : array_like of shape (T,)
        Sample times (s).
    reference : array_like of shape (T, 2n)
        Reference states ``[q, qd]``.
    prediction : array_like of shape (k, 2n), k <= T
        Predicted states at ``t[:k]`` (shorter when the prediction stopped early).
    divergence_bound : float, default=DEFAULT_DIVERGENCE_BOUND
        Position error beyond which the prediction has diverged.
    failure : str or None, default=None
        Why the prediction stopped early.
    coordinate_names : sequence of str, default=None
        Names of the coordinates; None: ``q0, q1, ...``.
    forces : array_like of shape (T, n), default=None
        The forces that drove the run, kept for the plots.

    Returns
    -------
    ValidationResult
        The metrics and the trajectories.

    Raises
    ------
    ValueError
        When the shapes do not match.

    Examples
    --------
    >>> t = np.linspace(0, 1, 11)
    >>> ref = np.column_stack([t, np.ones_like(t)])
    >>> r = compare_trajectories(t, ref, ref + [0.01, 0.0])
    >>> round(r.position_rmse, 6), r.valid
    (0.01, True)
    """
    t = np.asarray(t, dtype=float)
    reference = np.asarray(reference, dtype=float)
    prediction = np.asarray(prediction, dtype=float)
    if reference.ndim != 2 or reference.shape[0] != len(t) or reference.shape[1] % 2:
        raise ValueError(f"reference: expected shape (len(t), 2n), got {reference.shape}")
    if prediction.ndim != 2 or prediction.shape[1] != reference.shape[1] or len(
        prediction
    ) > len(t):
        raise ValueError(f"prediction: expected shape (k <= {len(t)}, {reference.shape[1]}), got "
                         f"{prediction.shape}")
    if not np.isfinite(divergence_bound) or divergence_bound <= 0:
        raise ValueError(f"divergence_bound: expected a positive number, got {divergence_bound!r}")
    n = reference.shape[1] // 2
    k = len(prediction)
    finite = np.all(np.isfinite(prediction), axis=1)
    if not finite.all():  # keep only the finite prefix
        k = int(np.argmin(finite))
        prediction = prediction[:k]
        failure = failure or "non-finite state"
    if k < len(t) and failure is None:
        failure = "incomplete prediction"
    error = prediction[:, :n] - reference[:k, :n]
    simulated = float(np.sqrt(np.mean(error**2))) if k else np.inf
    # a model that could not follow the whole horizon has no finite error over it
    per_coordinate, rmse = ((np.sqrt(np.mean(error**2, axis=0)), simulated) if k == len(t)
                            else (np.full(n, np.inf), np.inf))
    scale = np.maximum(1.0, np.ptp(reference[:, :n], axis=0))
    exceeded = np.flatnonzero(np.any(np.abs(error) > divergence_bound * scale, axis=1))
    divergence_time = None
    if len(exceeded):
        divergence_time = float(t[exceeded[0]])
    elif k < len(t):
        divergence_time = float(t[k]) if k else float(t[0])
    names = tuple(coordinate_names) if coordinate_names is not None else tuple(
        f"q{i}" for i in range(n))
    return ValidationResult(t=t, reference=reference, prediction=prediction,
                            forces=np.zeros((len(t), n)) if forces is None
                            else np.asarray(forces, dtype=float),
                            position_rmse=rmse, position_rmse_per_coordinate=per_coordinate,
                            divergence_time=divergence_time,
                            valid=divergence_time is None and failure is None, failure=failure,
                            divergence_bound=float(divergence_bound), coordinate_names=names,
                            simulated_rmse=simulated)


def validate_model(model, system=None, trajectory: Trajectory | None = None,
                   duration: float = 10.0, forcing: str = "explicit", actuators=None, seed=None,
                   divergence_bound: float = DEFAULT_DIVERGENCE_BOUND, force_input: str = "tau",
                   sample_every: int = 10, substeps: int = 4, initial_scale: float = 1.0,
                   amplitude=None, constraints: str = "truncate", drive: str = "auto",
                   force_bound: float = DEFAULT_FORCE_BOUND, simulator: str = "auto",
                   control: str = "auto", **integrator_options) -> ValidationResult:
    """Simulate an identified model against a fresh MuJoCo trajectory and score it.

    Parameters
    ----------
    model : fitted XLSINDy
        Anything with ``simulate(x0, t, u)`` (and ``feedback=`` for closed loop) raising
        :class:`pysindy_xl.dynamics.SimulationError` on failure.
    system : MuJoCoSystem or str, optional
        Simulated to produce the reference (ignored when ``trajectory`` is given).
    trajectory : Trajectory, optional
        Reference trajectory to use instead of simulating one.
    duration, forcing, actuators, seed, sample_every, substeps, initial_scale, amplitude, control
        Of the fresh trajectory, as in :func:`validation_trajectory`.
    divergence_bound, force_bound : float
        See the module docstring (``force_bound``: closed loop only).
    force_input : {"tau", "u"}, default "tau"
        Generalized forces, or joint forces (a model fitted with
        ``interlink=system.force_matrix()``).
    constraints : {"truncate", "ignore"}, default "truncate"
        ``truncate`` compares up to the first sample where a constraint acts in the
        reference (the result's ``constrained_at``).
    drive : {"auto", "closed-loop", "open-loop"}, default "auto"
        ``auto``: closed loop when the actuators have a state-dependent law (servos) and the
        reference's controls are known (``trajectory.info["signals"]``); ``closed-loop``
        requires both; ``open-loop`` replays the recorded forces.
    simulator : {"auto", "mujoco", "model"}, default "auto"
        In closed loop: ``auto`` is ``mujoco`` where the model can be stated in MuJoCo;
        ``mujoco`` refuses a model it cannot state.
    **integrator_options
        Passed to ``model.simulate`` by the ``model`` simulator (``method``, ``rtol``...).

    Returns
    -------
    ValidationResult

    Raises
    ------
    ValueError
        If neither ``system`` nor ``trajectory`` is given, on a shape mismatch, with
        ``drive="closed-loop"`` without an actuator law or known controls, or with
        ``simulator="mujoco"`` for a model MuJoCo cannot state.

    Examples
    --------
    Identify a cart-pole from one second of data and validate it on another second:

    >>> import pysindy_xl as px
    >>> from pysindy_xl.mujoco import generate_dataset, reference_catalog
    >>> data = generate_dataset("cart-pole", n_trajectories=1, duration=1.0, seed=0,
    ...                         progress=False)
    >>> catalog = reference_catalog("cart-pole", "mixed", trig_degree=1)
    >>> model = px.XLSINDy(catalog, px.ExplicitOptimizer()).fit(**data.fit_arguments())
    >>> result = validate_model(model, "cart-pole", duration=1.0, seed=1)
    >>> result.valid, result.divergence_time, bool(result.position_rmse < 1e-3)
    (True, None, True)
    >>> result.drive  # a motor on the cart: its force is a function of time
    'open-loop'
    """
    from ..dynamics import SimulationError
    if trajectory is None:
        if system is None:
            raise ValueError("system: give a system to simulate or a reference trajectory")
        options = {} if amplitude is None else {"amplitude": amplitude}
        trajectory = validation_trajectory(system, duration, forcing, actuators, seed, sample_every,
                                           initial_scale, substeps, control=control, **options)
        names = get_system(system).coordinate_names
    else:
        if not isinstance(trajectory, Trajectory):
            raise TypeError(f"trajectory: expected a Trajectory, got {type(trajectory).__name__}")
        names = get_system(system).coordinate_names if system is not None else None
    if trajectory.qd is None:
        raise ValueError("trajectory: the reference needs velocities (qd)")
    if constraints not in ("truncate", "ignore"):
        raise ValueError(f"constraints: expected 'truncate' or 'ignore', got {constraints!r}")
    constrained_at = None
    active = trajectory.constraint_active
    if constraints == "truncate" and active is not None and active.any():
        k = max(int(np.argmax(active)), 2)
        constrained_at = float(trajectory.t[k])
        trajectory = Trajectory(**{
            key: (value[:k] if isinstance(value, np.ndarray) else value)
            for key, value in vars(trajectory).items()})
    if force_input not in ("tau", "u"):
        raise ValueError(f"force_input: expected 'tau' or 'u', got {force_input!r}")
    forces = getattr(trajectory, force_input)
    n = trajectory.q.shape[1]
    n_model = getattr(model, "n_coordinates_", n)  # any model with simulate: trusted
    if n_model != n:
        raise ValueError(f"model: identified on {n_model} coordinates, but the reference has {n}"
                         f"{'' if names is None else ' ' + str(list(names))}; validate a model on "
                         "the system it was identified on")
    if forces is None:
        forces = np.zeros((trajectory.n_samples, n))
    if drive not in DRIVES:
        raise ValueError(f"drive: expected one of {DRIVES}, got {drive!r}")
    if not (isinstance(force_bound, (int, float)) and force_bound > 0):
        raise ValueError(f"force_bound: expected a positive number, got {force_bound!r}")
    reference = trajectory.state
    law = None
    known = "signals" in trajectory.info  # None: recorded without controls (all zero)
    controller = trajectory.info.get("tracking")
    if system is not None and known:
        signals = trajectory.info["signals"]
        actuated = None if controller is None else tracked_model(
            get_system(system).mj_model(), controller)
        law = actuator_law(system, None if signals is None else SumOfSinusoids.from_dict(
            signals), force_input, actuated)
    if drive == "closed-loop" and law is None:
        raise ValueError(
            "drive: closed loop needs the system's actuator law (a system given, every "
            "actuator on a joint without activation dynamics) and the reference's controls "
            "(trajectory.info['signals']); " + (
                "no system given" if system is None else "the trajectory has no controls"
                if not known else "an actuator is outside the supported law"))
    closed = law is not None and drive != "open-loop" and (
        law.state_dependent or drive == "closed-loop")
    if simulator not in SIMULATORS:
        raise ValueError(f"simulator: expected one of {SIMULATORS}, got {simulator!r}")
    if closed and simulator != "model":
        stepped = mujoco_closed_loop(model, get_system(system), trajectory, substeps,
                                      required=simulator == "mujoco")
        if stepped is not None:
            prediction, failure = stepped
            result = compare_trajectories(trajectory.t, reference, prediction,
                                          divergence_bound, failure, names, forces)
            return _closed_result(result, law, constrained_at, force_bound, "mujoco")
    use_forces, options = None, dict(integrator_options)
    if closed:
        options["feedback"] = law  # the servos act on the model's own state
        if options.get("method") == "ROS2" and "step" not in options and system is not None:
            interval = float(np.min(np.diff(trajectory.t)))
            options["step"] = min(float(get_system(system).mj_model().opt.timestep), interval)
    elif law is not None and not law.state_dependent:
        use_forces = law  # the continuous signal MuJoCo applied at each internal step
    elif np.any(forces != 0):
        # A C2 cubic spline of the force samples: the adaptive integrator rejects many steps at
        # the kinks of a piecewise-linear interpolant.
        use_forces = CubicSpline(trajectory.t, forces, axis=0)
    failure = None
    try:
        prediction = model.simulate(reference[0], trajectory.t, use_forces, **options)
    except SimulationError as error:
        prediction, failure = error.states, error.reason
    result = compare_trajectories(trajectory.t, reference, prediction, divergence_bound,
                                  failure, names, forces)
    if closed:
        return _closed_result(result, law, constrained_at, force_bound, "model")
    result.constrained_at = constrained_at
    return result


def _closed_result(result, law, constrained_at, force_bound, simulator) -> ValidationResult:
    """A closed-loop result: its force error, the verdict with it, and who simulated."""
    result.constrained_at, result.drive, result.simulator = (constrained_at, "closed-loop",
                                                             simulator)
    result.force_error = _closed_loop_force_error(law, result)
    result.valid = result.valid and result.force_error <= force_bound
    return result


def _closed_loop_force_error(law, result: ValidationResult) -> float:
    """Relative RMS difference of the actuator forces along the model's and MuJoCo's runs."""
    n, k = result.n, len(result.prediction)
    if k == 0:
        return float("inf")
    t, model, reference = result.t[:k], result.prediction, result.reference[:k]
    model_forces = law(t, model[:, :n], model[:, n:])
    mujoco_forces = law(t, reference[:, :n], reference[:, n:])
    error = np.sqrt(np.mean((model_forces - mujoco_forces) ** 2))
    scale = np.sqrt(np.mean(mujoco_forces ** 2))
    return float(error / scale) if scale > 0 else (0.0 if error == 0 else float("inf"))


