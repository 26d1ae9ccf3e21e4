"""The receding-horizon controller: sampling MPC far from the goal, LQR near it.

Every control period :class:`PredictiveController` either applies the LQR law of the model
linearized at the goal (when the state is inside its region, measured by the LQR cost-to-go
``e^T P e``, with hysteresis) or replans with the compiled sampling planner
(:mod:`.sampling`), warm-started from the previous plan shifted by one period, and applies the
first command. The planning time of every period is recorded."""

from __future__ import annotations

import time

import numpy as np

from .._optional import import_optional
from .._validation import check_option
from .costs import angle_error
from .lqr import discrete_lqr, linearize
from .sampling import sampling_planner

jax = import_optional("jax", purpose="pysindy_xl.control")
jnp = import_optional("jax.numpy", purpose="pysindy_xl.control")

__all__ = ["PredictiveController"]


class PredictiveController:
    """Sampling MPC with an LQR catch near the goal, on a discrete model.

    Parameters
    ----------
    step : callable
        ``x_{k+1} = step(x_k, u_k)``
        (:func:`~pysindy_xl.control.discrete.discrete_dynamics`), the identified model.
    cost : Cost
        The planner's cost (:mod:`pysindy_xl.control.costs`).
    control_limit : float or array (m,)
        Box on the commands.
    horizon : int, default 60
        Planning horizon (control periods).
    goal : array (2n,), optional
        Equilibrium for the LQR catch (none without it).
    angles : sequence of int, default ()
        Coordinates compared on the circle.
    lqr_weights : tuple (Q, R), optional
        Weights of the LQR (default ``Q = diag(1, ..., 10 per angle, 0.1 per velocity)``,
        ``R = 0.1``).
    lqr_region : float, default 0.25
        The LQR acts while ``e^T P e`` is below that of an error of ``lqr_region`` rad on every
        angle (and leaves above twice that).
    seed : int, default 0
        Seed of the planner's samples.
    **planner_options
        ``n_samples``, ``noise``, ``knots``, ``temperature``, ``iterations`` of
        :func:`~pysindy_xl.control.sampling.sampling_planner`.

    Attributes
    ----------
    planning_ms : list of float
        Wall time of each sampling-planner call (ms).
    lqr : LQRGain or None
        The LQR of the model at the goal (None when it has none).

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from pysindy_xl.control import discrete_dynamics, quadratic_cost
    >>> step = discrete_dynamics(lambda x, tau: jnp.array([x[1], tau[0]]), 0.1, [[1.0]], 1)
    >>> controller = PredictiveController(step, quadratic_cost([0.0, 0.0], [1.0, 0.1], [0.01]),
    ...                                   control_limit=2.0, horizon=20, goal=[0.0, 0.0])
    >>> x = np.array([1.0, 0.0])
    >>> for _ in range(80):
    ...     x = np.asarray(step(jnp.asarray(x), jnp.asarray(controller(x))))
    >>> bool(np.all(np.abs(x) < 0.05))
    True
    """

    def __init__(self, step, cost, control_limit, horizon: int = 60, goal=None, angles=(),
                 lqr_weights=None, lqr_region: float = 0.25, seed: int = 0, **planner_options):
        check_option("lqr_region", lqr_region, "real", low=0, low_open=True)
        self.step = step
        self.cost = cost
        self.planner = sampling_planner(step, cost, horizon, control_limit, **planner_options)
        m = self.planner.n_controls
        limit = np.asarray(control_limit, dtype=float).reshape(-1)
        self.control_limit = np.full(m, limit[0]) if limit.size == 1 else limit
        self.angles = tuple(int(i) for i in angles)
        self.planning_ms: list[float] = []
        self.modes: list[str] = []
        self._keys = np.asarray(jax.random.split(jax.random.PRNGKey(int(seed)), 4096))
        self.goal = None if goal is None else np.asarray(goal, dtype=float)
        self.lqr = None
        if self.goal is not None:
            self.lqr, self._region = self._lqr(lqr_weights, float(lqr_region))
        self.reset()
        # compile before the first period (not counted as planning time)
        start = np.zeros(2 * getattr(step, "n_coordinates", len(self.goal) // 2
                                     if self.goal is not None else 1))
        jax.block_until_ready(self.planner.plan(start, self._plan, self._keys[0]))

    def _lqr(self, weights, region):
        n2 = self.goal.size
        mask = np.zeros(n2, dtype=bool)
        mask[list(self.angles)] = True
        if weights is None:
            q = np.where(mask, 10.0, 1.0)
            q[n2 // 2:] = 0.1
            weights = (q, np.full(self.planner.n_controls, 0.1))
        try:
            a, b = linearize(self.step, self.goal, np.zeros(self.planner.n_controls))
            gain = discrete_lqr(a, b, *weights)
        except ValueError:
            return None, 0.0
        reference = np.where(mask, region, 0.0)
        return gain, float(reference @ gain.cost_to_go @ reference)

    def reset(self) -> None:
        """Forget the plan and the LQR mode (keeps the compiled planner)."""
        self._plan = self.planner.init()
        self._count = 0
        self._in_lqr = False

    def error(self, state) -> np.ndarray:
        """The error to the goal, ``state - goal`` with the angles wrapped to ``[-pi, pi)``.

        Parameters
        ----------
        state : array (2n,)
            The plant's state ``[q, qd]``.

        Returns
        -------
        numpy.ndarray
            The error (2n,).
        """
        mask = np.zeros(self.goal.size, dtype=bool)
        mask[list(self.angles)] = True
        return np.asarray(angle_error(np.asarray(state, float), self.goal, mask))

    def __call__(self, state, t=None) -> np.ndarray:
        """The command for the plant's state: the LQR law inside its region, else the first
        command of a new plan.

        Parameters
        ----------
        state : array (2n,)
            The plant's state ``[q, qd]``.
        t : float, optional
            Time (s); unused (the signature of a policy of :meth:`MuJoCoPlant.run`).

        Returns
        -------
        numpy.ndarray
            The command (m,), within ``control_limit``.
        """
        state = np.asarray(state, dtype=float)
        if self.lqr is not None:
            e = self.error(state)
            value = float(e @ self.lqr.cost_to_go @ e)
            self._in_lqr = value < (2.0 if self._in_lqr else 1.0) * self._region
            if self._in_lqr:
                self.modes.append("lqr")
                self._plan = self.planner.shift(self._plan)
                return np.clip(-self.lqr.gain @ e, -self.control_limit, self.control_limit)
        key = self._keys[self._count % len(self._keys)]
        self._count += 1
        start = time.perf_counter()
        u, plan, _ = self.planner.plan(state, self._plan, key)
        u = np.asarray(u, dtype=float)
        self.planning_ms.append(1e3 * (time.perf_counter() - start))
        self._plan = self.planner.shift(plan)
        self.modes.append("mpc")
        return u

