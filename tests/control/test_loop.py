"""The learning loop on the MuJoCo cart-pole, the swing-up task's scoring, and bad input.

Ground truth: MuJoCo is the plant; the true model is the system's Lagrangian equations
(sympy), which stand in for an identification in the fast tests."""

import json

import numpy as np
import pytest
from support.control import FAST_PLANNER, true_model

import pysindy_xl as px
from pysindy_xl.control import discrete_dynamics, sampling_planner, swing_up_cost
from pysindy_xl.control.command import run_control
from pysindy_xl.control.discrete import continuous_dynamics
from pysindy_xl.control.loop import learn_to_control
from pysindy_xl.control.plant import Episode, MuJoCoPlant
from pysindy_xl.control.tasks import get_task
from pysindy_xl.mujoco import get_system


@pytest.mark.slow
def test_loop_explores_identifies_and_swings_up_the_cart_pole():
    """The loop's cycle on the plant, its identification step given the true equations."""
    seen = []

    def identify(system, data):
        seen.append([(q.shape, t.shape, tau.shape) for q, t, tau in data])
        return true_model("cart-pole")

    messages = []
    result = learn_to_control("cart-pole", identify=identify, explore_s=0.5, seed=1,
                              planner=FAST_PLANNER, log=messages.append)
    assert result.success
    assert result.upright_s >= 2.0 - 0.05
    assert result.max_abs_force <= 10.0 + 1e-9 and result.max_abs_x <= 1.5
    kinds = [h["kind"] for h in result.history]
    assert kinds == ["explore", "attempt"] and result.episodes == 2
    # every plant second is counted: the exploration and the successful attempt
    assert result.interaction_s == pytest.approx(sum(h["duration_s"] for h in result.history))
    assert seen == [[((501, 2), (501,), (501, 2))]]  # positions only, 1 kHz, forces
    assert any("explore" in m for m in messages) and any("attempt" in m for m in messages)
    assert result.mpc_step_ms > 0 and 0 < result.lqr_fraction < 1
    json.dumps(result.to_dict(), allow_nan=False)


def test_noise_reaches_the_identification():
    data_seen = []

    def identify(system, data):
        # a refused identification: the loop explores again instead of planning, so the
        # test reads what the identification is given without running a controller
        data_seen.extend(data)
        raise ValueError("recorded")

    result = learn_to_control("cart-pole", identify=identify, explore_s=0.3, noise=0.05,
                              seed=0, max_episodes=2, planner=FAST_PLANNER)
    assert [h["kind"] for h in result.history] == ["explore", "explore"]
    q = data_seen[0][0]
    steps = np.diff(q[:, 1])
    # 5 % of the angle's spread as white noise: sample-to-sample jumps far above the motion's
    assert np.std(steps) > 0.02 * np.std(q[:, 1])


def test_swing_up_scoring_on_a_recorded_episode():
    task = get_task("cart-pole")
    system = get_system("cart-pole")
    t = np.arange(0, 3.001, 0.001)
    theta = np.where(t < 0.5, 0.0, np.pi + 0.1)
    q = np.c_[0.2 * np.sin(t), theta]
    episode = Episode(t, q, np.zeros_like(q), np.zeros_like(q), np.full((150, 1), 3.0), 3.0,
                      "duration")
    scores = task.evaluate(episode, system)
    assert scores["success"] and scores["upright_s"] == pytest.approx(2.5, abs=2e-3)
    assert scores["max_abs_force"] == 3.0
    q[:, 0] = 1.6  # off the track
    assert not task.evaluate(episode, system)["success"]


def test_the_plant_clips_to_the_force_limit_and_counts_time():
    plant = MuJoCoPlant("cart-double-pendulum", ["x"], force_limit=4.0, control_dt=0.01)
    plant.reset()
    episode = plant.run(lambda state, t: np.array([-50.0]), 0.2)
    assert np.all(episode.controls == -4.0) and np.all(episode.tau[:, 0] == -4.0)
    assert np.all(episode.tau[:, 1:] == 0.0)
    assert plant.interaction_s == pytest.approx(0.2)
    assert episode.q[-1, 0] < 0  # pushed backwards


@pytest.mark.parametrize("kwargs, error, match", [
    ({"task": "balance"}, ValueError, "task: expected one of"),
    ({"system": "double-pendulum"}, ValueError, "system: the swing-up task"),
    ({"catalog": "mjcf"}, ValueError, "catalog: expected one of"),
    ({"force_limit": -1.0}, ValueError, "force_limit: expected a positive number"),
    ({"noise": -0.1}, ValueError, "noise: expected"),
    ({"model": object()}, TypeError, "model: expected"),
    ({"max_episodes": 0}, ValueError, "max_episodes: expected an integer >= 1"),
    ({"max_interaction_s": 0.0}, ValueError, "max_interaction_s: expected a real number > 0"),
    ({"log": "stderr"}, TypeError, "log: expected a callable"),
    ({"planner": {"horizons": 30}}, ValueError, r"planner: unknown settings \['horizons'\]"),
])
def test_bad_input_to_the_loop(kwargs, error, match):
    with pytest.raises(error, match=match):
        learn_to_control(**{"max_episodes": 1, **kwargs})


def test_a_model_without_accelerations_is_refused():
    unfitted = px.XLSINDy(px.CatalogRepartition([px.ExternalForces(px.Coordinates(["x"]))]))
    with pytest.raises(TypeError, match="model: expected a fitted model"):
        continuous_dynamics(unfitted)


def test_limits_of_the_wrong_shape_are_refused():
    f = continuous_dynamics(true_model("cart-pole"))
    step = discrete_dynamics(f, 0.02, [[1.0], [0.0]])
    cost = swing_up_cost(2, [1])
    with pytest.raises(ValueError, match="control_limit: expected a positive number or 1"):
        sampling_planner(step, cost, 10, control_limit=[10.0, 5.0])
    with pytest.raises(ValueError, match="actuation: expected 2 rows"):
        discrete_dynamics(f, 0.02, [[1.0]])
    with pytest.raises(ValueError, match="force_limit: expected a positive number or 1"):
        MuJoCoPlant("cart-pole", ["x"], force_limit=[1.0, 2.0])
    with pytest.raises(ValueError, match="actuated: expected"):
        MuJoCoPlant("cart-pole", ["y"], force_limit=1.0)


def test_cli_reports_an_error_without_a_traceback(capsys):
    from pysindy_xl.cli import main
    with pytest.raises(SystemExit):
        main(["control", "triple-pendulum"])
    assert "invalid choice" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("catalog", ["automatic", "kinematic", "generic"])
def test_cli_learns_the_cart_pole_swing_up(tmp_path, catalog):
    """The whole loop, identified from noisy positions, through the command line."""
    from pysindy_xl.cli import main
    out = tmp_path / "control.json"
    status = main(["control", "cart-pole", "--seed", "0", "--catalog", catalog,
                   "--out", str(out), "--quiet"])
    report = json.loads(out.read_text())
    assert status == 0 and report["success"] and report["catalog"] == catalog
    for key in ("interaction_s", "episodes", "force_limit", "max_abs_force", "track_limit",
                "max_abs_x", "upright_s", "mpc_step_ms", "equations"):
        assert key in report
    assert report["max_abs_force"] <= 10.0 and report["max_abs_x"] <= 1.5
    assert run_control is not None
