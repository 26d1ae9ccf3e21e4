"""Validation of an identified model against a fresh MuJoCo trajectory.

The model is simulated from the initial state of a new, noise-free MuJoCo trajectory and under
the same forces, and the two position histories are compared.

Faithfulness: the MuJoCo reference is integrated with RK4 at a fine internal step (the
model's ``timestep / substeps``, ``substeps=4`` by default) with the control updated at every
internal step (read at the step's midpoint, a second-order hold), and the identified model
receives the same continuous force signal (exact for
joint motors, see :func:`~pysindy_xl.mujoco.generate.actuator_force_function`; otherwise a
cubic spline of the recorded forces). Sample times do not depend on ``substeps``.

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
``valid``
    The model was simulated over the whole horizon and never diverged.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline

from ..data.dataset import Trajectory
from .forcing import FORCING_MODES, SumOfSinusoids
from .generate import actuator_force_function, actuator_signals, simulate_trajectory
from .systems import get_system

__all__ = ["ValidationResult", "validate_model", "compare_trajectories",
           "validation_trajectory", "DEFAULT_DIVERGENCE_BOUND", "compare_physics"]

DEFAULT_DIVERGENCE_BOUND = 0.2


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
        Forces given to the model.
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
            ``simulated_rmse`` and ``constrained_at``.

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
         "constrained_at": null}
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


def validation_trajectory(system, duration: float = 10.0, forcing: str = "explicit",
                          actuators=None, seed=None, sample_every: int = 10,
                          initial_scale: float = 1.0, substeps: int = 4,
                          backoff: bool = True, **signal_options) -> Trajectory:
    """A fresh noise-free MuJoCo trajectory with random initial state and forcing.

    Parameters
    ----------
    system : MuJoCoSystem or str
        A system, a registry name or an MJCF path.
    duration : float, default 10.0
        Simulated time (s).
    forcing : {"explicit", "implicit", "mixed"}
        Which actuators are driven (see :func:`generate_dataset`).
    actuators : list of str, optional
        Driven actuators in ``mixed`` mode.
    seed : int, optional
        Seed of the initial state and the signals.
    sample_every : int, default 10
        Record every ``sample_every``-th MuJoCo step.
    initial_scale : float, default 1.0
        Scale of the random initial state.
    substeps : int, default 4
        MuJoCo internal steps per model time step (a finer reference, see the module
        docstring).
    backoff : bool, default True
        When a joint limit, contact or equality constraint acts, draw again with half the
        forcing amplitude and initial spread (at most three times) and keep the draw whose
        first constraint comes latest (``info["backoff"]`` records the factor).
    **signal_options
        ``n_components``, ``max_frequency``, ``amplitude_scale``, ``amplitude`` of the random
        forces.

    Returns
    -------
    Trajectory
        With clean ``q, qd, qdd, tau, u`` and the constraint data.

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
    best, best_start, factor = None, -1, 1.0
    for _ in range(4 if backoff else 1):
        q0, qd0 = system.random_initial_state(rng, scale=initial_scale * factor)
        signals = actuator_signals(system, model, forcing, rng, actuators, backoff=factor,
                                   **signal_options)
        trajectory = simulate_trajectory(system, duration, signals, q0, qd0, sample_every,
                                         substeps=substeps, control_at="midpoint")
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


def validate_model(model, system=None, trajectory: Trajectory | None = None,
                   duration: float = 10.0, forcing: str = "explicit", actuators=None, seed=None,
                   divergence_bound: float = DEFAULT_DIVERGENCE_BOUND, force_input: str = "tau",
                   sample_every: int = 10, substeps: int = 4, initial_scale: float = 1.0,
                   amplitude=None, constraints: str = "truncate",
                   **integrator_options) -> ValidationResult:
    """Simulate an identified model against a fresh MuJoCo trajectory and score it.

    Parameters
    ----------
    model : fitted XLSINDy
        Anything with ``simulate(x0, t, u)`` raising
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
    **integrator_options
        Passed to ``model.simulate`` (``rtol``, ``atol``, ``timeout``...).

    Returns
    -------
    ValidationResult

    Raises
    ------
    ValueError
        If neither ``system`` nor ``trajectory`` is given, or on a shape mismatch.

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
    """
    from ..dynamics import SimulationError

    if trajectory is None:
        if system is None:
            raise ValueError("system: give a system to simulate or a reference trajectory")
        options = {} if amplitude is None else {"amplitude": amplitude}
        trajectory = validation_trajectory(system, duration, forcing, actuators, seed,
                                           sample_every, initial_scale, substeps, **options)
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
    if forces is None:
        forces = np.zeros((trajectory.n_samples, n))
    reference = trajectory.state
    use_forces = None
    exact = None
    if system is not None and "signals" in trajectory.info:
        exact = actuator_force_function(
            system, SumOfSinusoids.from_dict(trajectory.info["signals"]), force_input)
    if exact is not None:
        use_forces = exact  # the continuous signal MuJoCo applied at each internal step
    elif np.any(forces != 0):
        # A C2 cubic spline of the force samples: the adaptive integrator rejects many steps at
        # the kinks of a piecewise-linear interpolant.
        spline = CubicSpline(trajectory.t, forces, axis=0)
        use_forces = spline
    failure = None
    try:
        prediction = model.simulate(reference[0], trajectory.t, use_forces,
                                    **integrator_options)
    except SimulationError as error:
        prediction, failure = error.states, error.reason
    result = compare_trajectories(trajectory.t, reference, prediction, divergence_bound,
                                  failure, names, forces)
    result.constrained_at = constrained_at
    return result


