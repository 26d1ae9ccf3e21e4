r"""Computed-torque tracking with an identified model (arms and other fully actuated systems).

For a reference ``q_r(t)`` with ``qd_r``, ``qdd_r``, the identified inverse dynamics
``tau = M(q, qd) qdd - f(q, qd, 0)`` (:meth:`~pysindy_xl.XLSINDy.predict_forces`) gives the
forces of the motion, and a PD law corrects what the model misses:

- ``"feedforward"``: :math:`\tau = \tau_{model}(q_r, \dot q_r, \ddot q_r) + K_p e + K_d \dot e`
  (the model along the reference, computed once for the whole trajectory);
- ``"computed-torque"``: :math:`\tau = M(q, \dot q)(\ddot q_r + K_p e + K_d \dot e)
  - f(q, \dot q, 0)` (the model at the measured state, every period);

with ``e = q_r - q``. ``model=None`` leaves the PD law alone.

A model whose dry friction has a lead in the acceleration (MuJoCo's regularized
``frictionloss``, :func:`~pysindy_xl.physical.friction.regularized_dry_friction`) carries,
to first order, a large inertia ``F tau / s`` inside the sticking zone ``|qd| < s``: the
impulse of the early switch. Evaluated pointwise along a sampled reference it gives a spike
whenever a sample falls inside that zone. ``min_speed`` evaluates the feedforward with each
reference speed raised to at least that value (its sign kept), i.e. with the sliding law
``F sign(qd)``."""

from __future__ import annotations

import numpy as np

__all__ = ["ComputedTorque"]

_MODES = ("feedforward", "computed-torque")


def _gains(value, n: int, name: str) -> np.ndarray:
    value = np.asarray(value, dtype=float)
    if value.ndim == 0:
        value = np.full(n, float(value))
    if value.shape != (n,) or not np.all(np.isfinite(value)) or np.any(value < 0):
        raise ValueError(f"{name}: expected a gain >= 0 or {n} of them, got shape "
                         f"{value.shape}")
    return value


