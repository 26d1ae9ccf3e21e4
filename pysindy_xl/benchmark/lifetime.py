"""No process of a local grid outlives it: a forked run dies with its worker
(:func:`die_with_parent`), a worker exits when the grid process is gone (:func:`watch_grid`),
and the grid turns SIGTERM into the interruption that stops joblib (:func:`sigterm_as_interrupt`).
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
    """Ask the kernel to SIGKILL this process when its parent (the thread that forked it) dies;
    Linux only, a no-op elsewhere."""
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG = 1
    except (OSError, AttributeError):
        pass


def watch_grid(grid_pid: int) -> None:
    """In a local worker of the grid process ``grid_pid``, start a daemon thread that kills the
    worker's forked runs and exits as soon as the grid is gone (nothing in the grid process or
    in a Dask / Ray worker).

    Parameters
    ----------
    grid_pid : int
        Process id of the grid.
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
    """Turn SIGTERM into KeyboardInterrupt during the grid (joblib then kills the workers), then
    end the process by SIGTERM; only in the main thread where SIGTERM has its default action."""
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
