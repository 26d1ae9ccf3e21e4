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

**Stamps that are not sampling times.** A logger that stamps each sample when it arrives
(over a bus, in a loop) records the arrival times of samples taken at a fixed rate: the
delays then pass for motion, and positions that are smooth in sample order look noisy at
their stamps. Where samples were taken at their stamps it is the other way round (a smooth
signal read in sample order on jittered stamps looks noisy). :func:`stamp_noise_ratio`
compares the two noise levels; the fit warns when the positions are more than
:data:`STAMP_NOISE_RATIO` times noisier at their stamps and records the ratio
(``weak_info_["time_grid"]["stamp_noise_ratio"]``); the stamps are still used as given.

**Repeated stamps** (a step of zero or a negative one) are refused at the input with a
``ValueError`` naming the first of them: two positions at one time are two measurements of
one sample, and which to keep (or their mean) is the user's decision.
"""

from __future__ import annotations

import numpy as np

from .smoothing import _choose_lambda, is_uniform

__all__ = ["split_at_gaps", "grid_summary", "stamp_noise_ratio", "STAMP_NOISE_RATIO"]

#: Median over coordinates of the noise at the stamps over the noise in sample order above
#: which the stamps are suspected not to be sampling times (true stamps give less than 1:
#: a smooth signal read in sample order on jittered stamps looks noisy; arrival stamps
#: jittering by a tenth of the step give 10 or more).
STAMP_NOISE_RATIO = 2.0


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
        cuts = np.flatnonzero(steps > max_gap * (1 + 1e-9))  # not the stamps' rounding
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


def stamp_noise_ratio(t, x, noise, order: int = 3) -> float:
    """Median over coordinates of the positions' noise at their stamps over their noise read
    at uniform steps.

    Parameters
    ----------
    t : array, shape (N,)
    x : array, shape (N, n)
    noise : array, shape (n,)
        The noise level at the stamps (e.g. a :class:`~pysindy_xl.WhittakerSmoother`'s
        ``noise_`` on ``t``).
    order : int, default 3
        Order of the smoother's penalty.

    Returns
    -------
    float
        Below 1 for stamps that are the sampling times of a smooth motion; above
        :data:`STAMP_NOISE_RATIO`, the stamps look like arrival times.

    Examples
    --------
    Samples taken every 10 ms, stamped late by up to 3 ms:

    >>> import numpy as np
    >>> from pysindy_xl.weak import WhittakerSmoother
    >>> taken = np.arange(1000) * 0.01
    >>> stamps = taken + 0.003 * np.random.default_rng(0).random(1000)
    >>> x = np.column_stack([np.sin(taken), np.cos(0.5 * taken)])
    >>> smoother = WhittakerSmoother()
    >>> _ = smoother.smooth(stamps, x)
    >>> bool(stamp_noise_ratio(stamps, x, smoother.noise_) > STAMP_NOISE_RATIO)
    True
    """
    steps = np.arange(len(t), dtype=float)
    in_order = np.array([_choose_lambda(steps, column, order, "gcv")[1]
                         for column in np.asarray(x, dtype=float).T])
    return float(np.median(np.asarray(noise, dtype=float) / np.maximum(in_order, 1e-300)))