class ComputedTorque:
    """Tracking controller ``policy(state, t) -> tau`` (n,) (module docstring).

    Parameters
    ----------
    model : XLSINDy or MassMatrixDynamics or None
        The identified model (its ``predict_forces``, or ``mass_and_forcing`` for dynamics);
        None for PD alone.
    reference : callable
        ``reference(t) -> (q_r, qd_r, qdd_r)``, each (n,), or arrays over times with
        ``reference_times`` (then vectorized).
    kp, kd : float or array (n,)
        PD gains (``K_p`` and ``K_d`` diagonal; in ``"computed-torque"`` mode they act on
        accelerations, else on forces).
    n : int
        Number of coordinates.
    mode : {"feedforward", "computed-torque"}, default "feedforward"
    force_limit : float or array (n,), optional
        Clip the output.
    feedforward_times : array (T,), optional
        In ``"feedforward"`` mode: evaluate the model along the reference at these times once,
        vectorized, and interpolate linearly in between (the per-period cost drops to a
        lookup).
    min_speed : float or array (n,), optional
        In ``"feedforward"`` mode: evaluate the model with each reference speed raised to at
        least this value, its sign kept (zero counts as positive): the sliding side of a dry
        friction law (module docstring). Default None: the reference speeds as they are.

    Examples
    --------
    A unit mass on a spring ``x'' + 4 x = tau``, its true model, tracking ``sin(t)``:

    >>> import pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> model = px.MassMatrixDynamics(c, [c.qdd[0] + 4 * c.q[0] - c.tau[0]])
    >>> ref = lambda t: (np.array([np.sin(t)]), np.array([np.cos(t)]), np.array([-np.sin(t)]))
    >>> control = ComputedTorque(model, ref, kp=10.0, kd=2.0, n=1)
    >>> control(np.array([0.0, 1.0]), 0.0)  # on the reference: the model's force only
    array([0.])
    >>> round(float(control(np.array([np.sin(1), np.cos(1)]), 1.0)[0]), 4)  # 3 sin(1)
    2.5244
    """

    def __init__(self, model, reference, kp, kd, n: int, mode: str = "feedforward",
                 force_limit=None, feedforward_times=None, min_speed=None):
        if mode not in _MODES:
            raise ValueError(f"mode: expected one of {_MODES}, got {mode!r}")
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise ValueError(f"n: expected a positive number of coordinates, got {n!r}")
        if not callable(reference):
            raise TypeError(f"reference: expected a callable t -> (q, qd, qdd), got "
                            f"{type(reference).__name__}")
        if model is not None and not (hasattr(model, "predict_forces")
                                      or hasattr(model, "mass_and_forcing")):
            raise TypeError(f"model: expected a fitted model with predict_forces or dynamics "
                            f"with mass_and_forcing (a model that gives accelerations), got "
                            f"{type(model).__name__}")
        self.model = model
        self.reference = reference
        self.n = int(n)
        self.kp = _gains(kp, self.n, "kp")
        self.kd = _gains(kd, self.n, "kd")
        self.mode = mode
        self.force_limit = None if force_limit is None else _gains(force_limit, self.n,
                                                                   "force_limit")
        self.min_speed = None if min_speed is None else _gains(min_speed, self.n, "min_speed")
        self._table = None
        if feedforward_times is not None and mode == "feedforward":
            times = np.asarray(feedforward_times, dtype=float).reshape(-1)
            if times.size < 2 or np.any(np.diff(times) <= 0):
                raise ValueError("feedforward_times: expected increasing times (at least two)")
            q_r, qd_r, qdd_r = (np.stack([np.asarray(part, dtype=float).reshape(self.n)
                                          for part in parts])
                                for parts in zip(*(reference(t) for t in times), strict=True))
            self._table = (times, self.inverse_dynamics(q_r, self._sliding(qd_r), qdd_r))

    def _sliding(self, qd) -> np.ndarray:
        """``qd`` with each speed raised to at least ``min_speed`` (sign kept)."""
        if self.min_speed is None:
            return qd
        qd = np.asarray(qd, dtype=float)
        floor = np.where(qd < 0, -self.min_speed, self.min_speed)
        return np.where(np.abs(qd) < self.min_speed, floor, qd)

    def inverse_dynamics(self, q, qd, qdd) -> np.ndarray:
        """The model's forces of a motion, ``M(q, qd) qdd - f(q, qd, 0)``.

        Parameters
        ----------
        q, qd, qdd : array (N, n) or (n,)
            Positions, velocities and accelerations.

        Returns
        -------
        numpy.ndarray
            Generalized forces (N, n); zeros without a model.
        """
        q, qd, qdd = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (q, qd, qdd))
        if self.model is None:
            return np.zeros_like(q)
        if hasattr(self.model, "predict_forces"):
            return np.asarray(self.model.predict_forces(q, qd, qdd))
        from ..feature_library import stack_variables
        mass, free = self.model.mass_and_forcing(stack_variables(q, qd))
        return np.einsum("sij,sj->si", mass, qdd) - free

    def __call__(self, state, t) -> np.ndarray:
        """The forces at the measured state and time (module docstring for the law).

        Parameters
        ----------
        state : array (2n,)
            The measured ``[q, qd]``.
        t : float
            Time (s) at which the reference is read.

        Returns
        -------
        numpy.ndarray
            Generalized forces (n,), clipped to ``force_limit`` when it is given.
        """
        state = np.asarray(state, dtype=float)
        if state.shape != (2 * self.n,):
            raise ValueError(f"state: expected shape ({2 * self.n},), got {state.shape}")
        q, qd = state[:self.n], state[self.n:]
        q_r, qd_r, qdd_r = (np.asarray(a, dtype=float).reshape(self.n)
                            for a in self.reference(t))
        e, ed = q_r - q, qd_r - qd
        if self.mode == "feedforward":
            if self._table is not None:
                times, forces = self._table
                model = np.array([np.interp(t, times, forces[:, j]) for j in range(self.n)])
            else:
                model = self.inverse_dynamics(q_r, self._sliding(qd_r), qdd_r)[0]
            tau = model + self.kp * e + self.kd * ed
        else:
            tau = self.inverse_dynamics(q, qd, qdd_r + self.kp * e + self.kd * ed)[0]
        if self.force_limit is not None:
            tau = np.clip(tau, -self.force_limit, self.force_limit)
        return tau
