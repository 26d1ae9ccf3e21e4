"""Control tasks on the paper's systems: what to reach, within which limits, and when it counts
as done.

A :class:`SwingUpTask` starts with every pendulum hanging at rest and succeeds when all angles
stay within ``tolerance`` of upright for ``hold_s`` seconds, the commands within the force limit
(the plant clips them) and the cart within the track (``|x| <= track_limit``; leaving it ends the
episode as a failure)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["TASKS", "SwingUpTask", "get_task"]

#: Tasks by name (:func:`get_task`).
TASKS = ("swing-up",)

#: Default force limit (N) per system of the swing-up.
_FORCE_LIMITS = {"cart-pole": 10.0, "cart-double-pendulum": 20.0}


@dataclass(frozen=True)
class SwingUpTask:
    """Swing every pendulum of a cart system up and hold it there.

    Parameters
    ----------
    system : str
        Registry name of the system (``"cart-pole"``, ``"cart-double-pendulum"``).
    force_limit : float
        Largest force on the cart (N).
    track_limit : float, default 1.5
        Half length of the track (m).
    tolerance : float, default 0.2
        Largest angle from upright (rad) that counts as upright.
    hold_s : float, default 2.0
        Seconds upright in a row for success.
    max_duration : float, default 6.0
        Longest attempt (s).
    actuated : tuple of str, default ("x",)
        The pushed coordinate.

    Examples
    --------
    >>> from pysindy_xl.mujoco import get_system
    >>> task = SwingUpTask("cart-pole", force_limit=10.0)
    >>> task.upright(np.array([[0.0, np.pi - 0.1, 0.0, 0.0]]), get_system("cart-pole"))
    array([ True])
    """

    system: str
    force_limit: float
    track_limit: float = 1.5
    tolerance: float = 0.2
    hold_s: float = 2.0
    max_duration: float = 6.0
    actuated: tuple = ("x",)
    name: str = field(default="swing-up", init=False)

    def __post_init__(self):
        for attribute in ("force_limit", "track_limit", "tolerance", "hold_s", "max_duration"):
            value = getattr(self, attribute)
            if isinstance(value, bool) or not np.isfinite(value) or value <= 0:
                raise ValueError(f"{attribute}: expected a positive number, got {value!r}")

    def angles(self, system) -> list[int]:
        """Indices of the pendulum angles of ``system``.

        Parameters
        ----------
        system : MuJoCoSystem
            The plant's system (:func:`pysindy_xl.mujoco.get_system`).

        Returns
        -------
        list of int
            Indices of its angle coordinates.
        """
        return list(system.angle_coordinates)

    def goal(self, system) -> np.ndarray:
        """Goal state: every angle at ``pi`` (upright), the rest zero.

        Parameters
        ----------
        system : MuJoCoSystem
            The plant's system, with ``n`` coordinates.

        Returns
        -------
        numpy.ndarray
            The goal ``[q, qd]`` (2n,).
        """
        goal = np.zeros(2 * system.n)
        goal[self.angles(system)] = np.pi
        return goal

    def upright(self, states, system) -> np.ndarray:
        """Whether each state has every angle within ``tolerance`` of upright.

        Parameters
        ----------
        states : array (N, 2n) or (2n,)
            States ``[q, qd]``.
        system : MuJoCoSystem
            The plant's system.

        Returns
        -------
        numpy.ndarray
            Booleans (N,): the wrapped distance of every angle from ``pi`` is at most
            ``tolerance``.
        """
        states = np.atleast_2d(states)
        theta = states[:, self.angles(system)]
        error = np.abs((theta - np.pi + np.pi) % (2 * np.pi) - np.pi)
        return np.all(error <= self.tolerance, axis=1)

    def outside_track(self, states, system) -> np.ndarray:
        """Whether each state has a linear coordinate beyond ``track_limit``.

        Parameters
        ----------
        states : array (N, 2n) or (2n,)
            States ``[q, qd]``.
        system : MuJoCoSystem
            The plant's system.

        Returns
        -------
        numpy.ndarray
            Booleans (N,): some non-angle coordinate has ``|q_i| > track_limit``.
        """
        states = np.atleast_2d(states)
        linear = [i for i in range(system.n) if i not in self.angles(system)]
        return np.any(np.abs(states[:, linear]) > self.track_limit, axis=1)

    def stop_rule(self, system, control_dt: float):
        """The stop rule of an attempt, for :meth:`MuJoCoPlant.run`.

        Parameters
        ----------
        system : MuJoCoSystem
            The plant's system.
        control_dt : float
            Control period (s) of the plant; unused by the swing-up rule, which reads the
            time ``t`` it is called with.

        Returns
        -------
        callable
            ``stop(state (2n,), t) -> str or None``: ``"success"`` after ``hold_s`` seconds
            upright in a row, ``"track"`` when the cart leaves the track, None otherwise. It
            keeps the start of the current upright run, so use a new one per episode.

        Examples
        --------
        >>> from pysindy_xl.mujoco import get_system
        >>> system = get_system("cart-pole")
        >>> stop = SwingUpTask("cart-pole", force_limit=10.0, hold_s=0.5).stop_rule(system, 0.1)
        >>> up = np.array([0.0, np.pi, 0.0, 0.0])
        >>> [stop(up, t) for t in (0.0, 0.3, 0.5)], stop(np.array([2.0, 0.0, 0.0, 0.0]), 0.6)
        ([None, None, 'success'], 'track')
        """
        held = {"since": None}

        def stop(state, t):
            if self.outside_track(state, system)[0]:
                return "track"
            if self.upright(state, system)[0]:
                if held["since"] is None:
                    held["since"] = t
                if t - held["since"] >= self.hold_s - 1e-9:
                    return "success"
            else:
                held["since"] = None
            return None

        return stop

    def evaluate(self, episode, system) -> dict:
        """Score an episode from its true states at every MuJoCo step.

        Parameters
        ----------
        episode : Episode
            A run on the plant (:meth:`MuJoCoPlant.run`).
        system : MuJoCoSystem
            The plant's system.

        Returns
        -------
        dict
            ``success`` (upright ``hold_s`` in a row, never off the track, forces within the
            limit), ``upright_s`` (longest time upright in a row), ``max_abs_x`` (largest
            distance of a linear coordinate from the centre), ``max_abs_force``.
        """
        states = episode.states
        dt = float(episode.t[1] - episode.t[0]) if len(episode.t) > 1 else 0.0
        up = self.upright(states, system)
        longest, run = 0, 0
        for flag in up:
            run = run + 1 if flag else 0
            longest = max(longest, run)
        upright_s = max(longest - 1, 0) * dt
        linear = [i for i in range(system.n) if i not in self.angles(system)]
        max_x = float(np.max(np.abs(episode.q[:, linear]))) if linear else 0.0
        max_force = float(np.max(np.abs(episode.controls))) if episode.controls.size else 0.0
        success = (upright_s >= self.hold_s - 0.05 and max_x <= self.track_limit
                   and max_force <= self.force_limit + 1e-9)
        return {"success": bool(success), "upright_s": float(upright_s), "max_abs_x": max_x,
                "max_abs_force": max_force}


def get_task(system: str, task: str = "swing-up", force_limit: float | None = None,
             track_limit: float = 1.5, **options) -> SwingUpTask:
    """The task ``task`` on ``system``.

    Parameters
    ----------
    system : str
        ``"cart-pole"`` or ``"cart-double-pendulum"``.
    task : {"swing-up"}, default "swing-up"
        Name of the task (:data:`TASKS`).
    force_limit : float, optional
        Largest force on the cart (N); default 10 N for the cart-pole, 20 N for the cart
        double pendulum.
    track_limit : float, default 1.5
        Half length of the track (m).
    **options
        Further fields of :class:`SwingUpTask`.

    Returns
    -------
    SwingUpTask

    Examples
    --------
    >>> get_task("cart-pole").force_limit
    10.0
    >>> get_task("cart-pole", "balance")
    Traceback (most recent call last):
    ...
    ValueError: task: expected one of ('swing-up',), got 'balance'
    """
    if task not in TASKS:
        raise ValueError(f"task: expected one of {TASKS}, got {task!r}")
    if system not in _FORCE_LIMITS:
        raise ValueError(f"system: the swing-up task is defined for {sorted(_FORCE_LIMITS)}, "
                         f"got {system!r}")
    limit = _FORCE_LIMITS[system] if force_limit is None else float(force_limit)
    return SwingUpTask(system, limit, float(track_limit), **options)
