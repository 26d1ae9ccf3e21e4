"""ROS bags of sensor_msgs/JointState: written with rosbags' own writers, read back."""

from __future__ import annotations

import numpy as np
import pytest

rosbags = pytest.importorskip("rosbags")

from rosbags.typesys import Stores, get_typestore  # noqa: E402

from pysindy_xl.data import DatasetError, load_data, read_rosbag  # noqa: E402
from pysindy_xl.data.rosbag import JOINT_STATE  # noqa: E402

JOINTS = ["shoulder", "elbow", "wrist"]


def _states(n=200, seed=0, repeat=None):
    """Stamps (ns, jittered, one gap), positions, velocities, efforts of three joints."""
    rng = np.random.default_rng(seed)
    steps = np.full(n - 1, 1_000_000) + rng.integers(-200_000, 200_000, n - 1)
    steps[50] = 8_800_000  # a gap of 8.8 ms
    if repeat is not None:
        steps[repeat] = 0
    stamps = 1_700_000_000 * 10**9 + 123 + np.r_[0, np.cumsum(steps)]
    t = (stamps - stamps[0]) * 1e-9
    q = np.column_stack([np.sin(t + k) for k in range(3)])
    qd = np.column_stack([np.cos(t + k) for k in range(3)])
    tau = np.column_stack([10 * np.sin(2 * t + k) for k in range(3)])
    return stamps, q, qd, tau


