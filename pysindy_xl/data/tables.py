"""Your own data: CSV files, pandas DataFrames and column mappings into a :class:`Dataset`.

A table has one row per sample and a header naming its columns, by default ``t`` (or
``time``: sample times, strictly increasing within each trajectory), ``NAME`` (the position of
coordinate ``NAME``), optionally ``NAME_dot`` and ``NAME_ddot`` (velocities, accelerations: all
coordinates or none), ``tau_NAME`` (the generalized force; a coordinate without one is
unactuated) and ``trajectory`` (ids, numbers or labels, splitting the trajectories in order of
first appearance). ``columns`` maps these keys to other headers (``{"t": "time_s"}``); without
``coordinates`` every other column is a coordinate, in header order. A mistake raises
:class:`~pysindy_xl.data.DatasetError` naming the file, the column and the line of a bad cell.
"""

from __future__ import annotations

import csv
import os

import numpy as np

from .files import DatasetError, coordinate_names

__all__ = ["read_csv", "from_dataframe", "from_columns", "load_data", "coordinate_names",
           "CSV_SUFFIXES"]

CSV_SUFFIXES = (".csv", ".tsv", ".txt")
_TIME_NAMES = ("t", "time")


def _sniff_delimiter(header_line: str, delimiter: str) -> str | None:
    """The delimiter the header seems to use when it is not ``delimiter``."""
    return next((candidate for candidate in (",", ";", "\t", "|", " ")
                 if candidate != delimiter and candidate in header_line.strip()), None)


