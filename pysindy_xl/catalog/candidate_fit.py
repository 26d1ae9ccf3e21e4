"""One candidate catalog's fit and score: fitted on each split's training pieces, scored on
the split's held-out blocks (:func:`evaluate_candidate`), or the reason it was not fitted
(:func:`unfitted`). :class:`~.candidates.CandidateFits` calls it, once per catalog.
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from .automatic import AutomaticCatalog
from .criterion import combine_errors
from .floor import combined_floor, held_out_scores
from .search_data import SearchData

__all__ = ["evaluate_candidate", "support_criterion", "unfitted"]


def unfitted(note, size=0, description="") -> dict:
    """The fields of a candidate that was not fitted (or whose fit failed), and why.

    Parameters
    ----------
    note : str
        Why (``"ceiling: ..."``, ``"budget: ..."``, ``"fit failed: ..."``, ...).
    size : int, default 0
        The catalog's terms.
    description : str, default ""
        The catalog's description.

    Returns
    -------
    dict
        The fields of :func:`evaluate_candidate`, with an infinite criterion.

    Examples
    --------
    >>> unfitted("budget: spent", 12)["criterion"]
    inf
    """
    return {"description": description, "terms": size, "active": 0, "time_error": np.inf,
            "region_error": np.inf, "criterion": np.inf, "note": note, "seconds": 0.0,
            "cpu_seconds": 0.0, "definite": 0.0, "block_errors": (), "support": (),
            "noise_floor": float("nan")}


def evaluate_candidate(search: SearchData, parameters) -> dict:
    """Fit one candidate catalog on each split's training pieces and score it on the split's
    held-out blocks.

    Parameters
    ----------
    search : SearchData
        The growth's data and template.
    parameters : dict
        The growing catalog parameters.

    Returns
    -------
    dict
        ``description``, ``terms``, ``active``, ``time_error``, ``region_error``,
        ``criterion`` (the blocks' errors combined by :func:`~.criterion.combine_errors` with
        ``search.combine``; inf when the catalog was not fitted), ``block_errors`` (the
        held-out error of each block, in order over the splits; empty when not fitted),
        ``note`` (why not), ``seconds``, ``cpu_seconds`` and ``definite`` (the smallest
        fraction, over the splits' fits, of the training states at which the fitted mass
        matrix is positive definite: ``XLSINDy.mass_matrix_check_``; 0 when not fitted),
        ``support`` (the names of the terms each split's fit kept; empty when a fit failed)
        and ``noise_floor`` (the criterion's noise floor,
        :data:`~.search_data.SearchData.floor`; NaN where not computed): the fields of a
        :class:`~.growth.GrowthStep` but its move and verdict; with
        ``search.floor == "later"`` and a fitted catalog, also ``models`` (the fitted model of
        each split, None where its fit failed).
    """
    from sklearn.base import clone

    catalog = AutomaticCatalog(**search.splits[0].fixed, **parameters)
    started, cpu = time.perf_counter(), time.process_time()

    failed = unfitted
    try:
        size = catalog.n_terms
    except ValueError as error:
        return failed(str(error))
    if size > search.max_terms:
        return failed(f"ceiling: {size} > max_terms {search.max_terms}", size)
    description = catalog.describe()
    n = search.splits[0].train["x"][0].shape[1]
    if min(sum(len(p) for p in split.train["x"]) for split in search.splits) * n < 10 * size:
        return failed("too few samples for this size", size, description)
    errors, floors, active, definite, notes, support, models = [], [], [], [], [], [], []
    now = search.floor == "now"
    for split in search.splits:
        try:
            model = clone(search.template).set_params(
                feature_library=AutomaticCatalog(**split.fixed, **parameters))
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                model.fit(**split.train)
            if model.dynamics_ is None:
                raise ValueError("no acceleration in the identified equations")
            scores = [held_out_scores(model, held, search.forced, now) for held in split.blocks]
            errors += [error for error, _ in scores]
            floors += [floor for _, floor in scores]
        except Exception as error:  # noqa: BLE001 - a failed candidate loses, reported
            note = f"fit failed: {type(error).__name__}: {error}"[:200]
            if search.combine == "rms":
                return failed(note, size, description)
            errors += [np.inf] * len(split.blocks)  # the trimmed criterion may leave it out
            floors += [np.inf] * len(split.blocks)
            notes.append(note)
            models.append(None)
            continue
        models.append(model)
        coefficients = model.coefficients()
        active.append(int(np.count_nonzero(coefficients)))
        support.append(tuple(name for name, value in zip(model.get_feature_names(), coefficients,
                                                          strict=True) if value != 0))
        check = model.mass_matrix_check_ or {}
        definite.append(float(check.get("positive_definite_fraction", 0.0)))
    if not active:
        return failed(notes[0], size, description)
    value = combine_errors(errors, search.combine)
    time_block, region_block = search.reported
    extra = {"models": tuple(models)} if search.floor == "later" else {}
    return {**extra, "description": description, "terms": size, "active": int(np.median(active)),
            "time_error": errors[time_block], "region_error": errors[region_block],
            "criterion": value, "note": (f"{len(notes)} of {len(search.splits)} fits failed"
                                         if notes else ""),
            "seconds": time.perf_counter() - started, "cpu_seconds": time.process_time() - cpu,
            "definite": min(definite) if not notes else 0.0,
            "block_errors": tuple(float(e) for e in errors),
            "support": tuple(support) if not notes else (),
            "noise_floor": (combined_floor(errors, floors, search.combine) if now
                            else float("nan"))}


def support_criterion(search: SearchData, parameters, optimizer, columns) -> float:
    """The search's criterion of one catalog fitted on given columns, nothing selected.

    Each split's catalog (its end knots, ``parameters``) is fitted on the split's training
    pieces with the columns ``columns`` alone, every one kept
    (:class:`~pysindy_xl.optimizers.RestrictedOptimizer` with ``select=False`` around
    ``optimizer``), and scored on the split's held-out blocks as
    :func:`evaluate_candidate` scores a catalog.

    Parameters
    ----------
    search : SearchData
        The growth's data and template.
    parameters : dict
        The catalog's growing parameters.
    optimizer : catalog optimizer
        The selection whose refit of a given support is used (itself, or the single fit of
        an ensemble).
    columns : sequence of int
        The catalog columns kept.

    Returns
    -------
    float
        The blocks' errors combined (``search.combine``); inf where a fit fails.
    """
    from sklearn.base import clone

    from ..optimizers import RestrictedOptimizer
    errors = []
    for split in search.splits:
        model = clone(search.template).set_params(
            feature_library=AutomaticCatalog(**split.fixed, **parameters),
            optimizer=RestrictedOptimizer(clone(optimizer), columns=list(columns),
                                          select=False))
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                model.fit(**split.train)
            errors += [held_out_scores(model, held, search.forced, False)[0]
                       for held in split.blocks]
        except Exception:  # noqa: BLE001 - no law on these columns: they do not win
            return float("inf")
    return combine_errors(errors, search.combine)
