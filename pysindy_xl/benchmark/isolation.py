"""Process isolation, time limit and BLAS threads of one run (:mod:`.runner`): a forked child or
an interval-timer signal, and a threadpoolctl limit."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import threading
import time

from .lifetime import die_with_parent, runs_in_flight
from .records import base_record, failed_record, json_finite

__all__ = ["RunTimeout", "blas_thread_limit"]

ISOLATIONS = ("auto", "process", "signal", "none")


class RunTimeout(Exception):
    """Raised inside a run when its time limit is reached (signal isolation)."""


def resolve_isolation(isolation: str) -> str:
    """The isolation a run gets: ``auto`` resolved to ``process`` where fork exists, else
    ``signal`` in the main thread, else ``none``.

    Parameters
    ----------
    isolation : {"auto", "process", "signal", "none"}
        The requested isolation.

    Returns
    -------
    str
        ``"process"``, ``"signal"`` or ``"none"``.

    Raises
    ------
    ValueError
        When ``isolation`` is unknown.
    """
    if isolation not in ISOLATIONS:
        raise ValueError(f"isolation: expected one of {ISOLATIONS}, got {isolation!r}")
    if isolation != "auto":
        return isolation
    import multiprocessing
    if "fork" in multiprocessing.get_all_start_methods():
        return "process"
    if hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread():
        return "signal"
    return "none"


def _child(connection, function, task, settings, deadline, parent_pid):
    """Body of the forked child: run, send JSON lines (stages, then the record), exit."""
    die_with_parent()
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # not the grid's handler (n_jobs=1)
    if os.getppid() != parent_pid:  # the parent died before the request took effect
        os._exit(1)

    def send(message):
        connection.send_bytes(json.dumps(message, allow_nan=False).encode())

    # Self-destruct a little after the deadline even if the parent died without killing us
    # (default SIGALRM action: terminate), so no orphan run can outlive its time limit.
    signal.signal(signal.SIGALRM, signal.SIG_DFL)
    signal.alarm(max(int(deadline - time.perf_counter()) + 10, 1))
    try:
        record = function(task, settings, deadline, lambda name: send({"stage": name}))
        send({"record": json_finite(record)})
    except BaseException as error:  # report everything: the parent must learn why
        send({"record": failed_record(base_record(task, settings), "error", error, True)})
    finally:
        connection.close()


def run_in_process(function, task, settings, timeout):
    """Run ``function`` in a forked child, killed at the time limit.

    Parameters
    ----------
    function : callable
        ``function(task, settings, deadline, stage) -> record``.
    task : Task
        The run.
    settings : GridSettings
        The grid's settings.
    timeout : float
        Seconds allowed.

    Returns
    -------
    dict
        The run's record; ``timeout`` or ``error`` when it did not finish.
    """
    import multiprocessing
    context = multiprocessing.get_context("fork")
    receiver, sender = context.Pipe(duplex=False)
    start = time.perf_counter()
    deadline = start + timeout
    process = context.Process(target=_child, daemon=True,
                              args=(sender, function, task, settings, deadline, os.getpid()))
    process.start()
    runs_in_flight.add(process)
    sender.close()
    last_stage, record = "start", None
    try:
        while record is None:
            remaining = deadline - time.perf_counter()
            if remaining <= 0 or not receiver.poll(remaining):
                break
            try:
                message = json.loads(receiver.recv_bytes())
            except EOFError:  # the child died without a record
                break
            if "stage" in message:
                last_stage = message["stage"]
            else:
                record = message["record"]
    finally:
        if record is None and process.is_alive():
            process.kill()
        process.join(5)
        runs_in_flight.discard(process)
        receiver.close()
    elapsed = time.perf_counter() - start
    if record is not None:
        return record
    base = base_record(task, settings)
    base["time_s"] = {"run": elapsed}
    if elapsed >= timeout:
        base["status"] = "timeout"
        base["message"] = f"stopped after {timeout:g} s (during {last_stage})"
    else:
        base["message"] = (f"the run's process died with exit code {process.exitcode} "
                           f"(during {last_stage})")
    return json_finite(base)


def run_with_signal(function, task, settings, timeout):
    """Run ``function`` in this process, interrupted at the time limit by an interval timer.

    Parameters
    ----------
    function : callable
        ``function(task, settings, deadline, stage) -> record``.
    task : Task
        The run.
    settings : GridSettings
        The grid's settings.
    timeout : float
        Seconds allowed.

    Returns
    -------
    dict
        The run's record; ``timeout`` or ``error`` when it did not finish.
    """
    def alarm(signum, frame):
        raise RunTimeout()

    start = time.perf_counter()
    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        return function(task, settings, start + timeout, None)
    except RunTimeout:
        base = base_record(task, settings)
        base.update(status="timeout", message=f"stopped after {timeout:g} s",
                    time_s={"run": time.perf_counter() - start})
        return json_finite(base)
    except Exception as error:
        return failed_record(base_record(task, settings), "error", error, True)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def blas_thread_limit(blas_threads: int | None):
    """A context limiting every loaded BLAS's threads to ``blas_threads`` (>= 1) through
    :func:`threadpoolctl.threadpool_limits`; None leaves them alone.

    Parameters
    ----------
    blas_threads : int or None
        Threads allowed (>= 1); None leaves them alone.

    Returns
    -------
    contextlib.AbstractContextManager
        The context.

    Examples
    --------
    >>> from threadpoolctl import threadpool_info
    >>> with blas_thread_limit(1):
    ...     print({pool["num_threads"] for pool in threadpool_info()
    ...            if pool["user_api"] == "blas"} <= {1})
    True
    """
    if blas_threads is None:
        return contextlib.nullcontext()
    if isinstance(blas_threads, bool) or not isinstance(blas_threads, int) or blas_threads < 1:
        raise ValueError(f"blas_threads: expected None or an integer >= 1, got {blas_threads!r}")
    from threadpoolctl import threadpool_limits
    return threadpool_limits(limits=blas_threads, user_api="blas")


def resolve_blas_threads(blas_threads, n_jobs, backend):
    """The BLAS threads per run: ``"auto"`` is 1 when runs go in parallel, no limit otherwise.

    Parameters
    ----------
    blas_threads : "auto", int or None
        The requested limit.
    n_jobs : int
        Parallel processes (joblib convention).
    backend : str or None
        The joblib backend (Dask and Ray count as parallel).

    Returns
    -------
    int or None
        The limit, None for none.
    """
    if blas_threads != "auto":
        return blas_threads
    import joblib
    parallel = backend in ("dask", "ray") or joblib.effective_n_jobs(n_jobs) > 1
    return 1 if parallel else None
