"""Reading the user's own data: CSV, DataFrame, NPZ; one test per mistake a user makes."""

import numpy as np
import pytest
from support.files import pendulum, write_csv

from pysindy_xl.data import DatasetError, from_columns, from_dataframe, load_data, read_csv
from pysindy_xl.mujoco import coordinate_system


def test_csv_with_header(tmp_path):
    t, q, qd, qdd, tau = pendulum()
    path = write_csv(tmp_path / "p.csv", ["t", "theta", "theta_dot", "theta_ddot", "tau_theta"],
                     [t, q, qd, qdd, tau])
    data = read_csv(path)
    assert data.coordinate_names == ("theta",) and data.n_trajectories == 1
    tr = data.trajectories[0]
    np.testing.assert_array_equal(tr.t, t)
    np.testing.assert_array_equal(tr.q[:, 0], q)
    np.testing.assert_array_equal(tr.qd[:, 0], qd)
    np.testing.assert_array_equal(tr.qdd[:, 0], qdd)
    np.testing.assert_array_equal(tr.tau[:, 0], tau)


def test_csv_with_column_map_and_float_ids(tmp_path):
    t, q, _, _, tau = pendulum()
    t2, q2, _, _, tau2 = pendulum(phase=0.5)
    ids = np.r_[np.full(len(t), 1.0), np.full(len(t2), 2.5)]
    path = write_csv(tmp_path / "mine.csv", ["time_s", "angle", "torque", "run"],
                     [np.r_[t, t2], np.r_[q, q2], np.r_[tau, tau2], ids])
    data = read_csv(path, coordinates=["theta"],
                    columns={"t": "time_s", "theta": "angle", "tau_theta": "torque",
                             "trajectory": "run"})
    assert data.n_trajectories == 2 and data.coordinate_names == ("theta",)
    assert [tr.info["id"] for tr in data.trajectories] == [1.0, 2.5]
    np.testing.assert_array_equal(data.trajectories[1].q[:, 0], q2)
    np.testing.assert_array_equal(data.trajectories[1].tau[:, 0], tau2)
    assert not data.has("qd")
    assert data.metadata["columns"]["trajectory"] == "run"


def test_several_trajectories_with_label_ids_and_partial_forces(tmp_path):
    """Ids may be labels; a coordinate without a tau_ column is unactuated (zero force)."""
    t = np.linspace(0, 1, 5)
    text = "t,x,theta,tau_x,trajectory\n" + "".join(
        f"{ti},{ti},{2 * ti},{3 * ti},{label}\n" for label in ("a", "b") for ti in t)
    path = tmp_path / "two.csv"
    path.write_text(text)
    data = read_csv(path)
    assert data.coordinate_names == ("x", "theta") and data.n_trajectories == 2
    np.testing.assert_array_equal(data.trajectories[1].tau, np.c_[3 * t, np.zeros(5)])


def test_tsv_and_semicolon_with_delimiter(tmp_path):
    t, q, *_ = pendulum(11)
    tsv = write_csv(tmp_path / "p.tsv", ["t", "theta"], [t, q], delimiter="\t")
    np.testing.assert_array_equal(load_data(tsv).trajectories[0].q[:, 0], q)
    semi = write_csv(tmp_path / "p.csv", ["t", "theta"], [t, q], delimiter=";")
    np.testing.assert_array_equal(read_csv(semi, delimiter=";").trajectories[0].q[:, 0], q)


def test_npz_float_ids_and_renamed_coordinates(tmp_path):
    t, q, *_ = pendulum(20)
    path = tmp_path / "d.npz"
    np.savez(path, t=np.r_[t, t], q=np.r_[q, q], trajectory=np.r_[[0.5] * 20, [7.0] * 20])
    data = load_data(path, coordinates="theta")
    assert data.coordinate_names == ("theta",) and data.n_trajectories == 2
    with pytest.raises(DatasetError, match=r"coordinates: 2 names \['x', 'y'\] for the 1"):
        load_data(path, coordinates="x,y")
    with pytest.raises(ValueError, match="columns: a column mapping applies to tables"):
        load_data(path, columns={"t": "time"})


# -- mistakes -----------------------------------------------------------------------------------
def test_missing_column_names_file_and_column(tmp_path):
    t, q, *_ = pendulum(11)
    path = write_csv(tmp_path / "p.csv", ["t", "theta"], [t, q])
    with pytest.raises(DatasetError, match=r"p\.csv'.*column 'x' \(position of coordinate 'x'\)"):
        read_csv(path, coordinates=["x", "theta"])
    with pytest.raises(DatasetError, match=r"p\.csv': column 'force' \(mapped from 'tau_theta'\)"):
        read_csv(path, columns={"tau_theta": "force"})
    nott = write_csv(tmp_path / "q.csv", ["seconds", "theta"], [t, q])
    with pytest.raises(DatasetError, match=r"q\.csv': no time column 't'"):
        read_csv(nott)
    part = write_csv(tmp_path / "r.csv", ["t", "x", "y", "x_dot"], [t, q, q, q])
    with pytest.raises(DatasetError, match=r"r\.csv': column\(s\) \['y_dot'\] missing"):
        read_csv(part)


