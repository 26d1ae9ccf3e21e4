"""Fitting and scoring the candidate catalogs of a growth, each once, several at a time.

A candidate is the parameters of an :class:`~.automatic.AutomaticCatalog`. Its fit (on the
search's training pieces) and its held-out errors depend on nothing else, so a growth can fit
the candidates it will probably need next while it fits the one it needs now: the climb
rejects most moves, so the next candidates are those that follow if the current one is
rejected. :class:`CandidateFits` fits the needed candidate in the calling process and up to
``n_jobs - 1`` of the next ones in joblib's worker processes at the same time (and, while a
worker still fits the one needed now, the next guess in the calling process); a result is
the same whichever process computed it (the fits are deterministic), and the growth consumes
results in its own order, so the path, the choice and the fitted model do not depend on
``n_jobs``.
"""

from __future__ import annotations

import dataclasses
import time
import warnings

import numpy as np

from ..fit.kinetic_scale import INERTIA_STATES as INERTIA_STATES
from ..fit.kinetic_scale import inertial_columns as inertial_columns
from .automatic import AutomaticCatalog
from .floor import combined_floor, held_out_scores

__all__ = ["SearchSplit", "SearchData", "CandidateFits", "candidate_content", "evaluate_candidate",
           "held_out_error", "inertial_columns", "INERTIA_STATES", "parameters_key",
           "search_rows", "combine_errors", "COMBINES", "MIN_TRIMMED_BLOCKS", "unfitted"]

#: How a candidate's held-out block errors make its criterion (:func:`combine_errors`):
#: ``"rms"`` (all of them) or ``"trimmed"`` (all but the largest).
COMBINES = ("rms", "trimmed")
#: Fewest held-out blocks from which ``"trimmed"`` may leave the worst one out.
MIN_TRIMMED_BLOCKS = 4


def combine_errors(errors, combine: str = "rms") -> float:
    r"""The criterion of a candidate catalog from its held-out block errors.

    With ``"rms"``, the root mean square of the ``n`` errors :math:`e_1, \dots, e_n`;
    with ``"trimmed"``, that of all but the largest: for the sorted errors
    :math:`e_{(1)} \le \dots \le e_{(n)}`,

    .. math:: c_\text{rms} = \sqrt{\frac{1}{n} \sum_{i=1}^{n} e_i^2}, \qquad
              c_\text{trimmed} = \sqrt{\frac{1}{n - 1} \sum_{i=1}^{n-1} e_{(i)}^2}.

    Cross-validated on a recording of a few seconds, one block (the largest swings) can
    hold most of what identifies the configuration-dependent terms: the fit without it fails
    for the right catalog too, and that one error (tens of percent where the others are
    below one) decides the RMS, so the growth refuses the right move. The trimmed criterion
    tolerates one failing fit out of ``n``. It needs :data:`MIN_TRIMMED_BLOCKS` (4) blocks
    at least: a catalog is then still judged on ``n - 1 >= 3`` blocks, each by a fit on
    other data, so a stand-in that holds along the trajectories but fails wherever it
    extrapolates must fail on one block only to pass; with two or three blocks, the one
    left out would be half or a third of the evidence (and the time and region blocks of
    the default split would be one judgment).

    Parameters
    ----------
    errors : sequence of float
        The held-out relative errors, one per block (inf for a failed fit).
    combine : {"rms", "trimmed"}, default "rms"
        How they are combined (:data:`COMBINES`).

    Returns
    -------
    float
        The criterion (inf when a retained error is not finite).

    Examples
    --------
    >>> errors = [0.005, 0.004, 0.9, 0.006, 0.005]   # one fit of five fails
    >>> round(combine_errors(errors), 3), round(combine_errors(errors, "trimmed"), 4)
    (0.403, 0.005)
    """
    if combine not in COMBINES:
        raise ValueError(f"combine: expected one of {COMBINES}, got {combine!r}")
    errors = np.asarray(errors, dtype=float).ravel()
    if combine == "trimmed":
        if len(errors) < MIN_TRIMMED_BLOCKS:
            raise ValueError(f"combine='trimmed' needs at least {MIN_TRIMMED_BLOCKS} held-out "
                             f"blocks, got {len(errors)}")
        errors = np.sort(errors)[:-1]
    value = float(np.sqrt(np.mean(np.square(errors))))
    return value if np.isfinite(value) else float("inf")