def compare_physics(model, system, n_states: int = 5, seed=0, scale: float = 0.8) -> dict:
    """Compare the identified mass matrix and unforced dynamics with MuJoCo's at a few states.

    At random states (``system.random_initial_state``, inside the joint ranges) the identified
    equations ``M(q, qd) qdd = f(q, qd, u)`` are evaluated with ``u = 0`` and compared with
    MuJoCo's ``mj_fullM`` and ``qfrc_passive - qfrc_bias + qfrc_constraint`` (gravity,
    Coriolis, damping, springs, dry friction), both mapped to the system's coordinates
    (``B M B^T``, ``B f``). An implicit (unforced) law is defined up to a factor: both are
    first scaled by the least-squares factor that best matches the mass matrices.

    Parameters
    ----------
    model : fitted XLSINDy
        With dynamics (its equations contain accelerations).
    system : MuJoCoSystem or str
        The system the data came from.
    n_states : int, default 5
        Number of random states.
    seed : int, optional
        Seed of the states.
    scale : float, default 0.8
        Spread of the states (see ``random_initial_state``).

    Returns
    -------
    dict
        ``mass_error`` and ``force_error``: largest error relative to the largest entry of
        MuJoCo's matrix / vector over the states; ``scale``: the factor applied to the
        identified model (1 for a force-normalized fit); ``positive_definite``: the
        identified mass matrix is positive definite at every state; ``condition``: its
        largest condition number; ``unidentified``: names of the coordinates whose row of
        the identified mass matrix is zero at every state (no inertia identified, e.g. a
        passive body that no force excites: leave its joints out with ``joints=``);
        ``held``: the coordinates the model holds still (``still_coordinates_``), left out of
        the comparison (the others are compared as MuJoCo's equations of their own, exact
        for a held body that is decoupled from them).

    Examples
    --------
    >>> import pysindy_xl as px
    >>> from pysindy_xl.mujoco import generate_dataset, reference_catalog
    >>> data = generate_dataset("cart-pole", n_trajectories=1, duration=1.0, seed=0,
    ...                         progress=False)
    >>> catalog = reference_catalog("cart-pole", "mixed", trig_degree=1)
    >>> model = px.XLSINDy(catalog, px.ExplicitOptimizer()).fit(**data.fit_arguments())
    >>> physics = compare_physics(model, "cart-pole")
    >>> bool(physics["mass_error"] < 1e-6 and physics["force_error"] < 1e-6)
    True
    >>> physics["positive_definite"], physics["scale"]
    (True, 1.0)
    """
    import mujoco

    from .. import stack_variables

    system = get_system(system)
    dynamics = model._require_dynamics() if hasattr(model, "_require_dynamics") else None
    if dynamics is None:
        raise TypeError("model: expected a fitted XLSINDy with dynamics")
    rng = np.random.default_rng(seed)
    states = [system.random_initial_state(rng, scale=scale) for _ in range(n_states)]
    q = np.array([s[0] for s in states])
    qd = np.array([s[1] for s in states])
    mj_model = system.mj_model()
    data = mujoco.MjData(mj_model)
    matrix = system.force_matrix()
    mass_ref = np.empty((n_states, system.n, system.n))
    force_ref = np.empty((n_states, system.n))
    full = np.empty((mj_model.nv, mj_model.nv))
    for k in range(n_states):
        data.qpos[:], data.qvel[:] = system.from_generalized(q[k], qd[k])
        data.ctrl[:] = 0.0
        mujoco.mj_forward(mj_model, data)
        try:
            mujoco.mj_fullM(mj_model, data, full)  # MuJoCo >= 3.4
        except TypeError:
            mujoco.mj_fullM(mj_model, full, data.qM)
        mass_ref[k] = matrix @ full @ matrix.T
        force_ref[k] = matrix @ (data.qfrc_passive - data.qfrc_bias + data.qfrc_constraint)
    z = stack_variables(q, qd, None, np.zeros_like(q), np.zeros(n_states))
    mass, force = dynamics.mass_and_forcing(z)
    held = np.isin(system.coordinate_names, list(getattr(model, "still_coordinates_", ())))
    names = [name for name, h in zip(system.coordinate_names, held, strict=True) if not h]
    mass, mass_ref = (m[:, ~held][:, :, ~held] for m in (mass, mass_ref))
    force, force_ref = force[:, ~held], force_ref[:, ~held]
    factor = float(np.sum(mass * mass_ref) / np.sum(mass * mass)) if np.any(mass) else 1.0
    forces = model.feature_library_.force_columns_
    if np.allclose(model.coefficients()[forces], -1.0):
        factor = 1.0  # force-normalized: compare in absolute terms
    mass, force = mass * factor, force * factor
    eigenvalues = np.linalg.eigvalsh((mass + np.swapaxes(mass, 1, 2)) / 2)
    empty = np.all(np.abs(mass) <= 1e-12 * max(np.abs(mass).max(), 1e-300), axis=(0, 2))
    return {
        "unidentified": [names[i] for i in np.flatnonzero(empty)],
        "held": [name for name, h in zip(system.coordinate_names, held, strict=True) if h],
        "mass_error": float(np.abs(mass - mass_ref).max() / np.abs(mass_ref).max()),
        "force_error": float(np.abs(force - force_ref).max()
                             / max(np.abs(force_ref).max(), 1e-300)),
        "scale": factor,
        "positive_definite": bool(np.all(eigenvalues > 0)),
        "condition": float(np.max(np.abs(eigenvalues).max(axis=1)
                                  / np.maximum(np.abs(eigenvalues).min(axis=1), 1e-300))),
    }
