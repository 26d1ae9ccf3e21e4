"""The data of a catalog growth: the checks before it starts, and where its splines end.

The splines of an :class:`~.automatic.AutomaticCatalog` end at :data:`END_PERCENTILE` of the
positions (and ``100 -`` it): beyond, the potential's slope is fitted to the extreme samples
instead of following a cubic piece that a few samples constrain.
"""

from __future__ import annotations

import numpy as np

from .._validation import check_instance, check_option
from ..optimizers.defaults import SOLVER_KINDS
from .criterion import COMBINES, MIN_TRIMMED_BLOCKS
from .folds import REGIONS
from .moves import MORE_MOVES, MOVES

__all__ = ["check_growth_data", "check_growth_options", "data_span", "thinned",
           "END_PERCENTILE", "GROWTH_REGIONS"]

#: The values of ``region`` of :func:`~.growth.grow_catalog`: the folds of
#: :func:`~.folds.held_out_splits` (:data:`~.folds.REGIONS`), or ``"consensus"``: the
#: ``"block"`` fold and the ``"extremes"`` fold as two judges, a change kept when one accepts
#: it and the other does not find it worse (:func:`~.keep_rules.consensus_keeps`).
GROWTH_REGIONS = (*REGIONS, "consensus")


def check_growth_data(xs, names, n_terms: int | None = None) -> None:
    """``ValueError`` for a constant coordinate or data too short for ``n_terms`` terms.

    Parameters
    ----------
    xs : list of ndarray, each of shape (n_samples, n)
        Positions of each trajectory.
    names : list of str
        Coordinate names, for the messages.
    n_terms : int, optional
        Size of the catalog to fit (at least 10 equations per term are needed); None: the
        coordinates only (before a catalog is built on their ranges).

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
    if n_terms is not None and rows < 10 * n_terms:
        raise ValueError(f"x: {len(stacked)} samples of {len(names)} coordinates are too short "
                         f"for a catalog of {n_terms} terms (at least {10 * n_terms} equations "
                         "needed); record longer, or lower max_terms")


#: Percentile of the data at which splines end (and ``100 -`` it): beyond, the potential's
#: slope is fitted to the extreme samples instead of following a cubic piece that a few
#: samples constrain.
END_PERCENTILE = 1.0


def check_growth_options(*, max_terms, n_blocks, cross_validate, region, physical, steepest,
                         tie_break, noise_floor, work_budget, combine, tolerance, good_enough,
                         moves, search_optimizer="auto", search_samples=6000) -> None:
    """Check the options of :func:`~.growth.grow_catalog` before any data are read.

    Parameters
    ----------
    max_terms, n_blocks, cross_validate, region, physical, steepest, tie_break, noise_floor, \
work_budget, combine, tolerance, good_enough, moves, search_optimizer, search_samples
        As :func:`~.growth.grow_catalog` takes them (``search_optimizer`` default ``"auto"``,
        ``search_samples`` default 6000).

    Raises
    ------
    ValueError, TypeError
        Naming the option and what was expected.

    Examples
    --------
    >>> check_growth_options(max_terms="auto", n_blocks=2, cross_validate=False,
    ...                      region="block", physical=False, steepest=False, tie_break=True,
    ...                      noise_floor=True, work_budget=None, combine="rms", tolerance=0.05,
    ...                      good_enough=0.002, moves=("degree",))
    Traceback (most recent call last):
    ...
    ValueError: n_blocks: expected an integer >= 3, got 2
    """
    if isinstance(max_terms, str) and max_terms != "auto":
        raise ValueError(f"max_terms: expected a positive int or 'auto', got {max_terms!r}")
    if max_terms != "auto":
        check_option("max_terms", max_terms, "int", low=1)
    check_option("n_blocks", n_blocks, "int", low=3)
    check_option("cross_validate", cross_validate, "bool")
    if not isinstance(region, str) or region not in GROWTH_REGIONS:
        raise ValueError(f"region: expected one of {GROWTH_REGIONS}, got {region!r}")
    check_option("physical", physical, "bool")
    check_option("steepest", steepest, "bool")
    check_option("tie_break", tie_break, "bool")
    check_option("noise_floor", noise_floor, "bool")
    check_option("work_budget", work_budget, "real", low=0, allow_none=True, allow_inf=True)
    if combine not in COMBINES:
        raise ValueError(f"combine: expected one of {COMBINES}, got {combine!r}")
    if combine == "trimmed" and not (cross_validate and n_blocks >= MIN_TRIMMED_BLOCKS):
        raise ValueError(f"combine: 'trimmed' needs cross_validate=True and n_blocks >= "
                         f"{MIN_TRIMMED_BLOCKS} (got cross_validate={cross_validate}, "
                         f"n_blocks={n_blocks}): one block out of fewer is too much evidence "
                         "to leave out")
    check_option("tolerance", tolerance, "real", low=0, high=1, high_open=True)
    check_option("good_enough", good_enough, "real", low=0)
    check_option("search_samples", search_samples, "int", low=1, allow_none=True)
    # what XLSINDy's optimizer takes, or "auto": a search whose every fit fails on its
    # optimizer would otherwise end on the final fit alone
    if isinstance(search_optimizer, str):
        if search_optimizer not in ("auto", *SOLVER_KINDS):
            raise ValueError(f"search_optimizer: expected 'auto', one of {SOLVER_KINDS} or an "
                             f"optimizer, got {search_optimizer!r}")
    elif search_optimizer is not None:
        check_instance("search_optimizer", search_optimizer, "an optimizer")
        if not (hasattr(search_optimizer, "fit_catalog")
                or callable(getattr(search_optimizer, "fit", None))):
            raise TypeError("search_optimizer: expected a catalog optimizer with fit_catalog or "
                            "a regressor with fit(X, y), got "
                            f"{type(search_optimizer).__name__}")
    unknown = [m for m in moves if m not in MOVES + MORE_MOVES]
    if unknown:
        raise ValueError(f"moves: unknown {unknown}; expected some of {MOVES + MORE_MOVES}")


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
