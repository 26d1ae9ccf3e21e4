"""The time grid of recorded trajectories: what the weak form does with jitter and gaps.

Logged time stamps are rarely uniform: a 1 kHz robot log has steps that jitter about their
median and occasional gaps of several steps where samples were lost. Every part of the weak
form works on the stamps as recorded: the smoother penalizes divided differences on the actual
times, each weighted by the time it spans (:mod:`~pysindy_xl.weak.smoothing`), the test
functions are placed in time and integrated with quadrature weights of the actual grid
(:mod:`~pysindy_xl.weak.bumps`), and the propagated noise is drawn per recorded sample.

**Gaps.** A gap is harmless while the signal is resolved across it: the smoother interpolates
it as a smoothing spline would, and a test function whose support covers it is still
integrated accurately. A test function of half-width ``h`` counts as resolved with
``min_samples`` samples per half-width (:class:`~pysindy_xl.weak.BumpTestFunctions`), so a
step longer than ``h / min_samples`` is a gap no test function or smoother may span: the
trajectory is cut there into segments, each smoothed and integrated on its own
(:func:`split_at_gaps`). The fit records each cut (``weak_info_["gaps"]``) and warns about
segments too short for a test function, which are left out.

**Repeated stamps** (a step of zero or a negative one) are refused at the input with a
``ValueError`` naming the first of them: two positions at one time are two measurements of
one sample, and which to keep (or their mean) is the user's decision.
"""

from __future__ import annotations

import numpy as np

from .smoothing import is_uniform

__all__ = ["split_at_gaps", "grid_summary"]


def split_at_gaps(trajectories, max_gap: float):
    """Cut trajectories where a time step exceeds ``max_gap``.

    Parameters
    ----------
    trajectories : list of dict
        Each with ``"t"`` (N,) and other arrays of N samples along their first axis (or None).
    max_gap : float
        Longest step kept inside a segment (time units).

    Returns
    -------
    segments : list of dict
        The pieces, in order, with the same keys; a trajectory without a gap is passed as is.
    source : ndarray of int
        For each segment, the index of its trajectory.
    gaps : list of dict
        One per cut: ``trajectory``, ``time`` (the last stamp before the gap) and ``length``.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.array([0.0, 0.1, 0.2, 1.0, 1.1])
    >>> segments, source, gaps = split_at_gaps([{"t": t, "x": t[:, None], "u": None}], 0.5)
    >>> [s["t"].tolist() for s in segments], source.tolist(), gaps
    ([[0.0, 0.1, 0.2], [1.0, 1.1]], [0, 0], [{'trajectory': 0, 'time': 0.2, 'length': 0.8}])
    """
    segments, source, gaps = [], [], []
    for k, d in enumerate(trajectories):
        steps = np.diff(d["t"])
        cuts = np.flatnonzero(steps > max_gap)
        if cuts.size == 0:
            segments.append(d)
            source.append(k)
            continue
        gaps += [{"trajectory": k, "time": float(d["t"][i]), "length": float(steps[i])}
                 for i in cuts]
        n_samples = len(d["t"])
        for piece in np.split(np.arange(n_samples), cuts + 1):
            segments.append({key: value[piece] if _per_sample(value, n_samples) else value
                             for key, value in d.items()})
            source.append(k)
    return segments, np.array(source, dtype=int), gaps


def _per_sample(value, n_samples: int) -> bool:
    return isinstance(value, np.ndarray) and value.ndim >= 1 and len(value) == n_samples


def grid_summary(times) -> dict:
    """Median and largest time step, and whether the grids are uniform.

    Parameters
    ----------
    times : list of arrays
        The stamps of each trajectory.

    Returns
    -------
    dict
        ``uniform`` (every grid's steps equal to 1e-3 of their mean), ``median_step``,
        ``max_step`` and ``min_step`` over all trajectories.

    Examples
    --------
    >>> import numpy as np
    >>> grid_summary([np.array([0.0, 0.5, 1.0, 3.0])])
    {'uniform': False, 'median_step': 0.5, 'max_step': 2.0, 'min_step': 0.5}
    """
    steps = np.concatenate([np.diff(np.asarray(t, dtype=float)) for t in times])
    return {"uniform": all(is_uniform(t) for t in times),
            "median_step": float(np.median(steps)), "max_step": float(steps.max()),
            "min_step": float(steps.min())}
