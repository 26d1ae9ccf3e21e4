"""Reading and checking dataset files (NPZ arrays, JSON metadata) into a :class:`Dataset`.

File layout: see :mod:`pysindy_xl.mujoco.dataset`, which re-exports :func:`load_dataset`.
"""

from __future__ import annotations

import json
import os
import zipfile
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .dataset import Dataset

__all__ = ["load_dataset"]


def _read_npz(path: str) -> dict:
    from .dataset import DatasetError

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
                    raise DatasetError(
                        f"path: array {key!r} of {path!r} cannot be read without pickle "
                        f"({error}); store plain numeric arrays"
                    ) from None
            return arrays
    except DatasetError:
        raise
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as error:
        raise DatasetError(f"path: {path!r} is not a readable NPZ file ({error})") from None


def load_dataset(path) -> Dataset:
    """Read a dataset NPZ (with embedded or side-car JSON metadata, or none).

    Parameters
    ----------
    path : str or os.PathLike
        An ``.npz`` file holding at least ``t`` (N,) and ``q`` (N, n); see the module docstring.

    Returns
    -------
    Dataset

    Raises
    ------
    DatasetError
        With a message naming the missing or malformed array.

    Examples
    --------
    A user's own NPZ needs only ``t`` and ``q``; ``trajectory`` ids split it:

    >>> import tempfile, pathlib, numpy as np
    >>> t = np.r_[np.linspace(0, 1, 11), np.linspace(0, 2, 21)]
    >>> ids = np.r_[np.zeros(11, dtype=int), np.ones(21, dtype=int)]
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = pathlib.Path(tmp) / "mine.npz"
    ...     np.savez(path, t=t, q=np.sin(t), trajectory=ids)
    ...     data = load_dataset(path)
    >>> data
    Dataset(coordinates=['q0'], trajectories=2, samples=32)

    A missing array is named in the error:

    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = pathlib.Path(tmp) / "bad.npz"
    ...     np.savez(path, t=t)
    ...     load_dataset(path)
    Traceback (most recent call last):
    ...
    pysindy_xl.mujoco.dataset.DatasetError: path: '...bad.npz' lacks the required array(s)
    ['q']; ...
    """
    from .dataset import _MASKS, _SERIES, Dataset, DatasetError, Trajectory

    path = os.fspath(path)
    arrays = _read_npz(path)
    missing = [k for k in ("t", "q") if k not in arrays]
    if missing:
        raise DatasetError(
            f"path: {path!r} lacks the required array(s) {missing}; found {sorted(arrays)} "
            "(expected t (N,), q (N, n), optionally qd, qdd, tau, u, trajectory)"
        )
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
        q = q[:, None]
    if q.ndim != 2:
        raise DatasetError(f"q: expected shape (N, n), got {arrays['q'].shape}")
    n_samples, n = q.shape
    t = np.asarray(arrays["t"], dtype=float)
    if t.shape != (n_samples,):
        raise DatasetError(f"t: expected shape ({n_samples},) like q's rows, got {t.shape}")
    if "constraint_active" in arrays and arrays["constraint_active"].shape != (n_samples,):
        raise DatasetError(
            f"constraint_active: expected shape ({n_samples},) like q's rows, got "
            f"{arrays['constraint_active'].shape}"
        )
    for key in _SERIES[1:]:
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
    if len(names) != n:
        raise DatasetError(
            f"metadata: coordinate_names has {len(names)} names, q has {n} columns"
        )
    infos = metadata.pop("trajectory_info", None)
    trajectories = []
    starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
    ends = np.r_[starts[1:], n_samples]
    if len(set(ids[starts].tolist())) != len(starts):
        raise DatasetError("trajectory: the samples of each trajectory must be contiguous")
    for k, (a, b) in enumerate(zip(starts, ends, strict=True)):
        series = {}
        for key in _SERIES + _MASKS:
            if key in arrays:
                series[key] = arrays[key][a:b]
        info = infos[k] if isinstance(infos, list) and len(infos) == len(starts) else {}
        try:
            trajectories.append(Trajectory(t=t[a:b], info=info, **series))
        except DatasetError as error:
            raise DatasetError(f"{error} (trajectory {ids[a]} of {path!r})") from None
    for key in ("format", "version", "coordinate_names"):
        metadata.pop(key, None)
    return Dataset(trajectories, names, metadata)


def _parse_json(text: str, where: str) -> dict:
    from .dataset import DatasetError

    try:
        data = json.loads(text)
    except json.JSONDecodeError as error:
        raise DatasetError(f"metadata: invalid JSON in {where}: {error}") from None
    if not isinstance(data, dict):
        raise DatasetError(f"metadata: expected a JSON object in {where}")
    return data
