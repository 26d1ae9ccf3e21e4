"""The search's data: the splits a candidate catalog is fitted and scored on, the same for
every candidate of a growth (:class:`SearchData`), and the rows its fits have
(:func:`search_rows`, the data-sized ceiling of the catalog's size).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .growth_data import data_span

__all__ = ["SearchSplit", "SearchData", "judge_data", "search_rows"]


@dataclasses.dataclass
class SearchSplit:
    """One split of the search's data: a catalog is fitted on ``train`` and scored on each of
    ``blocks``.

    Parameters
    ----------
    fixed : dict
        The catalog parameters that do not grow (coordinates, kinds, bounds, ...): the
        splines end where this split's training data do.
    train : dict
        Keyword arguments of the fit (``x``, ``t``, ``u``, ``x_dot``, ``x_ddot``): the
        training pieces.
    blocks : list of dict
        The held-out blocks (``x``, ``t``, ``u``), each scored on its own.
    """

    fixed: dict
    train: dict
    blocks: list


@dataclasses.dataclass
class SearchData:
    """What a candidate's fit and scoring need (the same for every candidate of a growth).

    Parameters
    ----------
    splits : list of SearchSplit
        The splits a candidate is fitted and scored on (one fit per split); its criterion is
        the RMS of all the splits' block errors, in order.
    template : XLSINDy
        Unfitted model; each candidate fits a clone with its catalog.
    max_terms : int
        Ceiling of the catalog's size.
    forced : bool
        Whether the data have forces (the criterion's kind, :func:`~.criterion.held_out_error`).
    reported : tuple of int, default (0, 1)
        Which of the block errors (in order over the splits) a step reports as its time and
        region errors.
    combine : {"rms", "trimmed"}, default "rms"
        How the block errors make the criterion (:func:`~.criterion.combine_errors`). With
        ``"trimmed"``, a split whose fit raises scores inf on its blocks instead of failing
        the candidate (the trimmed criterion may leave it out).
    floor : {"now", "later", "off"}, default "now"
        The criterion's noise floor (:func:`~.floor.held_out_scores`): computed with the
        errors (``noise_floor``); ``"later"``: not computed, the fitted models returned
        (``models``, one per split, None where a fit failed) for
        :func:`~.floor.models_floor` to compute it where it is asked for (the growth asks
        only of the catalogs it keeps); ``"off"``: not computed (NaN).
    """

    splits: list
    template: object
    max_terms: int
    forced: bool
    reported: tuple = (0, 1)
    combine: str = "rms"
    floor: str = "now"


def search_rows(search: SearchData, weak: bool) -> int:
    r"""Fewest equations (rows) a candidate's fit has, over the search's splits.

    In the weak form each coordinate gives one row per test function: ``n * sum_p K_p`` over
    the training pieces ``p`` of a split, with ``K_p`` the test functions that
    ``search.template.test_functions`` places on piece ``p`` at the split's shared half-width
    (pieces cut at gaps, those shorter than one test function left out, as the fit does);
    in the strong form one row per sample and coordinate.

    Parameters
    ----------
    search : SearchData
        The growth's splits and template (whose ``test_functions`` the weak form uses).
    weak : bool
        Whether the search's fits use the weak form.

    Returns
    -------
    int
        The smallest row count over the splits.
    """
    from ..weak.regression import shared_half_width
    from ..weak.timegrid import split_at_gaps
    counts = []
    for split in search.splits:
        xs, ts = split.train["x"], split.train["t"]
        n = xs[0].shape[1]
        if not weak:
            counts.append(n * sum(len(tk) for tk in ts))
            continue
        functions = search.template.test_functions
        pieces = [{"t": np.asarray(tk, dtype=float), "x": xk}
                  for tk, xk in zip(ts, xs, strict=True)]
        try:
            h = shared_half_width(functions, pieces)
        except ValueError:
            counts.append(0)  # no piece holds a test function
            continue
        segments, _, _ = split_at_gaps(pieces, functions.max_gap(h))
        counts.append(n * sum(functions.matrices(d["t"], half_width=h)[0].shape[0]
                              for d in segments if d["t"][-1] - d["t"][0] >= 2 * h))
    return int(min(counts))


def judge_data(splits, fixed, template, max_terms, forced):
    """The search's data on a judge's splits (``"consensus"``'s second fold, the near ties').

    Parameters
    ----------
    splits : list of (dict, list of dict)
        The splits' training pieces and held-out blocks (:func:`~.folds.held_out_splits`).
    fixed : dict
        The catalog parameters that do not grow (the splines end where each split's training
        data do).
    template, max_terms, forced : XLSINDy, int, bool
        As :class:`~.search_data.SearchData`'s.

    Returns
    -------
    SearchData
        Without noise floors.
    """
    return SearchData([SearchSplit(dict(fixed, bounds=data_span(train["x"])), train, held)
                       for train, held in splits], template, max_terms, forced, floor="off")
