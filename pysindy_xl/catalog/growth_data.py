"""The data of a catalog growth: the checks before it starts, and where its splines end.

The splines of an :class:`~.automatic.AutomaticCatalog` end at :data:`END_PERCENTILE` of the
positions (and ``100 -`` it): beyond, the potential's slope is fitted to the extreme samples
instead of following a cubic piece that a few samples constrain.
"""

from __future__ import annotations

import numpy as np

__all__ = ["check_growth_data", "data_span", "thinned", "END_PERCENTILE"]

def check_growth_data(xs, names, n_terms: int) -> None:
    """``ValueError`` for a constant coordinate or data too short for ``n_terms`` terms.

    Parameters
    ----------
    xs : list of ndarray, each of shape (n_samples, n)
        Positions of each trajectory.
    names : list of str
        Coordinate names, for the messages.
    n_terms : int
        Size of the catalog to fit (at least 10 equations per term are needed).

    Returns
    -------
    None
    """
    stacked = np.vstack(xs)
    spread = stacked.max(axis=0) - stacked.min(axis=0)
    scale = np.maximum(np.abs(stacked).max(axis=0), 1.0)
    for name, s, sc in zip(names, spread, scale, strict=True):
        if not s > 1e-9 * sc:
            raise ValueError(f"x: coordinate {name!r} is constant in the data; nothing about its "
                             "dynamics can be identified (leave it out, or excite it)")
    rows = len(stacked) * len(names)
    if rows < 10 * n_terms:
        raise ValueError(f"x: {len(stacked)} samples of {len(names)} coordinates are too short "
                         f"for a catalog of {n_terms} terms (at least {10 * n_terms} equations "
                         "needed); record longer, or lower max_terms")


#: Percentile of the data at which splines end (and ``100 -`` it): beyond, the potential's
#: slope is fitted to the extreme samples instead of following a cubic piece that a few
#: samples constrain.
END_PERCENTILE = 1.0


def data_span(xs) -> list:
    """The splines' end knots per coordinate: :data:`END_PERCENTILE` and ``100 -`` it of the
    runs' positions.

    Parameters
    ----------
    xs : list of ndarray, each of shape (n_samples, n)
        Positions of each run.

    Returns
    -------
    list of (float, float)
        ``(low, high)`` per coordinate.

    Examples
    --------
    >>> import numpy as np
    >>> data_span([np.linspace(0.0, 1.0, 101)[:, None]])
    [(0.01, 0.99)]
    """
    low, high = np.percentile(np.vstack(xs), [END_PERCENTILE, 100 - END_PERCENTILE], axis=0)
    return [(float(a), float(b)) for a, b in zip(low, high, strict=True)]


def thinned(arrays, stride) -> dict:
    """``x``, ``t``, ``u`` and ``x_dot`` of every run, every ``stride``-th sample (the search's
    samples, its held-out blocks too): the data on which the exponentials' rates are fitted.

    Parameters
    ----------
    arrays : dict
        ``x``, ``t``, ``u``, ``x_dot`` (and possibly others): lists of arrays, one per run, or
        None.
    stride : int
        Keep every ``stride``-th sample.

    Returns
    -------
    dict
        ``x``, ``t``, ``u`` and ``x_dot``, each a list of float arrays or None.

    Examples
    --------
    >>> thinned({"x": [np.arange(6.0)], "t": [np.arange(6.0)], "u": None, "x_dot": None},
    ...         2)["x"]
    [array([0., 2., 4.])]
    """
    return {key: None if arrays[key] is None else
            [np.asarray(value, dtype=float)[::stride] for value in arrays[key]]
            for key in ("x", "t", "u", "x_dot")}
