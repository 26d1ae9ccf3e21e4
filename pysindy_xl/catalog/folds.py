"""The held-out folds of a catalog growth: which samples fit a candidate catalog and which
judge it.

Each run is cut into ``n_blocks`` contiguous time blocks. One split holds out the last block of
every run (**time**: how the model predicts later) and a region (how it extrapolates): the
block of each run whose states reach farthest from the run's median (``"block"``,
:func:`run_blocks`), or the stretches around the most extreme states of all the runs
(``"extremes"``, :func:`extreme_masks`: the training states all lie inside a threshold that the
held-out ones cross, so a stand-in fitted along the trajectories must extrapolate), or both.
Cross-validated, every block is held out in turn, one split per block (and with the extremes,
one more split judged on them). The training pieces are thinned to every ``stride``-th sample;
the held-out pieces are kept whole (the weak form integrates over them), and no test function
straddles the fold: each piece is fitted or judged on its own.
"""

from __future__ import annotations

import numpy as np

__all__ = ["held_out_splits", "run_blocks", "extreme_masks", "REGIONS"]

#: The region folds of :func:`held_out_splits`: ``"block"`` (the time block reaching farthest,
#: :func:`run_blocks`), ``"extremes"`` (the stretches around the most extreme states of all
#: runs, :func:`extreme_masks`) or ``"both"``.
REGIONS = ("block", "extremes", "both")
#: Share of the samples outside the last blocks that the extreme stretches hold out: enough
#: rows that the extremes' error is not noise where a stand-in and the law differ by little.
EXTREME_SHARE = 0.3


def run_blocks(t, x, n_blocks: int):
    """The default fold of one run.

    Parameters
    ----------
    t : array, shape (N,)
        Times.
    x : array, shape (N, n)
        Positions.
    n_blocks : int
        Contiguous time blocks of the run.

    Returns
    -------
    train : ndarray of bool, shape (N,)
        The samples outside the two held-out blocks.
    time_block : slice
        The last block.
    region_block : slice
        Of the other blocks, the one whose 90th percentile of the states' largest distance
        from the median (per coordinate, in interquartile ranges) is largest.
    """
    n = len(t)
    edges = np.linspace(0, n, n_blocks + 1).round().astype(int)
    spans = [slice(a, b) for a, b in zip(edges[:-1], edges[1:], strict=True)]
    scale = np.subtract(*np.percentile(x, [75, 25], axis=0))
    scale = np.where(scale > 0, scale, 1.0)
    reach = np.abs(x - np.median(x, axis=0)) / scale
    extreme = [float(np.percentile(reach[s].max(axis=1), 90)) for s in spans[:-1]]
    region = spans[int(np.argmax(extreme))]
    train = np.ones(n, dtype=bool)
    train[spans[-1]] = False
    train[region] = False
    return train, spans[-1], region


def _dilated(mask, margin: int):
    """``mask`` grown by ``margin`` samples on each side (a running maximum)."""
    counts = np.cumsum(np.r_[0, mask.astype(int)])
    index = np.arange(len(mask))
    low = np.clip(index - margin, 0, len(mask))
    high = np.clip(index + margin + 1, 0, len(mask))
    return counts[high] - counts[low] > 0


