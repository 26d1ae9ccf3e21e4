"""Gymnasium environments driven by identified dynamics (model-based reinforcement learning).

Observation: the state ``[q, qd]`` (float64); action: the forces of the actuated coordinates,
held over a step of ``dt`` seconds (float32, within ``action_bounds``); dynamics: the
identified ``M(q, qd) qdd = f(q, qd, u)`` by fixed-step Runge-Kutta 4; reward and
termination: your functions. An episode ends with ``info["failure"]`` where the dynamics
cannot be evaluated. Needs the ``gym`` extra (``pip install "pysindy-xl[gym]"``)."""

from __future__ import annotations

import numpy as np

from .._optional import import_optional
from .._validation import check_numeric_array, check_option
from ..dynamics import DynamicsError

gymnasium = import_optional("gymnasium", purpose="XLSINDy.to_gymnasium (pysindy_xl.export.gym_env)")
spaces = gymnasium.spaces

__all__ = ["IdentifiedDynamicsEnv", "make_env"]


def _bounds(value, size: int, name: str) -> np.ndarray:
    a = np.broadcast_to(np.asarray(value, dtype=float), (size,)).copy() if np.ndim(value) == 0 \
        else np.asarray(value, dtype=float)
    if a.shape != (size,):
        raise ValueError(f"{name}: expected a number or {size} values, got shape {a.shape}")
    if np.any(np.isnan(a)) or np.any(a <= 0):
        raise ValueError(f"{name}: expected positive bounds, got {a.tolist()}")
    return a


