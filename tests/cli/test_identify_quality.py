"""``pysindy-xl identify``: --formulation, the fit-quality R^2, --plot and progress lines."""

import re

import numpy as np
import pytest
from support.files import HEADER, two_trajectories, write_csv

from pysindy_xl.cli import build_parser, fit_quality, main, run_identify


def _r2(text):
    match = re.search(r"fit quality: R\^2 = (-?[0-9.]+|nan) \(theta (-?[0-9.]+|nan)\)", text)
    assert match, text
    return float(match.group(1))


@pytest.fixture
def csv_file(tmp_path):
    return write_csv(tmp_path / "pendulum.csv", HEADER, two_trajectories())


@pytest.fixture
def positions_csv(tmp_path):
    t, q, qd, qdd, tau, ids = two_trajectories()
    return write_csv(tmp_path / "positions.csv", ["t", "theta", "tau_theta", "trajectory"],
                     [t, q, tau, ids])


@pytest.mark.parametrize("formulation, expected", [("auto", "strong"), ("strong", "strong"),
                                                   ("weak", "weak")])
def test_formulation_option_with_measured_derivatives(csv_file, capsys, formulation,
                                                      expected):
    model = run_identify(build_parser().parse_args([
        "identify", str(csv_file), "--angles", "theta", "--trig-degree", "1",
        "--formulation", formulation, "--quiet"]))
    assert model.formulation_ == expected
    text = capsys.readouterr().out
    assert f"explicit solver, {expected} formulation" in text
    found = dict(zip(model.get_feature_names(), model.coefficients(), strict=True))
    # exact data: both forms find the true pendulum (weak: quadrature error only)
    assert found["L[cos(theta)]"] == pytest.approx(4.9, rel=1e-6 if expected == "strong" else 1e-3)
    assert found["C_theta[theta_dot]"] == pytest.approx(0.2, rel=1e-5 if expected == "strong"
                                                        else 1e-2)
    assert _r2(text) > 0.9999
    assert ("weak form: equations integrated against test functions" in text) == (
        expected == "weak")


def test_positions_only_defaults_to_weak_and_strong_is_selectable(positions_csv, capsys):
    args = ["identify", str(positions_csv), "--coordinates", "theta", "--angles", "theta",
            "--trig-degree", "1", "--quiet"]
    weak = run_identify(build_parser().parse_args(args))
    captured = capsys.readouterr()
    assert weak.formulation_ == "weak"
    assert "weak formulation on smoothed positions" in captured.err
    strong = run_identify(build_parser().parse_args([*args, "--formulation", "strong"]))
    captured = capsys.readouterr()
    assert strong.formulation_ == "strong"
    assert "strong formulation on differentiated positions" in captured.err
    for model in (weak, strong):
        found = dict(zip(model.get_feature_names(), model.coefficients(), strict=True))
        assert found["L[cos(theta)]"] == pytest.approx(4.9, rel=2e-2)


def test_positions_only_fit_reports_the_stability_of_its_terms(positions_csv, capsys):
    from pysindy_xl.data import load_data

    model = run_identify(build_parser().parse_args([
        "identify", str(positions_csv), "--coordinates", "theta", "--angles", "theta",
        "--trig-degree", "1", "--quiet"]))
    text = capsys.readouterr().out
    assert model.inclusion_probability_ is not None  # positions only: bagged by default
    quality = fit_quality(model, load_data(str(positions_csv), coordinates=["theta"])
                          .fit_arguments())
    kept, dropped = quality["stability"]["kept_least"], quality["stability"]["dropped_most"]
    names = model.get_feature_names()
    assert kept[1] == model.inclusion_probability_[model.coef_ != 0][1:].min()
    assert model.coef_[names.index(kept[0])] != 0 and model.coef_[names.index(dropped[0])] == 0
    assert kept[1] >= 0.5 > dropped[1]
    assert f"every kept term in {kept[1]:.0%} of them or more (least: {kept[0]})" in text


