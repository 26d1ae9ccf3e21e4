"""Reading and checking dataset files: NPZ arrays and JSON metadata, never pickle.

File layout: see :mod:`pysindy_xl.data.dataset`, whose :func:`~pysindy_xl.data.dataset.load_dataset`
builds the trajectories from what :func:`read_dataset_arrays` returns.
"""

from __future__ import annotations

import json
import os
import zipfile

import numpy as np

__all__ = ["DatasetError", "read_dataset_arrays", "coordinate_names", "FORMAT", "VERSION",
           "SERIES", "MASKS"]

FORMAT = "pysindy-xl-dataset"
VERSION = 1
#: per-sample series of a trajectory (float arrays) and its boolean masks
SERIES = ("q", "qd", "qdd", "tau", "u", "tau_constraint", "u_constraint")
MASKS = ("constraint_active",)


class DatasetError(ValueError):
    """A dataset file or array that cannot be used (bad file, missing or malformed arrays).

    A :class:`ValueError`, so ``except ValueError`` catches it too.

    Examples
    --------
    >>> from pysindy_xl.data import Trajectory
    >>> Trajectory(t=[0.0, 1.0, 0.5], q=[[0.0], [1.0], [2.0]])
    Traceback (most recent call last):
    ...
    pysindy_xl.data.files.DatasetError: t: times must be strictly increasing; ...
    """


def _read_npz(path: str) -> dict:
    if not os.path.isfile(path):
        raise DatasetError(f"path: dataset file {path!r} does not exist")
    try:
        with np.load(path, allow_pickle=False) as npz:
            if not hasattr(npz, "files"):
                raise DatasetError(f"path: {path!r} holds a single array, expected an NPZ archive")
            arrays = {}
            for key in npz.files:
                try:
                    arrays[key] = npz[key]
                except ValueError as error:
                    raise DatasetError(f"path: array {key!r} of {path!r} cannot be read without "
                                       f"pickle ({error}); store plain numeric arrays") from None
            return arrays
    except DatasetError:
        raise
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as error:
        raise DatasetError(f"path: {path!r} is not a readable NPZ file ({error})") from None


