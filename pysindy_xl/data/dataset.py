"""Trajectories and datasets: NPZ arrays plus JSON metadata, never pickle.

``Dataset.save`` writes ``DATA.npz``: the series of :class:`Trajectory` (``t``, ``q``, ``qd``,
``qdd``, ``tau``, ``u``, ``tau_constraint``, ``u_constraint``, ``constraint_active``) of all
trajectories concatenated, ``trajectory`` (each sample's id, int or float) and ``metadata``
(JSON text, also written to ``DATA.json`` for people). A user's own NPZ needs only ``t`` and
``q``.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import numpy as np

from .._validation import check_numeric_array, check_times
from .files import FORMAT, MASKS, SERIES, VERSION, DatasetError, read_dataset_arrays

__all__ = ["Trajectory", "Dataset", "load_dataset", "DatasetError"]

CONSTRAINT_HANDLING = ("exclude", "known", "include")


@dataclass
class Trajectory:
    """One sampled trajectory in generalized coordinates.

    The parameters are the attributes, checked on construction (a :class:`DatasetError`
    names a wrong shape, NaN or inf, or times that do not increase).

    Parameters
    ----------
    t : array, shape (N,)
        Sample times, strictly increasing, at least 2.
    q : array, shape (N, n) or (N,)
        Generalized positions (1-D: one coordinate).
    qd, qdd, tau : array, shape (N, n), optional
        Velocities, accelerations, generalized forces on the coordinates.
    u : array, shape (N, n), optional
        Joint forces (one per MuJoCo degree of freedom); ``tau = u @ B.T``.
    info : dict, optional
        JSON-serializable description (initial state, forcing signals...).
    tau_constraint, u_constraint : array, shape (N, n), optional
        Constraint forces (MuJoCo's ``qfrc_constraint``) on the coordinates and on the joints.
    constraint_active : array of bool, shape (N,), optional
        Samples where a limit, contact or equality constraint acts (not frictionloss, which
        the catalogs can model).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0.0, 1.0, 5)
    >>> trajectory = Trajectory(t, q=np.sin(t), qd=np.cos(t))
    >>> trajectory.q.shape, trajectory.n_samples, trajectory.state.shape
    ((5, 1), 5, (5, 2))
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray | None = None
    qdd: np.ndarray | None = None
    tau: np.ndarray | None = None
    u: np.ndarray | None = None
    info: dict = field(default_factory=dict)
    tau_constraint: np.ndarray | None = None
    u_constraint: np.ndarray | None = None
    constraint_active: np.ndarray | None = None

    def __post_init__(self):
        self.t = _check_times(self.t, "t")
        self.q = _check_series(self.q, "q", len(self.t), None)
        n = self.q.shape[1]
        for name in SERIES[1:]:
            value = getattr(self, name)
            if value is not None:
                setattr(self, name, _check_series(value, name, len(self.t), n))
        if self.constraint_active is not None:
            mask = np.asarray(self.constraint_active)
            if mask.shape != (len(self.t),) or mask.dtype.kind not in "biu":
                raise DatasetError("constraint_active: expected a boolean array of shape "
                                   f"({len(self.t)},), got {mask.dtype} {mask.shape}")
            self.constraint_active = mask.astype(bool)

    @property
    def n_samples(self) -> int:
        """Number of samples ``N``."""
        return len(self.t)

    @property
    def state(self) -> np.ndarray:
        """``[q, qd]``, shape (N, 2n)."""
        if self.qd is None:
            raise ValueError("qd: the trajectory has no velocities")
        return np.hstack([self.q, self.qd])


def _check_times(t, name: str) -> np.ndarray:
    try:
        return check_times(t, name)
    except ValueError as err:
        raise DatasetError(str(err)) from None