def test_bad_formulation_is_a_usage_error(csv_file, capsys):
    with pytest.raises(SystemExit) as info:
        main(["identify", str(csv_file), "--formulation", "medium"])
    assert info.value.code == 2
    assert "--formulation: invalid choice: 'medium'" in capsys.readouterr().err


@pytest.mark.parametrize("formulation", ["strong", "weak"])
def test_fit_quality_drops_for_a_wrong_model(csv_file, formulation):
    """R^2 is ~1 for the identified model and clearly lower when a true term is removed."""
    from pysindy_xl.data import load_data

    model = run_identify(build_parser().parse_args([
        "identify", str(csv_file), "--angles", "theta", "--trig-degree", "1",
        "--formulation", formulation, "--quiet"]))
    arguments = load_data(str(csv_file)).fit_arguments()
    quality = fit_quality(model, arguments)
    assert quality["formulation"] == formulation and quality["target"] == "forces"
    assert quality["r2"] > 0.9999
    assert quality["r2_per_coordinate"]["theta"] == pytest.approx(quality["r2"])
    names = model.get_feature_names()
    model.coef_ = model.coef_.copy()
    model.coef_[names.index("C_theta[theta_dot]")] = 0.0  # drop the damping
    damaged = fit_quality(model, arguments)["r2"]
    assert damaged < 0.999
    model.coef_[names.index("L[cos(theta)]")] = 0.0  # and gravity: far worse
    assert fit_quality(model, arguments)["r2"] < damaged - 0.1
    with pytest.raises(TypeError, match="arguments: expected the dict of fit arguments"):
        fit_quality(model, [arguments["x"]])


def test_fit_quality_of_an_unforced_fit_uses_the_kinetic_part(tmp_path):
    path = tmp_path / "free.npz"
    # unforced exact pendulum: 0.5 qdd + 4.9 sin q = 0 -> qdd = -9.8 sin q
    from scipy.integrate import solve_ivp

    solution = solve_ivp(lambda _, y: [y[1], -9.8 * np.sin(y[0])], (0, 4), [1.0, 0.0],
                         t_eval=np.linspace(0, 4, 801), rtol=1e-11, atol=1e-12)
    q = solution.y[0]
    np.savez(path, t=solution.t, q=q, qd=solution.y[1], qdd=-9.8 * np.sin(q))
    from pysindy_xl.data import load_data

    model = run_identify(build_parser().parse_args([
        "identify", str(path), "--coordinates", "theta", "--angles", "theta",
        "--trig-degree", "1", "--quiet"]))
    quality = fit_quality(model, load_data(str(path), coordinates=["theta"]).fit_arguments(
        forces=None))
    assert quality["target"] == "kinetic"
    assert quality["r2"] > 0.999


def test_plot_and_progress(csv_file, tmp_path, capsys):
    plot = tmp_path / "fit.png"
    assert main(["identify", str(csv_file), "--angles", "theta", "--trig-degree", "1",
                 "--plot", str(plot)]) == 0
    captured = capsys.readouterr()
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    match = re.search(r"validation plot: .*fit\.png \(position RMSE theta ([0-9.e-]+), over 2 s\)",
                      captured.out)
    assert match, captured.out
    assert float(match.group(1)) < 1e-3  # exact model, exact data: the curves coincide
    progress = [line for line in captured.err.splitlines() if line.startswith("[")]
    assert any("fitting (strong form" in line for line in progress)
    assert any("computing the fit quality" in line for line in progress)
    assert any("simulating the model" in line for line in progress)
    assert progress[-1].endswith("done")


def test_quiet_plot_of_a_wrong_directory_fails_before_fitting(csv_file, tmp_path, capsys):
    assert main(["identify", str(csv_file), "--angles", "theta", "--trig-degree", "1",
                 "--plot", str(tmp_path / "missing" / "fit.png"), "--quiet"]) == 1
    captured = capsys.readouterr()
    assert "pysindy-xl: error: --plot: directory" in captured.err
    assert "fit quality" not in captured.out  # nothing was fitted
    assert not [line for line in captured.err.splitlines() if line.startswith("[")]