def read_dataset_arrays(path) -> tuple[dict, dict, list, list]:
    """The checked contents of a dataset NPZ: ``(arrays, metadata, coordinate_names,
    bounds)``, every numeric array by name (``q`` as (N, n)), the metadata (embedded, side-car
    JSON or none) and the contiguous sample range ``(start, stop)`` of each trajectory. A
    :class:`DatasetError` says what is wrong with a missing, non-NPZ or malformed file.

    Parameters
    ----------
    path : str or os.PathLike
        The NPZ file.

    Returns
    -------
    arrays : dict of str to numpy.ndarray
        Every numeric array by name (``q`` as (N, n)).
    metadata : dict
        Embedded, side-car JSON, or empty.
    coordinate_names : list of str
        The coordinates.
    bounds : list of tuple of int
        The contiguous sample range ``(start, stop)`` of each trajectory.

    Raises
    ------
    DatasetError
        When the file is missing, not an NPZ, or malformed.
    """
    path = os.fspath(path)
    arrays = _read_npz(path)
    missing = [k for k in ("t", "q") if k not in arrays]
    if missing:
        raise DatasetError(f"path: {path!r} lacks the required array(s) {missing}; found "
                           f"{sorted(arrays)} (expected t (N,), q (N, n), optionally qd, qdd, tau, "
                           "u, trajectory)")
    metadata = {}
    if "metadata" in arrays:
        raw = arrays.pop("metadata")
        if raw.dtype.kind != "U" or raw.ndim != 0:
            raise DatasetError("metadata: expected a 0-d string array holding JSON text")
        metadata = _parse_json(str(raw), f"{path!r} (embedded metadata)")
    else:
        sidecar = os.path.splitext(path)[0] + ".json"
        if os.path.isfile(sidecar):
            with open(sidecar, encoding="utf-8") as handle:
                metadata = _parse_json(handle.read(), repr(sidecar))
    for key, a in arrays.items():
        if a.dtype.kind not in "fiub":
            raise DatasetError(f"{key}: expected a numeric array, got dtype {a.dtype}")
    q = arrays["q"]
    if q.ndim == 1:
        q = arrays["q"] = q[:, None]
    if q.ndim != 2:
        raise DatasetError(f"q: expected shape (N, n), got {arrays['q'].shape}")
    n_samples, n = q.shape
    t = np.asarray(arrays["t"], dtype=float)
    if t.shape != (n_samples,):
        raise DatasetError(f"t: expected shape ({n_samples},) like q's rows, got {t.shape}")
    if "constraint_active" in arrays and arrays["constraint_active"].shape != (n_samples,):
        raise DatasetError(f"constraint_active: expected shape ({n_samples},) like q's rows, got "
                           f"{arrays['constraint_active'].shape}")
    for key in SERIES[1:]:
        if key in arrays:
            shape = arrays[key].shape
            if shape not in ((n_samples, n),) + (((n_samples,),) if n == 1 else ()):
                raise DatasetError(f"{key}: expected shape ({n_samples}, {n}) like q, got {shape}")
    ids = arrays.get("trajectory", np.zeros(n_samples, dtype=np.int64))
    if ids.shape != (n_samples,) or ids.dtype.kind not in "iuf" or (
            ids.dtype.kind == "f" and not np.all(np.isfinite(ids))):
        raise DatasetError(f"trajectory: expected numeric (integer or float) finite ids of "
                           f"shape ({n_samples},), got dtype {ids.dtype}, shape {ids.shape}")
    names = metadata.get("coordinate_names") or [f"q{k}" for k in range(n)]
    if not isinstance(names, list) or not all(isinstance(name, str) for name in names):
        raise DatasetError(f"metadata: coordinate_names: expected a list of str, got {names!r}")
    if len(names) != n:
        raise DatasetError(f"metadata: coordinate_names has {len(names)} names, q has {n} columns")
    starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
    ends = np.r_[starts[1:], n_samples]
    if len(set(ids[starts].tolist())) != len(starts):
        raise DatasetError("trajectory: the samples of each trajectory must be contiguous")
    arrays["trajectory"] = ids
    return arrays, metadata, list(names), [(int(a), int(b)) for a, b in zip(starts, ends,
                                                                          strict=True)]


def _parse_json(text: str, where: str) -> dict:
    try:
        data = json.loads(text)
    except json.JSONDecodeError as error:
        raise DatasetError(f"metadata: invalid JSON in {where}: {error}") from None
    if not isinstance(data, dict):
        raise DatasetError(f"metadata: expected a JSON object in {where}")
    return data


def coordinate_names(coordinates) -> list[str]:
    """Coordinate names given as a list of str or one comma-separated str.

    Parameters
    ----------
    coordinates : str or sequence of str
        Names, a sequence or one comma-separated string.

    Returns
    -------
    list of str
        The names, stripped.

    Raises
    ------
    TypeError
        When ``coordinates`` is neither.

    Examples
    --------
    >>> coordinate_names("x, theta")
    ['x', 'theta']
    >>> coordinate_names(3)
    Traceback (most recent call last):
    ...
    TypeError: coordinates: expected a list of names or a comma-separated str, got the int 3
    """
    if isinstance(coordinates, str):
        coordinates = [c.strip() for c in coordinates.split(",")]
    if not isinstance(coordinates, (list, tuple)):
        raise TypeError("coordinates: expected a list of names or a comma-separated str, got "
                        f"the {type(coordinates).__name__} {coordinates!r}")
    names = list(coordinates)
    if not names or not all(isinstance(n, str) and n for n in names):
        raise ValueError(f"coordinates: expected a non-empty list of names, got {names!r}")
    return names
