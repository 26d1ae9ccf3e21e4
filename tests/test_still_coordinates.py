"""Coordinates that hold still in the data (issue 34): detected, left out, held by the model.

The MJCF model ``pendulum_and_target.xml`` is a driven pendulum next to a passive target on
two slide joints, decoupled from it. A target at rest stays at rest: its recorded positions
are constant (plus sensor noise), which carries no information about its dynamics.
"""

import pathlib
import pickle
import warnings

import numpy as np
import pytest

import pysindy_xl as px
from pysindy_xl.evaluation.physics import compare_physics
from pysindy_xl.fit.still import driven_coordinates, noise_level, still_coordinates
from pysindy_xl.mujoco import MJCFSystem, generate_dataset, reference_catalog
from pysindy_xl.quality import fit_quality, quality_lines

MODELS = pathlib.Path(__file__).parent / "models"
PATH = MODELS / "pendulum_and_target.xml"
TARGET = ["target_x", "target_y"]
REST = np.array([0.3, -0.2])  # where the target rests


@pytest.fixture(scope="module")
def systems():
    return MJCFSystem(PATH), MJCFSystem(PATH, joints=["swing"])


def _with_resting_target(arguments, sensor_noise=0.0, seed=1):
    """The pendulum's data with the target at rest appended (zero force, zero motion)."""
    rng = np.random.default_rng(seed)
    out = dict(arguments)
    out["x"] = [np.column_stack([x, REST + sensor_noise * rng.normal(size=(len(x), 2))])
                for x in arguments["x"]]
    for key in ("x_dot", "x_ddot", "u"):
        if arguments.get(key) is not None:
            out[key] = [np.column_stack([v, np.zeros((len(v), 2))]) for v in arguments[key]]
    return out


def _pendulum_data(swing, noise):
    data = generate_dataset(swing, n_trajectories=2, duration=3.0, noise=noise, seed=0,
                            sample_every=2, progress=False)
    return data.fit_arguments()


@pytest.mark.parametrize("noise, sensor, tolerance", [(0.0, 0.0, 1e-8), (0.01, 1e-4, 0.01)])
@pytest.mark.parametrize("optimizer", [None, "mixed"])
def test_fit_with_resting_target_leaves_it_out(systems, noise, sensor, tolerance, optimizer,
                                               capsys):
    full, swing = systems
    arguments = _with_resting_target(_pendulum_data(swing, noise), sensor)
    with warnings.catch_warnings():
        warnings.simplefilter("error", px.IdentificationWarning)
        model = px.XLSINDy(reference_catalog(full, "kinematic", trig_degree=1),
                           optimizer=optimizer).fit(**arguments)
    assert model.still_coordinates_ == TARGET
    dropped = {name: reason for name, reason in model.dropped_features_.items()
               if "still" in reason}
    assert dropped and all("target" in name for name in dropped)
    # the pendulum's law against MuJoCo's mass matrix and bias forces (mj_fullM, qfrc_bias)
    physics = compare_physics(model, full)
    assert physics["held"] == TARGET and not physics["unidentified"]
    assert physics["mass_error"] < tolerance and physics["force_error"] < tolerance
    # the held target: zero acceleration, fixed at rest in a simulation
    assert model.equations()[1:] == ["target_x_ddot = 0 (held still)",
                                     "target_y_ddot = 0 (held still)"]
    states = model.simulate(np.r_[0.5, REST, 0.0, 0.0, 0.0], np.linspace(0, 1, 11))
    assert np.all(states[:, 1:3] == REST) and np.all(states[:, 4:] == 0)
    acc = model.predict(arguments["x"][0][:5], np.zeros((5, 3)))
    assert np.all(acc[:, 1:] == 0) and np.all(np.isfinite(acc))
    model.print()
    assert "held still" in capsys.readouterr().out
    quality = fit_quality(model, arguments)
    assert quality["held_still"] == TARGET and list(quality["r2_per_coordinate"]) == ["swing"]
    assert quality["r2"] > 0.99
    assert any("held still: target_x, target_y" in line for line in quality_lines(quality))


def test_drifting_decoupled_target_is_held(systems):
    """MuJoCo's own data: the target drifts at its random initial velocity, undriven."""
    full, _ = systems
    data = generate_dataset(full, n_trajectories=2, duration=3.0, seed=0, sample_every=2,
                            progress=False)
    model = px.XLSINDy(reference_catalog(full, "kinematic", trig_degree=1)).fit(
        **data.fit_arguments())
    assert model.still_coordinates_ == TARGET
    physics = compare_physics(model, full)
    assert physics["mass_error"] < 1e-8 and physics["force_error"] < 1e-8
    # a held coordinate keeps its velocity, as the decoupled body does
    states = model.simulate(np.r_[0.0, REST, 0.0, 0.5, -0.1], np.linspace(0, 1, 3))
    assert np.allclose(states[-1, 1:3], REST + [0.5, -0.1]) and np.allclose(states[:, 4:],
                                                                           [0.5, -0.1])


