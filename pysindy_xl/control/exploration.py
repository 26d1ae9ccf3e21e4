"""Exploration of a plant for identification: a model-free excitation within the force limit,
kept on a finite track.

:func:`exploration_policy` excites the actuated linear coordinate (a random sum of sinusoids
plus energy pumping, with a weak pull to the centre). On its own it can run a cart into the
end of its track when the force limit is large for the system (at 20 N the cart double
pendulum's cart reaches 5-6 m/s), which ends the recording early. :class:`TrackGuard` wraps
any such policy: when the cart, moving outwards, is predicted to come within a margin of the
track's end, it takes over and brings the cart back towards the centre with a
proportional-derivative force, then hands control back to the excitation. The recording goes
on throughout (the forces of the return are recorded like any other, so its data serve the
identification as well), and every second of it is plant time."""

from __future__ import annotations

import numpy as np

__all__ = ["TrackGuard", "exploration_policy"]


def exploration_policy(force_limit: float, rng: np.random.Generator, n_components: int = 6,
                       frequencies=(0.3, 2.5), centering=(4.0, 2.0), linear: int = 0,
                       pump: float = 0.6, angle: int | None = 1):
    r"""``policy(state, t) -> u`` (1,) exciting the cart within the limits, model-free.

    .. math:: u = s(t) + \rho\, u_{max} \tanh(-2 \dot\theta \cos\theta)
              - k_p p - k_d \dot p

    ``s``: a random sum of ``n_components`` sinusoids (amplitude ``0.6 force_limit`` in total,
    frequencies uniform in ``frequencies``); the second term pumps energy into the pendulum of
    angle ``angle`` (the cart accelerates against ``theta_dot cos(theta)``, which raises the
    energy of any pendulum on a cart, whatever its length and mass; ``pump`` = ``rho``, 0 to
    switch off); the last keeps the linear coordinate ``linear`` near the centre. The plant
    clips the sum to the force limit.

    Parameters
    ----------
    force_limit : float
        Largest force (N).
    rng : numpy.random.Generator
        Draws the sinusoids.
    n_components : int, default 6
        Number of sinusoids.
    frequencies : tuple of float, default (0.3, 2.5)
        Range of the sinusoids' frequencies (Hz).
    centering : tuple of float, default (4.0, 2.0)
        ``k_p``, ``k_d``.
    linear : int, default 0
        Index of the pushed linear coordinate.
    pump : float, default 0.6
        Weight ``rho`` of the energy pumping, as a fraction of the force limit (0: none).
    angle : int or None, default 1
        Index of the pumped angle (None: no pumping).

    Returns
    -------
    callable
        ``policy(state (2n,), t) -> u (1,)``.

    Examples
    --------
    >>> policy = exploration_policy(10.0, np.random.default_rng(0))
    >>> policy(np.zeros(4), 0.0).shape
    (1,)
    """
    freq = rng.uniform(*frequencies, n_components)
    phase = rng.uniform(0.0, 2 * np.pi, n_components)
    weight = rng.uniform(0.5, 1.0, n_components)
    weight = 0.6 * force_limit * weight / weight.sum()
    kp, kd = centering

    def policy(state, t):
        n = len(state) // 2
        signal = float(weight @ np.sin(2 * np.pi * freq * t + phase))
        if angle is not None and pump:
            signal += pump * force_limit * np.tanh(-2.0 * state[n + angle]
                                                   * np.cos(state[angle]))
        return np.array([signal - kp * state[linear] - kd * state[n + linear]])

    return policy


