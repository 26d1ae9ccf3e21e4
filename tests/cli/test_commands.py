"""The ``pysindy-xl`` command end to end: demo, generate, identify, errors."""

import json

import numpy as np
import pytest
from support.files import MODELS

from pysindy_xl.cli import CLIError, main
from pysindy_xl.cli.steps import _optimizer
from pysindy_xl.mujoco import SYSTEMS

SHORT = ["--duration", "2", "--trajectories", "1", "--validation-duration", "1", "--no-plots",
         "--quiet"]


def read_report(directory):
    return json.loads((directory / "report.json").read_text())


@pytest.mark.slow
def test_readme_demo_cart_pole(tmp_path, capsys):
    """``pysindy-xl demo cart-pole``: the README's main command, default options."""
    assert main(["demo", "cart-pole", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "(x) " in out and "(theta) " in out and "VALID" in out
    report = read_report(tmp_path)
    assert report["validation"]["valid"] is True
    assert report["validation"]["position_rmse"] < 0.01
    assert report["validation"]["horizon"] == pytest.approx(4.0)  # the demo's default
    assert report["coefficient_summary"]["support_recovered"] is True
    assert report["coefficient_summary"]["max_relative_error"] < 1e-6
    assert (tmp_path / "validation.png").stat().st_size > 10_000
    assert report["timings_s"]["total"] < 60


def solver_available(solver):
    try:
        _optimizer(solver)
    except CLIError:
        return False
    return True


@pytest.mark.parametrize("system", sorted(SYSTEMS))
@pytest.mark.parametrize("forcing", ["explicit", "implicit", "mixed"])
def test_demo_each_system_and_forcing(system, forcing, tmp_path, capsys):
    options = []
    if forcing != "explicit" and system != "cart-pole":
        # SINDy-PI solves one regression per column: keep the catalog small in this smoke test
        options = ["--trig-degree", "1"]
    status = main(["demo", system, "--forcing", forcing, "--out", str(tmp_path), *SHORT,
                   *options])
    err = capsys.readouterr().err
    if not solver_available(forcing):
        # the implicit and mixed solvers are optional parts: a clear message, no traceback
        assert status == 1 and "is not available" in err
        return
    if options and status == 1:
        # the reduced catalog may hold no law: reported as such, without a traceback
        assert err.startswith("pysindy-xl: error: identification failed")
        return
    assert status == 0, err
    report = read_report(tmp_path)
    assert report["system"] == system and report["options"]["forcing"] == forcing
    assert len(report["coefficients"]) == len(report["features"])
    assert set(report["validation"]) >= {"valid", "failure"}
    if forcing == "explicit":
        assert report["validation"]["valid"] is True
        assert report["coefficient_summary"]["max_relative_error"] < 1e-3


@pytest.mark.parametrize("system", sorted(SYSTEMS))
def test_demo_mixed_forcing_with_explicit_solver(system, tmp_path):
    assert main(["demo", system, "--forcing", "mixed", "--solver", "explicit", "--out",
                 str(tmp_path), *SHORT]) == 0
    report = read_report(tmp_path)
    assert report["solver"] == "explicit"
    assert report["validation"]["valid"] is True


def test_demo_with_noise_and_other_catalog(tmp_path, capsys):
    # a short, noisy recording leaves the classical catalog without a usable inertia: the
    # report and the data are written, and the demo says the model fails (exit status 1)
    assert main(["demo", "cart-pole", "--noise", "0.01", "--catalog", "classical", "--seed",
                 "3", "--out", str(tmp_path), "--save-data", *SHORT]) == 1
    assert capsys.readouterr().err.startswith(
        "pysindy-xl: error: validation: the identified model does not reproduce a fresh")
    report = read_report(tmp_path)
    assert report["validation"]["valid"] is False
    assert report["options"]["noise"] == 0.01
    assert all(not f.startswith("L[") for f in report["features"][1:])
    assert (tmp_path / "training_data.npz").exists()


def test_generate_then_identify(tmp_path, capsys):
    path = tmp_path / "data.npz"
    assert main(["generate", "cart-pole", str(path), "--duration", "3", "--trajectories", "2",
                 "--seed", "1"]) == 0
    assert path.exists() and (tmp_path / "data.json").exists()
    capsys.readouterr()
    model_path = tmp_path / "model.json"
    assert main(["identify", str(path), "--catalog", "mixed", "--out", str(model_path)]) == 0
    out = capsys.readouterr().out
    assert "cart-pole: 2 trajectories" in out
    assert "1.5*x_ddot" in out and "0.5*x_dot" in out and "support recovered: True" in out
    assert model_path.exists()
    # named coordinates must match the system's
    assert main(["identify", str(path), "--system", "double-pendulum"]) == 1
    assert "do not match" in capsys.readouterr().err


def test_identify_user_npz_without_metadata(tmp_path, capsys):
    """A user's NPZ with only t, q, qd, qdd, tau and a --system for the coordinates."""
    from pysindy_xl.mujoco import generate_dataset

    tr = generate_dataset("cart-pole", n_trajectories=1, duration=3.0, seed=2,
                          progress=False).trajectories[0]
    path = tmp_path / "mine.npz"
    np.savez(path, t=tr.t, q=tr.q, qd=tr.qd, qdd=tr.qdd, tau=tr.tau)
    assert main(["identify", str(path), "--system", "cart-pole"]) == 0
    assert "(theta) 0.32*theta_ddot" in capsys.readouterr().out
    assert main(["identify", str(path)]) == 1
    assert "--system" in capsys.readouterr().err
    assert main(["identify", str(path), "--system", "cart-double-pendulum"]) == 1
    assert "the dataset has 2 coordinates" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv, message",
    [
        (["demo", "quadruple-pendulum"], "unknown system"),
        (["demo", "cart-pole", "--forcing", "implicit", "--solver", "explicit"],
         "--solver explicit needs forces"),
        (["demo", "cart-pole", "--forcing", "mixed", "--actuators", "elbow", "--solver",
          "explicit"], "actuators"),
        (["demo", "missing_model.xml"], "does not exist"),
    ],
)
def test_demo_errors(argv, message, tmp_path, capsys):
    assert main([*argv, "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("pysindy-xl: error:") and message in err


def test_identify_errors(tmp_path, capsys):
    assert main(["identify", str(tmp_path / "none.npz"), "--system", "cart-pole"]) == 1
    assert "does not exist" in capsys.readouterr().err
    bad = tmp_path / "bad.npz"
    bad.write_text("not an archive")
    assert main(["identify", str(bad), "--system", "cart-pole"]) == 1
    assert "not a readable NPZ" in capsys.readouterr().err
    partial = tmp_path / "partial.npz"
    np.savez(partial, q=np.zeros((10, 2)))
    assert main(["identify", str(partial), "--system", "cart-pole"]) == 1
    assert "required array(s) ['t']" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv",
    [
        ["demo", "cart-pole", "--noise", "-1"],
        ["demo", "cart-pole", "--catalog", "newtonian"],
        ["demo", "cart-pole", "--duration", "0"],
        ["demo"],
        [],
    ],
)
def test_usage_errors_exit_2(argv):
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2


def test_demo_on_a_user_mjcf(tmp_path, capsys):
    xml = tmp_path / "pendulum.xml"
    xml.write_text("""<mujoco><option timestep="0.001" integrator="RK4"/>
      <worldbody><body><joint name="swing" type="hinge" axis="0 1 0" damping="0.2"/>
      <inertial pos="0 0 -0.5" mass="1" diaginertia="1e-8 1e-8 1e-8"/></body></worldbody>
      <actuator><motor joint="swing"/></actuator></mujoco>""")
    out = tmp_path / "out"
    assert main(["demo", str(xml), "--out", str(out), "--duration", "3", "--trajectories", "1",
                 "--validation-duration", "2"]) == 0
    printed = capsys.readouterr().out
    assert "L = 0.125*swing_dot**2 + 4.905*cos(swing)" in printed
    report = read_report(out)
    # the kinematic catalog is exact for any MJCF: the true vector is the MJCF's own values
    np.testing.assert_allclose(report["coefficients"], report["true_coefficients"], atol=1e-6)
    assert report["true_coefficients"][report["features"].index("L[0.5*swing_dot**2]")] == \
        pytest.approx(0.25, rel=1e-6)  # m l^2 of the point mass
    assert report["validation"]["valid"] is True
    assert "true value" in printed and "swing: 0.2, 0 (true 0.2, 0)" in printed
    assert (out / "validation.png").exists()


def test_generate_then_identify_a_user_mjcf_with_include(tmp_path, capsys):
    """The dataset of a user's MJCF identifies alone, even once the model files are gone."""
    import shutil

    for name in ("included_arm.xml", "included_arm_body.xml"):
        shutil.copy(MODELS / name, tmp_path / name)
    data = tmp_path / "arm.npz"
    assert main(["generate", str(tmp_path / "included_arm.xml"), str(data), "--duration", "3",
                 "--trajectories", "1"]) == 0
    assert "sampling every 2 step(s) of 1 ms = 2 ms" in capsys.readouterr().out
    (tmp_path / "included_arm.xml").unlink()  # the embedded XML is enough
    (tmp_path / "included_arm_body.xml").unlink()
    assert main(["identify", str(data), "--trig-degree", "1"]) == 0
    out = capsys.readouterr().out
    # 1.5 kg at 0.4 m: m l^2 / 2 = 0.12, m g l = 5.886; damping 0.3
    assert "mjcf: 1 trajectories" in out
    assert "0.12*shoulder_dot**2" in out and "5.886*cos(shoulder)" in out
    assert "0.3*shoulder_dot" in out


def test_generate_checks_the_output_before_simulating(tmp_path, capsys):
    import time

    start = time.perf_counter()
    assert main(["generate", "cart-pole", str(tmp_path / "missing" / "data.npz"),
                 "--duration", "1000"]) == 1  # 10^6 steps if it simulated first
    assert time.perf_counter() - start < 5
    assert "does not exist" in capsys.readouterr().err
    assert main(["generate", "cart-pole", str(tmp_path), "--duration", "1000"]) == 1
    assert "is a directory" in capsys.readouterr().err


def test_demo_out_on_an_existing_file(tmp_path, capsys):
    existing = tmp_path / "report.txt"
    existing.write_text("keep me")
    assert main(["demo", "cart-pole", "--out", str(existing), *SHORT]) == 1
    err = capsys.readouterr().err
    assert err.startswith("pysindy-xl: error: --out:") and "not a directory" in err
    assert "Traceback" not in err and existing.read_text() == "keep me"


def test_demo_noise_model_decides_what_the_fit_receives(tmp_path, capsys):
    assert main(["demo", "cart-pole", "--noise", "0.001", "--trig-degree", "1", "--out",
                 str(tmp_path), *SHORT]) == 0
    report = read_report(tmp_path)
    assert report["data"]["noise_model"] == "positions"
    assert report["data"]["derivatives"] == "none"
    assert report["data"]["noise"] == {"q": 0.001, "qd": 0.0, "qdd": 0.0, "tau": 0.0}
    assert "no velocity or acceleration given (weak formulation" in capsys.readouterr().out
    assert main(["demo", "cart-pole", "--noise", "0.001", "--noise-model", "all",
                 "--trig-degree", "1", "--out", str(tmp_path), *SHORT]) == 0
    report = read_report(tmp_path)
    assert report["data"]["derivatives"] == "mujoco" and report["data"]["noise"]["qdd"] == 0.001


def test_demo_joint_selection_and_limits(tmp_path, capsys):
    out = tmp_path / "target"
    assert main(["demo", str(MODELS / "pendulum_and_target.xml"), "--joints", "swing",
                 "--trig-degree", "1", "--out", str(out), *SHORT]) == 0
    report = read_report(out)
    assert report["excluded_joints"] == ["target_x", "target_y"]
    assert report["validation"]["valid"] is True
    assert main(["demo", "cart-pole", "--joints", "slider", "--out", str(out), *SHORT]) == 1
    assert "--joints: only for MJCF" in capsys.readouterr().err
    assert main(["demo", str(MODELS / "pendulum_and_target.xml"), "--joints", "elbow",
                 "--out", str(out), *SHORT]) == 1
    assert "--joints: expected a non-empty list of joint names" in capsys.readouterr().err
    rail = tmp_path / "rail"
    assert main(["demo", str(MODELS / "rail_cart.xml"), "--amplitude", "1", "--trig-degree",
                 "1", "--out", str(rail), "--duration", "5", "--trajectories", "2",
                 "--validation-duration", "2", "--no-plots"]) == 0
    printed = capsys.readouterr().out
    report = read_report(rail)
    constraints = report["data"]["constraints"]
    assert constraints["limit_hits"].keys() == {"slider"}
    assert "constraints act on" in printed and "slider" in printed
    assert report["validation"]["valid"] is True


def test_amplitude_option_checked():
    with pytest.raises(SystemExit) as info:
        main(["demo", "cart-pole", "--amplitude", "2"])
    assert info.value.code == 2


def test_demo_holds_a_passive_body_still(tmp_path, capsys):
    # the passive target drifts at its initial velocity, undriven and decoupled: its
    # coordinates leave the regression and the model holds them (issue 34)
    assert main(["demo", str(MODELS / "pendulum_and_target.xml"), "--trig-degree", "1",
                 "--out", str(tmp_path), *SHORT]) == 0
    printed = capsys.readouterr().out
    assert "held still" in printed and "target_x, target_y" in printed
    assert "no inertia identified" not in printed
    report = read_report(tmp_path)
    assert report["still_coordinates"] == ["target_x", "target_y"]
    assert report["physics"]["held"] == ["target_x", "target_y"]
    assert report["physics"]["unidentified"] == []
    assert report["physics"]["mass_error"] < 1e-6
    assert report["validation"]["valid"] is True


def test_demo_names_a_passive_body_and_how_to_leave_it_out(tmp_path, capsys):
    assert main(["demo", str(MODELS / "pendulum_and_target.xml"), "--trig-degree", "1",
                 "--no-hold-still", "--out", str(tmp_path), *SHORT]) == 1
    printed = capsys.readouterr().out
    assert "no inertia identified for target_x, target_y" in printed
    assert "--joints swing" in printed
    report = read_report(tmp_path)
    assert report["physics"]["unidentified"] == ["target_x", "target_y"]
    assert report["validation"]["valid"] is False
    # never "RMSE 0 ... INVALID": no finite error (null in the strict JSON report)
    assert report["validation"]["position_rmse"] is None
    assert report["validation"]["divergence_time"] is not None
    assert "position RMSE inf" in printed

def test_identify_out_checked_before_fitting(tmp_path, capsys):
    data = tmp_path / "data.npz"
    assert main(["generate", "cart-pole", str(data), "--duration", "0.5",
                 "--trajectories", "1"]) == 0
    capsys.readouterr()
    assert main(["identify", str(data), "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("pysindy-xl: error: --out:") and "is a directory" in err
    assert main(["identify", str(data), "--out", str(tmp_path / "no" / "m.json")]) == 1
    assert "does not exist" in capsys.readouterr().err
