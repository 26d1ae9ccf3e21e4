"""An identified model simulated along its own training runs: whether it stays in their range.

A law can fit its training rows well and still be no model of the system: a stand-in whose
potential is not convex where the system's is (two springs' terms traded for a third with
the wrong sign) holds the recorded rows within a fraction of a percent and drives every state
away from them, exponentially, once simulated (an unforced half-car at 1 % noise: 0.14 held
out, simulation off by 10 times the recorded velocities within a third of a second). The
rows cannot show it; a simulation of the recorded runs does, cheaply: a model that leaves
its own data by an order of magnitude is no model of it, whatever its residual.
:func:`own_runs_divergence` simulates each run from its first state under its recorded
forces and says where the states leave ``widen`` times the recorded range.

The verdict holds for free runs (no forces: a passive system keeps or loses the energy it
starts with, and a model of it stays near the states that energy reaches) and for forces that
do not depend on the state. Forces recorded under feedback (a balanced inverted pendulum, an
arm held by its servos) replayed open loop do not hold an unstable system, and its right
model leaves such a run too: :func:`~pysindy_xl.catalog.grow_catalog` asks it of unforced
data only.
"""

from __future__ import annotations

import numpy as np

from .._inputs import aligned, as_list, check_array

__all__ = ["own_runs_divergence", "WIDEN", "MAX_EVALUATIONS", "SAMPLES", "FREE_RUNS_ADVICE"]

#: How many times the recorded range (about its middle) a state may reach before the model is
#: said to leave its data: an order of magnitude, far beyond what a wrong but stable model's
#: drift or a resonance of the recorded forcing reaches, and crossed within a few time constants
#: by an exponential divergence.
WIDEN = 10.0

#: Right-hand sides per run before a simulation stops without a verdict (a stiff model: the
#: check says nothing then; a count, not a time, so the verdict does not depend on the machine).
MAX_EVALUATIONS = 100_000

#: Samples of a run the check reads at most (a longer run is read every k-th sample): its
#: range, its first state and the simulation's output times.
SAMPLES = 2000

#: What to try where a model leaves its own free runs.
FREE_RUNS_ADVICE = ("try longer or less noisy free runs, runs that reach further from rest, or "
                    "runs with measured forces")


