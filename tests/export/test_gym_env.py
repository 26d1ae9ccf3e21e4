"""XLSINDy.to_gymnasium: a Gymnasium environment driven by the identified dynamics."""

import importlib
import sys
import warnings

import numpy as np
import pytest
from support.files import pendulum

import pysindy_xl as px
from pysindy_xl._optional import MissingExtraError

gymnasium = pytest.importorskip("gymnasium")


@pytest.fixture(scope="module")
def model():
    """Damped pendulum 0.5 qdd + 0.2 qd + 4.9 sin q = tau, identified from exact data."""
    from pysindy_xl.mujoco import coordinate_system, reference_catalog

    t, q, qd, qdd, tau = pendulum(401)
    catalog = reference_catalog(coordinate_system("theta", angles="theta"), "mixed",
                                trig_degree=1)
    return px.XLSINDy(catalog, px.ExplicitOptimizer()).fit(
        q[:, None], t, x_dot=qd[:, None], x_ddot=qdd[:, None], u=tau[:, None])


def test_check_env_passes_without_warnings(model):
    from gymnasium.utils.env_checker import check_env

    env = model.to_gymnasium(0.05)  # dt alone is enough
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env, skip_render_check=True)
    assert env.observation_space.shape == (2,) and env.action_space.shape == (1,)


def test_steps_follow_the_identified_dynamics(model):
    env = model.to_gymnasium(0.01, substeps=4, action_bounds=2.0)
    x0 = np.array([0.3, -0.2])
    observation, _ = env.reset(seed=1, options={"state": x0})
    np.testing.assert_array_equal(observation, x0)
    states = [observation]
    for _ in range(100):
        observation, *_ = env.step(np.array([0.7], dtype=np.float32))
        states.append(observation)
    t = np.arange(101) * 0.01
    reference = model.simulate(x0, t, u=np.full((101, 1), 0.7), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(np.array(states), reference, atol=1e-7)
    # and the reference is the true pendulum, not something trivial: it moved
    assert abs(reference[-1, 0] - x0[0]) > 0.1


def test_user_reward_termination_and_truncation(model):
    env = model.to_gymnasium(0.05, reward=lambda s, a, s1: -float(s1[0] ** 2),
                             terminated=lambda s1: abs(s1[0]) > 0.5,
                             initial_state=[0.45, 2.0], max_episode_steps=50)
    observation, _ = env.reset(seed=0)
    np.testing.assert_array_equal(observation, [0.45, 2.0])
    observation, reward, terminated, truncated, info = env.step(np.zeros(1))
    assert reward == pytest.approx(-observation[0] ** 2)
    assert terminated and not truncated and observation[0] > 0.5
    assert info["time"] == pytest.approx(0.05)
    short = model.to_gymnasium(0.05, max_episode_steps=3)
    short.reset(seed=0)
    flags = [short.step(np.zeros(1))[3] for _ in range(3)]
    assert flags == [False, False, True]
    # a random initial state from the seed: reproducible
    a, _ = model.to_gymnasium(0.05).reset(seed=3)
    b, _ = model.to_gymnasium(0.05).reset(seed=3)
    np.testing.assert_array_equal(a, b)
    assert np.all(np.abs(a) <= 0.05) and np.any(a != 0)


def test_actions_are_clipped_and_checked(model):
    env = model.to_gymnasium(0.05, action_bounds=0.5)
    env.reset(options={"state": [0.0, 0.0]})
    clipped = env.step(np.array([10.0]))[0]
    env.reset(options={"state": [0.0, 0.0]})
    bound = env.step(np.array([0.5]))[0]
    np.testing.assert_array_equal(clipped, bound)
    with pytest.raises(ValueError, match=r"action: expected shape \(1,\)"):
        env.step(np.zeros(2))
    with pytest.raises(ValueError, match=r"action: expected finite values, got \[nan\]"):
        env.step(np.array([np.nan]))
    with pytest.raises(TypeError, match="action: expected real numbers, got complex values"):
        env.step(np.array([0.1 + 1j]))


@pytest.mark.parametrize("options, match", [
    ({"dt": 0.0}, "dt: expected a positive number"),
    ({"dt": "fast"}, "dt: expected a positive number"),
    ({"actuated": ["phi"]}, r"actuated: 'phi' is not a coordinate of \['theta'\]"),
    ({"action_bounds": [1.0, 2.0]}, "action_bounds: expected a number or 1 values"),
    ({"initial_state": [0.0]}, r"initial_state: expected 2 finite values"),
    ({"max_episode_steps": 0}, "max_episode_steps"),
    ({"substeps": 0}, "substeps"),
    ({"reward": 1.0}, "reward: expected a callable"),
])
def test_bad_options_name_the_argument(model, options, match):
    options = {"dt": 0.05, **options}
    with pytest.raises((ValueError, TypeError), match=match):
        model.to_gymnasium(**options)


def test_unfitted_model_is_refused():
    from sklearn.exceptions import NotFittedError

    coords = px.Coordinates(["x"])
    lib = px.CatalogRepartition([px.ExternalForces(coords),
                                 px.LagrangeLibrary(coords, [coords.qd[0] ** 2])])
    with pytest.raises(NotFittedError):
        px.XLSINDy(lib).to_gymnasium(0.1)


def test_missing_gymnasium_names_the_extra(model, monkeypatch):
    monkeypatch.setitem(sys.modules, "gymnasium", None)
    monkeypatch.delitem(sys.modules, "pysindy_xl.export.gym_env", raising=False)
    with pytest.raises(MissingExtraError, match=r'pip install "pysindy-xl\[gym\]"'):
        model.to_gymnasium(0.05)
    with pytest.raises(MissingExtraError):
        importlib.import_module("pysindy_xl.export.gym_env")
