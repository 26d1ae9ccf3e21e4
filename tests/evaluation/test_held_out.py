"""Held-out force prediction (``XLSINDy.score_forces``, blocked cross-validation) and the
``identify --validate`` verdict of the command line."""

from __future__ import annotations

import re

import numpy as np
import pytest
from support.files import TWO_LINK_URDF

import pysindy_xl as px
from pysindy_xl.held_out import (
    SCORING_DERIVATIVES,
    ForceScore,
    blocked_cross_validation,
    score_forces,
)

M, K = 2.0, 3.0  # x'' M + K sin(x) = u: a pendulum with known dynamics


def _pendulum(t, phase=0.0):
    t = t[:, None]
    x = 0.8 * np.sin(1.3 * t + phase) + 0.3 * np.sin(3.1 * t)
    xd = 1.04 * np.cos(1.3 * t + phase) + 0.93 * np.cos(3.1 * t)
    xdd = -1.352 * np.sin(1.3 * t + phase) - 2.883 * np.sin(3.1 * t)
    return x, xd, xdd, M * xdd + K * np.sin(x)


@pytest.fixture(scope="module")
def model():
    c = px.Coordinates(["theta"])
    library = px.LagrangeLibrary(c, [c.qd[0] ** 2, sp_cos(c.q[0])])
    t = np.linspace(0, 10, 1001)
    x, xd, xdd, tau = _pendulum(t)
    return px.XLSINDy(library).fit(x, t, x_dot=xd, x_ddot=xdd, u=tau)


def sp_cos(symbol):
    import sympy as sp

    return sp.cos(symbol)


def test_scores_of_a_known_disturbance_match_a_direct_computation(model):
    rng = np.random.default_rng(0)
    runs = [np.linspace(0, 4, 401), np.linspace(0, 3, 151)]
    data = [_pendulum(t, phase) for t, phase in zip(runs, (0.4, 1.1), strict=True)]
    disturbance = [0.05 * rng.standard_normal((len(t), 1)) + 0.02 for t in runs]
    measured = [d[3] + e for d, e in zip(data, disturbance, strict=True)]
    score = model.score_forces([d[0] for d in data], runs, measured, [d[1] for d in data],
                               [d[2] for d in data])
    error, tau = np.vstack(disturbance), np.vstack(measured)
    # the fitted model is the true one, so the prediction error is minus the disturbance
    assert score.rms[0] == pytest.approx(np.sqrt(np.mean(error**2)), rel=1e-6)
    assert score.measured_rms[0] == pytest.approx(np.sqrt(np.mean(tau**2)), rel=1e-12)
    assert score.relative[0] == pytest.approx(score.rms[0] / score.measured_rms[0], rel=1e-12)
    assert score.total == pytest.approx(np.linalg.norm(error) / np.linalg.norm(tau), rel=1e-6)
    assert score.n_samples == 552 and score.derivatives == "measured"
    assert len(score.predicted) == 2 and score.predicted[1].shape == (151, 1)
    assert score.to_dict()["rms"]["theta"] == pytest.approx(score.rms[0])


def test_derivatives_not_given_come_from_the_shared_smoother_whatever_the_model(model):
    t = np.sort(np.linspace(0, 6, 1201) + np.random.default_rng(1).uniform(0, 2e-3, 1201))
    x, _, _, tau = _pendulum(t)  # jittered stamps, used as recorded
    score = score_forces(model, x, t, tau)
    assert score.derivatives == SCORING_DERIVATIVES
    assert score.total < 0.02  # the smoothing's bias at the ends of the run, nothing else
    ends = np.r_[:25, len(t) - 25:len(t)]
    inner = np.delete(np.arange(len(t)), ends)
    error = score.predicted[0][inner] - tau[inner]
    assert np.linalg.norm(error) / np.linalg.norm(tau[inner]) < 3e-3
    # a 60 Hz ripple on the positions (accelerations of 14 rad/s^2) does not reach the score
    ripple = 1e-4 * np.sin(2 * np.pi * 60 * t)[:, None]
    assert score_forces(model, x + ripple, t, tau).total < 0.03
    with pytest.raises(ValueError, match="u"):
        score_forces(model, x, t, None)
    with pytest.raises(ValueError, match="t"):
        score_forces(model, x, t[::-1], tau)


def test_blocked_cross_validation_predicts_each_block_by_a_model_that_never_saw_it(model):
    t = np.linspace(0, 12, 1201)
    x, xd, xdd, tau = _pendulum(t)
    measured = tau.copy()
    blocks = np.linspace(0, 1201, 5).round().astype(int)
    a, b = blocks[2], blocks[3]
    bump = 0.3 * np.cos(7 * t[a:b])[:, None]
    measured[a:b] += bump  # only the third block's torques are off
    score = blocked_cross_validation(model, x, t, measured, xd, xdd, n_blocks=4)
    assert len(score.folds) == 4
    # the third fold's model is fitted on exact data: it predicts the true torques there
    expected = np.linalg.norm(bump) / np.linalg.norm(measured[a:b])
    assert score.folds[2] == pytest.approx(expected, rel=1e-4)
    # every sample gets an out-of-fold prediction, and the pooled score is their error
    predicted = score.predicted[0]
    assert predicted.shape == tau.shape
    assert score.total == pytest.approx(np.linalg.norm(predicted - measured)
                                        / np.linalg.norm(measured), rel=1e-12)
    with pytest.raises(ValueError, match="n_blocks"):
        blocked_cross_validation(model, x, t, tau, xd, xdd, n_blocks=1)