def _check_series(a, name: str, n_samples: int, n: int | None) -> np.ndarray:
    try:  # strings, complex numbers, booleans: refused with the argument's name
        a = check_numeric_array(a, name, finite=False, min_samples=0)
    except ValueError as err:
        raise DatasetError(str(err)) from None
    if a.ndim == 1 and n in (None, 1):
        a = a[:, None]
    if a.ndim != 2 or a.shape[0] != n_samples or (n is not None and a.shape[1] != n):
        want = f"({n_samples}, {n if n is not None else 'n'})"
        raise DatasetError(f"{name}: expected shape {want}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise DatasetError(f"{name}: contains NaN or inf")
    return a


class Dataset:
    """Several trajectories of one system plus JSON metadata (parameters = attributes).

    Parameters
    ----------
    trajectories : list of Trajectory
    coordinate_names : sequence of str
    metadata : dict, optional
        JSON-serializable (system name and parameters, forcing mode, noise, seed...).

    Raises
    ------
    TypeError
        For a wrong type of argument or metadata that are not JSON-serializable.
    DatasetError
        If the trajectories do not match ``coordinate_names`` or each other.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 11)
    >>> data = Dataset([Trajectory(t, np.sin(t), qd=np.cos(t))], ["theta"])
    >>> data.n_trajectories, data.n, data.has("qd"), data.has("tau")
    (1, 1, True, False)
    """

    def __init__(self, trajectories, coordinate_names, metadata=None):
        if isinstance(trajectories, Trajectory):
            trajectories = [trajectories]
        trajectories = list(trajectories)
        if not trajectories or not all(isinstance(tr, Trajectory) for tr in trajectories):
            raise TypeError("trajectories: expected a non-empty list of Trajectory")
        try:
            names = None if isinstance(coordinate_names, str) else tuple(coordinate_names)
        except TypeError:  # not iterable
            names = None
        if names is None or not all(isinstance(name, str) for name in names):
            raise TypeError("coordinate_names: expected a sequence of str, got "
                            f"{coordinate_names!r}")
        for k, tr in enumerate(trajectories):
            if tr.q.shape[1] != len(names):
                raise DatasetError(f"trajectories: trajectory {k} has {tr.q.shape[1]} coordinates, "
                                   f"coordinate_names has {len(names)}")
            for key in SERIES[1:] + MASKS:
                if (getattr(tr, key) is None) != (getattr(trajectories[0], key) is None):
                    raise DatasetError(f"trajectories: {key!r} present in some trajectories only")
        metadata = dict(metadata or {})
        try:
            json.dumps(metadata)
        except TypeError as error:
            raise TypeError(f"metadata: expected JSON-serializable values ({error})") from None
        self.trajectories = trajectories
        self.coordinate_names = names
        self.metadata = metadata

    @property
    def n(self) -> int:
        """Number of coordinates."""
        return len(self.coordinate_names)

    @property
    def n_trajectories(self) -> int:
        """Number of trajectories."""
        return len(self.trajectories)

    def has(self, key: str) -> bool:
        """Whether the trajectories hold the series ``key`` (an attribute of Trajectory).

        Parameters
        ----------
        key : str
            A series of :class:`Trajectory` (``"qd"``, ``"tau"``, ``"constraint_active"``...).

        Returns
        -------
        bool
            True when every trajectory holds it.
        """
        return getattr(self.trajectories[0], key) is not None

    def fit_arguments(self, forces: str | None = "tau", constraints: str = "exclude",
                      margin: int | None = None, min_length: int | None = None) -> dict:
        """Keyword arguments for ``XLSINDy.fit``: lists of per-trajectory arrays.

        Parameters
        ----------
        forces : {"tau", "u", None}, default "tau"
            Which forces to pass as ``u``: generalized forces (with the default interlink),
            joint forces (with ``interlink=B``), or none (implicit fit).
        constraints : {"exclude", "known", "include"}, default "exclude"
            Samples where a constraint acts (``constraint_active``): ``exclude`` splits each
            trajectory into its unconstrained runs (:func:`.constraints.unconstrained_samples`);
            ``known`` adds the recorded constraint forces to ``u``; ``include`` passes the data
            unchanged, as all three do without constraint data.
        margin : int, optional
            With ``exclude``: samples also dropped on each side of an active one. Default 0
            when velocities and accelerations are given, 10 when the fit differentiates.
        min_length : int, optional
            With ``exclude``: shortest run kept. Default 5 with derivatives, 25 without.

        Returns
        -------
        dict
            Keys ``x``, ``t``, ``x_dot``, ``x_ddot``, ``u``; a missing series gives None.

        Examples
        --------
        A sample where a constraint acts is left out, the trajectory split around it:

        >>> import numpy as np
        >>> t = np.linspace(0, 1, 11)
        >>> active = np.zeros(11, dtype=bool); active[5] = True
        >>> data = Dataset([Trajectory(t, np.sin(t), qd=np.cos(t), qdd=-np.sin(t),
        ...                            constraint_active=active)], ["theta"])
        >>> [x.shape[0] for x in data.fit_arguments(forces=None)["x"]]
        [5, 5]
        """
        from .constraints import contiguous_segments, unconstrained_samples
        if forces not in ("tau", "u", None):
            raise ValueError(f"forces: expected 'tau', 'u' or None, got {forces!r}")
        if constraints not in CONSTRAINT_HANDLING:
            raise ValueError(
                f"constraints: expected one of {CONSTRAINT_HANDLING}, got {constraints!r}"
            )
        if forces is not None and not self.has(forces):
            raise DatasetError(f"forces: the dataset has no {forces!r} array")
        trs = self.trajectories
        derivatives = self.has("qd") and self.has("qdd")
        force_lists = [getattr(tr, forces) for tr in trs] if forces else None
        if constraints == "known" and self.has("tau_constraint"):
            key = "u_constraint" if forces == "u" else "tau_constraint"
            extra = [getattr(tr, key) for tr in trs]
            force_lists = extra if force_lists is None else [
                f + c for f, c in zip(force_lists, extra, strict=True)]
        arguments = {"x": [tr.q for tr in trs],
                     "t": [tr.t for tr in trs],
                     "x_dot": [tr.qd for tr in trs] if self.has("qd") else None,
                     "x_ddot": [tr.qdd for tr in trs] if self.has("qdd") else None,
                     "u": force_lists}
        if constraints != "exclude" or not self.has("constraint_active") or not any(
                tr.constraint_active.any() for tr in trs):
            return arguments
        margin = (0 if derivatives else 10) if margin is None else margin
        min_length = (5 if derivatives else 25) if min_length is None else min_length
        out = {key: ([] if value is not None else None) for key, value in arguments.items()}
        for k, tr in enumerate(trs):
            keep = unconstrained_samples(tr.constraint_active, margin)
            for part in contiguous_segments(keep, min_length):
                for key, value in arguments.items():
                    if value is not None:
                        out[key].append(value[k][part])
        if not out["x"]:
            raise ValueError("constraints: every sample is constrained (limits, contacts or "
                             "equality constraints act throughout); lower the forcing amplitude or "
                             "the initial spread, or use constraints='known'")
        return out

    def constraint_summary(self) -> dict:
        """How much of the data a constraint touches: a dict of ``active_fraction`` (0 without
        constraint data), ``unconstrained_samples``, ``limit_hits`` (``{joint: samples}``, from
        the trajectories' ``info``), ``contact_samples``, ``equality_samples``.

        Returns
        -------
        dict
            ``active_fraction``, ``unconstrained_samples``, ``limit_hits``, ``contact_samples`` and
            ``equality_samples``.

        Examples
        --------
        >>> import numpy as np
        >>> t = np.linspace(0, 1, 4)
        >>> tr = Trajectory(t, np.sin(t), constraint_active=[0, 1, 1, 0],
        ...                 info={"limit_hits": {"slider": 2}})
        >>> Dataset([tr], ["x"]).constraint_summary()["active_fraction"]
        0.5
        """
        n_samples = sum(tr.n_samples for tr in self.trajectories)
        active = (int(sum(int(tr.constraint_active.sum()) for tr in self.trajectories))
                  if self.has("constraint_active") else 0)
        hits: dict = {}
        contacts = equality = 0
        for tr in self.trajectories:
            for joint, count in tr.info.get("limit_hits", {}).items():
                hits[joint] = hits.get(joint, 0) + int(count)
            contacts += int(tr.info.get("contact_samples", 0))
            equality += int(tr.info.get("equality_samples", 0))
        return {"active_fraction": active / n_samples,
                "unconstrained_samples": n_samples - active,
                "limit_hits": hits, "contact_samples": contacts, "equality_samples": equality}

    def to_arrays(self) -> dict:
        """The NPZ arrays of the module docstring: trajectories concatenated, with ids and metadata.

        Returns
        -------
        dict of str to numpy.ndarray
            ``t``, ``q``... concatenated, ``trajectory`` ids and the JSON ``metadata``.

        Examples
        --------
        >>> import numpy as np
        >>> t = np.linspace(0, 1, 11)
        >>> trajectory = Trajectory(t, np.sin(t))
        >>> arrays = Dataset([trajectory, trajectory], ["theta"]).to_arrays()
        >>> sorted(arrays), arrays["q"].shape, arrays["trajectory"][[0, -1]]
        (['metadata', 'q', 't', 'trajectory'], (22, 1), array([0, 1]))
        """
        trs = self.trajectories
        arrays = {
            "t": np.concatenate([tr.t for tr in trs]),
            "trajectory": np.concatenate(
                [np.full(tr.n_samples, k, dtype=np.int64) for k, tr in enumerate(trs)]
            ),
        }
        for key in SERIES + MASKS:
            if self.has(key):
                arrays[key] = np.concatenate([getattr(tr, key) for tr in trs])
        meta = dict(self.metadata, format=FORMAT, version=VERSION,
                    coordinate_names=list(self.coordinate_names),
                    trajectory_info=[tr.info for tr in trs])
        arrays["metadata"] = np.array(json.dumps(meta))
        return arrays

    def save(self, path, write_json: bool = True):
        """Write ``path`` (``.npz`` appended when missing) and return it; ``write_json`` also
        writes the metadata to the same name with ``.json`` (they are inside the NPZ anyway).

        Parameters
        ----------
        path : str or os.PathLike
            The file (``.npz`` appended when missing).
        write_json : bool, default=True
            Also write the metadata beside it, with ``.json``.

        Returns
        -------
        pathlib.Path
            The NPZ file written.

        Examples
        --------
        >>> import tempfile, pathlib, numpy as np
        >>> t = np.linspace(0, 1, 11)
        >>> data = Dataset([Trajectory(t, np.sin(t))], ["theta"], {"system": "pendulum"})
        >>> with tempfile.TemporaryDirectory() as tmp:
        ...     path = data.save(pathlib.Path(tmp) / "pendulum")
        ...     copy = Dataset.load(path)
        ...     print(path.name, path.with_suffix(".json").exists())
        pendulum.npz True
        >>> copy.metadata, bool(np.array_equal(copy.trajectories[0].q, data.trajectories[0].q))
        ({'system': 'pendulum'}, True)
        """
        import pathlib
        path = pathlib.Path(path)
        if path.suffix != ".npz":
            path = path.with_name(path.name + ".npz")
        arrays = self.to_arrays()
        np.savez_compressed(path, **arrays)
        if write_json:
            meta = json.loads(str(arrays["metadata"]))
            path.with_suffix(".json").write_text(json.dumps(meta, indent=2) + "\n")
        return path

    @classmethod
    def load(cls, path) -> Dataset:
        """Read a dataset written by :meth:`save` or a user's NPZ: :func:`load_dataset`.

        Parameters
        ----------
        path : str or os.PathLike
            The NPZ file.

        Returns
        -------
        Dataset
            The dataset (see :func:`load_dataset`).
        """
        return load_dataset(path)

    def __repr__(self) -> str:
        n_samples = sum(tr.n_samples for tr in self.trajectories)
        return (f"Dataset(coordinates={list(self.coordinate_names)}, "
                f"trajectories={self.n_trajectories}, samples={n_samples})")


def load_dataset(path) -> Dataset:
    """Read a dataset NPZ (with embedded or side-car JSON metadata, or none).

    ``path`` holds at least ``t`` (N,) and ``q`` (N, n) (the module docstring lists the
    arrays); a :class:`DatasetError` names a missing or malformed array.

    Parameters
    ----------
    path : str or os.PathLike
        The NPZ file.

    Returns
    -------
    Dataset
        The trajectories, coordinate names and metadata of the file.

    Raises
    ------
    DatasetError
        When the file is missing, not an NPZ, or an array is missing or malformed.

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
    """
    path = os.fspath(path)
    arrays, metadata, names, bounds = read_dataset_arrays(path)
    t = np.asarray(arrays["t"], dtype=float)
    infos = metadata.pop("trajectory_info", None)
    trajectories = []
    ids = arrays["trajectory"]
    for k, (a, b) in enumerate(bounds):
        series = {key: arrays[key][a:b] for key in SERIES + MASKS if key in arrays}
        info = infos[k] if isinstance(infos, list) and len(infos) == len(bounds) else {}
        try:
            trajectories.append(Trajectory(t=t[a:b], info=info, **series))
        except DatasetError as error:
            raise DatasetError(f"{error} (trajectory {ids[a]} of {path!r})") from None
    for key in ("format", "version", "coordinate_names"):
        metadata.pop(key, None)
    return Dataset(trajectories, names, metadata)


