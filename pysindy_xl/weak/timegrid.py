"""The time grid of recorded trajectories: what the weak form does with jitter and gaps.

The weak form works on the stamps as recorded (the smoother's divided differences, the test
functions' quadrature, the noise drawn per sample). A step longer than ``h / min_samples``
(:class:`~pysindy_xl.weak.BumpTestFunctions`) is a gap that no test function or smoother may span:
the trajectory is cut there into segments handled on their own (:func:`split_at_gaps`;
``weak_info_["gaps"]``). Stamps that are arrival times rather than sampling times make positions
smooth in sample order look noisy at their stamps: :func:`stamp_noise_ratio` compares the two, and
the fit warns above :data:`STAMP_NOISE_RATIO`. Repeated stamps are refused at the input.
"""

from __future__ import annotations

import numpy as np

from .smoothing import choose_lambda, is_uniform

__all__ = ["split_at_gaps", "grid_summary", "stamp_noise_ratio", "STAMP_NOISE_RATIO"]

#: :func:`stamp_noise_ratio` above which the stamps are suspected not to be sampling times.
STAMP_NOISE_RATIO = 2.0


def split_at_gaps(trajectories, max_gap: float):
    """Cut ``trajectories`` (dicts with ``"t"`` (N,) and arrays of N samples, or None) where a time
    step exceeds ``max_gap``.

    Returns the segments (a trajectory without a gap passed as is), the index of each segment's
    trajectory, and one dict per cut: ``trajectory``, ``time`` (the last stamp before the gap)
    and ``length``.

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
    """Median, largest and smallest time step over ``times`` (one array per trajectory), and
    whether every grid is uniform.

    >>> import numpy as np
    >>> grid_summary([np.array([0.0, 0.5, 1.0, 3.0])])
    {'uniform': False, 'median_step': 0.5, 'max_step': 2.0, 'min_step': 0.5}
    """
    steps = np.concatenate([np.diff(np.asarray(t, dtype=float)) for t in times])
    return {"uniform": all(is_uniform(t) for t in times), "median_step": float(np.median(steps)),
            "max_step": float(steps.max()), "min_step": float(steps.min())}


def stamp_noise_ratio(t, x, noise, order: int = 3) -> float:
    """Median over coordinates of the positions' ``noise`` (n,) at their stamps ``t`` over their
    noise read at uniform steps (smoother penalty of ``order``).

    Below 1 for stamps that are the sampling times of a smooth motion; above
    :data:`STAMP_NOISE_RATIO`, the stamps look like arrival times.

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
    in_order = np.array([choose_lambda(steps, column, order, "gcv")[1]
                         for column in np.asarray(x, dtype=float).T])
    return float(np.median(np.asarray(noise, dtype=float) / np.maximum(in_order, 1e-300)))