class IdentifiedDynamicsEnv(gymnasium.Env):
    """A Gymnasium environment whose dynamics are an identified model (module docstring); built by
    :func:`make_env` or :meth:`XLSINDy.to_gymnasium <pysindy_xl.XLSINDy.to_gymnasium>`.

    Parameters
    ----------
    model : XLSINDy
        A fitted model whose equations contain accelerations.
    dt : float
        Seconds per step.
    reward, terminated : callable, optional
        ``reward(state, action, next_state) -> float`` (default 0) and
        ``terminated(next_state) -> bool`` (default: never).
    initial_state : array (2n,) or callable, optional
        Start of each episode, or ``initial_state(rng) -> array (2n,)`` with ``np_random``;
        default: uniform in ``[-0.05, 0.05]``.
    actuated : list of str or int, optional
        Coordinates (names or indices) whose forces are the action; default: all.
    action_bounds, observation_bounds : float or array, default 1.0 and 1e6
        Actions are clipped to ``[-bound, bound]``; a state leaving its bounds terminates the
        episode with ``info["failure"]``.
    max_episode_steps : int or None, default 1000
        Truncation after this many steps (None: never).
    substeps : int, default 1
        Runge-Kutta 4 steps per ``dt``.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> from pysindy_xl.export.gym_env import make_env
    >>> coords = px.Coordinates(["x"])
    >>> t = np.linspace(0, 10, 1001)
    >>> x = (np.sin(t) + 0.5 * np.sin(2.3 * t))[:, None]
    >>> xdd = -(np.sin(t) + 0.5 * 2.3**2 * np.sin(2.3 * t))[:, None]
    >>> lib = px.CatalogRepartition([px.ExternalForces(coords),
    ...                              px.LagrangeLibrary(coords, [coords.qd[0] ** 2])])
    >>> model = px.XLSINDy(lib, px.ExplicitOptimizer()).fit(x, t, u=2.0 * xdd)
    >>> env = make_env(model, dt=0.1, reward=lambda s, a, s1: -float(s1[0] ** 2))
    >>> observation, info = env.reset(seed=0)
    >>> observation, reward, terminated, truncated, info = env.step(np.array([1.0]))
    >>> round(float(observation[1] - env.observation_history[0][1]), 3)  # qd += u / 2 * dt
    0.05
    """

    metadata = {"render_modes": []}

    def __init__(self, model, dt, reward=None, terminated=None, initial_state=None,
                 actuated=None, action_bounds=1.0, max_episode_steps=1000, substeps=1,
                 observation_bounds=1e6):
        dynamics = model._require_dynamics()
        self.model = model
        self._dynamics = dynamics
        coords = model.feature_library_.coords
        n = coords.n
        self.n = n
        try:
            dt = float(dt)
        except (TypeError, ValueError):
            raise TypeError(f"dt: expected a positive number of seconds, got {dt!r}") from None
        if not np.isfinite(dt) or dt <= 0:
            raise ValueError(f"dt: expected a positive number of seconds, got {dt!r}")
        self.dt = dt
        self.substeps = check_option("substeps", substeps, "int", low=1)
        self.max_episode_steps = check_option("max_episode_steps", max_episode_steps, "int",
                                              low=1, allow_none=True)
        for name, f in (("reward", reward), ("terminated", terminated)):
            if f is not None and not callable(f):
                raise TypeError(f"{name}: expected a callable, got {type(f).__name__}")
        self._reward, self._terminated = reward, terminated
        if actuated is None:
            actuated = list(range(n))
        indices = []
        for a in actuated:
            if isinstance(a, str) and a in coords.names:
                indices.append(coords.names.index(a))
            elif isinstance(a, (int, np.integer)) and not isinstance(a, bool) and 0 <= a < n:
                indices.append(int(a))
            else:
                raise ValueError(f"actuated: {a!r} is not a coordinate of {list(coords.names)}")
        if not indices or len(set(indices)) != len(indices):
            raise ValueError(f"actuated: expected distinct coordinates, got {list(actuated)}")
        self.actuated = tuple(indices)
        bound = _bounds(action_bounds, len(indices), "action_bounds")
        self.action_space = spaces.Box(-bound.astype(np.float32), bound.astype(np.float32),
                                       dtype=np.float32)
        high = _bounds(observation_bounds, 2 * n, "observation_bounds")
        self.observation_space = spaces.Box(-high, high, dtype=np.float64)
        if initial_state is not None and not callable(initial_state):
            initial_state = np.asarray(initial_state, dtype=float)
            if initial_state.shape != (2 * n,) or not np.all(np.isfinite(initial_state)):
                raise ValueError(f"initial_state: expected {2 * n} finite values "
                                 f"[q, qd], got shape {initial_state.shape}")
        self._initial_state = initial_state
        self.state = np.zeros(2 * n)
        self.observation_history = []
        self._steps = 0

    def reset(self, *, seed=None, options=None):
        """Start an episode (``seed`` seeds ``np_random``; ``options={"state": x0}`` starts at
        ``x0``); returns ``(observation, info)``.

        Parameters
        ----------
        seed : int, default=None
            Seeds ``np_random``.
        options : dict, default=None
            ``{"state": x0}`` starts the episode at ``x0`` (2n,).

        Returns
        -------
        observation : numpy.ndarray of shape (2n,)
            The initial state ``[q, qd]``.
        info : dict
            Empty.
        """
        super().reset(seed=seed)
        if options and "state" in options:
            state = np.asarray(options["state"], dtype=float)
        elif callable(self._initial_state):
            state = np.asarray(self._initial_state(self.np_random), dtype=float)
        elif self._initial_state is not None:
            state = self._initial_state.copy()
        else:
            state = self.np_random.uniform(-0.05, 0.05, size=2 * self.n)
        if state.shape != (2 * self.n,) or not np.all(np.isfinite(state)):
            raise ValueError(f"initial state: expected {2 * self.n} finite values, got "
                             f"shape {state.shape}")
        self.state = state
        self._steps = 0
        self.observation_history = [state.copy()]
        return state.copy(), {}

    def step(self, action):
        """Advance ``dt`` seconds with the action (clipped) held; returns ``(observation, reward,
        terminated, truncated, info)``, ``info`` with ``"time"`` and, on failure, ``"failure"``.

        Parameters
        ----------
        action : array_like of shape (n_actuated,)
            Forces on the actuated coordinates, clipped to the action bounds.

        Returns
        -------
        observation : numpy.ndarray of shape (2n,)
            The state after ``dt`` seconds.
        reward : float
            ``reward(state, action, next_state)``.
        terminated : bool
            ``terminated(next_state)``, or the state left its bounds.
        truncated : bool
            The episode reached ``max_episode_steps``.
        info : dict
            ``"time"`` and, on failure, ``"failure"``.
        """
        action = check_numeric_array(action, "action", min_samples=0, finite=False).reshape(-1)
        if action.shape != self.action_space.shape:
            raise ValueError(f"action: expected shape {self.action_space.shape}, got "
                             f"{action.shape}")
        if not np.all(np.isfinite(action)):  # (clipping would pass NaN on to the model)
            raise ValueError(f"action: expected finite values, got {action.tolist()}")
        action = np.clip(action, self.action_space.low, self.action_space.high)
        u = np.zeros(self.n)
        u[list(self.actuated)] = action
        state = self.state
        info = {}
        try:
            next_state = self._integrate(state, u)
        except (DynamicsError, FloatingPointError, np.linalg.LinAlgError) as error:
            next_state, info["failure"] = state.copy(), str(error)
        if not np.all(np.isfinite(next_state)):
            next_state, info["failure"] = state.copy(), "the state is not finite"
        elif not self.observation_space.contains(next_state):
            next_state = np.clip(next_state, self.observation_space.low,
                                 self.observation_space.high)
            info["failure"] = "the state left the observation space (observation_bounds)"
        self._steps += 1
        self.state = next_state
        self.observation_history.append(next_state.copy())
        info["time"] = self._steps * self.dt
        reward = 0.0 if self._reward is None else float(self._reward(state, action, next_state))
        terminated = "failure" in info or (
            self._terminated is not None and bool(self._terminated(next_state)))
        truncated = (self.max_episode_steps is not None
                     and self._steps >= self.max_episode_steps and not terminated)
        return next_state.copy(), reward, terminated, truncated, info

    def _integrate(self, state, u):
        f = self._dynamics.state_derivative
        h = self.dt / self.substeps
        with np.errstate(over="raise", invalid="raise"):
            for _ in range(self.substeps):
                k1 = f(state, u)
                k2 = f(state + 0.5 * h * k1, u)
                k3 = f(state + 0.5 * h * k2, u)
                k4 = f(state + h * k3, u)
                state = state + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        return state