def test_plot_of_the_weak_fit_from_noisy_positions(tmp_path, capsys):
    """Positions-only data with noise: the plot simulates from the smoother's velocity."""
    t, q, qd, qdd, tau, ids = two_trajectories()
    rng = np.random.default_rng(0)
    noisy = q + 0.01 * q.std() * rng.standard_normal(q.shape)
    path = write_csv(tmp_path / "noisy.csv", ["t", "theta", "tau_theta", "trajectory"],
                     [t, noisy, tau, ids])
    plot = tmp_path / "noisy.png"
    assert main(["identify", str(path), "--angles", "theta", "--trig-degree", "1", "--quiet",
                 "--plot", str(plot)]) == 0
    text = capsys.readouterr().out
    assert "weak formulation" in text and plot.exists()
    assert _r2(text) > 0.99
    rmse = float(re.search(r"position RMSE theta ([0-9.e-]+)", text).group(1))
    assert rmse < 0.05 * q.std()


def test_joint_models_option_finds_a_torque_sensor_offset(tmp_path, capsys):
    """``--joint-models``: the kinematic catalog offers the joint models of real arms, and the
    fit finds the constant offset of a torque sensor (ground truth: the offset added to the
    torques MuJoCo applied); without the option there is no offset to find."""
    from pysindy_xl.mujoco import MJCFSystem, generate_dataset

    xml = tmp_path / "pendulum.xml"
    xml.write_text("""<mujoco><option timestep="0.001" integrator="RK4"/>
      <worldbody><body><joint name="swing" type="hinge" axis="0 1 0" damping="0.2"/>
      <inertial pos="0 0 -0.5" mass="1" diaginertia="0.01 0.01 0.01"/></body></worldbody>
      <actuator><motor joint="swing"/></actuator></mujoco>""")
    run = generate_dataset(MJCFSystem(str(xml)), n_trajectories=1, duration=6.0, seed=1,
                           progress=False).trajectories[0]
    offset = 0.3
    data = write_csv(tmp_path / "log.csv", ["t", "swing", "tau_swing"],
                     [run.t, run.q[:, 0], run.tau[:, 0] + offset])
    arguments = ["identify", str(data), "--system", str(xml), "--quiet", "--cv-blocks", "0"]
    model = run_identify(build_parser().parse_args(
        [*arguments, "--joint-models", "viscous,offset"]))
    found = model.physical_parameters()["joint_friction"]["swing"]
    assert found["offset"] == pytest.approx(offset, rel=0.02)
    assert found["viscous"] == pytest.approx(0.2, rel=0.05)
    plain = run_identify(build_parser().parse_args(arguments))
    assert "joint_friction" not in plain.physical_parameters()
    assert main([*arguments, "--catalog", "mixed", "--joint-models", "all"]) == 1
    assert "only the 'kinematic' catalog offers joint models" in capsys.readouterr().err
    assert main([*arguments, "--joint-models", "all", "--coulomb-law", "mujoco"]) == 1
    assert "--coulomb-law: 'mujoco' is a law of the Coulomb candidate" in capsys.readouterr().err


@pytest.mark.parametrize("argv, law", [
    (["demo", "arm.xml"], "mujoco"),  # the demo's data come from MuJoCo
    (["demo", "arm.xml", "--joint-models", "all"], "smooth"),
    (["demo", "arm.xml", "--coulomb-law", "smooth"], "smooth"),
    (["identify", "log.csv"], "smooth"),  # a log may come from a real joint
    (["identify", "log.csv", "--coulomb-law", "mujoco"], "mujoco"),
])
def test_coulomb_law_defaults_follow_the_data_source(argv, law):
    from pysindy_xl.cli.steps import coulomb_law
    from pysindy_xl.mujoco import generate_dataset

    args = build_parser().parse_args(argv)
    assert coulomb_law(args) == law
    # a dataset MuJoCo generated (pysindy-xl generate) is MuJoCo's data whatever the command
    simulated = generate_dataset("cart-pole", n_trajectories=1, duration=0.05, progress=False)
    given = "--coulomb-law" in argv or "--joint-models" in argv
    assert coulomb_law(args, simulated) == (law if given else "mujoco")
