"""Data generation with MuJoCo: random forcing, several trajectories, noise, reproducible.

Accelerations are MuJoCo's own ``qacc``, computed by ``mj_forward`` at each recorded state
and control (not finite differences), so noise-free data satisfy the equations of motion up to
floating point. Forces are recorded as ``qfrc_actuator`` (generalized joint forces, whatever
the actuator type) and mapped to the textbook coordinates with the system's force matrix.
"""

from __future__ import annotations

import copy
import os

import numpy as np

from .._optional import import_mujoco
from .._validation import check_option
from ..data.dataset import Dataset, Trajectory
from ..data.noise import NOISE_KEYS, NOISE_MODELS, add_noise, noise_levels
from ..mujoco.systems.actuation import actuator_force_function, start_on_reference
from ..mujoco.systems.registry import get_system
from ..mujoco.systems.tracking import tracked_model
from .forcing import FORCING_MODES, SumOfSinusoids
from .integration import (
    INTEGRATORS,
    Integration,
    UnstableSimulationError,
    check_run,
    choose_integration,
    settled,
    settling_time,
)
from .signals import CONTROLS, actuator_signals, checked_fraction, motor_tracking
from .stepping import ROLLOUT_MIN_STEPS, new_runner, step_controls

__all__ = ["simulate_trajectory", "generate_dataset", "add_noise", "noise_levels", "NOISE_KEYS",
           "NOISE_MODELS", "ConstraintWarning", "INTEGRATORS", "UnstableSimulationError",
           "choose_integration", "CONTROLS", "actuator_force_function"]


#: Kinds of constraint rows (:func:`_constraint_kinds`).
_CONTACT, _FRICTION, _LIMIT, _EQUALITY = range(4)


def _constraint_kinds():
    """A lookup table of the kind of every MuJoCo constraint type (indexed by ``efc_type``),
    and the joint-limit type."""
    mujoco = import_mujoco()
    c = mujoco.mjtConstraint
    kinds = np.full(max(int(v) for v in c.__members__.values()) + 1, _CONTACT, dtype=np.int8)
    kinds[[int(c.mjCNSTR_FRICTION_DOF), int(c.mjCNSTR_FRICTION_TENDON)]] = _FRICTION
    kinds[[int(c.mjCNSTR_LIMIT_JOINT), int(c.mjCNSTR_LIMIT_TENDON)]] = _LIMIT
    kinds[int(c.mjCNSTR_EQUALITY)] = _EQUALITY
    return kinds, int(c.mjCNSTR_LIMIT_JOINT)


def _controls(signals, times, nu: int, substeps: int = 1) -> np.ndarray:
    """``signals(times)`` checked to shape (len(times), nu); a sum of sinusoids is evaluated on
    the grid of ``substeps`` evenly spaced times (:meth:`SumOfSinusoids.on_grid`)."""
    if isinstance(signals, SumOfSinusoids) and substeps > 1 and len(times) % substeps == 0:
        step = (times[-1] - times[0]) / (len(times) - 1)
        values = signals.on_grid(times[::substeps], np.arange(substeps) * step)
    else:
        values = np.asarray(signals(times), dtype=float)
    if values.shape != (len(times), nu):
        raise ValueError(f"signals: expected values of shape (n_times, nu={nu}), got "
                         f"{values.shape}")
    return values