def make_env(model, dt, **options) -> IdentifiedDynamicsEnv:
    """A Gymnasium environment driven by a fitted model; ``**options`` as in
    :class:`IdentifiedDynamicsEnv`. Raises ValueError if the model defines no dynamics or an
    option is out of range.

    Parameters
    ----------
    model : pysindy_xl.XLSINDy
        A fitted model whose equations contain accelerations.
    dt : float
        Seconds per step.
    **options
        ``reward``, ``terminated``, ``initial_state``, ``actuated``, ``action_bounds``,
        ``max_episode_steps``, ``substeps``, ``observation_bounds``, as in
        :class:`IdentifiedDynamicsEnv`.

    Returns
    -------
    IdentifiedDynamicsEnv
        The environment.

    Raises
    ------
    ValueError
        When the model defines no dynamics or an option is out of range.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> from gymnasium.utils.env_checker import check_env
    >>> coords = px.Coordinates(["x"])
    >>> t = np.linspace(0, 10, 1001)
    >>> x = np.sin(t)[:, None]
    >>> lib = px.CatalogRepartition([px.ExternalForces(coords),
    ...                              px.LagrangeLibrary(coords, [coords.qd[0] ** 2])])
    >>> model = px.XLSINDy(lib, px.ExplicitOptimizer()).fit(x, t, u=-x)
    >>> check_env(make_env(model, 0.05), skip_render_check=True)  # no rendering
    """
    return IdentifiedDynamicsEnv(model, dt, **options)
