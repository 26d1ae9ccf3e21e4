"""Result records: one JSON object per run, appended to a JSONL file as each run finishes.

Each record is one ``write`` of one line, flushed and fsynced: a torn last line (a killed
writer) is cut off by :class:`RecordStore` and skipped by :func:`read_records`, and its run
is run again; for a run id recorded twice the last record wins. Fields: what ran
(``run_id``, ``trajectory_id``, ``config`` and the :class:`~.grid.Task` fields); ``status``
``"ok"`` (simulated over the whole validation horizon), ``"invalid"`` (diverged, failed or
no acceleration), ``"timeout"`` or ``"error"`` (the paper's "uncompleted"); ``message``
(why, unless ok); ``metrics`` (``position_rmse`` ranks); ``time_s`` (``generate``,
``fit``, ``validate``, ``run``)."""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import time
import traceback
import warnings

from ..registry import json_finite
from .grid import GridSettings, Task

__all__ = ["STATUSES", "RecordStore", "GridBusyError", "read_records", "latest_records",
           "check_record"]

STATUSES = ("ok", "invalid", "timeout", "error")
_REQUIRED = ("run_id", "trajectory_id", "config", "status")


def check_record(record) -> dict:
    """Validate a record's required fields and status; returns it.

    Parameters
    ----------
    record : dict
        A run record.

    Returns
    -------
    dict
        The same record.

    Raises
    ------
    TypeError
        When ``record`` is not a dict.
    ValueError
        When a required field is missing, the status is unknown, or an ``ok`` record lacks
        a finite ``metrics.position_rmse``.
    """
    if not isinstance(record, dict):
        raise TypeError(f"record: expected a dict, got {type(record).__name__}")
    missing = [k for k in _REQUIRED if k not in record]
    if missing:
        raise ValueError(f"record: missing fields {missing}")
    if record["status"] not in STATUSES:
        raise ValueError(f"record: status must be one of {STATUSES}, got {record['status']!r}")
    if record["status"] == "ok":
        rmse = (record.get("metrics") or {}).get("position_rmse")
        if not isinstance(rmse, (int, float)) or not rmse == rmse or rmse < 0:
            raise ValueError(f"record {record['run_id']!r}: status 'ok' needs a finite "
                             f"metrics.position_rmse, got {rmse!r}")
    return record


class GridBusyError(RuntimeError):
    """Another grid holds the records file (see :meth:`RecordStore.lock`)."""


def read_records(path) -> list[dict]:
    """All complete records of a JSONL file, in file order (duplicates kept); unreadable lines
    are skipped with a warning naming them, and their runs count as not done.

    Parameters
    ----------
    path : str or os.PathLike
        The JSONL file.

    Returns
    -------
    list of dict
        The records (empty when the file does not exist).

    Examples
    --------
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "records.jsonl")
    >>> RecordStore(path).append({"run_id": "a", "trajectory_id": "t", "config": "c",
    ...                           "status": "timeout"})
    >>> with open(path, "a") as handle:  # a torn line, as a killed writer leaves
    ...     _ = handle.write('{"run_id": "b", "traj')
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     ids = [record["run_id"] for record in read_records(path)]
    >>> ids, caught[0].category.__name__
    (['a'], 'RuntimeWarning')
    """
    if not os.path.exists(path):
        return []
    with open(path, encoding="utf-8") as handle:
        text = handle.read()
    lines = text.split("\n")
    out = []
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        is_last = number == len(lines)  # no newline after it: possibly torn
        try:
            record = json.loads(line)
        except json.JSONDecodeError as error:
            if is_last:
                warnings.warn(f"{path}: skipping a torn last line ({len(line)} characters)",
                              RuntimeWarning, stacklevel=2)
                continue
            warnings.warn(f"{path}: skipping line {number}, which is not valid JSON ({error}); "
                          "its run will be run again", RuntimeWarning, stacklevel=2)
            continue
        if is_last:  # complete JSON but no trailing newline: also an interrupted write
            warnings.warn(f"{path}: skipping a last line without newline", RuntimeWarning,
                          stacklevel=2)
            continue
        out.append(check_record(record))
    return out


def latest_records(records) -> list[dict]:
    """One record per run id, the last one written, in order of first appearance.

    Parameters
    ----------
    records : iterable of dict
        Run records.

    Returns
    -------
    list of dict
        The last record of every run id.
    """
    by_id: dict = {}
    for record in records:
        by_id[record["run_id"]] = record  # dict keeps the first insertion position
    return list(by_id.values())