def parameters_key(parameters) -> str:
    """A hashable, order-free key of catalog parameters.

    Parameters
    ----------
    parameters : dict
        Catalog parameters (of :class:`~.automatic.AutomaticCatalog`).

    Returns
    -------
    str
        The same string for equal parameters, whatever their order.
    """
    return repr(sorted(parameters.items()))


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
        Whether the data have forces (the criterion's kind, :func:`held_out_error`).
    reported : tuple of int, default (0, 1)
        Which of the block errors (in order over the splits) a step reports as its time and
        region errors.
    combine : {"rms", "trimmed"}, default "rms"
        How the block errors make the criterion (:func:`combine_errors`). With
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


def held_out_error(model, held, forced) -> float:
    r"""Relative residual of a fitted model's weak-form equations on held-out runs.

    With forces, ``||Theta xi|| / ||Theta_F xi_F||`` (the residual over the forces' part).
    Unforced, each coordinate's block of rows ``i`` over the kinetic part of its equation:

    .. math:: e_i = \frac{\|\Theta_i \xi\|}{\|\sum_{j \in K} \Theta_{ij} \xi_j\|},
              \qquad e = \sqrt{\tfrac1n \textstyle\sum_i e_i^2},

    with ``K`` the columns that carry inertia (a nonzero mass matrix,
    :func:`~pysindy_xl.fit.kinetic_scale.inertial_columns`: the terms quadratic in the
    velocities; ``e_i`` is :func:`~pysindy_xl.fit.kinetic_scale.kinetic_relative_residuals`,
    which also makes the ``R^2`` of unforced fits, :func:`~pysindy_xl.quality.fit_quality`).
    An implicit law fixes each equation only up to its own factor, so each
    block needs its own scale; its kinetic part, ``d/dt dT/dqd - dT/dq``, is the one that
    states the accelerations, and the ratio is about the relative error of the accelerations
    the law predicts. A scale taken from single terms (the largest ``||Theta_j xi_j||``)
    is not one of the law: a law can keep a large potential term that its other terms
    nearly cancel (``r cos(theta) - 0.25 r^2 cos(theta) - 0.58 cos(theta)`` for
    ``0.25 r cos(theta)``, a flexible family of ``r`` absorbing the rest) and shrink the
    kinetic part, whose columns carry most of the noise of positions, to a quarter: its
    residual shrinks with it against an unchanged largest term. Judged over the kinetic
    part, a law whose inertia cancels, or that has none in an equation, scores inf. The
    strong form where the blocks are shorter than a test function.

    Parameters
    ----------
    model : XLSINDy
        Fitted model.
    held : dict
        ``x``, ``t`` and ``u`` (None when unforced) of the held-out runs.
    forced : bool
        Whether the data have forces.

    Returns
    -------
    float
        The relative error (inf where the norm is zero).
    """
    return held_out_scores(model, held, forced, floor=False)[0]


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
        ``criterion`` (the blocks' errors combined by :func:`combine_errors` with
        ``search.combine``; inf when the catalog was not fitted), ``block_errors`` (the
        held-out error of each block, in order over the splits; empty when not fitted),
        ``note`` (why not), ``seconds``, ``cpu_seconds`` and ``definite`` (the smallest
        fraction, over the splits' fits, of the training states at which the fitted mass
        matrix is positive definite: ``XLSINDy.mass_matrix_check_``; 0 when not fitted),
        ``support`` (the names of the terms each split's fit kept; empty when a fit failed)
        and ``noise_floor`` (the criterion's noise floor, :data:`SearchData.floor`; NaN
        where not computed): the fields of a :class:`~.growth.GrowthStep` but its move and
        verdict; with ``search.floor == "later"`` and a fitted catalog, also ``models`` (the
        fitted model of each split, None where its fit failed).
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


def candidate_content(search: SearchData, parameters):
    """What a candidate's catalogs hold, on every split of the search: a hashable key, equal
    for parameters whose fits are the same (:meth:`~.automatic.AutomaticCatalog.content_key`).

    Parameters
    ----------
    search : SearchData
        The growth's data (the splits' fixed catalog parameters).
    parameters : dict
        The growing catalog parameters.

    Returns
    -------
    tuple or None
        One :meth:`~.automatic.AutomaticCatalog.content_key` per split; None where the
        parameters do not make a catalog (its fit reports why).
    """
    try:
        return tuple(AutomaticCatalog(**split.fixed, **parameters).content_key()
                     for split in search.splits)
    except (ValueError, TypeError):
        return None


def _warm_up() -> None:
    """Import what a candidate's fit needs (a worker's first task)."""
    from .. import model  # noqa: F401
    from ..weak import regression  # noqa: F401


_POOL = {}  # the workers, kept between growths: {"size": int, "executor": executor}


def _pool(size: int):
    """A loky process pool of ``size`` workers of its own (kept between calls; idle workers
    exit after 300 s). Not joblib's shared executor: joblib restarts that one whenever its
    arguments change and expects its own subclass of it, so sharing it would break, or
    restart, the user's other ``joblib.Parallel`` calls."""
    from joblib.externals.loky import ProcessPoolExecutor
    if _POOL.get("size") != size:
        if _POOL.get("executor") is not None:
            _POOL["executor"].shutdown(wait=False, kill_workers=True)
        _POOL.update(size=size, executor=ProcessPoolExecutor(max_workers=size, timeout=300))
    return _POOL["executor"]


def _forget_pool() -> None:
    """Drop a pool that failed (a lost worker breaks it): the next growth starts another."""
    executor = _POOL.pop("executor", None)
    _POOL.pop("size", None)
    if executor is not None:
        executor.shutdown(wait=False, kill_workers=True)


class CandidateFits:
    """The candidates' fits and scores, each computed once, the next ones in parallel.

    The candidate needed now is fitted in the calling process; meanwhile up to ``n_jobs - 1``
    worker processes (a loky process pool, joblib's) fit the first candidates of ``ahead``
    that are neither done nor running. A guess that the growth never needs costs a worker's
    time, not the caller's.

    Parameters
    ----------
    search : SearchData
        The growth's data and template.
    n_jobs : int or None, default None
        Processes: the calling one and ``n_jobs - 1`` workers (joblib's convention: None is
        1, -1 all cores).

    Attributes
    ----------
    results : dict
        The fields of each computed candidate, by :func:`parameters_key`.
    events : list of (str, str)
        What happened, in order: ``("submit", key)`` (sent to a worker), ``("local", key)``
        (fitted here), ``("worker", key)`` (a worker's result first needed here) and
        ``("same", key)`` (parameters whose catalogs hold what an earlier candidate's hold,
        :func:`candidate_content`: that candidate's fit, not fitted again); with the steps'
        ``cpu_seconds`` they let a benchmark replay the schedule on idle cores.
    """

    def __init__(self, search: SearchData, n_jobs=None):
        import joblib
        self.search = search
        self.n_jobs = joblib.effective_n_jobs(n_jobs)
        self.results = {}
        self.events = []
        self._canonical = {}  # parameters_key -> key of the first parameters of equal content
        self._contents = {}  # candidate_content -> that first key
        self._first = {}  # that first key -> its parameters
        self._aliases = {}  # key of a catalog met before -> its fields (the first's, copied)
        self._workers_results = set()  # computed by a worker, not yet needed here
        self._running = {}  # key -> future of a worker's fit
        self._executor = None

    def _workers(self):
        if self._executor is None:
            self._executor = _pool(self.n_jobs - 1)
        return self._executor

    def warm_up(self) -> None:
        """Start the workers (their imports) while the calling process works."""
        if self.n_jobs > 1:
            for _ in range(self.n_jobs - 1):
                self._workers().submit(_warm_up)

    def _collect(self, key, wait=False):
        future = self._running.get(key)
        if future is None or not (wait or future.done()):
            return
        del self._running[key]
        try:
            self.results[key] = future.result()
            self._workers_results.add(key)
        except Exception:  # noqa: BLE001 - the workers cannot fit (a lost worker, an
            self._disable()  # optimizer that does not pickle): the caller fits them all

    def get(self, parameters, ahead=()) -> dict:
        """The fields of a candidate's step (:func:`evaluate_candidate`), computed once.

        Parameters
        ----------
        parameters : dict
            The candidate.
        ahead : iterable of dict, default ()
            Candidates probably needed next, best guess first: the idle workers fit the
            first of them that are neither done nor running, and while a worker still fits
            the one needed now, this process fits the next of them.

        Returns
        -------
        dict
            As :func:`evaluate_candidate` (the same object on each call).
        """
        own = parameters_key(parameters)
        key = self._key(parameters, own)
        if key != own:  # a catalog met before under other parameters: its fit, once
            if own not in self._aliases:
                started, cpu = time.perf_counter(), time.process_time()
                fields = dict(self.get(self._first[key], ahead))
                if fields["description"]:
                    fields["description"] = AutomaticCatalog(**self.search.splits[0].fixed,
                                                             **parameters).describe()
                fields.update(seconds=time.perf_counter() - started,
                              cpu_seconds=time.process_time() - cpu)
                self._aliases[own] = fields
                self.events.append(("same", own))
            return self._aliases[own]
        for other in list(self._running):
            self._collect(other)
        if key not in self.results and key not in self._running:
            self._submit(ahead, key)
            self._local(key, parameters)
            return self.results[key]
        while key in self._running and not self._running[key].done():
            # a worker fits it: fit the next guess here meanwhile (most moves are rejected)
            guess = next(((k, c) for k, c in self._guesses(ahead, key)
                          if k not in self.results and k not in self._running), None)
            if guess is None:
                break
            self._local(*guess)
        self._collect(key, wait=True)
        if key in self._workers_results:
            self._workers_results.discard(key)
            self.events.append(("worker", key))
        if key not in self.results:  # (a worker failed)
            self._local(key, parameters)
        self._submit(ahead, key)
        return self.results[key]

    def fit_key(self, parameters) -> str:
        """The key of the one fit that serves ``parameters`` (equal for parameters of equal
        content, fitted once for all of them by :meth:`get`: see :meth:`_key`).

        Parameters
        ----------
        parameters : dict
            A candidate.

        Returns
        -------
        str

        Examples
        --------
        >>> CandidateFits.fit_key.__name__
        'fit_key'
        """
        return self._key(parameters)

    def _key(self, parameters, own=None) -> str:
        """The :func:`parameters_key` of the first parameters met whose catalogs hold what
        those of ``parameters`` hold (:func:`candidate_content`): equal catalogs give equal
        fits, so one fit serves all their parameters."""
        own = parameters_key(parameters) if own is None else own
        if own not in self._canonical:
            content = candidate_content(self.search, parameters)
            first = own if content is None else self._contents.setdefault(content, own)
            self._canonical[own] = first
            self._first.setdefault(first, parameters)
        return self._canonical[own]

    def _guesses(self, ahead, key):
        """``(key, parameters)`` of the distinct catalogs of ``ahead`` but ``key``'s, in order,
        each read when asked for (only as many as the workers take are compared)."""
        seen = {key}
        for parameters in ahead:
            other = self._key(parameters)
            if other not in seen:
                seen.add(other)
                yield other, self._first[other]

    def _submit(self, ahead, key) -> None:
        """Give the idle workers the first guesses of ``ahead`` neither done nor running."""
        if len(self._running) >= self.n_jobs - 1:
            return
        for other, candidate in self._guesses(ahead, key):
            if len(self._running) >= self.n_jobs - 1:
                break
            if other != key and other not in self.results and other not in self._running:
                try:
                    self._running[other] = self._workers().submit(evaluate_candidate,
                                                                  self.search, candidate)
                except Exception:  # noqa: BLE001 - a broken pool: the caller fits them all
                    self._disable()
                    return
                self.events.append(("submit", other))

    def _local(self, key, parameters) -> None:
        self.events.append(("local", key))
        self.results[key] = evaluate_candidate(self.search, parameters)

    def _disable(self) -> None:
        self.n_jobs = 1
        for future in self._running.values():
            future.cancel()
        self._running = {}
        _forget_pool()

    def close(self) -> None:
        """Forget the workers' guesses (those not started are cancelled)."""
        for future in self._running.values():
            future.cancel()
        self._running = {}