def own_runs_divergence(model, x, t, u=None, x_dot=None, *, kinds=None, widen: float = WIDEN,
                        max_evaluations: int = MAX_EVALUATIONS) -> str | None:
    r"""Where a fitted model, simulated along its own runs, leaves them: the reason, or None.

    Each run is simulated from its first state (positions and velocities: ``x_dot`` where
    given, else a smoothing spline's, :class:`~pysindy_xl.weak.WhittakerSmoother`) under its
    recorded forces ``u`` (cubic between samples), to a relative precision of ``1e-4`` (a
    verdict on an order of magnitude); a run longer than :data:`SAMPLES` samples is read
    every k-th sample. The model leaves the run where a state
    component ``s`` (each velocity, and each position but an angle's: a pendulum may go over
    the top and turn on) leaves ``widen`` times the recorded range about its middle,

    .. math:: |s(t) - c| > w\,h, \qquad c = \tfrac12(\max s + \min s), \quad
              h = \tfrac12(\max s - \min s),

    or where the simulation stops on a singular mass matrix, a non-finite derivative or an
    integrator failure. A simulation that reaches ``max_evaluations`` right-hand sides stops
    without a verdict (stiff, not divergent as far as it went), and so does one whose angle
    turns past ``widen`` squared times the largest checked bound (the velocities in range).

    Parameters
    ----------
    model : XLSINDy
        Fitted, with accelerations (``dynamics_``).
    x : array (N, n) or list of them
        The training positions.
    t : array (N,) or list of them
        Their times.
    u : array (N, n), list of them or None, default None
        The recorded generalized forces (None: unforced).
    x_dot : array (N, n), list of them or None, default None
        Measured velocities; None: estimated from ``x``.
    kinds : sequence of {"linear", "angle"} or None, default None
        Each coordinate's kind (None: all linear, every position checked).
    widen : float, default :data:`WIDEN`
        Times the recorded range a state may reach (``w``).
    max_evaluations : int, default :data:`MAX_EVALUATIONS`
        Right-hand sides per run before a simulation stops without a verdict.

    Returns
    -------
    str or None
        ``"run k leaves its recorded range (name) at t = ... s"`` or ``"run k: simulation
        stopped at t = ... s (reason)"`` for the first run the model leaves, else None.

    Raises
    ------
    ValueError
        When the model has no accelerations, ``widen`` is not above 1, ``kinds`` is not one
        kind per coordinate, or the runs' arrays do not match (a column per coordinate, a
        time per sample, the same layout as ``x``).

    Examples
    --------
    Two laws identified from forced runs, the spring ``2 x'' + 3 x = u`` and the same with the
    spring's sign turned, each simulated along a free run of the spring:

    >>> import numpy as np, pysindy_xl as px
    >>> t = np.linspace(0, 20, 2001)
    >>> x = np.c_[np.sin(t) + 0.5 * np.sin(2.7 * t)]
    >>> x_ddot = (-np.sin(t) - 3.645 * np.sin(2.7 * t))[:, None]
    >>> catalog = px.AutomaticCatalog(["x"], kinetic="constant")
    >>> spring = px.XLSINDy(catalog).fit(x, t, u=2 * x_ddot + 3 * x)
    >>> turned = px.XLSINDy(catalog).fit(x, t, u=2 * x_ddot - 3 * x)
    >>> free = np.c_[np.cos(np.sqrt(1.5) * t)]
    >>> own_runs_divergence(spring, free, t) is None
    True
    >>> own_runs_divergence(turned, free, t)
    'run 0 leaves its recorded range (x) at t = 2.5 s'
    """
    from ..dynamics.inputs import force_function
    from ..dynamics.mass_matrix import SimulationError
    from ..weak import WhittakerSmoother

    if getattr(model, "dynamics_", None) is None:
        raise ValueError("model: expected a fitted model with accelerations (dynamics_)")
    if not widen > 1:
        raise ValueError(f"widen: expected a number above 1, got {widen!r}")
    xs, is_list = as_list(x, "x")
    ts, us, x_dots = (aligned(value, name, xs, is_list, "runs")
                      for value, name in ((t, "t"), (u, "u"), (x_dot, "x_dot")))
    names = list(model.feature_library_.coords.names)
    n = len(names)
    kinds = ["linear"] * n if kinds is None else list(kinds)
    if len(kinds) != n or not set(kinds) <= {"linear", "angle"}:
        raise ValueError(f"kinds: expected {n} of 'linear' or 'angle' (one per coordinate "
                         f"{names}), got {kinds}")
    angles = np.array([kind == "angle" for kind in kinds])
    checked = np.r_[~angles, np.ones(n, dtype=bool)]
    labels = names + [f"{name}_dot" for name in names]
    for k, (xk, tk, uk, vk) in enumerate(zip(xs, ts, us, x_dots, strict=True)):
        label = f"[{k}]" if is_list else ""
        xk = check_array(xk, f"x{label}", n_columns=n)
        tk = np.asarray(tk, dtype=float)
        if tk.shape != (len(xk),):
            raise ValueError(f"t{label}: expected {len(xk)} times, got shape {tk.shape}")
        forces = None if uk is None else force_function(np.asarray(uk, dtype=float), tk, n)
        # a range and a start need no more than a few thousand samples of a run
        every = slice(None, None, max(1, len(tk) // SAMPLES))
        xk, tk = xk[every], tk[every]
        velocities = (WhittakerSmoother().smooth(tk, xk)[1] if vk is None
                      else np.asarray(vk, dtype=float).reshape(-1, n)[every])
        recorded = np.c_[xk, velocities]
        low, high = recorded.min(axis=0), recorded.max(axis=0)
        middle, half = (high + low) / 2, np.maximum((high - low) / 2, np.finfo(float).tiny)
        # a state past the box by far stops the run: beyond it the verdict is settled
        bound = float(np.max((np.abs(middle) + widen * half)[checked])) * widen
        try:
            states, stopped = model.simulate(recorded[0], tk, forces, rtol=1e-4, atol=1e-8,
                                             divergence_bound=bound, timeout=None,
                                             max_evaluations=max_evaluations), None
        except SimulationError as error:
            states, stopped = error.states, error
        outside = np.abs(states[:, checked] - middle[checked]) > widen * half[checked]
        if outside.any():
            row, column = np.argwhere(outside)[0]
            return (f"run {k} leaves its recorded range ({np.array(labels)[checked][column]}) "
                    f"at t = {tk[row] - tk[0]:.2g} s")
        # (a stop at the bound with every checked state inside the box: an angle turned past
        # it; a checked state cannot cross from the box to ten times beyond within a sample)
        if stopped is not None and stopped.reason not in ("too many evaluations", "diverged"):
            return (f"run {k}: simulation stopped at t = {stopped.t_failed - tk[0]:.2g} s "
                    f"({stopped.reason})")
    return None
