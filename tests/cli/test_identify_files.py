"""``pysindy-xl identify`` on the user's own files, ``--version`` and the light ``--help``."""

import json
import subprocess
import sys

import numpy as np
import pytest
from support.files import HEADER, two_trajectories, write_csv

import pysindy_xl
from pysindy_xl.cli import main

TRUE = {"L[theta_dot**2]": 0.25, "L[cos(theta)]": 4.9, "C_theta[theta_dot]": 0.2,
        "F[tau]": -1.0}


def assert_true_model(model):
    found = {n: c for n, c in zip(model.get_feature_names(), model.coefficients(), strict=True)
             if c != 0}
    assert set(found) == set(TRUE)
    for name, value in TRUE.items():
        assert found[name] == pytest.approx(value, rel=1e-6)


def test_identify_csv_with_header(tmp_path, capsys):
    path = write_csv(tmp_path / "pendulum.csv", HEADER, two_trajectories())
    out = tmp_path / "model.json"
    assert main(["identify", str(path), "--angles", "theta", "--trig-degree", "1",
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "2 trajectories, 402 samples" in text
    assert "(theta) 0.5*theta_ddot + 0.2*theta_dot + 4.9*sin(theta) = tau_theta" in text
    assert json.loads(out.read_text())["coefficients"]
    from pysindy_xl.model import XLSINDy

    assert_true_model(XLSINDy.load(out))


def test_identify_csv_with_column_map(tmp_path):
    t, q, qd, qdd, tau, ids = two_trajectories()
    path = write_csv(tmp_path / "lab.csv", ["time_s", "angle", "torque", "run"],
                     [t, q, tau, ids])
    from pysindy_xl.cli import build_parser, run_identify

    args = build_parser().parse_args([
        "identify", str(path), "--coordinates", "theta", "--angles", "theta",
        "--column", "t=time_s", "--column", "theta=angle", "--column", "tau_theta=torque",
        "--column", "trajectory=run", "--trig-degree", "1"])
    model = run_identify(args)  # positions only: velocities by differentiation
    found = dict(zip(model.get_feature_names(), model.coefficients(), strict=True))
    assert found["L[cos(theta)]"] == pytest.approx(4.9, rel=2e-2)
    assert found["C_theta[theta_dot]"] == pytest.approx(0.2, rel=5e-2)


def test_identify_npz_with_coordinates(tmp_path, capsys):
    t, q, qd, qdd, tau, ids = two_trajectories()
    path = tmp_path / "mine.npz"
    np.savez(path, t=t, q=q, qd=qd, qdd=qdd, tau=tau, trajectory=ids)  # float ids
    from pysindy_xl.cli import build_parser, run_identify

    model = run_identify(build_parser().parse_args(
        ["identify", str(path), "--coordinates", "theta", "--angles", "theta",
         "--trig-degree", "1"]))
    assert_true_model(model)
    assert main(["identify", str(path), "--column", "t=time"]) == 1
    assert "apply to CSV files" in capsys.readouterr().err


@pytest.mark.parametrize(
    "name, text, argv, message",
    [
        ("missing.csv", "t,angle\n0,0\n1,1\n", ["--coordinates", "theta"],
         "'{path}': column 'theta' (position of coordinate 'theta') not found"),
        ("semicolon.csv", "t;theta\n0;0\n1;1\n", [],
         "'{path}': the header has a single column 't;theta'"),
        ("cell.csv", "t,theta\n0,0\n1,one\n2,2\n", [],
         "'{path}', column 'theta', line 3: 'one' is not a number"),
        ("unsorted.csv", "t,theta\n0,0\n2,1\n1,2\n", [],
         "'{path}', column 't', line 4: time 1 after 2; times must be strictly increasing"),
        ("map.csv", "t,theta\n0,0\n1,1\n", ["--column", "tau_theta=force"],
         "'{path}': column 'force' (mapped from 'tau_theta') not found"),
        ("angles.csv", "t,theta\n0,0\n1,1\n", ["--angles", "phi"],
         "--angles: angles: ['phi'] not among the coordinates"),
        ("column.csv", "t,theta\n0,0\n1,1\n", ["--column", "theta"],
         "--column: expected KEY=HEADER"),
        ("twice.csv", "t,theta\n0,0\n1,1\n", ["--coordinates", "theta,theta"],
         "--coordinates: the names ['theta'] are given more than once"),
        ("twice_angles.csv", "t,theta\n0,0\n1,1\n", ["--angles", "theta, theta"],
         "--angles: the names ['theta'] are given more than once"),
    ],
)
def test_identify_mistakes_name_file_and_column(tmp_path, capsys, name, text, argv, message):
    path = tmp_path / name
    path.write_text(text)
    out = tmp_path / "model.json"
    assert main(["identify", str(path), *argv, "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("pysindy-xl: error: ")
    assert message.format(path=path) in err
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_out_is_never_half_written(tmp_path, monkeypatch, capsys):
    path = write_csv(tmp_path / "p.csv", HEADER, two_trajectories())
    out = tmp_path / "model.json"
    from pysindy_xl.model import XLSINDy

    def failing_save(self, target):
        with open(target, "w") as handle:
            handle.write("{")
        raise OSError("disk full")

    monkeypatch.setattr(XLSINDy, "save", failing_save)
    with pytest.raises(OSError, match="disk full"):
        main(["identify", str(path), "--angles", "theta", "--trig-degree", "1",
              "--out", str(out)])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.csv"]


def test_version(capsys):
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"pysindy-xl {pysindy_xl.__version__}"


def test_help_and_import_stay_light():
    """``--help`` and ``import pysindy_xl`` load no heavy back end (checked in a fresh process)."""
    code = ("import sys, runpy, contextlib, io\n"
            "import pysindy_xl\n"
            "light = [m for m in ('sympy', 'pysindy', 'cvxpy', 'jax', 'mujoco', 'matplotlib')\n"
            "         if m in sys.modules]\n"
            "sys.argv = ['pysindy-xl', '--help']\n"
            "with contextlib.redirect_stdout(io.StringIO()) as text:\n"
            "    try:\n"
            "        runpy.run_module('pysindy_xl.cli', run_name='__main__')\n"
            "    except SystemExit:\n"
            "        pass\n"
            "heavy = [m for m in ('sympy', 'pysindy', 'cvxpy', 'jax', 'mujoco', 'matplotlib')\n"
            "         if m in sys.modules]\n"
            "print(light, heavy, 'identify' in text.getvalue())\n")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=True)
    assert result.stdout.strip() == "[] [] True"