def simulate_trajectory(system, duration: float, signals=None, q0=None, qd0=None,
                        sample_every: int = 1, progress=None, substeps: int = 1,
                        control_at: str = "start", integrator: str | None = None,
                        mj_model=None) -> Trajectory:
    """Simulate one MuJoCo trajectory and return it in generalized coordinates.

    Each sample is recorded by ``mj_forward`` at its state, under the control of its instant;
    the internal steps between two samples are taken in C (:func:`~.stepping.step_controls`,
    the same data as ``mj_step`` called step by step).

    Parameters
    ----------
    system : MuJoCoSystem or str
        A system or a name / MJCF path accepted by :func:`get_system`.
    duration : float
        Simulated time (s); rounded to a whole number of MuJoCo time steps.
    signals : callable, optional
        ``signals(times) -> (len(times), nu)`` control of every actuator (e.g. a
        :class:`SumOfSinusoids`). None: no control.
    q0, qd0 : array, shape (n,), optional
        Initial generalized state (default: the model's ``qpos0``, at rest).
    sample_every : int, default 1
        Record every ``sample_every``-th time step of the model.
    progress : tqdm.tqdm, optional
        Advanced by the number of simulated steps.
    substeps : int, default 1
        MuJoCo integrates with ``timestep / substeps``; sample times do not change.
    control_at : {"start", "midpoint"}, default "start"
        Where ``signals`` is read for each internal step (midpoint: second order; a start
        hold lags by half a step, which a servo's ``kp`` turns into a viscous friction).
    integrator : {"auto", "Euler", "RK4", "implicit", "implicitfast"} or Integration, optional
        Default: the model's. ``"auto"``: :func:`choose_integration`.
    mj_model : mujoco.MjModel, optional
        The compiled model to step, copied (default ``system.mj_model()``).

    Returns
    -------
    Trajectory
        ``t, q, qd, qdd, tau, u`` (``u``: MuJoCo joint forces; ``tau = u @ B.T``),
        ``u_constraint``, ``tau_constraint``, the mask ``constraint_active``; ``info`` counts
        ``limit_hits`` per joint, contact and equality samples.

    Raises
    ------
    UnstableSimulationError
        The run left the physics (:func:`~pysindy_xl.mujoco.integration.check_run`).

    Examples
    --------
    A forced cart-pole's recorded accelerations satisfy the true equations ``lhs = tau``:

    >>> import sympy as sp
    >>> system = get_system("cart-pole")
    >>> force = SumOfSinusoids([[1.0], [0.0]], [[1.0], [1.0]], [[0.0], [0.0]])
    >>> trajectory = simulate_trajectory(system, 0.2, force, q0=[0.0, 0.5], sample_every=10)
    >>> c = system.coords
    >>> lhs = sp.lambdify([*c.q, *c.qd, *c.qdd], system.equations_of_motion())
    >>> values = np.array(lhs(*trajectory.q.T, *trajectory.qd.T, *trajectory.qdd.T)).T
    >>> bool(np.abs(values - trajectory.tau).max() < 1e-9)
    True
    """
    mujoco = import_mujoco()
    system = get_system(system)
    duration = check_option("duration", duration, "real", low=0, low_open=True)
    sample_every = check_option("sample_every", sample_every, "int", low=1)
    substeps = check_option("substeps", substeps, "int", low=1)
    # a given model is copied: the run sets its time step and integrator
    model = system.mj_model() if mj_model is None else copy.deepcopy(mj_model)
    data = mujoco.MjData(model)
    n = system.n
    if model.nq != n or model.nv != n:
        raise ValueError(f"system: MJCF has nq={model.nq}, nv={model.nv}, expected {n} each")
    rest_q, rest_qd, _ = system.to_generalized(model.qpos0, np.zeros(n))
    q0 = rest_q if q0 is None else np.asarray(q0, dtype=float)
    qd0 = rest_qd if qd0 is None else np.asarray(qd0, dtype=float)
    for name, a in (("q0", q0), ("qd0", qd0)):
        if a.shape != (n,) or not np.all(np.isfinite(a)):
            raise ValueError(f"{name}: expected {n} finite numbers, got {a!r}")
    data.qpos[:], data.qvel[:] = system.from_generalized(q0, qd0)

    dt = model.opt.timestep
    n_steps = int(round(duration / dt))
    if n_steps < sample_every:
        raise ValueError(f"sample_every: recording every {sample_every} steps of {dt:g} s leaves "
                         f"fewer than two samples in a run of {duration:g} s ({n_steps} steps); "
                         "lower sample_every or lengthen the run")
    integration = integrator if isinstance(integrator, Integration) else choose_integration(
        model, "model" if integrator is None else integrator, substeps)
    substeps = integration.substeps
    model.opt.timestep = dt / substeps
    model.opt.integrator = INTEGRATORS[integration.integrator]
    if signals is None:  # unforced: the total energy must not grow
        model.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    n_fine = n_steps * substeps
    fine_times = np.arange(n_fine + 1) * (dt / substeps)
    if control_at not in ("start", "midpoint"):
        raise ValueError(f"control_at: expected 'start' or 'midpoint', got {control_at!r}")
    record_every = sample_every * substeps
    recorded = np.arange(0, n_fine + 1, record_every)
    recorded_ctrl = (np.zeros((len(recorded), model.nu)) if signals is None
                     else _controls(signals, fine_times[recorded], model.nu))
    shift = dt / substeps / 2 if control_at == "midpoint" else 0.0
    chunk = max(record_every, (200_000 // record_every) * record_every)
    qpos, qvel, qacc, force, constraint = (np.empty((len(recorded), n)) for _ in range(5))
    energy = np.empty((len(recorded), 2))
    active = np.zeros(len(recorded), dtype=bool)
    kind_of, joint_limit = _constraint_kinds()
    limit_hits = np.zeros(model.njnt, dtype=np.int64)
    contact_samples = equality_samples = 0
    runner = new_runner()
    reported = 0  # model steps reported to the progress bar
    for r, k in enumerate(range(0, n_fine + 1, record_every)):
        # mj_step leaves an intermediate RK4 stage in qacc: recompute at this state, under
        # the control of this instant (the continuous law the samples should obey)
        data.ctrl[:] = recorded_ctrl[r]
        mujoco.mj_forward(model, data)
        qpos[r], qvel[r], qacc[r], energy[r] = data.qpos, data.qvel, data.qacc, data.energy
        force[r] = data.qfrc_actuator
        constraint[r] = data.qfrc_constraint
        if data.nefc:
            types = data.efc_type[:data.nefc]
            kinds = kind_of[types]
            pushing = (np.abs(data.efc_force[:data.nefc]) > 0) & (kinds != _FRICTION)
            if pushing.any():
                active[r] = True
                hit = pushing & (types == joint_limit)
                limit_hits[np.unique(data.efc_id[:data.nefc][hit])] += 1
                contact_samples += bool(np.any(pushing & (kinds == _CONTACT)))
                equality_samples += bool(np.any(pushing & (kinds == _EQUALITY)))
        if k == n_fine:
            break
        if k % chunk == 0:  # the controls of the next chunk of internal steps
            ctrl = np.zeros((min(chunk, n_fine - k), model.nu)) if signals is None else \
                _controls(signals, fine_times[k:k + chunk] + shift, model.nu, substeps)
        # the internal steps to the next sample (past the last one: to the end of the run)
        start = k % chunk
        steps = record_every if k + record_every <= n_fine else n_fine - k
        if steps == 1:  # a sample every internal step
            data.ctrl[:] = ctrl[start]
            mujoco.mj_step(model, data)
        elif steps >= ROLLOUT_MIN_STEPS:
            step_controls(model, data, ctrl[start:start + steps], runner)
        else:  # a few steps: a call of rollout would cost more than they do
            for j in range(start, start + steps):
                data.ctrl[:] = ctrl[j]
                mujoco.mj_step(model, data)
        if progress is not None:
            done = (k + steps) // (1000 * substeps) * 1000
            if done > reported:
                progress.update(done - reported)
                reported = done
    if progress is not None:
        progress.update(n_steps + 1 - reported)
    bad = data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number
    passive = signals is None and not np.any(force)  # no actuator force: energy only decays
    checked = check_run(model, qpos, qvel, qacc, energy if passive else None, bad,
                        integration, f"MuJoCo simulation of {system!r}")
    q, qd, qdd = system.to_generalized(qpos, qvel, qacc)
    matrix = system.force_matrix()
    joint_names = list(system.joint_names)
    info = {"q0": q0.tolist(), "qd0": qd0.tolist(),
            "limit_hits": {joint_names[j]: int(limit_hits[j]) for j in np.flatnonzero(limit_hits)},
            "contact_samples": int(contact_samples), "equality_samples": int(equality_samples)}
    if substeps > 1:
        info["substeps"] = int(substeps)
    if integrator is not None:
        info["integrator"] = integration.integrator
    info["peak_velocity"] = checked["peak_velocity"]
    if isinstance(signals, SumOfSinusoids):
        info["signals"] = signals.to_dict()
    return Trajectory(t=fine_times[recorded], q=q, qd=qd, qdd=qdd, tau=force @ matrix.T,
                      u=force, info=info, tau_constraint=constraint @ matrix.T,
                      u_constraint=constraint, constraint_active=active)


def faithful_integrator(model) -> str | None:
    """The integrator :func:`choose_integration` picks where it differs from the model's.

    None to keep the model's.

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.

    Returns
    -------
    str or None
        The integrator name, or None to keep the model's.

    Examples
    --------
    >>> from pysindy_xl.mujoco import get_system
    >>> print(faithful_integrator(get_system("cart-pole").mj_model()))  # already RK4
    None
    """
    chosen = choose_integration(model).integrator
    return None if INTEGRATORS[chosen] == int(model.opt.integrator) else chosen


class ConstraintWarning(UserWarning):
    """Joint limits, contacts or equality constraints act on much of the generated data.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     warnings.warn("joint limits act on 40 % of the samples", ConstraintWarning)
    >>> issubclass(caught[0].category, UserWarning)
    True
    """


def generate_dataset(system, n_trajectories: int = 4, duration: float = 10.0,
                     forcing: str = "explicit", actuators=None, noise=0.0, seed=None,
                     sample_every: int = 1, n_components: int = 6, max_frequency: float = 1.5,
                     amplitude_scale: float = 1.0, initial_scale: float = 1.0,
                     progress=None, noise_model: str = "positions", derivatives=None,
                     amplitude=None, backoff: bool = True, max_constrained: float = 0.1,
                     min_unconstrained: float = 0.5, integrator: str = "auto",
                     reference=None, control: str = "auto") -> Dataset:
    """Simulate several randomly forced MuJoCo trajectories of a system.

    Parameters
    ----------
    system : MuJoCoSystem or str
        A system, a registry name (``"cart-pole"``...) or a path to a user's MJCF file.
    n_trajectories, duration : int, float
        Trajectories (each its own initial state and signals) and seconds per trajectory.
    forcing : {"explicit", "implicit", "mixed"}
        ``implicit``: no force, random initial condition only; ``explicit``: every actuator
        driven by a random sum of sinusoids; ``mixed``: only ``actuators`` driven.
    actuators : list of str, optional
        Actuator or joint names driven in ``mixed`` mode (default ``system.mixed_actuators``).
    noise : float or dict, default 0.0
        Relative Gaussian noise levels: std = level x each coordinate's standard deviation
        over the trajectory (:func:`noise_levels`, :func:`add_noise`).
    seed : int, optional
        Seed of every random draw (initial states, signals, noise).
    sample_every : int, default 1
        Record every ``sample_every``-th MuJoCo step.
    n_components, max_frequency, amplitude_scale, amplitude
        Shape of the random signals (:func:`actuator_signals`).
    initial_scale : float, default 1.0
        Scale of the random initial state; position servos start on their reference
        (:func:`~pysindy_xl.mujoco.start_on_reference`).
    progress : bool, optional
        Show a tqdm progress bar (default: only on a terminal).
    noise_model : {"positions", "all"}, default "positions"
        ``positions``: noisy positions only, no velocities or accelerations recorded;
        ``all``: the paper's model, noise on positions, velocities, accelerations, forces.
    derivatives : bool, optional
        Keep MuJoCo's exact velocities and accelerations. Default: kept unless
        ``noise_model="positions"`` with position noise > 0.
    backoff, max_constrained : bool, float
        When more than ``max_constrained`` of a trajectory's samples are constrained,
        simulate it again with half the forcing amplitude and initial spread (three times).
    min_unconstrained : float, default 0.5
        Warn (:class:`ConstraintWarning`) below this unconstrained fraction of all samples.
    integrator : {"auto", "model", "Euler", "RK4", "implicit", "implicitfast"}, default "auto"
        ``"auto"``: stable and faithful to the continuous equations
        (:func:`choose_integration`); ``"model"``: as authored; a name: that integrator.
    reference : FourierTrajectory, optional
        A planned trajectory (e.g. :func:`~pysindy_xl.mujoco.excitation_trajectory`) every run
        plays through the position servos instead of random signals; no back-off.
    control : {"auto", "open-loop", "tracking"}, default "auto"
        How plain torque motors are driven (:func:`motor_tracking`).

    Returns
    -------
    Dataset
        Its metadata hold ``constraints`` (:meth:`Dataset.constraint_summary`), the
        integration, ``peak_velocity``, ``reference``, ``tracking`` and, for a user's MJCF,
        the model's path and XML.

    Raises
    ------
    UnstableSimulationError
        If a run left the physics (see :func:`simulate_trajectory`).

    Examples
    --------
    >>> data = generate_dataset("cart-pole", n_trajectories=1, duration=0.1, seed=0,
    ...                         progress=False)
    >>> data.trajectories[0].q.shape, data.metadata["constraints"]["active_fraction"]
    ((101, 2), 0.0)
    """
    import warnings

    from tqdm.auto import tqdm
    duration = check_option("duration", duration, "real", low=0, low_open=True)
    sample_every = check_option("sample_every", sample_every, "int", low=1)
    system = get_system(system)
    if forcing not in FORCING_MODES:
        raise ValueError(f"forcing: expected one of {FORCING_MODES}, got {forcing!r}")
    if not isinstance(n_trajectories, (int, np.integer)) or n_trajectories < 1:
        raise ValueError(f"n_trajectories: expected an integer >= 1, got {n_trajectories!r}")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer))):
        raise TypeError(f"seed: expected an integer or None, got {type(seed).__name__}")
    levels = noise_levels(noise, noise_model)
    if derivatives is None:
        derivatives = not (noise_model == "positions" and levels["q"] > 0)
    elif not isinstance(derivatives, (bool, np.bool_)):
        raise TypeError(f"derivatives: expected True, False or None, got {derivatives!r}")
    if amplitude is not None:
        amplitude = checked_fraction(amplitude, "amplitude")
    initial_scale = float(initial_scale)
    if not (np.isfinite(initial_scale) and initial_scale >= 0):
        raise ValueError(f"initial_scale: expected a non-negative number, got {initial_scale!r}")
    for name, value in (("max_constrained", max_constrained),
                        ("min_unconstrained", min_unconstrained)):
        if not (isinstance(value, (int, float)) and 0 <= value <= 1):
            raise ValueError(f"{name}: expected a number in [0, 1], got {value!r}")
    if reference is not None and not callable(getattr(reference, "controls", None)):
        raise TypeError(f"reference: expected a FourierTrajectory, got {type(reference).__name__}")
    model = system.mj_model()
    controller = None if reference is not None else motor_tracking(
        system, model, forcing, actuators, amplitude_scale, amplitude, control)
    if controller is not None:
        model = tracked_model(model, controller)
    rng = np.random.default_rng(seed)
    n_steps = int(round(float(duration) / model.opt.timestep)) + 1
    if n_steps > 100_000_000:
        raise ValueError(f"duration: {duration} s is {n_steps:.3g} MuJoCo steps per trajectory "
                         "(at most 1e8); record shorter trajectories")
    # a time-varying control is held over each step: accurate, not only stable, substeps
    integration = choose_integration(model, integrator, held_control=forcing != "implicit")
    # a servo started on its reference is not at rest there (gravity, the reference's
    # acceleration): its stiff modes ring for a few time constants, faster than the samples
    # resolve; the recorded part starts once they have died out
    settle = settling_time(model, forced=forcing != "implicit")
    bar = tqdm(total=n_steps * n_trajectories, desc=f"MuJoCo {system.name}", unit="step",
               disable=None if progress is None else not progress, leave=False)
    trajectories = []
    with bar:
        for _ in range(n_trajectories):
            factor, attempts = 1.0, 4 if backoff and reference is None else 1
            for attempt in range(attempts):
                q0, qd0 = system.random_initial_state(rng, scale=initial_scale * factor)
                signals = reference.controls(system) if reference is not None else \
                    actuator_signals(system, model, forcing, rng, actuators, n_components,
                                     max_frequency, amplitude_scale, amplitude, backoff=factor,
                                     tracking=controller)
                q0, qd0 = start_on_reference(system, signals, q0, qd0, model)
                clean = simulate_trajectory(system, duration + settle, signals, q0, qd0,
                                            sample_every, bar if attempt == 0 else None,
                                            control_at="midpoint", integrator=integration,
                                            mj_model=model)
                clean = settled(clean, settle)
                if clean.constraint_active.mean() <= max_constrained or attempt == attempts - 1:
                    break
                factor /= 2
            if factor < 1:
                clean.info["backoff"] = factor
            if controller is not None:
                clean.info["tracking"] = controller
            noisy = add_noise(clean, levels, rng, system.force_matrix())
            if not derivatives:
                noisy.qd = noisy.qdd = None
            trajectories.append(noisy)
    metadata = {"system": system.name,
                "parameters": system.parameters,
                "forcing": forcing,
                "actuators": None if actuators is None else list(np.atleast_1d(actuators).tolist()),
                "noise": levels,
                "noise_model": noise_model,
                "derivatives": "mujoco" if derivatives else "none",
                "seed": None if seed is None else int(seed),
                "duration": float(duration),
                "sample_every": int(sample_every),
                "timestep": float(model.opt.timestep),
                "integrator": integration.integrator,
                "substeps": integration.substeps,
                "integration": integration.to_dict(),
                "peak_velocity": {joint: max(tr.info["peak_velocity"][joint] for tr in trajectories)
                                  for joint in trajectories[0].info["peak_velocity"]},
                "amplitude": amplitude,
                "initial_scale": initial_scale,
                "force_matrix": system.force_matrix().tolist(),
                "joint_names": list(system.joint_names),
                "reference": None if reference is None else reference.to_dict(),
                "tracking": controller}
    metadata.update(getattr(system, "metadata", lambda: {})())
    dataset = Dataset(trajectories, system.coordinate_names, metadata)
    summary = dataset.constraint_summary()
    dataset.metadata["constraints"] = summary
    if 1 - summary["active_fraction"] < min_unconstrained:
        label = os.path.basename(getattr(system, "path", None) or "") or system.name
        joints = ", ".join(f"{j} ({c} samples)" for j, c in summary["limit_hits"].items())
        warnings.warn(
            f"constraints act on {summary['active_fraction']:.0%} of the samples of "
            f"{label}: only {summary['unconstrained_samples']} unconstrained samples "
            f"left for the regression; joint limits hit: {joints or 'none'}; contact samples: "
            f"{summary['contact_samples']}. Lower amplitude / initial_scale, or pass the "
            "constraint forces as known forces (fit_arguments(constraints='known'))",
            ConstraintWarning, stacklevel=2,
        )
    return dataset
