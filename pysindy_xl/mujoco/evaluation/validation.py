"""Validation of an identified model against a fresh MuJoCo trajectory.

The model is simulated from the initial state of a new, noise-free MuJoCo trajectory, driven
the way MuJoCo was, and the two position histories are compared.

Drive: how the identified model is forced (``ValidationResult.drive``).

``open-loop``
    The model receives the forces MuJoCo applied, as a function of time: exactly the
    continuous signal for actuators whose force does not depend on the state (joint motors,
    see :func:`~pysindy_xl.mujoco.actuation.actuator_force_function`), otherwise a cubic
    spline of the recorded forces.
``closed-loop``
    For servos (``position`` / ``velocity`` actuators, ``general`` ones with an affine bias
    or gain), whose force depends on the joint state: the MJCF's actuator law
    (:func:`~pysindy_xl.mujoco.actuation.actuator_law`), driven by the reference controls
    of the run (the trajectory's ``info["signals"]``), acts on the model's own simulated
    state, as MuJoCo's servos acted on MuJoCo's. Replaying a servo run's forces open loop
    compares two different experiments: an exact model drifts away as soon as rounding
    moves it (nothing corrects it), and a wrong one can look right while the servos sit on
    their force limits.

Simulator: what steps the identified model in closed loop (``ValidationResult.simulator``).

``mujoco``
    MuJoCo itself, on a copy of the system's model that carries the identified parameters
    (:func:`~pysindy_xl.export.mjcf.identified_mj_model`: accepted only where MuJoCo then
    reproduces the identified ``M`` and ``f`` exactly), under the MJCF's own actuators and the
    integration :func:`~pysindy_xl.mujoco.integration.choose_integration` picks for it, joint
    limits and contacts off (the identified equations have none): the same equations as
    ``model``, stepped in compiled code, in a fraction of a second for seconds of a stiff
    seven-joint closed loop. The model's dry friction acts as MuJoCo's ``frictionloss``
    (the reference's mechanism) rather than its smooth sign.
``model``
    The identified equations integrated by ``model.simulate`` with the actuator law as
    feedback (scipy's ``DOP853`` by default): any model, thousands of evaluations per second
    of a stiff closed loop.

Faithfulness: the MuJoCo reference is integrated at a fine internal step (the model's
``timestep / substeps``, ``substeps=4`` by default or more where the integration that
:func:`~pysindy_xl.mujoco.integration.choose_integration` picks, stable and faithful to the
continuous equations, needs more) with the control updated at every
internal step (read at the step's midpoint, a second-order hold); the identified model sees
the same continuous controls. Sample times do not depend on ``substeps``.

Metrics
-------
``position_rmse``
    Root mean square of the position error over all samples and coordinates (in the
    coordinates' units, rad or m), over the **whole horizon**: infinite when the model could
    not be simulated to the end (its ``divergence_time`` says when it stopped).
``simulated_rmse``
    The same over the part the model could simulate (for diagnosis only).
``divergence_time``
    First time at which the error of some coordinate ``i`` exceeds
    ``divergence_bound * max(1, ptp_i)``, with ``ptp_i`` the peak-to-peak range of that
    coordinate in the MuJoCo trajectory (so the bound is relative to the motion, and absolute,
    in rad or m, for coordinates that barely move); or the time at which the simulation of the
    model failed (blow-up, singular mass matrix). None when neither happens.
``force_error`` (closed loop only)
    Root mean square, over the simulated samples and coordinates, of the difference between
    the actuator forces along the model's run and along MuJoCo's (the same law, at each
    run's own states), relative to the root mean square of MuJoCo's. Feedback hides model
    error in the positions (stiff servos track their reference whatever the inertia) and
    shows it in the forces the servos need: the closed-loop counterpart of torque
    prediction.
``valid``
    The model was simulated over the whole horizon and never diverged; in closed loop, also
    ``force_error <= force_bound`` (see :func:`validate_model`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline

from ...data.dataset import Trajectory
from ..simulation.forcing import SumOfSinusoids
from ..systems.actuation import actuator_law
from ..systems.registry import get_system
from ..systems.tracking import tracked_model
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

    Usually made by :func:`compare_trajectories` or :func:`validate_model`, which compute the
    metrics (see the module docstring); the fields are stored as given.

    Parameters
    ----------
    t : ndarray, shape (T,)
        Sample times.
    reference : ndarray, shape (T, 2n)
        MuJoCo state ``[q, qd]``.
    prediction : ndarray, shape (k, 2n)
        Model state at ``t[:k]``; ``k < T`` when the simulation failed.
    forces : ndarray, shape (T, n)
        Forces given to the model in open loop; in closed loop, the forces MuJoCo's
        actuators applied in the reference (the model's follow from its own state).
    position_rmse : float
        Root mean square position error over the whole horizon (inf when the simulation
        stopped early).
    position_rmse_per_coordinate : ndarray, shape (n,)
        The same per coordinate.
    divergence_time : float or None
        When the prediction left the bound or stopped; None when neither happened.
    valid : bool
        Simulated over the whole horizon and never diverged.
    failure : str or None
        Reason of a failed simulation (``SimulationError.reason``).
    divergence_bound : float
        Relative bound of the divergence test.
    coordinate_names : tuple of str, optional
        Names used in plots and in :meth:`to_dict`.
    simulated_rmse : float, optional
        Root mean square position error over the simulated part (inf when nothing was).
    constrained_at : float or None, optional
        When a constraint (joint limit, contact) started to act in the reference, where the
        comparison stopped (see :func:`validate_model`); None when none acted.
    drive : {"open-loop", "closed-loop"}, default "open-loop"
        How the model was driven (see the module docstring).
    force_error : float or None, optional
        Relative actuator-force error of a closed-loop run (see the module docstring); None
        in open loop.
    simulator : {"model", "mujoco"}, default "model"
        What stepped the identified model (see the module docstring).

    Attributes
    ----------
    n : int
        Number of coordinates.
    simulated_fraction : float
        Fraction of the horizon the model could simulate.

    Examples
    --------
    A prediction that stops half-way:

    >>> import numpy as np
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
        """JSON-serializable summary (metrics, no arrays).

        Returns
        -------
        dict
            ``position_rmse`` (``inf`` when the simulation stopped early; the demo report and
            the benchmark records write it as null),
            ``position_rmse_per_coordinate`` (by name), ``divergence_time``, ``valid``,
            ``failure``, ``divergence_bound``, ``horizon`` (s), ``simulated_fraction``,
            ``simulated_rmse``, ``constrained_at``, ``drive``, ``force_error`` and
            ``simulator``.

        Examples
        --------
        >>> import json, numpy as np
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
        return {
            "position_rmse": float(self.position_rmse),
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
            "simulator": self.simulator,
        }