def test_all_moving_unchanged(systems):
    """Every coordinate moves: nothing is held, the fit is the same as without the option."""
    _, swing = systems
    for noise in (0.0, 0.01):
        arguments = _pendulum_data(swing, noise)
        catalog = reference_catalog(swing, "kinematic", trig_degree=1)
        held = px.XLSINDy(catalog).fit(**arguments)
        plain = px.XLSINDy(catalog, hold_still=False).fit(**arguments)
        assert held.still_coordinates_ == [] == plain.still_coordinates_
        np.testing.assert_array_equal(held.coefficients(), plain.coefficients())
        assert held.dropped_features_ == plain.dropped_features_


def test_round_trip_keeps_the_still_set(systems, tmp_path):
    full, swing = systems
    arguments = _with_resting_target(_pendulum_data(swing, 0.0))
    model = px.XLSINDy(reference_catalog(full, "kinematic", trig_degree=1)).fit(**arguments)
    path = tmp_path / "model.json"
    model.save(path)
    x0, t = np.r_[0.5, REST, 1.0, 0.1, 0.0], np.linspace(0, 1, 11)
    for loaded in (px.XLSINDy.load(path), pickle.loads(pickle.dumps(model))):
        assert loaded.still_coordinates_ == TARGET and loaded.hold_still == 2.0
        assert loaded.equations() == model.equations()
        np.testing.assert_array_equal(loaded.simulate(x0, t), model.simulate(x0, t))


def test_disabled_restores_todays_behaviour(systems):
    full, swing = systems
    catalog = reference_catalog(full, "kinematic", trig_degree=1)
    arguments = _with_resting_target(_pendulum_data(swing, 0.0))
    with pytest.raises(ValueError, match="'target_x' is constant on every sample"):
        px.XLSINDy(catalog, hold_still=False).fit(**arguments)
    # with sensor noise on the resting target, the default (mixed) fit fails as before
    jittered = _with_resting_target(_pendulum_data(swing, 0.0), sensor_noise=1e-4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ValueError, match="receive no force"):
            px.XLSINDy(catalog, hold_still=False).fit(**jittered)
        model = px.XLSINDy(catalog, px.ImplicitOptimizer(), hold_still=False).fit(**jittered)
    assert model.still_coordinates_ == []
    assert not any("still" in reason for reason in model.dropped_features_.values())
    with pytest.raises(TypeError, match="hold_still"):
        px.XLSINDy(catalog, hold_still=True).fit(**jittered)
    with pytest.raises(ValueError, match="hold_still"):
        px.XLSINDy(catalog, hold_still=-1.0).fit(**jittered)


def test_criterion():
    rng = np.random.default_rng(0)
    t = np.linspace(0, 10, 2001)
    sigma = 0.01
    noise = sigma * rng.normal(size=(len(t), 4))
    x = np.column_stack([np.sin(t), 0.2 * np.ones_like(t), 6 * sigma * np.sin(2 * t),
                         0.5 + 0.2 * t]) + noise
    assert abs(noise_level(x)[1] - sigma) < 0.1 * sigma
    undriven = np.zeros(4, dtype=bool)
    # at rest and drifting: still; a motion of a few noise levels: still only below kappa
    assert still_coordinates([x], [t], undriven, 3.0).tolist() == [False, True, False, True]
    assert still_coordinates([x], [t], undriven, 10.0).tolist() == [False, True, True, True]
    # a driven coordinate is never still; still must hold on every trajectory
    assert not still_coordinates([x], [t], np.ones(4, dtype=bool), 3.0).any()
    moving = x.copy()
    moving[:, 1] = np.cos(t)
    assert still_coordinates([x, moving], [t, t], undriven, 3.0).tolist() == [
        False, False, False, True]
    c = px.Coordinates(["a", "b"])
    library = px.CatalogRepartition([px.LagrangeLibrary(c, [c.qd[0] ** 2])]).fit()
    assert driven_coordinates(library, None).tolist() == [False, False]
    assert driven_coordinates(library, [np.zeros((3, 2))]).tolist() == [False, False]


def test_nothing_moves_is_an_error():
    c = px.Coordinates(["x"])
    library = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
    t = np.linspace(0, 1, 101)
    with pytest.raises(ValueError, match="no coordinate moves"):
        px.XLSINDy(library).fit(np.full((101, 1), 0.5), t, x_dot=np.zeros((101, 1)),
                                x_ddot=np.zeros((101, 1)))