def test_wrong_delimiter(tmp_path):
    t, q, *_ = pendulum(11)
    path = write_csv(tmp_path / "p.csv", ["t", "theta"], [t, q], delimiter=";")
    with pytest.raises(DatasetError, match=r"p\.csv': the header has a single column 't;theta'"
                                           r".*seems to use ';'"):
        read_csv(path)
    ragged = tmp_path / "ragged.csv"
    ragged.write_text("t,theta\n0,1\n0.1,2,3\n")
    with pytest.raises(DatasetError, match=r"ragged\.csv', line 3: 3 fields, the header has 2"):
        read_csv(ragged)


@pytest.mark.parametrize("cell, what", [("abc", "'abc' is not a number"),
                                        ("", "an empty cell is not a number"),
                                        ("nan", "NaN or inf")])
def test_non_numeric_cell(tmp_path, cell, what):
    path = tmp_path / "p.csv"
    path.write_text(f"t,theta\n0.0,0.1\n0.1,{cell}\n0.2,0.3\n")
    with pytest.raises(DatasetError, match=rf"p\.csv', column 'theta', line 3: {what}"):
        read_csv(path)


def test_unsorted_time(tmp_path):
    path = tmp_path / "p.csv"
    path.write_text("# comment line\nt,theta,trajectory\n0,0,1\n1,1,1\n0,0,2\n0.5,1,2\n0.4,2,2\n")
    with pytest.raises(DatasetError, match=r"p\.csv', column 't', line 7: time 0.4 after 0.5; "
                                           r"times must be strictly increasing \(trajectory 2.0"):
        read_csv(path)


def test_one_sample_trajectory_and_empty_file(tmp_path):
    path = tmp_path / "p.csv"
    path.write_text("t,theta,trajectory\n0,0,1\n1,1,1\n0,0,2\n")
    with pytest.raises(DatasetError, match=r"1 sample \(trajectory 2.0"):
        read_csv(path)
    empty = tmp_path / "e.csv"
    empty.write_text("t,theta\n")
    with pytest.raises(DatasetError, match=r"e\.csv': no data rows"):
        read_csv(empty)
    with pytest.raises(DatasetError, match="does not exist"):
        read_csv(tmp_path / "none.csv")
    with pytest.raises(DatasetError, match="unknown format '.xlsx'"):
        load_data(tmp_path / "data.xlsx")


# -- Python API ---------------------------------------------------------------------------------
def test_dataframe_matches_csv(tmp_path):
    pd = pytest.importorskip("pandas")
    t, q, qd, qdd, tau = pendulum()
    frame = pd.DataFrame({"t": t, "theta": q, "theta_dot": qd, "theta_ddot": qdd,
                          "tau_theta": tau})
    path = tmp_path / "p.csv"
    frame.to_csv(path, index=False)
    a, b = from_dataframe(frame), read_csv(path)
    assert a.coordinate_names == b.coordinate_names
    for key in ("t", "q", "qd", "qdd", "tau"):
        np.testing.assert_allclose(getattr(a.trajectories[0], key),
                                   getattr(b.trajectories[0], key), rtol=1e-15)
    assert load_data(frame).n_trajectories == 1
    bad = frame.astype({"theta": object})
    bad.loc[3, "theta"] = "x"
    with pytest.raises(DatasetError, match=r"DataFrame, column 'theta', row 3: 'x' is not"):
        from_dataframe(bad)
    with pytest.raises(TypeError, match="frame: expected a pandas DataFrame"):
        from_dataframe(np.zeros((3, 2)))


def test_mapped_columns_without_coordinates():
    t = np.linspace(0, 1, 5)
    data = from_columns({"time": t, "pos": t**2, "acc": np.full(5, 2.0), "F": 3 * t},
                        columns={"x": "pos", "x_ddot": "acc", "tau_x": "F"})
    assert data.coordinate_names == ("x",) and data.has("qdd") and not data.has("qd")
    np.testing.assert_array_equal(data.trajectories[0].tau[:, 0], 3 * t)
    np.testing.assert_array_equal(data.trajectories[0].t, t)  # "time" found by name


def test_from_columns_checks():
    with pytest.raises(DatasetError, match="columns of different lengths"):
        from_columns({"t": [0, 1, 2], "x": [0, 1]})
    with pytest.raises(TypeError, match="data: expected a mapping"):
        from_columns([1, 2])
    with pytest.raises(TypeError, match="source: expected a file path"):
        load_data(3.0)


def test_coordinate_system():
    system = coordinate_system(["x", "theta"], angles=["theta"])
    assert system.n == 2 and system.angle_coordinates == (1,) and not system.has_ground_truth
    np.testing.assert_array_equal(system.friction_pattern(), np.eye(2, dtype=bool))
    with pytest.raises(ValueError, match=r"angles: \['phi'\] not among the coordinates"):
        coordinate_system("x,theta", angles="phi")
