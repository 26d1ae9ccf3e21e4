"""Constraint-aware data: which samples and test-function windows a fit may use.

While a joint limit, a contact or an equality constraint pushes, the motion obeys
``EL(L) + friction = tau + tau_constraint``, which the catalogs cannot express unless
``tau_constraint`` is given as a known force; by default the strong form drops those samples
(:func:`unconstrained_samples`), the weak form the windows touching one
(:func:`unconstrained_windows`). Frictionloss marks no sample: the catalogs model it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["unconstrained_samples", "unconstrained_windows", "contiguous_segments"]


def _mask(active, name: str = "constraint_active") -> np.ndarray:
    a = np.asarray(active)
    if a.ndim != 1 or a.dtype.kind not in "biu":
        raise ValueError(f"{name}: expected a 1-D boolean array, got {a.dtype} {a.shape}")
    return a.astype(bool)


def unconstrained_samples(constraint_active, margin: int = 0):
    """Samples a strong-form (pointwise) fit may keep: no constraint acts within ``margin``.

    Parameters
    ----------
    constraint_active : array of bool, shape (N,), or list of such arrays
        The per-sample mask of a trajectory (:attr:`Trajectory.constraint_active`), or one per
        trajectory.
    margin : int, default 0
        Also drop this many samples on each side of an active one (differentiated positions
        smear a constraint impulse over the differentiation window).

    Returns
    -------
    ndarray of bool, shape (N,), or list of them
        ``True`` for the samples to keep; same structure as the input.

    Examples
    --------
    >>> import numpy as np
    >>> active = np.array([0, 0, 0, 1, 0, 0, 0, 0], dtype=bool)
    >>> unconstrained_samples(active).astype(int)
    array([1, 1, 1, 0, 1, 1, 1, 1])
    >>> unconstrained_samples(active, margin=2).astype(int)
    array([1, 0, 0, 0, 0, 0, 1, 1])
    """
    if isinstance(margin, bool) or not isinstance(margin, (int, np.integer)) or margin < 0:
        raise ValueError(f"margin: expected an integer >= 0, got {margin!r}")
    if isinstance(constraint_active, (list, tuple)):
        return [unconstrained_samples(a, margin) for a in constraint_active]
    active = _mask(constraint_active)
    if margin and active.any():
        # dilation by a box of width 2 margin + 1
        counts = np.concatenate([[0], np.cumsum(active)])
        idx = np.arange(active.size)
        low = np.clip(idx - margin, 0, active.size)
        high = np.clip(idx + margin + 1, 0, active.size)
        active = counts[high] - counts[low] > 0
    return ~active


def unconstrained_windows(support, constraint_active) -> np.ndarray:
    """Test-function windows a weak-form fit may keep: their support touches no active sample.

    ``support[w, k]`` (shape (W, N)): sample ``k`` lies in the support of test function ``w``
    (``Phi != 0`` of one trajectory); ``constraint_active`` (N,) is that trajectory's mask.
    Returns a bool array (W,), ``True`` for the windows to keep.

    Parameters
    ----------
    support : array_like of bool, shape (W, N)
        ``support[w, k]``: sample ``k`` lies in the support of test function ``w``.
    constraint_active : array_like of bool, shape (N,)
        The trajectory's mask.

    Returns
    -------
    numpy.ndarray of bool, shape (W,)
        True for the windows to keep.

    Examples
    --------
    >>> import numpy as np
    >>> support = np.array([[1, 1, 1, 0, 0, 0],
    ...                     [0, 0, 1, 1, 1, 0],
    ...                     [0, 0, 0, 0, 1, 1]], dtype=bool)
    >>> unconstrained_windows(support, np.array([0, 0, 0, 1, 0, 0], dtype=bool))
    array([ True, False,  True])
    """
    active = _mask(constraint_active)
    support = np.asarray(support)
    if support.ndim != 2 or support.shape[1] != active.size:
        raise ValueError(f"support: expected shape (n_windows, {active.size}) like "
                         f"constraint_active, got {support.shape}")
    return ~(support != 0)[:, active].any(axis=1)


def contiguous_segments(keep, min_length: int = 2) -> list[slice]:
    """Runs of consecutive kept samples, as slices, dropping runs shorter than ``min_length``.

    ``keep`` (N,) marks the samples to keep (e.g. from :func:`unconstrained_samples`).

    Parameters
    ----------
    keep : array_like of bool, shape (N,)
        The samples to keep (e.g. from :func:`unconstrained_samples`).
    min_length : int, default=2
        Shortest run kept.

    Returns
    -------
    list of slice
        The runs, in order.

    Examples
    --------
    >>> import numpy as np
    >>> contiguous_segments(np.array([1, 1, 0, 1, 0, 1, 1, 1], dtype=bool))
    [slice(0, 2, None), slice(5, 8, None)]
    """
    keep = _mask(keep, "keep")
    if (isinstance(min_length, bool) or not isinstance(min_length, (int, np.integer))
            or min_length < 1):
        raise ValueError(f"min_length: expected an integer >= 1, got {min_length!r}")
    edges = np.diff(np.concatenate([[0], keep.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return [slice(int(a), int(b)) for a, b in zip(starts, ends, strict=True)
            if b - a >= min_length]