def extreme_masks(ts, xs, eligible, margin: float, fraction: float):
    """The stretches of the runs around their most extreme states: a fold that leaves out a
    region of the state space rather than a time block.

    A sample's reach is its largest distance from the median over the coordinates, each in
    interquartile ranges of all the runs' eligible samples. Every eligible sample reaching
    beyond a threshold is held out with ``margin`` of time on either side (so each held-out
    stretch holds a test function of half-width ``margin``, and the training pieces keep that
    far from it); the threshold is the lowest that holds out at most ``fraction`` of the
    eligible samples. The training samples then all lie inside the threshold: a model fitted
    on them is judged where it extrapolates, in every run at once.

    Parameters
    ----------
    ts : list of ndarray, each of shape (N_k,)
        Times of each run.
    xs : list of ndarray, each of shape (N_k, n)
        Positions of each run.
    eligible : list of ndarray of bool, each of shape (N_k,)
        Samples that may be held out (the others, e.g. another held-out block, are neither
        held out here nor counted).
    margin : float
        Time held out on either side of an extreme sample (a test function's half-width).
    fraction : float
        Largest share of the eligible samples held out, in (0, 1).

    Returns
    -------
    list of ndarray of bool, each of shape (N_k,)
        The held-out samples of each run (a subset of ``eligible``).

    Examples
    --------
    >>> t = np.linspace(0.0, 10.0, 1001)
    >>> x = (np.sin(3 * t) * (1 + t / 10))[:, None]     # the swing grows
    >>> held = extreme_masks([t], [x], [t < 8], margin=0.3, fraction=0.2)[0]
    >>> bool(held[t >= 8].any()), round(float(held.mean()), 2)
    (False, 0.15)
    >>> bool(np.abs(x[t < 8][~held[t < 8]]).max() < np.abs(x[held]).max())
    True
    """
    pool = np.vstack([xk[ok] for xk, ok in zip(xs, eligible, strict=True)])
    center = np.median(pool, axis=0)
    scale = np.subtract(*np.percentile(pool, [75, 25], axis=0))
    scale = np.where(scale > 0, scale, 1.0)
    reach = [np.where(ok, (np.abs(xk - center) / scale).max(axis=1), -np.inf)
             for xk, ok in zip(xs, eligible, strict=True)]
    margins = [max(1, int(np.ceil(margin / float(np.median(np.diff(tk)))))) for tk in ts]
    total = sum(int(ok.sum()) for ok in eligible)

    def held(threshold):
        return [_dilated(r > threshold, m) & ok
                for r, m, ok in zip(reach, margins, eligible, strict=True)]

    # bisection on the quantile of the reach: the held-out share falls as the threshold rises
    values = np.sort(np.concatenate([r[np.isfinite(r)] for r in reach]))
    low, high = 0, len(values) - 1  # held(values[high]) is empty
    while high - low > 1:
        middle = (low + high) // 2
        if sum(int(m.sum()) for m in held(values[middle])) <= fraction * total:
            high = middle
        else:
            low = middle
    return held(values[high])


def _pieces(mask):
    """``(start, stop)`` of each run of True in ``mask``."""
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(int), 0]))
    return list(zip(edges[::2], edges[1::2], strict=True))


def _outside(n, span):
    """Mask of ``n`` samples without ``span``."""
    mask = np.ones(n, dtype=bool)
    mask[span] = False
    return mask


def _split(arrays, masks, held, stride):
    """One split of the runs: ``(train, blocks)``, ``train`` the pieces of each run's mask
    (every ``stride``-th sample) and ``blocks`` one run-list per held-out block, each block
    given as ``(run, slice)`` pieces."""
    train = {key: [] for key in arrays}
    for k, mask in enumerate(masks):
        for a, b in _pieces(mask):
            for key, values in arrays.items():
                train[key].append(None if values is None or values[k] is None
                                  else np.asarray(values[k], dtype=float)[a:b:stride])
    for key in ("u", "x_dot", "x_ddot"):
        if any(v is None for v in train[key]):
            train[key] = None
    blocks = []
    for pieces in held:
        blocks.append({"x": [np.asarray(arrays["x"][k])[span] for k, span in pieces],
                       "t": [np.asarray(arrays["t"][k])[span] for k, span in pieces],
                       "u": None if arrays["u"] is None else
                       [np.asarray(arrays["u"][k], dtype=float)[span] for k, span in pieces]})
    return train, blocks


def _without_short(mask, length: int):
    """``mask`` without its runs of True shorter than ``length`` samples."""
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(int), 0]))
    starts, stops = edges[::2], edges[1::2]
    short = stops - starts < length
    marks = np.zeros(len(mask) + 1, dtype=int)
    np.add.at(marks, starts[short], 1)
    np.add.at(marks, stops[short], -1)
    return mask & ~(np.cumsum(marks)[:-1] > 0)


def _trained(ts, masks, margin):
    """Training masks without the pieces shorter than a test function of half-width
    ``margin`` (the gaps between extreme stretches: they give the weak form no row)."""
    return [_without_short(m, 2 * int(np.ceil(margin / float(np.median(np.diff(tk))))) + 1)
            for tk, m in zip(ts, masks, strict=True)]


def _extremes(arrays, spans, margin):
    """The held-out mask of the extreme states of each run outside its last block
    (:func:`extreme_masks`, a share :data:`EXTREME_SHARE` of those samples) and its pieces."""
    ts = [np.asarray(tk, dtype=float) for tk in arrays["t"]]
    xs = [np.asarray(xk, dtype=float).reshape(len(tk), -1) for tk, xk in zip(ts, arrays["x"],
                                                                          strict=True)]
    masks = extreme_masks(ts, xs, [_outside(len(tk), run[-1]) for tk, run in
                                   zip(ts, spans, strict=True)],
                          margin, EXTREME_SHARE)
    return masks, [(k, slice(a, b)) for k, mask in enumerate(masks) for a, b in _pieces(mask)]


