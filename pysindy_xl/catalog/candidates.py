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

The candidate's fit and score are :func:`~.candidate_fit.evaluate_candidate`'s, its criterion
:mod:`.criterion`'s, the data it is fitted on :class:`~.search_data.SearchData`; their names
are importable from here too.
"""

from __future__ import annotations

import time

from ..fit.kinetic_scale import INERTIA_STATES as INERTIA_STATES
from ..fit.kinetic_scale import inertial_columns as inertial_columns
from .automatic import AutomaticCatalog
from .candidate_fit import evaluate_candidate, unfitted
from .criterion import COMBINES, MIN_TRIMMED_BLOCKS, combine_errors, held_out_error
from .search_data import SearchData, SearchSplit, search_rows

__all__ = ["SearchSplit", "SearchData", "CandidateFits", "candidate_content", "evaluate_candidate",
           "held_out_error", "inertial_columns", "INERTIA_STATES", "parameters_key",
           "search_rows", "combine_errors", "COMBINES", "MIN_TRIMMED_BLOCKS", "unfitted"]


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
