"""ROS bags of ``sensor_msgs/JointState`` into a :class:`~pysindy_xl.data.Dataset`.

:func:`read_rosbag` reads ROS 1 bags (``.bag``) and ROS 2 bags (the directory, or its
``.db3`` / ``.mcap`` file) through the pure-Python ``rosbags`` package
(``pip install pysindy-xl[ros]``), one bag per run: ``header.stamp`` gives ``t`` (seconds from
the run's first stamp, as recorded; the receive times when no message has a stamp),
``position`` ``q``, ``velocity`` ``qd`` and ``effort`` ``tau`` (each when every message
carries it). As for a CSV file, ``coordinates`` names the coordinates in order and ``columns``
maps one to its joint; messages without every chosen joint are skipped and counted in the
trajectory's ``info``.
"""

from __future__ import annotations

import os
import re

import numpy as np

from .._optional import import_optional
from .files import DatasetError, coordinate_names

__all__ = ["read_rosbag", "is_rosbag", "JOINT_STATE"]

JOINT_STATE = "sensor_msgs/msg/JointState"
_BAG_SUFFIXES = (".bag", ".db3", ".mcap")


def is_rosbag(path) -> bool:
    """Whether ``path`` names a ROS bag: a ``.bag``, ``.db3`` or ``.mcap`` file, or a ROS 2 bag
    directory (with its ``metadata.yaml``).

    Parameters
    ----------
    path : str or os.PathLike
        A file or directory.

    Returns
    -------
    bool
        True for a ``.bag``, ``.db3`` or ``.mcap`` file or a ROS 2 bag directory.

    Examples
    --------
    >>> is_rosbag("run1.bag"), is_rosbag("log.csv")
    (True, False)
    """
    path = os.fspath(path)
    if os.path.isdir(path):
        return os.path.isfile(os.path.join(path, "metadata.yaml"))
    return path.lower().endswith(_BAG_SUFFIXES)


def _bag_path(path: str):
    """What ``rosbags`` opens: a ROS 1 file, or the directory of a ROS 2 bag."""
    import pathlib
    if not os.path.exists(path):
        raise DatasetError(f"path: ROS bag {path!r} does not exist")
    if path.lower().endswith((".db3", ".mcap")) and os.path.isfile(path):
        parent = os.path.dirname(os.path.abspath(path))
        if os.path.isfile(os.path.join(parent, "metadata.yaml")):
            return pathlib.Path(parent)
    return pathlib.Path(path)


def _default_names(joints) -> list:
    """Coordinate names for joint names: symbols need identifiers."""
    names = [re.sub(r"\W", "_", joint) or "q" for joint in joints]
    return [f"q_{name}" if name[0].isdigit() else name for name in names]


def _messages(path: str, topic):
    """``(stamp_ns, log_ns, names, position, velocity, effort)`` of every JointState message
    of one bag, and the topic read."""
    highlevel = import_optional("rosbags.highlevel", purpose="reading ROS bags", extra="ros")
    typesys = import_optional("rosbags.typesys", purpose="reading ROS bags", extra="ros")
    store = typesys.get_typestore(typesys.Stores.LATEST)
    try:
        reader = highlevel.AnyReader([_bag_path(path)], default_typestore=store)
        reader.open()
    except Exception as error:  # rosbags raises its own errors for unreadable bags
        if isinstance(error, DatasetError):
            raise
        raise DatasetError(f"path: {path!r} is not a readable ROS bag ({error})") from None
    try:
        states = sorted({c.topic for c in reader.connections if c.msgtype == JOINT_STATE})
        if topic is None:
            if len(states) != 1:
                raise DatasetError(f"topic: {path!r} has {len(states)} sensor_msgs/JointState "
                                   f"topics {states}; name one (topic=..., --topic)")
            topic = states[0]
        elif topic not in states:
            raise DatasetError(f"topic: {path!r} has no sensor_msgs/JointState topic {topic!r}; it "
                               f"has {states}")
        connections = [c for c in reader.connections if c.topic == topic]
        rows = []
        for connection, log_ns, raw in reader.messages(connections=connections):
            msg = reader.deserialize(raw, connection.msgtype)
            stamp = msg.header.stamp
            rows.append((int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec), int(log_ns),
                         tuple(msg.name), msg.position, msg.velocity, msg.effort))
    finally:
        reader.close()
    if not rows:
        raise DatasetError(f"topic: {path!r} has no message on {topic!r}")
    return rows, topic


