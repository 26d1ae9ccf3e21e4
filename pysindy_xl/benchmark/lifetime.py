"""Lifetime of a local grid's processes: none outlives the grid (see
:mod:`pysindy_xl.benchmark.runner`, "Killing the grid").

Three mechanisms, each where the process it guards runs: a forked run asks the kernel to be
killed with its worker (:func:`die_with_parent`), a worker watches the grid process and exits
when it is gone (:func:`watch_grid`), and the grid turns SIGTERM into the interruption that
makes joblib stop its workers (:func:`sigterm_as_interrupt`).
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time

__all__ = ["die_with_parent", "watch_grid", "sigterm_as_interrupt", "runs_in_flight"]

_WATCH_INTERVAL = 0.5  # seconds between two checks of a worker's parent
_watched = None  # (this process, grid process) once the watchdog of this worker runs
#: Forked runs in flight in this process (killed by the watchdog when the grid is gone).
runs_in_flight = set()


def die_with_parent() -> None:
    """Ask the kernel to SIGKILL this process when its parent dies (Linux; no-op elsewhere).

    The parent "dies" when the thread that forked this process ends; callers fork from a
    thread that waits for the child, so the two coincide.
    """
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG = 1
    except (OSError, AttributeError):
        pass


def watch_grid(grid_pid: int) -> None:
    """In a local worker of the grid process ``grid_pid``: exit as soon as it is gone.

    Started once per worker (a daemon thread polling ``os.getppid()``). Nothing happens in
    the grid process itself (``n_jobs=1``) or in a worker that is not its child (Dask, Ray).
    A dying worker kills its forked runs (which also die with it through
    :func:`die_with_parent`).
    """
    global _watched
    pid = os.getpid()
    if pid == grid_pid or os.getppid() != grid_pid or _watched == (pid, grid_pid):
        return
    _watched = (pid, grid_pid)

    def watch():
        while os.getppid() == grid_pid:
            time.sleep(_WATCH_INTERVAL)
        for process in list(runs_in_flight):
            with contextlib.suppress(Exception):
                os.kill(process.pid, signal.SIGKILL)
        os._exit(1)

    threading.Thread(target=watch, name="pysindy-xl-grid-watchdog", daemon=True).start()


@contextlib.contextmanager
def sigterm_as_interrupt():
    """Turn SIGTERM into KeyboardInterrupt during the grid, so that it stops like on Ctrl-C
    (joblib kills the workers); afterwards the process still ends by SIGTERM.

    Only in the main thread and where SIGTERM has its default action (a handler of the
    application is left alone).
    """
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL):
        yield
        return
    received = []

    def handler(signum, frame):
        received.append(signum)
        raise KeyboardInterrupt(f"signal {signum}")

    signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        if received:  # the default action, now that the workers are gone
            os.kill(os.getpid(), signal.SIGTERM)