def compare_trajectories(t, reference, prediction, divergence_bound=DEFAULT_DIVERGENCE_BOUND,
                         failure=None, coordinate_names=None, forces=None) -> ValidationResult:
    """Metrics of a predicted trajectory against a reference (see the module docstring).

    Parameters
    ----------
    t : array, shape (T,)
        Sample times.
    reference : array, shape (T, 2n)
        Reference states ``[q, qd]``.
    prediction : array, shape (k, 2n), k <= T
        Predicted states at ``t[:k]`` (shorter when the prediction stopped early).
    divergence_bound : float, default 0.2
        Relative bound of the divergence test (see the module docstring).
    failure : str, optional
        Why the prediction stopped early.
    coordinate_names : sequence of str, optional
        Default ``q0, q1, ...``.
    forces : array, shape (T, n), optional
        Forces given to the model, kept for the plots (default zero).

    Returns
    -------
    ValidationResult

    Examples
    --------
    >>> import numpy as np
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
        raise ValueError(
            f"prediction: expected shape (k <= {len(t)}, {reference.shape[1]}), got "
            f"{prediction.shape}"
        )
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
    if k == len(t):
        per_coordinate = np.sqrt(np.mean(error**2, axis=0))
        rmse = simulated
    else:  # the model could not follow the whole horizon: no finite error over it
        per_coordinate, rmse = np.full(n, np.inf), np.inf
    scale = np.maximum(1.0, np.ptp(reference[:, :n], axis=0))
    exceeded = np.flatnonzero(np.any(np.abs(error) > divergence_bound * scale, axis=1))
    divergence_time = None
    if len(exceeded):
        divergence_time = float(t[exceeded[0]])
    elif k < len(t):
        divergence_time = float(t[k]) if k else float(t[0])
    names = tuple(coordinate_names) if coordinate_names is not None else tuple(
        f"q{i}" for i in range(n))
    return ValidationResult(
        t=t, reference=reference, prediction=prediction,
        forces=np.zeros((len(t), n)) if forces is None else np.asarray(forces, dtype=float),
        position_rmse=rmse, position_rmse_per_coordinate=per_coordinate,
        divergence_time=divergence_time,
        valid=divergence_time is None and failure is None,
        failure=failure, divergence_bound=float(divergence_bound), coordinate_names=names,
        simulated_rmse=simulated,
    )


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
    duration, forcing, actuators, seed, sample_every
        Of the fresh trajectory (see :func:`validation_trajectory`).
    divergence_bound : float, default 0.2
        See the module docstring.
    force_input : {"tau", "u"}, default "tau"
        Forces given to the model: generalized forces (default interlink) or joint forces
        (for a model fitted with ``interlink=system.force_matrix()``).
    substeps, initial_scale, amplitude
        Of the fresh trajectory (see :func:`validation_trajectory`).
    constraints : {"truncate", "ignore"}, default "truncate"
        When a joint limit, contact or equality constraint acts in the reference (its
        ``constraint_active`` mask), which the identified model cannot reproduce:
        ``truncate`` compares up to the first such sample (``constrained_at`` of the result
        says when), ``ignore`` compares over the whole horizon anyway.
    drive : {"auto", "closed-loop", "open-loop"}, default "auto"
        How the model is driven (see the module docstring). ``auto``: closed loop when the
        system's actuators have a state-dependent law (servos) and the reference's controls
        are known (``trajectory.info["signals"]``, which :func:`validation_trajectory`
        records), open loop otherwise. ``closed-loop`` requires both the law and the
        controls; ``open-loop`` replays the recorded forces whatever the actuators.
    force_bound : float, default 0.05
        In closed loop, the largest relative actuator-force error (``force_error``, see the
        module docstring) of a valid model.
    simulator : {"auto", "mujoco", "model"}, default "auto"
        What steps the model in closed loop (see the module docstring): ``auto`` is
        ``mujoco`` where the model can be stated in MuJoCo, ``model`` otherwise; ``mujoco``
        refuses a model it cannot state. Open loop always uses ``model``.
    control : {"auto", "open-loop", "tracking"}, default "auto"
        How the fresh trajectory drives plain torque motors (see
        :func:`validation_trajectory`); a tracked reference (``info["tracking"]``) drives the
        model in closed loop with the same controller.
    **integrator_options
        Passed to ``model.simulate`` by the ``model`` simulator (``method``, ``rtol``,
        ``atol``, ``timeout``...). The default, scipy's ``DOP853`` at tight tolerances, is
        the accurate path; servos make the closed loop stiff, so it takes thousands of
        evaluations of the model per second of motion. ``method="ROS2"`` (an L-stable
        Rosenbrock method, :mod:`pysindy_xl.dynamics.rosenbrock`, steps of at most the MuJoCo
        model's time step under a
        local error bound of ``1e-3``) takes fewer at a looser accuracy (see
        ``benchmarks/closed_loop_validation.py``).

    Returns
    -------
    ValidationResult
        Its ``drive`` says which drive was used.

    Raises
    ------
    ValueError
        If neither ``system`` nor ``trajectory`` is given, on a shape mismatch, with
        ``drive="closed-loop"`` when there is no actuator law or no known controls, or with
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
    from ...dynamics import SimulationError

    if trajectory is None:
        if system is None:
            raise ValueError("system: give a system to simulate or a reference trajectory")
        options = {} if amplitude is None else {"amplitude": amplitude}
        trajectory = validation_trajectory(system, duration, forcing, actuators, seed,
                                           sample_every, initial_scale, substeps,
                                           control=control, **options)
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
        raise ValueError(
            f"model: identified on {n_model} coordinates, but the reference has {n}"
            f"{'' if names is None else ' ' + str(list(names))}; validate a model on the "
            "system it was identified on")
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
        spline = CubicSpline(trajectory.t, forces, axis=0)
        use_forces = spline
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