def _read_text_table(path: str, delimiter: str):
    """Header, raw string columns and the file line number of each row."""
    if not os.path.isfile(path):
        raise DatasetError(f"path: data file {path!r} does not exist")
    try:
        with open(path, encoding="utf-8-sig", newline="") as handle:
            lines = list(enumerate(handle, start=1))
    except (OSError, UnicodeDecodeError) as error:
        raise DatasetError(f"path: cannot read {path!r} as text ({error})") from None
    lines = [(k, line) for k, line in lines if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise DatasetError(f"{path!r}: the file is empty (expected a header line and data rows)")
    rows = list(csv.reader([line for _, line in lines], delimiter=delimiter,
                           skipinitialspace=True))
    header = [name.strip() for name in rows[0]]
    if len(header) == 1:
        other = _sniff_delimiter(lines[0][1], delimiter)
        hint = (f"; the file seems to use {other!r} as delimiter (delimiter={other!r}, "
                f"--delimiter {other!r})" if other else "")
        raise DatasetError(f"{path!r}: the header has a single column {header[0]!r} with delimiter "
                           f"{delimiter!r}{hint}")
    if len(set(header)) != len(header) or "" in header:
        dup = sorted({h for h in header if header.count(h) > 1 or h == ""})
        raise DatasetError(f"{path!r}: empty or duplicate column names in the header: {dup}")
    numbers = []
    for (line_no, _), row in zip(lines[1:], rows[1:], strict=True):
        if len(row) != len(header):
            raise DatasetError(f"{path!r}, line {line_no}: {len(row)} fields, the header has "
                               f"{len(header)} ({header}); check the delimiter ({delimiter!r})")
        numbers.append(line_no)
    if not numbers:
        raise DatasetError(f"{path!r}: no data rows after the header")
    columns = {name: [row[j].strip() for row in rows[1:]] for j, name in enumerate(header)}
    return header, columns, np.asarray(numbers)


def _as_float(values, column: str, source: str, where) -> np.ndarray:
    """A raw column as floats; the first bad cell named by column and line."""
    try:
        a = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        a = None
    if a is None:
        for k, value in enumerate(values):
            try:
                float(value)
            except (TypeError, ValueError):
                what = "an empty cell" if str(value).strip() == "" else f"{value!r}"
                raise DatasetError(f"{source}, column {column!r}, {where(k)}: {what} is not a "
                                   "number") from None
    bad = np.flatnonzero(~np.isfinite(a))
    if len(bad):
        raise DatasetError(f"{source}, column {column!r}, {where(bad[0])}: NaN or inf "
                           f"({values[bad[0]]!r})")
    return a


def _trajectory_groups(ids, source: str, column: str):
    """Row indices of each trajectory, in order of first appearance."""
    try:
        keys = np.asarray(ids, dtype=float)
        if not np.all(np.isfinite(keys)):
            raise ValueError
        keys = keys.tolist()
    except (TypeError, ValueError):
        keys = [str(v).strip() for v in ids]
    groups: dict = {}
    for row, key in enumerate(keys):
        groups.setdefault(key, []).append(row)
    return [(key, np.asarray(rows)) for key, rows in groups.items()]


def _resolve(header, coordinates, columns, source):
    """Map the roles (time, id, q, qd, qdd, tau) to header names."""
    columns = dict(columns or {})
    for key, name in columns.items():
        if not isinstance(key, str) or not isinstance(name, str):
            raise TypeError("columns: expected a mapping of str to str")
        if name not in header:
            raise DatasetError(f"{source}: column {name!r} (mapped from {key!r}) not found in the "
                               f"header {header}")
    mapped = set(columns.values())

    def column_of(key):
        if key in columns:
            return columns[key]
        return key if key in header and key not in mapped else None

    time = column_of("t") or next((c for c in _TIME_NAMES[1:] if c in header), None)
    if time is None:
        raise DatasetError(f"{source}: no time column 't' in the header {header}; name it 't' "
                           "or map it (columns={'t': NAME}, --column t=NAME)")
    trajectory = column_of("trajectory")
    if coordinates is None:
        roles = {time, trajectory} | mapped
        names = [c for c in header if c not in roles and not c.endswith(("_dot", "_ddot"))
                 and not c.startswith("tau_")]
        names += [k for k in columns if k not in ("t", "trajectory") and k not in names
                  and not k.endswith(("_dot", "_ddot")) and not k.startswith("tau_")]
        if not names:
            raise DatasetError(f"{source}: no coordinate column in the header {header}")
    else:
        names = coordinate_names(coordinates)
    from ..symbols import Coordinates
    Coordinates(names)  # same name rules as the symbols (raises ValueError naming them)
    q = []
    for name in names:
        col = column_of(name)
        if col is None:
            raise DatasetError(f"{source}: column {name!r} (position of coordinate {name!r}) not "
                               f"found in the header {header}; map it with columns={{{name!r}: "
                               f"NAME}} (--column {name}=NAME)")
        q.append(col)
    series = {}
    for key, suffix in (("qd", "{}_dot"), ("qdd", "{}_ddot")):
        found = [column_of(suffix.format(n)) for n in names]
        if any(found):
            if not all(found):
                lacking = [suffix.format(n) for n, c in zip(names, found, strict=True) if not c]
                raise DatasetError(f"{source}: column(s) {lacking} missing while "
                                   f"{[c for c in found if c]} are present (give all or none)")
            series[key] = found
    forces = [column_of(f"tau_{n}") for n in names]
    if any(forces):
        series["tau"] = forces
    return time, trajectory, names, q, series


def _build(raw, header, coordinates, columns, source, where, metadata=None):
    from .dataset import Dataset, Trajectory
    time, id_column, names, q_cols, series = _resolve(header, coordinates, columns, source)
    cache = {}

    def numeric(col):
        if col not in cache:
            cache[col] = _as_float(raw[col], col, source, where)
        return cache[col]

    n_rows = len(raw[time])
    t = numeric(time)
    groups = (_trajectory_groups(raw[id_column], source, id_column) if id_column
              else [(None, np.arange(n_rows))])
    arrays = {"q": np.column_stack([numeric(c) for c in q_cols])}
    for key, cols in series.items():
        arrays[key] = np.column_stack(
            [numeric(c) if c is not None else np.zeros(n_rows) for c in cols])
    trajectories = []
    for key, rows in groups:
        label = "" if key is None else f" (trajectory {key!r} of column {id_column!r})"
        if len(rows) < 2:
            raise DatasetError(
                f"{source}: {len(rows)} sample{label}; a trajectory needs at least 2")
        steps = np.diff(t[rows])
        bad = np.flatnonzero(steps <= 0)
        if len(bad):
            k = rows[bad[0] + 1]
            raise DatasetError(f"{source}, column {time!r}, {where(k)}: time {t[k]:g} after "
                               f"{t[rows[bad[0]]]:g}; times must be strictly increasing{label}")
        trajectories.append(Trajectory(t=t[rows], info={} if key is None else {"id": key},
                                       **{k: a[rows] for k, a in arrays.items()}))
    info = dict(metadata or {})
    info["columns"] = {"t": time, "q": q_cols,
                       **{k: [c for c in v if c] for k, v in series.items()}}
    if id_column:
        info["columns"]["trajectory"] = id_column
    return Dataset(trajectories, names, info)


def read_csv(path, coordinates=None, columns=None, delimiter=","):
    """Read a CSV file (header + one row per sample) into a :class:`Dataset`.

    Parameters
    ----------
    path : str or os.PathLike
        The file; lines starting with ``#`` and blank lines are skipped.
    coordinates : list of str or str, optional
        Coordinate names, in order (``["x", "theta"]`` or ``"x,theta"``). Default: every
        column that has no other role (see the module docstring).
    columns : dict of str to str, optional
        Header of each role whose column is not named by default: keys ``"t"``,
        ``"trajectory"``, a coordinate name, ``NAME_dot``, ``NAME_ddot``, ``tau_NAME``.
    delimiter : str, default ","
        Field separator (``";"``, ``"\\t"``...).

    Returns
    -------
    Dataset
        ``metadata["columns"]`` records which columns were read.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> text = "t,theta,tau_theta\\n0.0,0.1,0.0\\n0.1,0.2,0.5\\n0.2,0.25,0.4\\n"
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = pathlib.Path(tmp) / "pendulum.csv"
    ...     _ = path.write_text(text)
    ...     data = read_csv(path)
    >>> data, data.trajectories[0].tau.ravel().tolist()
    (Dataset(coordinates=['theta'], trajectories=1, samples=3), [0.0, 0.5, 0.4])
    """
    path = os.fspath(path)
    if not isinstance(delimiter, str) or len(delimiter) != 1:
        raise ValueError(f"delimiter: expected a single character, got {delimiter!r}")
    header, raw, lines = _read_text_table(path, delimiter)
    return _build(raw, header, coordinates, columns, repr(path),
                  lambda k: f"line {lines[k]}", {"source": os.path.basename(path)})


def from_columns(data, coordinates=None, columns=None, name="data"):
    """A :class:`Dataset` from a mapping of column name to 1-D values (same rules as a CSV).

    ``data`` maps names to columns of equal length; ``coordinates`` and ``columns`` as in
    :func:`read_csv`; errors name the source ``name``.

    Parameters
    ----------
    data : mapping of str to array_like
        Column name to 1-D values, all of equal length.
    coordinates : list of str or str, optional
        Coordinate names, as in :func:`read_csv`.
    columns : dict of str to str, optional
        Header of each role not named by default, as in :func:`read_csv`.
    name : str, default="data"
        The source named in errors.

    Returns
    -------
    Dataset
        One trajectory per ``trajectory`` id (or one in all).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0.0, 1.0, 6)
    >>> data = from_columns({"time_s": np.r_[t, t], "x": np.r_[t, 2 * t],
    ...                      "run": [1.0] * 6 + [2.0] * 6},
    ...                     columns={"t": "time_s", "trajectory": "run"})
    >>> data, [tr.info["id"] for tr in data.trajectories]
    (Dataset(coordinates=['x'], trajectories=2, samples=12), [1.0, 2.0])
    """
    if not hasattr(data, "items"):
        raise TypeError(f"data: expected a mapping of column name to values, got "
                        f"{type(data).__name__}")
    raw = {}
    for key, values in data.items():
        values = np.asarray(values)
        if values.ndim != 1:
            raise DatasetError(f"{name}, column {key!r}: expected 1-D values, got shape "
                               f"{values.shape}")
        raw[str(key)] = values
    lengths = {len(v) for v in raw.values()}
    if len(lengths) > 1:
        raise DatasetError(f"{name}: columns of different lengths "
                           f"{ {k: len(v) for k, v in raw.items()} }")
    return _build(raw, list(raw), coordinates, columns, name, lambda k: f"row {k}")


def from_dataframe(frame, coordinates=None, columns=None):
    """A :class:`Dataset` from a pandas DataFrame (same rules as a CSV file).

    ``frame`` is any object with ``columns`` and ``__getitem__`` returning 1-D values (pandas,
    polars), one row per sample; ``coordinates`` and ``columns`` as in :func:`read_csv`.

    Parameters
    ----------
    frame : pandas.DataFrame
        Or any object with ``columns`` and ``__getitem__`` returning 1-D values (polars), one row
        per sample.
    coordinates : list of str or str, optional
        Coordinate names, as in :func:`read_csv`.
    columns : dict of str to str, optional
        Header of each role not named by default, as in :func:`read_csv`.

    Returns
    -------
    Dataset
        One trajectory per ``trajectory`` id (or one in all).

    Examples
    --------
    >>> import numpy as np
    >>> pd = __import__("pytest").importorskip("pandas")
    >>> t = np.linspace(0.0, 1.0, 5)
    >>> frame = pd.DataFrame({"t": t, "x": t ** 2, "x_dot": 2 * t})
    >>> data = from_dataframe(frame)
    >>> data, data.has("qd")
    (Dataset(coordinates=['x'], trajectories=1, samples=5), True)
    """
    if not hasattr(frame, "columns") or not hasattr(frame, "__getitem__"):
        raise TypeError(f"frame: expected a pandas DataFrame, got {type(frame).__name__}")
    labels = list(getattr(frame, "index", range(len(frame))))
    raw = {}
    for key in frame.columns:
        column = frame[key]
        raw[str(key)] = np.asarray(column.to_numpy() if hasattr(column, "to_numpy") else column)
    return _build(raw, list(raw), coordinates, columns, "DataFrame", lambda k: f"row {labels[k]!r}")


def load_data(source, coordinates=None, columns=None, delimiter=None, topic=None):
    """Read a CSV or NPZ file, a DataFrame or a column mapping into a :class:`Dataset`.

    Parameters
    ----------
    source : str, os.PathLike, pandas.DataFrame or dict
        ``.csv`` / ``.txt`` (comma-separated) or ``.tsv`` (tab-separated) file, ``.npz``
        dataset (see :mod:`pysindy_xl.data.dataset`), ROS bag of ``sensor_msgs/JointState``
        (``.bag`` file or ROS 2 bag directory; :func:`~pysindy_xl.data.rosbag.read_rosbag`),
        DataFrame, or mapping of columns.
    coordinates : list of str or str, optional
        Coordinate names; for an NPZ file they rename the columns of ``q``.
    columns : dict, optional
        Column mapping of a table (:func:`read_csv`) or ``{coordinate: joint}`` of a ROS bag.
    delimiter : str, optional
        Field separator of a text file (default: tab for ``.tsv``, comma otherwise).
    topic : str, optional
        The ``sensor_msgs/JointState`` topic of a ROS bag (default: its only one).

    Returns
    -------
    Dataset
        The data, whatever the source.

    Raises
    ------
    DatasetError
        When the source cannot be read (unknown suffix, malformed file, missing column).
    ValueError
        When ``delimiter`` or ``topic`` does not apply to the source.

    Examples
    --------
    >>> import numpy as np, pathlib, tempfile
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = pathlib.Path(tmp) / "mine.npz"
    ...     np.savez(path, t=t, q=np.sin(t), trajectory=np.r_[[0.0] * 5, [1.0] * 6])
    ...     load_data(path, coordinates="theta")
    Dataset(coordinates=['theta'], trajectories=2, samples=11)
    """
    if isinstance(source, (str, os.PathLike)):
        path = os.fspath(source)
        suffix = os.path.splitext(path)[1].lower()
        from .rosbag import is_rosbag, read_rosbag
        if is_rosbag(path):
            if delimiter is not None:
                raise ValueError(f"delimiter: applies to text tables, not to the ROS bag {path!r}")
            return read_rosbag(path, coordinates, columns, topic)
        if topic is not None:
            raise ValueError(f"topic: applies to ROS bags, not to {path!r}")
        if suffix == ".npz":
            return _load_npz(path, coordinates, columns)
        if suffix not in CSV_SUFFIXES:
            raise DatasetError(f"path: {path!r} has an unknown format {suffix!r}; expected one of "
                               f"{['.npz', *CSV_SUFFIXES]}")
        if delimiter is None:
            delimiter = "\t" if suffix == ".tsv" else ","
        return read_csv(path, coordinates, columns, delimiter)
    if hasattr(source, "columns"):
        return from_dataframe(source, coordinates, columns)
    if hasattr(source, "items"):
        return from_columns(source, coordinates, columns)
    raise TypeError(f"source: expected a file path, a DataFrame or a dict of columns, got "
                    f"{type(source).__name__}")


def _load_npz(path, coordinates, columns):
    from .dataset import Dataset, load_dataset
    if columns:
        raise ValueError("columns: a column mapping applies to tables (CSV, DataFrame), not "
                         f"to the NPZ file {path!r}")
    dataset = load_dataset(path)
    if coordinates is None:
        return dataset
    names = coordinate_names(coordinates)
    if len(names) != dataset.n:
        raise DatasetError(f"coordinates: {len(names)} names {names} for the {dataset.n} "
                           f"columns of q in {path!r}")
    from ..symbols import Coordinates
    Coordinates(names)
    return Dataset(dataset.trajectories, names, dataset.metadata)