def test_several_runs_are_the_folds(model):
    runs = [np.linspace(0, 4, 401), np.linspace(0, 5, 501), np.linspace(0, 4, 401)]
    data = [_pendulum(t, phase) for t, phase in zip(runs, (0.0, 0.7, 1.9), strict=True)]
    score = blocked_cross_validation(model, [d[0] for d in data], runs, [d[3] for d in data],
                                     [d[1] for d in data], [d[2] for d in data])
    assert len(score.folds) == 3 and max(score.folds) < 1e-6
    grouped = blocked_cross_validation(model, [d[0] for d in data], runs,
                                       [d[3] for d in data], [d[1] for d in data],
                                       [d[2] for d in data], n_blocks=2)
    assert len(grouped.folds) == 2 and max(grouped.folds) < 1e-6  # runs kept whole


def test_lines_and_plot(tmp_path):
    score = ForceScore.from_predictions(
        ["a", "b"], [np.linspace(0, 1, 20)], [np.ones((20, 2))],
        [np.ones((20, 2)) * [1.1, 0.8]], "measured")
    lines = score.lines(["N m", "N"])
    assert lines[0].strip() == "a: RMS 0.1 N m (10.00 % of 1 N m)"
    assert lines[1].strip() == "b: RMS 0.2 N (20.00 % of 1 N)"
    assert lines[2].strip() == f"all coordinates: {100 * np.sqrt(0.05 / 2):.2f} % (relative RMS)"
    score.plot(tmp_path / "f.png")
    assert (tmp_path / "f.png").read_bytes()[:4] == b"\x89PNG"


# -- command line ---------------------------------------------------------------------------


def _csv(path, trajectory, names):
    columns = {"t": trajectory.t[:, None], "": trajectory.q,
               "_dot": trajectory.qd, "_ddot": trajectory.qdd, "tau_": trajectory.tau}
    header, blocks = ["t"], [columns["t"]]
    for suffix in ("", "_dot", "_ddot"):
        header += [f"{name}{suffix}" for name in names]
        blocks.append(columns[suffix])
    header += [f"tau_{name}" for name in names]
    blocks.append(columns["tau_"])
    np.savetxt(path, np.hstack(blocks), delimiter=",", header=",".join(header), comments="")
    return path


@pytest.fixture(scope="module")
def arm_files(tmp_path_factory):
    pytest.importorskip("mujoco")
    from pysindy_xl.mujoco import MJCFSystem, generate_dataset

    folder = tmp_path_factory.mktemp("arm")
    urdf = folder / "arm.urdf"
    urdf.write_text(TWO_LINK_URDF)
    system = MJCFSystem(urdf)
    data = generate_dataset(system, n_trajectories=2, duration=3.0, seed=0, sample_every=4,
                            derivatives=True, progress=False)
    names = system.coordinate_names
    held_out = data.trajectories[1]
    # torque sensor noise on the validation run only: the model cannot predict it
    held_out.tau = held_out.tau + 0.02 * np.random.default_rng(3).standard_normal(
        held_out.tau.shape)
    return (urdf, _csv(folder / "train.csv", data.trajectories[0], names),
            _csv(folder / "test.csv", data.trajectories[1], names), data.trajectories[1])


def test_identify_validate_prints_held_out_torques_and_plots_them(arm_files, tmp_path, capsys):
    from pysindy_xl.cli import main

    urdf, train, test, truth = arm_files
    plot, out = tmp_path / "torques.png", tmp_path / "model.json"
    assert main(["identify", str(train), "--system", str(urdf), "--validate", str(test),
                 "--plot", str(plot), "--out", str(out)]) == 0
    captured = capsys.readouterr()
    text = captured.out
    assert (f"held-out torque prediction on test.csv (1 run, {len(truth.t)} samples); "
            "derivatives: measured:") in text
    found = {name: (float(rms), float(rel)) for name, rms, rel in re.findall(
        r"  (\w+): +RMS ([0-9.e+-]+) N m \(([0-9.]+) % of", text)}
    assert set(found) == {"shoulder", "elbow"}
    # independent: the saved model's inverse dynamics against the test file's torques
    model = px.XLSINDy.load(out)
    predicted = model.predict_forces(truth.q, truth.qd, truth.qdd)
    rms = np.sqrt(np.mean((predicted - truth.tau) ** 2, axis=0))
    relative = rms / np.sqrt(np.mean(truth.tau**2, axis=0))
    for k, name in enumerate(("shoulder", "elbow")):
        assert found[name][0] == pytest.approx(rms[k], rel=5e-3)  # printed to 3 digits
        assert found[name][1] == pytest.approx(100 * relative[k], abs=0.006)
        assert rms[k] == pytest.approx(0.02, rel=0.15)  # the sensor noise, nothing more
    assert plot.read_bytes()[:4] == b"\x89PNG" and "torque plot:" in text
    assert "validation plot" not in text  # no open-loop replay unless asked
    assert not any("simulating the model" in line for line in captured.err.splitlines())


def test_identify_one_run_cross_validates_and_replays_on_request(arm_files, tmp_path, capsys):
    from pysindy_xl.cli import main

    urdf, train, _, _ = arm_files
    replay = tmp_path / "replay.png"
    assert main(["identify", str(train), "--system", str(urdf), "--cv-blocks", "3",
                 "--open-loop", str(replay), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "held-out torque prediction by time-blocked cross-validation (3 contiguous " \
           "blocks" in text
    total = float(re.search(r"all coordinates: ([0-9.]+) %", text).group(1))
    assert total < 1.0
    assert len(re.search(r"per fold: (.*)", text).group(1).split(",")) == 3
    assert replay.exists() and "validation plot: " in text