def _write(path, version, stamps, q, qd, tau, extra_topic=False, gripper=False, shuffle=True,
           velocity=True):
    """A bag with the joints in a changing order (and a gripper group on the same topic)."""
    if version == 1:
        from rosbags.rosbag1 import Writer

        store = get_typestore(Stores.ROS1_NOETIC)
        writer, serialize = Writer(path), store.serialize_ros1
    else:
        from rosbags.rosbag2 import Writer

        store = get_typestore(Stores.ROS2_HUMBLE)
        writer, serialize = Writer(path, version=9), store.serialize_cdr
    State, Header = store.types[JOINT_STATE], store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]

    def header(ns):
        if version == 1:
            return Header(seq=0, stamp=Time(sec=int(ns // 10**9), nanosec=int(ns % 10**9)),
                          frame_id="")
        return Header(stamp=Time(sec=int(ns // 10**9), nanosec=int(ns % 10**9)), frame_id="")

    with writer:
        topic = writer.add_connection("/joint_states", JOINT_STATE, typestore=store)
        other = (writer.add_connection("/other/joint_states", JOINT_STATE, typestore=store)
                 if extra_topic else None)
        for k, ns in enumerate(stamps):
            order = np.roll(np.arange(3), k % 3) if shuffle else np.arange(3)
            msg = State(header(ns), [JOINTS[j] for j in order], q[k, order],
                        qd[k, order] if velocity else np.array([]), tau[k, order])
            writer.write(topic, int(ns) + 50_000, serialize(msg, JOINT_STATE))
            if gripper and k % 10 == 0:
                finger = State(header(ns), ["finger"], np.array([0.01]), np.array([]),
                               np.array([]))
                writer.write(topic, int(ns) + 60_000, serialize(finger, JOINT_STATE))
            if other is not None and k % 20 == 0:
                writer.write(other, int(ns) + 70_000, serialize(msg, JOINT_STATE))
    return path


@pytest.mark.parametrize("version", [1, 2])
def test_a_bag_reads_back_as_recorded(tmp_path, version):
    stamps, q, qd, tau = _states()
    path = _write(tmp_path / ("run.bag" if version == 1 else "run"), version, stamps, q, qd,
                  tau, gripper=True)
    data = read_rosbag(path, coordinates=["elbow", "shoulder", "wrist"])
    assert data.coordinate_names == ("elbow", "shoulder", "wrist")
    (run,) = data.trajectories
    order = [1, 0, 2]
    # stamps as recorded: jitter and the gap kept, to the nanosecond
    np.testing.assert_allclose(run.t, (stamps - stamps[0]) * 1e-9, rtol=0, atol=1e-15)
    assert np.diff(run.t).max() == pytest.approx(8.8e-3)
    np.testing.assert_array_equal(run.q, q[:, order])
    np.testing.assert_array_equal(run.qd, qd[:, order])
    np.testing.assert_array_equal(run.tau, tau[:, order])
    assert run.qdd is None
    assert run.info == {"bag": path.name, "t0_ns": int(stamps[0]), "stamps": "header.stamp",
                        "skipped_messages": 20}
    assert data.metadata["topic"] == "/joint_states"
    assert data.metadata["joints"] == {"elbow": "elbow", "shoulder": "shoulder",
                                       "wrist": "wrist"}
    # load_data takes bags like any data file
    same = load_data(path, coordinates=["elbow", "shoulder", "wrist"])
    np.testing.assert_array_equal(same.trajectories[0].q, run.q)


def test_several_bags_are_several_runs_with_renamed_coordinates(tmp_path):
    paths = []
    for seed in range(2):
        stamps, q, qd, tau = _states(100 + 20 * seed, seed)
        paths.append(_write(tmp_path / f"run{seed}.bag", 1, stamps, q, qd, tau, shuffle=False,
                            velocity=False))
    data = read_rosbag(paths, coordinates=["a", "b"], columns={"a": "wrist", "b": "shoulder"})
    assert [tr.n_samples for tr in data.trajectories] == [100, 120]
    assert not data.has("qd") and data.has("tau")
    _, q, _, _ = _states(120, 1)
    np.testing.assert_array_equal(data.trajectories[1].q, q[:, [2, 0]])
    # default: every joint of the first message, in its order
    assert read_rosbag(paths[0]).coordinate_names == tuple(JOINTS)


def test_bad_bags_are_refused_naming_the_bag(tmp_path):
    stamps, q, qd, tau = _states(60, repeat=10)
    path = _write(tmp_path / "repeat.bag", 1, stamps, q, qd, tau)
    with pytest.raises(DatasetError, match=r"repeat\.bag.*message 11.*strictly increasing"):
        read_rosbag(path)
    stamps, q, qd, tau = _states(60)
    two = _write(tmp_path / "two.bag", 1, stamps, q, qd, tau, extra_topic=True)
    with pytest.raises(DatasetError, match="2 sensor_msgs/JointState topics"):
        read_rosbag(two)
    assert read_rosbag(two, topic="/other/joint_states").trajectories[0].n_samples == 3
    with pytest.raises(DatasetError, match="no sensor_msgs/JointState topic '/nope'"):
        read_rosbag(two, topic="/nope")
    path = _write(tmp_path / "one.bag", 1, stamps, q, qd, tau)
    with pytest.raises(DatasetError, match="carry every joint"):
        read_rosbag(path, coordinates=["shoulder", "knee"])
    with pytest.raises(DatasetError, match="does not exist"):
        read_rosbag(tmp_path / "absent.bag")
    (tmp_path / "junk.bag").write_bytes(b"not a bag")
    with pytest.raises(DatasetError, match="not a readable ROS bag"):
        read_rosbag(tmp_path / "junk.bag")
    with pytest.raises(ValueError, match="topic"):
        load_data(tmp_path / "x.csv", topic="/joint_states")


def test_identify_reads_a_bag_with_the_urdf_joints(tmp_path, capsys):
    """A bag whose joints come in another order than the URDF's: the CLI maps them."""
    pytest.importorskip("mujoco")
    from support.files import TWO_LINK_URDF

    from pysindy_xl.cli import main
    from pysindy_xl.mujoco import MJCFSystem, generate_dataset

    urdf = tmp_path / "arm.urdf"
    urdf.write_text(TWO_LINK_URDF)
    data = generate_dataset(MJCFSystem(urdf), n_trajectories=2, duration=2.0, seed=1,
                            sample_every=4, derivatives=True, progress=False)
    bags = []
    for k, run in enumerate(data.trajectories):
        stamps = (10**9 * 5 + np.round(run.t * 1e9)).astype(np.int64)
        q = np.column_stack([run.q[:, ::-1], np.zeros(run.n_samples)])  # elbow, shoulder, _
        qd = np.column_stack([run.qd[:, ::-1], np.zeros(run.n_samples)])
        tau = np.column_stack([run.tau[:, ::-1], np.zeros(run.n_samples)])
        bags.append(_write_named(tmp_path / f"run{k}.bag", stamps, q, qd, tau))
    # a light toy arm under random torques: accelerations up to 9 Hz, above the 10 Hz bound
    # of the scoring derivatives' default (made for real arms)
    assert main(["identify", str(bags[0]), "--system", str(urdf), "--validate",
                 str(bags[1]), "--bandwidth", "40", "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "held-out torque prediction on run1.bag (1 run" in text
    assert "derivatives: measured velocities, accelerations from a quintic smoothing " \
           "spline" in text and "at most 40 Hz" in text  # bags carry no accelerations
    total = float(text.split("all coordinates: ")[1].split(" %")[0])
    assert total < 10.0  # joints swapped or misread would be off by 100 % or more


def _write_named(path, stamps, q, qd, tau):
    """A ROS 1 bag of joints elbow, shoulder and an unrelated 'gripper' joint."""
    from rosbags.rosbag1 import Writer

    store = get_typestore(Stores.ROS1_NOETIC)
    State, Header = store.types[JOINT_STATE], store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    with Writer(path) as writer:
        topic = writer.add_connection("/joint_states", JOINT_STATE, typestore=store)
        for k, ns in enumerate(stamps):
            msg = State(Header(seq=k, stamp=Time(sec=int(ns // 10**9),
                                                 nanosec=int(ns % 10**9)), frame_id=""),
                        ["elbow", "shoulder", "gripper"], q[k], qd[k], tau[k])
            writer.write(topic, int(ns), store.serialize_ros1(msg, JOINT_STATE))
    return path