def _run(path, rows, joints):
    """One trajectory's arrays from the messages of one bag."""
    from .dataset import Trajectory
    index_of: dict = {}
    kept, skipped = [], 0
    for row in rows:
        names = row[2]
        if names not in index_of:
            lookup = {name: k for k, name in enumerate(names)}
            index_of[names] = (np.array([lookup[j] for j in joints])
                               if all(j in lookup for j in joints) else None)
        if index_of[names] is None:
            skipped += 1
            continue
        kept.append(row)
    if len(kept) < 2:
        raise DatasetError(f"{path!r}: {len(kept)} message(s) carry every joint of {joints}; a run "
                           "needs at least 2")
    stamps = np.array([row[0] for row in kept], dtype=np.int64)
    source = "header.stamp"
    if not stamps.any():
        stamps, source = np.array([row[1] for row in kept], dtype=np.int64), "bag receive time"
    t = (stamps - stamps[0]) * 1e-9
    steps = np.diff(t)
    if np.any(steps <= 0):
        k = int(np.flatnonzero(steps <= 0)[0]) + 1
        raise DatasetError(f"{path!r}: message {k} is stamped {t[k]:.9g} s after the run's start, "
                           f"not after the message before it ({t[k - 1]:.9g} s); times must be "
                           "strictly increasing (stamps as recorded by the driver)")
    series = {}
    for key, field in (("q", 3), ("qd", 4), ("tau", 5)):
        if all(len(row[field]) == len(row[2]) for row in kept):
            series[key] = np.array([np.asarray(row[field], dtype=float)[index_of[row[2]]]
                                    for row in kept])
        elif key == "q":
            raise DatasetError(f"{path!r}: some messages have no position for every joint")
    info = {"bag": os.path.basename(os.path.normpath(path)), "t0_ns": int(stamps[0]),
            "stamps": source, "skipped_messages": skipped}
    return Trajectory(t=t, info=info, **series)


def read_rosbag(paths, coordinates=None, columns=None, topic=None):
    """Read ROS bags of ``sensor_msgs/JointState`` into a :class:`Dataset`, one run per bag.

    Parameters
    ----------
    paths : str, os.PathLike or list of them
        ROS 1 ``.bag`` files, ROS 2 bag directories (or their ``.db3`` / ``.mcap`` file).
    coordinates : list of str or str, optional
        Coordinate names, in order. Default: the joints of the first message, in its order.
    columns : dict of str to str, optional
        ``{coordinate: joint name}`` for coordinates named differently from their joint.
    topic : str, optional
        The JointState topic; default the bag's only one.

    Returns
    -------
    Dataset
        ``metadata`` records the bags, the topic and each coordinate's joint; each
        trajectory's ``info`` its bag, first stamp (``t0_ns``), time source, skipped messages.

    Examples
    --------
    A ROS 2 bag with two joints, written with rosbags' writer:

    >>> import pathlib, tempfile
    >>> from rosbags.rosbag2 import Writer
    >>> from rosbags.typesys import Stores, get_typestore
    >>> store = get_typestore(Stores.ROS2_HUMBLE)
    >>> State, Header = store.types[JOINT_STATE], store.types["std_msgs/msg/Header"]
    >>> Time = store.types["builtin_interfaces/msg/Time"]
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     bag = pathlib.Path(tmp) / "run"
    ...     with Writer(bag, version=9) as writer:
    ...         topic = writer.add_connection("/joint_states", JOINT_STATE, typestore=store)
    ...         for k in range(5):
    ...             msg = State(Header(Time(sec=7, nanosec=1_000_000 * k), ""),
    ...                         ["elbow", "shoulder"], np.array([0.1 * k, -0.1 * k]),
    ...                         np.array([]), np.array([1.0, 2.0]))
    ...             writer.write(topic, 10**9 + k, store.serialize_cdr(msg, JOINT_STATE))
    ...     data = read_rosbag(bag, coordinates=["shoulder", "elbow"])
    >>> data, data.trajectories[0].t.round(4).tolist(), data.has("qd")
    (Dataset(coordinates=['shoulder', 'elbow'], trajectories=1, samples=5), \
[0.0, 0.001, 0.002, 0.003, 0.004], False)
    >>> data.trajectories[0].tau[0].tolist()
    [2.0, 1.0]
    """
    from .dataset import Dataset
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    try:
        paths = [os.fspath(p) for p in paths]
    except TypeError:
        raise TypeError(f"paths: expected a bag path or a list of them, got {paths!r}") from None
    if not paths:
        raise ValueError("paths: expected at least one bag")
    columns = dict(columns or {})
    for key, value in columns.items():
        if not isinstance(key, str) or not isinstance(value, str):
            raise TypeError("columns: expected a mapping of coordinate name to joint name")
    runs, names, joints, read_topic = [], None, None, None
    for path in paths:
        rows, read_topic = _messages(path, topic)
        if names is None:
            names = (coordinate_names(coordinates) if coordinates is not None
                     else _default_names(rows[0][2]))
            default = dict(zip(names, rows[0][2], strict=False)) if coordinates is None else {}
            joints = [columns.get(name, default.get(name, name)) for name in names]
            from ..symbols import Coordinates
            Coordinates(names)
        runs.append(_run(path, rows, joints))
    metadata = {"source": [os.path.basename(os.path.normpath(p)) for p in paths],
                "format": "ROS bag, sensor_msgs/JointState", "topic": read_topic,
                "joints": dict(zip(names, joints, strict=True))}
    return Dataset(runs, names, metadata)
