"""The learning loop: explore the plant, identify, control on the model, run, repeat.

1. **Explore**: a random sum of sinusoids on the actuated coordinate plus a model-free
   energy-pumping term, with a proportional-derivative term that keeps the cart near the
   centre, clipped to the force limit (:func:`~.exploration.exploration_policy`). A
   :class:`~.exploration.TrackGuard` brings the cart back towards the centre whenever it is
   about to reach the end of the track, so the exploration records the seconds asked for;
   should the cart reach the end all the same, the plant is reset at the centre and the
   exploration goes on for the remaining seconds (a restart: a new recording).
2. **Identify**: on every episode so far, from positions only (relative Gaussian noise
   ``noise`` added: std = ``noise`` x each coordinate's standard deviation over the episode)
   and the applied forces: by default the automatic catalog grown on the data from the
   coordinates and their kinds (:class:`~.catalogs.AutomaticGrowth`), or
   :class:`~pysindy_xl.XLSINDy` with a fixed catalog.
3. **Control**: the receding-horizon controller (:class:`~.mpc.PredictiveController`) plans on
   the identified model only and acts on the plant from hanging at rest.
4. Until the task succeeds: the attempt's recording joins the data, and the model is identified
   again.

MuJoCo is the plant only; every plant second (exploration, the guard's returns to the
centre, and attempts) is counted in ``interaction_s``. A restart of the exploration after
the end of the track is a new plant episode: its seconds are counted, the number of restarts
is reported (``restarts``), and the reset itself takes no plant time (the simulated plant is
put back at the centre at once; on a rig, carrying the cart back would add to this).
The controller reads the plant's state ``[q, qd]`` (full-state feedback, without noise); the
identification sees only noisy positions and the forces."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field

import numpy as np

from .._validation import check_option
from .catalogs import catalog_identifier
from .costs import swing_up_cost
from .discrete import continuous_dynamics, discrete_dynamics
from .exploration import TrackGuard, exploration_policy
from .mpc import PredictiveController
from .plant import MuJoCoPlant
from .tasks import get_task

# exploration_policy: defined in .exploration, importable from here as well
__all__ = ["LearningResult", "exploration_policy", "learn_to_control", "noisy_positions"]

#: Seconds of the first exploration per system: enough pumped motion for a model that swings
#: up at the first attempt. The cart double pendulum's law needs products of two angles'
#: functions, an automatic catalog of about 140 candidates, which the data-sized ceiling
#: (:class:`~.catalogs.AutomaticGrowth`: 150 equations per candidate, 3 coordinates at 1 kHz)
#: admits from 7 s of data on.
EXPLORE_S = {"cart-pole": 2.5, "cart-double-pendulum": 8.0}

#: Most restarts of one exploration at the centre after the cart reached the end of the track.
_MAX_RESTARTS = 5
#: Shortest piece (s) of a restarted exploration that joins the data (the longest piece does
#: in any case): the identification's test functions are sized on the shortest recording,
#: which a short piece would narrow. Its seconds count all the same.
_MIN_SEGMENT_S = 1.0

#: Planner settings per system: control period (s), RK4 steps per period, horizon (periods),
#: samples, knots.
PLANNER_SETTINGS = {
    "cart-pole": {"control_dt": 0.02, "substeps": 1, "horizon": 60, "n_samples": 256,
                  "knots": 8},
    "cart-double-pendulum": {"control_dt": 0.02, "substeps": 2, "horizon": 60,
                             "n_samples": 256, "knots": 10},
}

#: The settings that ``planner`` of :func:`learn_to_control` may override.
PLANNER_OPTIONS = ("control_dt", "substeps", "horizon", "n_samples", "knots", "noise",
                   "temperature", "iterations", "lqr_region")


@dataclass
class LearningResult:
    """Outcome of :func:`learn_to_control` (``to_dict`` gives the JSON report).

    Parameters
    ----------
    success : bool
        The last attempt met the task.
    interaction_s : float
        Plant seconds in total, every exploration (with its returns to the centre and
        restarts) and attempt included.
    episodes : int
        Explorations and attempts on the plant (an exploration's restarts are counted in
        ``restarts``).
    catalog : str
        Name of the catalog (or ``"given model"``).
    force_limit : float
        Largest force on the cart (N).
    max_abs_force : float
        Largest force of the final attempt (N; :meth:`SwingUpTask.evaluate`).
    track_limit : float
        Half length of the track (m).
    max_abs_x, upright_s : float
        Of the final attempt (:meth:`SwingUpTask.evaluate`): largest distance of the cart from
        the centre (m), longest time upright in a row (s).
    mpc_step_ms : float or None
        Median wall time of a sampling-planner step over all attempts (ms; None without one).
    equations : list of str, default []
        The final model's equations.
    history : list of dict, default []
        Per episode: kind, duration, and the task's scores for attempts.
    system : str, default ""
        Registry name of the system.
    task : str, default ""
        Name of the task.
    noise : float, default 0.0
        Relative noise on the recorded positions.
    seed : int, default 0
        Seed of the run.
    lqr_fraction : float, default 0.0
        Share of the attempts' control periods under the LQR.
    final_episode : Episode or None, default None
        The last attempt on the plant (its true states).
    model : object, default None
        The model of the last attempt.
    identify_s : list of float, default []
        Wall time of each identification (s).
    catalog_description : str, default ""
        The catalog of the final model (for the automatic catalog, the grown catalog's
        description).
    restarts : int, default 0
        Explorations restarted at the centre after the cart reached the end of the track
        (each a new plant episode, its seconds in ``interaction_s``; not in ``episodes``).

    Examples
    --------
    >>> result = LearningResult(True, 6.7, 2, "generic", 10.0, 10.0, 1.5, 1.2, 2.0, 1.8)
    >>> result.to_dict()["interaction_s"]
    6.7
    """

    success: bool
    interaction_s: float
    episodes: int
    catalog: str
    force_limit: float
    max_abs_force: float
    track_limit: float
    max_abs_x: float
    upright_s: float
    mpc_step_ms: float | None
    equations: list = field(default_factory=list)
    history: list = field(default_factory=list)
    system: str = ""
    task: str = ""
    noise: float = 0.0
    seed: int = 0
    lqr_fraction: float = 0.0
    final_episode: object = field(default=None, repr=False)
    model: object = field(default=None, repr=False)
    identify_s: list = field(default_factory=list)
    catalog_description: str = ""
    restarts: int = 0

    def to_dict(self) -> dict:
        """The result as JSON-ready data.

        Returns
        -------
        dict
            Every field by name except ``final_episode`` and ``model``; ``history`` as a
            list of dicts.

        Examples
        --------
        >>> result = LearningResult(False, 2.5, 1, "generic", 10.0, 0.0, 1.5, 0.0, 0.0, None)
        >>> data = result.to_dict()
        >>> data["episodes"], "model" in data, "final_episode" in data
        (1, False, False)
        """
        data = asdict(self)
        data.pop("final_episode")
        data.pop("model")
        return data


def noisy_positions(episode, noise: float, rng: np.random.Generator) -> np.ndarray:
    """Positions with relative Gaussian noise, as a position sensor records them.

    Parameters
    ----------
    episode : Episode
        Its ``q`` (N, n).
    noise : float
        Std of the noise as a fraction of each column's standard deviation.
    rng : numpy.random.Generator
        Draws the noise.

    Returns
    -------
    numpy.ndarray
        Noisy positions (N, n).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> episode = SimpleNamespace(q=np.c_[np.linspace(0, 1, 5), np.zeros(5)])
    >>> noisy_positions(episode, 0.0, np.random.default_rng(0))[:, 0].tolist()
    [0.0, 0.25, 0.5, 0.75, 1.0]
    """
    q = episode.q
    return q + noise * q.std(axis=0) * rng.standard_normal(q.shape)


def _usable(f, system, goal) -> bool:
    """Whether the model's accelerations are finite and its mass matrix acts as positive at the
    start, the goal and random states (a non-physical fit fails here)."""
    import jax.numpy as jnp
    rng = np.random.default_rng(0)
    n = system.n
    states = np.concatenate([np.zeros((1, 2 * n)), goal[None],
                             np.c_[rng.uniform(-1, 1, (32, n)) * 2,
                                   rng.uniform(-2, 2, (32, n))]])
    probe = np.zeros((len(states), n))
    probe[:, 0] = 1.0
    base = np.asarray(f(jnp.asarray(states), jnp.zeros((len(states), n))))
    pushed = np.asarray(f(jnp.asarray(states), jnp.asarray(probe)))
    if not (np.all(np.isfinite(base)) and np.all(np.isfinite(pushed))):
        return False
    # a push on the cart must accelerate it forward (M^-1 positive definite => (M^-1)_00 > 0)
    return bool(np.all(pushed[:, n] - base[:, n] > 0))


def _equations(model) -> list[str]:
    try:
        return [str(e) for e in model.equations()]
    except (AttributeError, TypeError, ValueError):
        try:
            return [str(e) for e in model.equations]
        except (AttributeError, TypeError):
            return []


def learn_to_control(system: str = "cart-pole", task: str = "swing-up", catalog="automatic",
                     noise: float = 0.01, seed: int = 0, force_limit: float | None = None,
                     track_limit: float = 1.5, explore_s: float | None = None,
                     max_episodes: int = 6,
                     max_interaction_s: float = 30.0, model=None, identify=None,
                     planner: dict | None = None, check_model: bool = True,
                     log=None, keep_on_track: bool = True) -> LearningResult:
    """Learn to perform ``task`` on the MuJoCo ``system`` from its data alone (module docstring).

    Parameters
    ----------
    system : str, default "cart-pole"
        ``"cart-pole"`` or ``"cart-double-pendulum"``.
    task : {"swing-up"}, default "swing-up"
        Name of the task (:func:`~pysindy_xl.control.tasks.get_task`).
    catalog : str or callable, default "automatic"
        ``"automatic"`` (the automatic catalog grown on the data from the coordinates and
        their kinds, :class:`~pysindy_xl.control.catalogs.AutomaticGrowth`), ``"generic"`` (a
        fixed catalog from the coordinates and kinds), ``"kinematic"`` (from the MJCF), a
        factory ``catalog(system) -> library``, or a data-driven identifier
        (:mod:`pysindy_xl.control.catalogs`).
    noise : float, default 0.01
        Relative noise on the recorded positions.
    seed : int, default 0
        Seed of the exploration signal, the noise, the start perturbation and the planner.
    force_limit : float, optional
        Default from :func:`~pysindy_xl.control.tasks.get_task`.
    track_limit : float, default 1.5
        Half length of the track (m).
    explore_s : float, optional
        Seconds of the first exploration (and of each further one when a fit is unusable);
        default 2.5 for the cart-pole, 8.0 for the cart double pendulum.
    max_episodes : int, default 6
        Most episodes on the plant.
    max_interaction_s : float, default 30.0
        Most plant seconds.
    model : object, optional
        A fixed model to control with (for instance the true equations as a
        :class:`~pysindy_xl.MassMatrixDynamics`): no exploration, no identification.
    identify : callable, optional
        ``identify(system, data) -> model`` replacing the XLSINDy fit, ``data`` a list of
        ``(q_noisy (N, n), t (N,), tau (N, n))``; the model gives ``to_jax()`` or is a JAX
        function ``f(state, tau)`` with ``n_coordinates``.
    planner : dict, optional
        Overrides of the planner settings (``control_dt``, ``substeps``, ``horizon``,
        ``n_samples``, ``knots``, ``noise``, ``temperature``, ``iterations``, ``lqr_region``).
    check_model : bool, default True
        Refuse an identified model whose push on the cart does not accelerate it forward at
        the start, the goal and random states (then explore again); False lets every model
        try.
    log : callable, optional
        ``log(message)`` for progress (for instance to stderr).
    keep_on_track : bool, default True
        Guard the explorations with a :class:`~.exploration.TrackGuard` (returns to the
        centre before the end of the track). With or without it, an exploration that
        reaches the end of the track restarts at the centre until it has recorded
        ``explore_s`` seconds (at most 5 restarts, within ``max_interaction_s``; a piece
        shorter than 1 s is counted but not identified from, unless it is the longest).

    Returns
    -------
    LearningResult

    Raises
    ------
    ValueError
        For an unknown system, task or catalog, or limits that are not positive numbers.
    TypeError
        For a ``model`` that gives no accelerations.

    Examples
    --------
    One episode, the first exploration, counted on the plant: 0.5 s of excitation within the
    force limit, nothing identified yet, no attempt.

    >>> result = learn_to_control("cart-pole", explore_s=0.5, max_episodes=1, seed=0)
    >>> [h["kind"] for h in result.history], result.episodes, round(result.interaction_s, 3)
    (['explore'], 1, 0.5)
    >>> result.success, result.final_episode is None
    (False, True)

    The whole loop (explore, grow the automatic catalog on the data, swing up on the
    identified model) takes tens of seconds to minutes, not run here: the growth, the
    compilation of the planner, and up to 300 planned control periods per attempt. On the
    cart-pole it succeeds at the first attempt, after 2.5 s of exploration:

    >>> result = learn_to_control("cart-pole", noise=0.01, seed=0)  # doctest: +SKIP
    >>> result.success, result.episodes, result.max_abs_force <= 10.0  # doctest: +SKIP
    (True, 2, True)
    """
    from ..mujoco import get_system
    the_task = get_task(system, task, force_limit=force_limit, track_limit=track_limit)
    plant_system = get_system(system)
    if not (np.isfinite(noise) and noise >= 0):
        raise ValueError(f"noise: expected a relative level >= 0, got {noise!r}")
    if explore_s is None:
        explore_s = EXPLORE_S.get(system, 2.0)
    if not (np.isfinite(explore_s) and explore_s > 0):
        raise ValueError(f"explore_s: expected a positive number of seconds, got {explore_s!r}")
    catalog_name, identifier = ("given model", None) if model is not None else \
        ("custom identification", None) if identify is not None else \
        catalog_identifier(catalog)
    check_option("max_episodes", max_episodes, "int", low=1)
    check_option("max_interaction_s", max_interaction_s, "real", low=0, low_open=True)
    if log is not None and not callable(log):
        raise TypeError(f"log: expected a callable log(message) or None, got "
                        f"{type(log).__name__}")
    unknown = sorted(set(planner or {}) - set(PLANNER_OPTIONS))
    if unknown:  # (a misspelt setting would otherwise be dropped unseen)
        raise ValueError(f"planner: unknown settings {unknown}; expected some of "
                         f"{PLANNER_OPTIONS}")
    settings = dict(PLANNER_SETTINGS.get(system, PLANNER_SETTINGS["cart-pole"]))
    settings.update(planner or {})
    control_dt = settings.pop("control_dt")
    substeps = settings.pop("substeps")
    horizon = settings.pop("horizon")
    lqr_region = settings.pop("lqr_region", 0.25)
    say = log or (lambda message: None)
    rng = np.random.default_rng(seed)
    plant = MuJoCoPlant(plant_system, the_task.actuated, the_task.force_limit, control_dt)
    angles = the_task.angles(plant_system)
    goal = the_task.goal(plant_system)
    cost = swing_up_cost(plant_system.n, angles, track_limit=the_task.track_limit,
                         force_limit=the_task.force_limit)
    data, history, planning_ms, modes = [], [], [], []
    scores = {"success": False, "upright_s": 0.0, "max_abs_x": 0.0, "max_abs_force": 0.0}
    current = model
    identify_s, description = [], "given model" if model is not None else ""
    n_episodes = restarts = 0
    episode = None

    def record(episode):
        q = noisy_positions(episode, noise, rng)
        data.append((q, episode.t, episode.tau))

    def off_track(state, t):
        return "track" if the_task.outside_track(state, plant_system)[0] else None

    def explore():
        nonlocal restarts
        plant.reset(np.r_[0.0, rng.uniform(-0.05, 0.05, plant.n - 1)])
        excitation = exploration_policy(the_task.force_limit, rng)
        guard = TrackGuard(excitation, the_task.track_limit, the_task.force_limit) \
            if keep_on_track else None
        policy = guard or excitation
        done, pieces = 0.0, []
        while True:
            # a restart goes on with the excitation where it stopped
            pieces.append(plant.run(lambda s, t, t0=done: policy(s, t + t0),
                                    explore_s - done, stop=off_track))
            done += pieces[-1].duration
            if (pieces[-1].stopped != "track" or explore_s - done < plant.control_dt / 2
                    or len(pieces) > _MAX_RESTARTS
                    or plant.interaction_s >= max_interaction_s):
                break
            restarts += 1
            plant.reset(np.r_[0.0, rng.uniform(-0.05, 0.05, plant.n - 1)])
        # pieces under _MIN_SEGMENT_S are left out of the data (unless all are)
        kept = [p for p in pieces if p.duration >= _MIN_SEGMENT_S] or \
            [max(pieces, key=lambda p: p.duration)]
        for piece in kept:
            record(piece)
        unused = done - sum(piece.duration for piece in kept)
        segments = len(pieces)
        returned = float(np.sum(guard.guarded)) * plant.control_dt if guard else 0.0
        history.append({"kind": "explore", "duration_s": done, "segments": segments,
                        "returns": guard.returns if guard else 0, "return_s": returned,
                        "unused_s": unused})
        say(f"explore: {done:.2f} s on the plant in {segments} segment(s), "
            f"{guard.returns if guard else 0} return(s) to the centre ({returned:.2f} s; "
            f"total {plant.interaction_s:.2f} s)")

    while n_episodes < max_episodes and plant.interaction_s < max_interaction_s:
        if model is None:
            if not data:
                explore()
                n_episodes += 1
                continue
            start = time.perf_counter()
            try:
                if identify is not None:
                    current, description = identify(plant_system, data), catalog_name
                else:
                    current, description = identifier(plant_system, data)
                f = continuous_dynamics(current)
                usable = _usable(f, plant_system, goal) if check_model else True
            except (ValueError, TypeError, ArithmeticError, RuntimeError,
                    np.linalg.LinAlgError) as error:
                say(f"identification failed ({error})")
                usable = False
            identify_s.append(time.perf_counter() - start)
            say(f"identify: {sum(len(d[1]) for d in data)} samples, {identify_s[-1]:.1f} s, "
                f"usable: {usable}" + (f" ({description})" if description else ""))
            if not usable:
                explore()
                n_episodes += 1
                continue
        else:
            f = continuous_dynamics(current)
        step = discrete_dynamics(f, control_dt, plant.actuation, substeps)
        controller = PredictiveController(step, cost, the_task.force_limit, horizon, goal=goal,
                                          angles=angles, lqr_region=lqr_region,
                                          seed=seed + n_episodes, **settings)
        plant.reset(np.r_[0.0, rng.uniform(-0.05, 0.05, plant.n - 1)])
        episode = plant.run(controller, the_task.max_duration,
                            stop=the_task.stop_rule(plant_system, control_dt))
        n_episodes += 1
        scores = the_task.evaluate(episode, plant_system)
        planning_ms += controller.planning_ms
        modes += controller.modes
        history.append({"kind": "attempt", "duration_s": episode.duration,
                        "stopped": episode.stopped, **scores,
                        "lqr": controller.lqr is not None})
        say(f"attempt: {episode.duration:.2f} s, {episode.stopped}, upright "
            f"{scores['upright_s']:.2f} s, |x| <= {scores['max_abs_x']:.2f} m (total "
            f"{plant.interaction_s:.2f} s)")
        if scores["success"]:
            break
        if model is not None:
            continue
        record(episode)
    return LearningResult(
        success=bool(scores["success"]), interaction_s=float(plant.interaction_s),
        episodes=n_episodes, catalog=catalog_name, force_limit=float(the_task.force_limit),
        max_abs_force=scores["max_abs_force"], track_limit=float(the_task.track_limit),
        max_abs_x=scores["max_abs_x"], upright_s=scores["upright_s"],
        mpc_step_ms=float(np.median(planning_ms)) if planning_ms else None,
        equations=_equations(current) if current is not None else [], history=history,
        system=system, task=task, noise=float(noise), seed=int(seed),
        lqr_fraction=float(np.mean([m == "lqr" for m in modes])) if modes else 0.0,
        final_episode=episode if history and history[-1]["kind"] == "attempt" else None,
        model=current, identify_s=[float(s) for s in identify_s],
        catalog_description=description, restarts=restarts)
