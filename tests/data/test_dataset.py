"""Dataset persistence: NPZ + JSON, no pickle, clear errors on bad files."""

import json

import numpy as np
import pytest

from pysindy_xl.data import DatasetError
from pysindy_xl.mujoco import Dataset, Trajectory, generate_dataset, load_dataset


@pytest.fixture(scope="module")
def dataset():
    return generate_dataset("double-pendulum", n_trajectories=2, duration=0.3, forcing="mixed",
                            noise=0.01, noise_model="all", seed=4, progress=False)


def test_round_trip(dataset, tmp_path):
    path = dataset.save(tmp_path / "data")
    assert path.name == "data.npz"
    meta = json.loads((tmp_path / "data.json").read_text())
    assert meta["system"] == "double-pendulum" and meta["forcing"] == "mixed"
    assert meta["coordinate_names"] == ["theta1", "theta2"]
    loaded = load_dataset(path)
    assert loaded.coordinate_names == dataset.coordinate_names
    assert loaded.n_trajectories == 2
    assert loaded.metadata["seed"] == 4
    assert loaded.metadata["noise"] == dataset.metadata["noise"]
    for a, b in zip(loaded.trajectories, dataset.trajectories, strict=True):
        for key in ("t", "q", "qd", "qdd", "tau", "u", "tau_constraint", "constraint_active"):
            np.testing.assert_array_equal(getattr(a, key), getattr(b, key))
        assert a.info == b.info
    # only plain arrays in the file: readable without pickle
    with np.load(path, allow_pickle=False) as npz:
        assert set(npz.files) == {"t", "trajectory", "q", "qd", "qdd", "tau", "u", "metadata",
                                  "tau_constraint", "u_constraint", "constraint_active"}
        assert npz["constraint_active"].dtype == bool


def test_fit_arguments(dataset):
    args = dataset.fit_arguments()
    assert len(args["x"]) == 2 and args["u"][0] is dataset.trajectories[0].tau
    assert dataset.fit_arguments(forces=None)["u"] is None
    assert dataset.fit_arguments(forces="u")["u"][1] is dataset.trajectories[1].u
    with pytest.raises(ValueError, match="forces"):
        dataset.fit_arguments(forces="torque")


def test_user_npz_with_only_times_and_positions(tmp_path):
    t = np.linspace(0, 1, 50)
    path = tmp_path / "user.npz"
    np.savez(path, t=np.r_[t, t], q=np.c_[np.r_[t, t], np.r_[t, t] ** 2],
             trajectory=np.r_[np.zeros(50, int), np.ones(50, int)])
    data = load_dataset(path)
    assert data.coordinate_names == ("q0", "q1")
    assert data.n_trajectories == 2 and not data.has("qd")
    assert data.fit_arguments(forces=None)["x_dot"] is None


def test_bad_files(tmp_path):
    with pytest.raises(DatasetError, match="does not exist"):
        load_dataset(tmp_path / "nothing.npz")
    garbage = tmp_path / "garbage.npz"
    garbage.write_bytes(b"this is not a zip file")
    with pytest.raises(DatasetError, match="not a readable NPZ"):
        load_dataset(garbage)
    missing = tmp_path / "missing.npz"
    np.savez(missing, t=np.arange(3.0))
    with pytest.raises(DatasetError, match=r"required array\(s\) \['q'\]"):
        load_dataset(missing)
    pickled = tmp_path / "pickled.npz"
    np.savez(pickled, t=np.arange(3.0), q=np.array([{}, {}, {}], dtype=object))
    with pytest.raises(DatasetError, match="pickle"):
        load_dataset(pickled)
    shapes = tmp_path / "shapes.npz"
    np.savez(shapes, t=np.arange(3.0), q=np.zeros((3, 2)), qd=np.zeros((4, 2)))
    with pytest.raises(DatasetError, match="qd: expected shape"):
        load_dataset(shapes)
    nan = tmp_path / "nan.npz"
    np.savez(nan, t=np.arange(3.0), q=np.array([0.0, np.nan, 1.0]))
    with pytest.raises(DatasetError, match="NaN"):
        load_dataset(nan)
    backwards = tmp_path / "backwards.npz"
    np.savez(backwards, t=np.array([0.0, 2.0, 1.0]), q=np.zeros(3))
    with pytest.raises(DatasetError, match="increasing"):
        load_dataset(backwards)
    meta = tmp_path / "meta.npz"
    np.savez(meta, t=np.arange(3.0), q=np.zeros(3), metadata=np.array("{not json"))
    with pytest.raises(DatasetError, match="invalid JSON"):
        load_dataset(meta)
    interleaved = tmp_path / "interleaved.npz"
    np.savez(interleaved, t=np.array([0.0, 0.0, 1.0, 1.0]), q=np.zeros(4),
             trajectory=np.array([0, 1, 0, 1]))
    with pytest.raises(DatasetError, match="contiguous"):
        load_dataset(interleaved)


def test_dataset_checks_its_input():
    t = np.linspace(0, 1, 5)
    with pytest.raises(DatasetError, match="coordinate_names"):
        Dataset([Trajectory(t, np.zeros((5, 2)))], ["a"])
    with pytest.raises(TypeError, match="metadata"):
        Dataset([Trajectory(t, np.zeros((5, 1)))], ["a"], metadata={"x": object()})
    with pytest.raises(TypeError, match="trajectories"):
        Dataset([], ["a"])