class TrackGuard:
    r"""``guard(state, t) -> u``: a policy kept on a finite track by a return to the centre.

    With ``p`` the linear coordinate, ``v`` its velocity, ``L`` the half length of the
    track and ``T`` the look-ahead, the guard takes over from ``policy`` when the cart moves
    outwards (``p v > 0``) and

    .. math:: |p + v T| > L - m,

    and applies, clipped to the force limit ``u_{max}``,

    .. math:: u = -u_{max}\, \mathrm{clip}\big(p / (L/2) + v / v_r,\ -1,\ 1\big),

    a full brake while the cart still moves outwards faster than ``v_r``, then a
    proportional-derivative pull to the centre. It hands back once ``|p| < L/2`` and
    ``|p + v T| < L/2``. It needs no model: only the track's length, the force limit and the
    state.

    Parameters
    ----------
    policy : callable
        ``policy(state (2n,), t) -> u (1,)``, the excitation (for instance
        :func:`exploration_policy`).
    track_limit : float
        Half length of the track ``L`` (m).
    force_limit : float
        Largest force ``u_max`` (N).
    linear : int, default 0
        Index of the linear coordinate on the track (the actuated one).
    lookahead : float, default 0.1
        Look-ahead ``T`` (s).
    margin : float, default 0.2
        Margin ``m`` to the end of the track (m).
    return_speed : float, default 1.0
        Speed ``v_r`` (m/s) of the derivative term: at ``v_r`` outwards the brake is full.

    Attributes
    ----------
    returns : int
        Times the guard took over.
    guarded : list of bool
        Per call: whether the guard's force was applied (``sum(guarded) * control_dt`` are
        the seconds of return).

    Examples
    --------
    A cart at 1.2 m moving outwards at 2 m/s is braked at the full force; at the centre the
    excitation acts.

    >>> guard = TrackGuard(lambda state, t: np.array([5.0]), track_limit=1.5, force_limit=20.0)
    >>> guard(np.array([1.2, 0.0, 2.0, 0.0]), 0.0), guard.returns
    (array([-20.]), 1)
    >>> guard(np.array([0.1, 0.0, -0.1, 0.0]), 0.5), guard.guarded
    (array([5.]), [True, False])
    """

    def __init__(self, policy, track_limit: float, force_limit: float, linear: int = 0,
                 lookahead: float = 0.1, margin: float = 0.2, return_speed: float = 1.0):
        if not callable(policy):
            raise TypeError(f"policy: expected a callable policy(state, t) -> u, got "
                            f"{type(policy).__name__}")
        for name, value in (("track_limit", track_limit), ("force_limit", force_limit),
                            ("return_speed", return_speed)):
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name}: expected a positive number, got {value!r}")
        for name, value in (("lookahead", lookahead), ("margin", margin)):
            if not (np.isfinite(value) and value >= 0):
                raise ValueError(f"{name}: expected a number >= 0, got {value!r}")
        if margin >= track_limit / 2:
            raise ValueError(f"margin: expected less than half the track limit "
                             f"({track_limit / 2}), got {margin!r}")
        self.policy = policy
        self.track_limit = float(track_limit)
        self.force_limit = float(force_limit)
        self.linear = int(linear)
        self.lookahead = float(lookahead)
        self.margin = float(margin)
        self.return_speed = float(return_speed)
        self.returns = 0
        self.guarded = []
        self._returning = False

    def __call__(self, state, t):
        """The command at ``state`` and time ``t`` (class docstring).

        Parameters
        ----------
        state : array (2n,)
            ``[q, qd]``.
        t : float
            Time (s), passed to ``policy``.

        Returns
        -------
        numpy.ndarray
            ``u`` (1,).
        """
        state = np.asarray(state, dtype=float)
        n = len(state) // 2
        p, v = state[self.linear], state[n + self.linear]
        ahead = p + v * self.lookahead
        half = self.track_limit / 2
        if not self._returning and p * v > 0 \
                and abs(ahead) > self.track_limit - self.margin:
            self._returning = True
            self.returns += 1
        elif self._returning and abs(p) < half and abs(ahead) < half:
            self._returning = False
        self.guarded.append(self._returning)
        if self._returning:
            return np.array([-self.force_limit * float(np.clip(
                p / half + v / self.return_speed, -1.0, 1.0))])
        return np.asarray(self.policy(state, t), dtype=float).reshape(-1)