class RecordStore:
    """Append-only JSONL file of run records (module docstring), created with its directory.

    Parameters
    ----------
    path : str or os.PathLike
        The JSONL file (created with its directory; a torn last line is cut).

    Examples
    --------
    >>> import tempfile, os
    >>> path = os.path.join(tempfile.mkdtemp(), "records.jsonl")
    >>> store = RecordStore(path)
    >>> store.append({"run_id": "a", "trajectory_id": "t", "config": "c", "status": "error"})
    >>> sorted(store.finished_ids())
    ['a']
    """

    def __init__(self, path):
        self.path = os.fspath(path)
        directory = os.path.dirname(os.path.abspath(self.path))
        os.makedirs(directory, exist_ok=True)
        self._repair()

    def _repair(self):
        """Cut a torn last line left by a killed writer, so the next append starts clean."""
        if not os.path.exists(self.path):
            return
        with open(self.path, "rb+") as handle:
            data = handle.read()
            if not data or data.endswith(b"\n"):
                return
            keep = data.rfind(b"\n") + 1
            handle.truncate(keep)
            handle.flush()
            os.fsync(handle.fileno())
        warnings.warn(f"{self.path}: removed a torn last line ({len(data) - keep} bytes); that "
                      "run will be run again", RuntimeWarning, stacklevel=3)

    @contextlib.contextmanager
    def lock(self):
        """Exclusive use of the records file during a grid: a second grid refuses at once
        (:class:`GridBusyError` naming the holder); the ``flock`` on ``PATH.lock`` dies with its
        process, so no stale lock is left."""
        lock_path = self.path + ".lock"
        handle = open(lock_path, "a+")  # noqa: SIM115 - held for the whole context
        try:
            try:
                fcntl.flock(handle.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                handle.seek(0)
                holder = handle.read().strip() or "another process"
                raise GridBusyError(
                    f"records: another grid ({holder}) is writing to {self.path}; wait for it "
                    "to finish or use another output directory"
                ) from None
            handle.seek(0)
            handle.truncate()
            handle.write(f"pid {os.getpid()}")
            handle.flush()
            yield
        finally:
            handle.close()

    def records(self) -> list[dict]:
        """Latest record of every run id (see :func:`latest_records`).

        Returns
        -------
        list of dict
            The latest record of every run id.
        """
        return latest_records(read_records(self.path))

    def finished_ids(self, retry=()) -> set[str]:
        """Run ids with a record, except those whose latest status is in ``retry``.

        Parameters
        ----------
        retry : iterable of str, default=()
            Statuses that do not count as finished.

        Returns
        -------
        set of str
            The finished run ids.
        """
        retry = set(retry)
        unknown = retry - set(STATUSES)
        if unknown:
            raise ValueError(f"retry: expected statuses among {STATUSES}, got {sorted(unknown)}")
        return {r["run_id"] for r in self.records() if r["status"] not in retry}

    def append(self, record: dict) -> None:
        """Append one record durably (one write, flush, fsync).

        Parameters
        ----------
        record : dict
            A run record (JSON-serializable).
        """
        check_record(record)
        line = json.dumps(record, sort_keys=True, allow_nan=False) + "\n"
        data = line.encode("utf-8")
        fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        try:
            written = os.write(fd, data)
            while written < len(data):  # short writes are rare but legal
                written += os.write(fd, data[written:])
            os.fsync(fd)
        finally:
            os.close(fd)


def base_record(task: Task, settings: GridSettings) -> dict:
    """The record a run starts with: the task, the grid's name, status ``error`` until it ends.

    Parameters
    ----------
    task : Task
        The run.
    settings : GridSettings
        The grid's settings.

    Returns
    -------
    dict
        The record.
    """
    import pysindy_xl
    return {**task.to_dict(), "grid": settings.name, "status": "error", "message": None,
            "metrics": {}, "time_s": {}, "pid": os.getpid(),
            "version": getattr(pysindy_xl, "__version__", "unknown")}


def failed_record(record: dict, status: str, error: BaseException, with_traceback=False) -> dict:
    """Mark ``record`` as failed with ``status`` and the error's message.

    Parameters
    ----------
    record : dict
        The run's record, changed in place.
    status : {"error", "timeout", "invalid"}
        The status.
    error : BaseException
        What went wrong.
    with_traceback : bool, default=False
        Add the last three frames of the traceback to the message.

    Returns
    -------
    dict
        The record, JSON-safe (non-finite numbers as None).
    """
    record["status"] = status
    message = f"{type(error).__name__}: {error}"
    if with_traceback:
        frames = traceback.extract_tb(error.__traceback__)[-3:]
        message += " [" + " <- ".join(f"{os.path.basename(f.filename)}:{f.lineno} {f.name}"
                                      for f in reversed(frames)) + "]"
    record["message"] = message
    return json_finite(record)


def finish_record(record: dict) -> dict:
    """Stamp ``record`` with ``finished_at`` (local time, ISO 8601).

    Parameters
    ----------
    record : dict
        The run's record, changed in place.

    Returns
    -------
    dict
        The record.
    """
    record["finished_at"] = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    return record
