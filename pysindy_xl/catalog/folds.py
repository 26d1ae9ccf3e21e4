"""The held-out folds of a catalog growth: which samples fit a candidate catalog and which
judge it.

Each run is cut into ``n_blocks`` contiguous time blocks. By default one split holds out two
blocks of every run: the last (**time**: how the model predicts later) and the one whose
states reach farthest from the run's median (**region**: how it extrapolates). Cross-validated,
every block is held out in turn, one split per block. The training pieces are thinned to
every ``stride``-th sample; the held-out blocks are kept whole (the weak form integrates over
them).
"""

from __future__ import annotations

import numpy as np

__all__ = ["held_out_splits", "run_blocks"]


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


def _pieces(mask):
    """``(start, stop)`` of each run of True in ``mask``."""
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(int), 0]))
    return list(zip(edges[::2], edges[1::2], strict=True))


def _outside(n, span):
    """Mask of ``n`` samples without ``span``."""
    mask = np.ones(n, dtype=bool)
    mask[span] = False
    return mask


def _split(arrays, masks, held_spans, stride):
    """One split of the runs: ``(train, held)``, ``train`` the pieces of each run's mask
    (every ``stride``-th sample) and ``held`` one run-list per held-out span of each run."""
    train = {key: [] for key in arrays}
    for k, mask in enumerate(masks):
        for a, b in _pieces(mask):
            for key, values in arrays.items():
                train[key].append(None if values is None or values[k] is None
                                  else np.asarray(values[k], dtype=float)[a:b:stride])
    for key in ("u", "x_dot", "x_ddot"):
        if any(v is None for v in train[key]):
            train[key] = None
    held = []
    for which in range(len(held_spans[0])):
        held.append({"x": [np.asarray(arrays["x"][k])[spans[which]]
                           for k, spans in enumerate(held_spans)],
                     "t": [np.asarray(arrays["t"][k])[spans[which]]
                           for k, spans in enumerate(held_spans)],
                     "u": None if arrays["u"] is None else
                     [np.asarray(arrays["u"][k], dtype=float)[spans[which]]
                      for k, spans in enumerate(held_spans)]})
    return train, held


def held_out_splits(arrays: dict, n_blocks: int, stride: int = 1,
                    cross_validate: bool = False):
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

    Returns
    -------
    splits : list of (dict, list of dict)
        Per split, the training pieces (fit keyword arguments) and the held-out blocks (``x``,
        ``t``, ``u`` run-lists, one dict per block).
    reported : tuple of int
        Indices, into the held-out blocks of all splits in order, of the time and region
        blocks (cross-validated: the last block, and the first run's region block).

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
    """
    ts, xs = arrays["t"], arrays["x"]
    folds = [run_blocks(tk, np.asarray(xk).reshape(len(tk), -1), n_blocks)
             for tk, xk in zip(ts, xs, strict=True)]
    if not cross_validate:
        return ([_split(arrays, [fold[0] for fold in folds],
                        [[fold[1], fold[2]] for fold in folds], stride)], (0, 1))
    edges = [np.linspace(0, len(tk), n_blocks + 1).round().astype(int) for tk in ts]
    spans = [[slice(a, b) for a, b in zip(e[:-1], e[1:], strict=True)] for e in edges]
    splits = [_split(arrays, [_outside(len(tk), run[j]) for tk, run in zip(ts, spans, strict=True)],
                     [[run[j]] for run in spans], stride) for j in range(n_blocks)]
    return splits, (n_blocks - 1, int(np.searchsorted(edges[0], folds[0][2].start)))