def held_out_splits(arrays: dict, n_blocks: int, stride: int = 1,
                    cross_validate: bool = False, region: str = "block", margin=None):
    """The splits of a growth's search.

    Parameters
    ----------
    arrays : dict
        ``x``, ``t``, ``u``, ``x_dot``, ``x_ddot``: lists with one array per run (``u``,
        ``x_dot``, ``x_ddot`` may be None, or hold None per run).
    n_blocks : int
        Contiguous time blocks per run.
    stride : int, default 1
        The training pieces keep every ``stride``-th sample.
    cross_validate : bool, default False
        One split per block (each held out in turn) instead of one split holding out the time
        and region blocks (:func:`run_blocks`).
    region : {"block", "extremes", "both"}, default "block"
        What the region fold holds out besides the last block of each run: the block reaching
        farthest (:func:`run_blocks`), the stretches around the most extreme states of all the
        runs (:func:`extreme_masks`, a share :data:`EXTREME_SHARE` of the other samples, held
        out ``margin`` on either side), or both (three held-out blocks). Cross-validated,
        ``"extremes"`` and ``"both"`` add one split: fitted outside the extreme stretches and
        the last blocks, judged on the extreme stretches.
    margin : float, optional
        Time held out on either side of an extreme state: the test functions' half-width
        (needed unless ``region="block"``).

    Returns
    -------
    splits : list of (dict, list of dict)
        Per split, the training pieces (fit keyword arguments) and the held-out blocks (``x``,
        ``t``, ``u`` run-lists, one dict per block).
    reported : tuple of int
        Indices, into the held-out blocks of all splits in order, of the time and region
        blocks (cross-validated: the last block, and the first run's region block, or the
        extreme stretches).

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 100)
    >>> x = np.sin(6 * t)[:, None]
    >>> splits, reported = held_out_splits({"x": [x], "t": [t], "u": None, "x_dot": None,
    ...                                     "x_ddot": None}, n_blocks=5)
    >>> len(splits), len(splits[0][1]), reported
    (1, 2, (0, 1))
    >>> sum(len(piece) for piece in splits[0][0]["x"])
    60
    >>> splits, reported = held_out_splits({"x": [x], "t": [t], "u": None, "x_dot": None,
    ...                                     "x_ddot": None}, n_blocks=5, region="extremes",
    ...                                    margin=0.05)
    >>> len(splits[0][1]), reported
    (2, (0, 1))
    """
    if region not in REGIONS:
        raise ValueError(f"region: expected one of {REGIONS}, got {region!r}")
    if region != "block" and not (margin is not None and margin > 0):
        raise ValueError(f"margin: expected a positive time for region={region!r}, got {margin!r}")
    ts, xs = arrays["t"], arrays["x"]
    folds = [run_blocks(tk, np.asarray(xk).reshape(len(tk), -1), n_blocks)
             for tk, xk in zip(ts, xs, strict=True)]
    edges = [np.linspace(0, len(tk), n_blocks + 1).round().astype(int) for tk in ts]
    spans = [[slice(a, b) for a, b in zip(e[:-1], e[1:], strict=True)] for e in edges]
    if region != "block":
        extreme, pieces = _extremes(arrays, spans, margin)
    if not cross_validate:
        held = [[(k, fold[1]) for k, fold in enumerate(folds)]]
        masks = [_outside(len(tk), fold[1]) for tk, fold in zip(ts, folds, strict=True)]
        if region != "extremes":
            held.append([(k, fold[2]) for k, fold in enumerate(folds)])
            masks = [m & fold[0] for m, fold in zip(masks, folds, strict=True)]
        if region != "block":
            held.append(pieces)
            masks = _trained(ts, [m & ~e for m, e in zip(masks, extreme, strict=True)], margin)
        return [_split(arrays, masks, held, stride)], (0, 1)
    splits = [_split(arrays, [_outside(len(tk), run[j]) for tk, run in zip(ts, spans, strict=True)],
                     [[(k, run[j]) for k, run in enumerate(spans)]], stride)
              for j in range(n_blocks)]
    if region == "block":
        return splits, (n_blocks - 1, int(np.searchsorted(edges[0], folds[0][2].start)))
    masks = _trained(ts, [_outside(len(tk), run[-1]) & ~e for tk, run, e in
                          zip(ts, spans, extreme, strict=True)], margin)
    splits.append(_split(arrays, masks, [pieces], stride))
    return splits, (n_blocks - 1, n_blocks)
