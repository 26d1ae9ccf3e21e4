"""Users' MJCF models: joint limits, dry friction, joint selection, noise model, validation.

The models live in ``tests/models``: a cart on a short rail whose slider limit is hit, a
pendulum with a joint stop, a block with frictionloss, a pendulum next to a passive target on
two slide joints, an arm split over two files with ``<include>``.
"""

import pathlib
import warnings

import numpy as np
import pytest

import pysindy_xl as px
from pysindy_xl.data import noise_levels, unconstrained_samples, unconstrained_windows
from pysindy_xl.mujoco import (
    ConstraintWarning,
    MJCFSystem,
    SumOfSinusoids,
    compare_trajectories,
    generate_dataset,
    reference_catalog,
    simulate_trajectory,
    system_from_metadata,
    validate_model,
    validation_trajectory,
)
from pysindy_xl.simulation.generate import actuator_force_function

MODELS = pathlib.Path(__file__).parent / "models"

# cart 1 kg, bob 0.5 kg at 0.8 m (inertia 1e-6), dampings 0.5 and 0.1
RAIL_CART_TRUTH = {
    "L[slider_dot**2]": 0.75, "L[hinge_dot*slider_dot*cos(hinge)]": 0.4,
    "L[hinge_dot**2]": 0.160001, "L[cos(hinge)]": 3.924, "C_slider[slider_dot]": 0.5,
    "C_hinge[hinge_dot]": 0.1,
}


def fit(system, dataset, catalog=None, **arguments):
    catalog = catalog or reference_catalog(system, "mixed", trig_degree=1)
    model = px.XLSINDy(catalog, px.ExplicitOptimizer()).fit(**dataset.fit_arguments(
        **arguments))
    return model, dict(zip(model.get_feature_names(), model.coefficients(), strict=True))


def relative_errors(coefficients, truth):
    """Largest relative error on the true terms, and the spurious terms."""
    worst = max(abs(coefficients[k] - v) / abs(v) for k, v in truth.items())
    spurious = [k for k, v in coefficients.items()
                if v and k not in truth and not k.startswith("F[")]
    return worst, spurious


@pytest.fixture(scope="module")
def rail_cart():
    system = MJCFSystem(MODELS / "rail_cart.xml")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        data = generate_dataset(system, n_trajectories=2, duration=5.0, seed=0, amplitude=1.0,
                                backoff=False, sample_every=2, progress=False)
    return system, data, caught


def test_rail_cart_limit_is_recorded_and_reported(rail_cart):
    system, data, caught = rail_cart
    summary = data.metadata["constraints"]
    assert summary["active_fraction"] >= 0.10
    assert set(summary["limit_hits"]) == {"slider"}
    messages = [str(w.message) for w in caught if issubclass(w.category, ConstraintWarning)]
    assert len(messages) == 1 and "slider" in messages[0] and "rail_cart.xml" in messages[0]
    for tr in data.trajectories:
        # the slider stays near its rail (soft limit), the limit force acts exactly when marked
        assert np.abs(tr.q[:, 0]).max() < 0.3
        assert np.all(np.abs(tr.tau_constraint[~tr.constraint_active]) < 1e-12)
        assert np.all(np.abs(tr.tau_constraint[tr.constraint_active, 0]) > 0)
        np.testing.assert_allclose(tr.tau_constraint[:, 1], 0.0, atol=1e-12)


def test_rail_cart_constrained_samples_excluded_or_known(rail_cart):
    system, data, _ = rail_cart
    _, naive = fit(system, data, constraints="include")
    worst, _ = relative_errors(naive, RAIL_CART_TRUTH)
    assert worst > 0.5  # the limit force spoils a fit that ignores it
    for mode in ("exclude", "known"):
        _, coefficients = fit(system, data, constraints=mode)
        worst, spurious = relative_errors(coefficients, RAIL_CART_TRUTH)
        assert worst < 1e-4 and not spurious, mode
    kept = data.fit_arguments(constraints="exclude")
    n_kept = sum(len(x) for x in kept["x"])
    assert n_kept <= data.metadata["constraints"]["unconstrained_samples"]
    assert n_kept > 0.3 * sum(tr.n_samples for tr in data.trajectories)


def test_backoff_keeps_the_cart_off_its_stops():
    system = MJCFSystem(MODELS / "rail_cart.xml")
    data = generate_dataset(system, n_trajectories=2, duration=5.0, seed=0, amplitude=1.0,
                            sample_every=2, progress=False)
    for tr in data.trajectories:
        assert tr.constraint_active.mean() <= 0.10
        assert tr.info["backoff"] < 1.0


def test_pendulum_with_joint_stop():
    system = MJCFSystem(MODELS / "stop_pendulum.xml")
    rng = np.random.default_rng(0)
    starts = np.array([system.random_initial_state(rng)[0][0] for _ in range(200)])
    assert starts.min() >= -0.6 and starts.max() <= 0.6 and np.ptp(starts) > 0.8
    data = generate_dataset(system, n_trajectories=2, duration=5.0, seed=0, amplitude=1.0,
                            backoff=False, sample_every=2, progress=False)
    summary = data.metadata["constraints"]
    assert summary["limit_hits"].keys() == {"swing"} and summary["active_fraction"] > 0.02
    _, coefficients = fit(system, data)  # default: constrained samples excluded
    truth = {"L[swing_dot**2]": 0.125 + 5e-7, "L[cos(swing)]": 4.905,
             "C_swing[swing_dot]": 0.05}
    worst, spurious = relative_errors(coefficients, truth)
    assert worst < 1e-4 and not spurious
    _, naive = fit(system, data, constraints="include")
    assert relative_errors(naive, truth)[0] > 0.1


def test_initial_state_respects_ref_and_range():
    xml = """<mujoco><compiler angle="radian"/><option timestep="0.001"/><worldbody><body>
      <joint name="s" type="slide" axis="1 0 0" range="0 0.2" ref="0.05"/>
      <inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body></worldbody></mujoco>"""
    system = MJCFSystem(xml)
    rest = simulate_trajectory(system, 0.01)
    np.testing.assert_allclose(rest.q, 0.05)  # default start: the reference pose, at rest
    rng = np.random.default_rng(1)
    q0 = np.array([system.random_initial_state(rng, scale=0.5)[0][0] for _ in range(300)])
    # half of the way from ref to each end of the range (times 0.9)
    assert q0.min() >= 0.05 - 0.5 * 0.9 * 0.05 - 1e-12
    assert q0.max() <= 0.05 + 0.5 * 0.9 * 0.15 + 1e-12
    assert q0.min() < 0.04 and q0.max() > 0.1


def test_amplitude_is_a_fraction_of_ctrlrange():
    system = MJCFSystem(MODELS / "rail_cart.xml")
    for amplitude in (0.2, 1.0):
        data = generate_dataset(system, n_trajectories=1, duration=3.0, seed=0,
                                amplitude=amplitude, backoff=False, progress=False)
        peak = np.abs(data.trajectories[0].u).max(axis=0)
        assert np.all(peak <= amplitude * np.array([12.0, 2.0]) + 1e-12)
        assert peak[0] > 0.4 * amplitude * 12.0
    with pytest.raises(ValueError, match="amplitude"):
        generate_dataset(system, duration=0.1, amplitude=1.5, progress=False)


def test_frictionloss_is_recorded_and_identified():
    system = MJCFSystem(MODELS / "friction_slider.xml")
    np.testing.assert_array_equal(system.frictionloss, [0.5])
    data = generate_dataset(system, n_trajectories=2, duration=5.0, seed=0, sample_every=2,
                            progress=False)
    tr = data.trajectories[0]
    assert not tr.constraint_active.any()  # dry friction does not mark samples
    moving = np.abs(tr.qd[:, 0]) > 0.05
    assert moving.mean() > 0.5
    np.testing.assert_allclose(tr.tau_constraint[moving, 0], -0.5 * np.sign(tr.qd[moving, 0]),
                               atol=1e-6)
    catalog = reference_catalog(system, "mixed", trig_degree=1)
    assert "C_x[tanh(1000.0*x_dot)]" in catalog.fit().get_feature_names()
    model, coefficients = fit(system, data, catalog)
    assert coefficients["C_x[tanh(1000.0*x_dot)]"] == pytest.approx(0.5, rel=0.02)
    assert coefficients["C_x[x_dot]"] == pytest.approx(0.4, rel=0.02)
    assert coefficients["L[x_dot**2]"] == pytest.approx(1.0, rel=0.02)
    result = validate_model(model, system, duration=3.0, seed=5)
    assert result.valid and result.position_rmse < 0.01
    # without the dry-friction candidate the fit is biased; the known forces repair it
    plain = reference_catalog(system, "mixed", trig_degree=1, dry_friction=False)
    _, biased = fit(system, data, plain)
    assert abs(biased["C_x[x_dot]"] - 0.4) > 0.1
    _, known = fit(system, data, plain, constraints="known")
    assert known["C_x[x_dot]"] == pytest.approx(0.4, rel=1e-4)


def test_passive_decoupled_target_left_out():
    path = MODELS / "pendulum_and_target.xml"
    full = MJCFSystem(path)
    assert full.n == 3
    system = MJCFSystem(path, joints=["swing"])
    assert system.coordinate_names == ("swing",)
    assert system.excluded_joints == ("target_x", "target_y")
    data = generate_dataset(system, n_trajectories=2, duration=4.0, seed=0, sample_every=2,
                            progress=False)
    assert data.metadata["joints"] == ["swing"]
    model, coefficients = fit(system, data)
    m, l, g = 0.7, 0.6, 9.81
    truth = {"L[swing_dot**2]": m * l**2 / 2, "L[cos(swing)]": m * g * l,
             "C_swing[swing_dot]": 0.2}
    worst, spurious = relative_errors(coefficients, truth)
    assert worst < 1e-5 and not spurious
    assert validate_model(model, system, duration=3.0, seed=2).valid
    # the dataset rebuilds the same reduced system
    again = system_from_metadata(data.metadata)
    assert again.coordinate_names == ("swing",) and again.excluded_joints == system.excluded_joints
    with pytest.raises(ValueError, match="joints"):
        MJCFSystem(path, joints=["elbow"])


def test_include_resolves_and_dataset_embeds_flat_xml(tmp_path):
    system = MJCFSystem(MODELS / "included_arm.xml")
    assert system.coordinate_names == ("shoulder",)
    meta = system.metadata()
    assert "<include file" not in meta["model_xml"] and 'name="shoulder"' in meta["model_xml"]
    # without the files, the embedded XML rebuilds the model
    rebuilt = system_from_metadata({"system": "mjcf", "model_path": str(tmp_path / "gone.xml"),
                                    "model_xml": meta["model_xml"]})
    assert rebuilt.coordinate_names == ("shoulder",)
    assert rebuilt.mj_model().body_mass[1] == pytest.approx(1.5)


# -- noise model --------------------------------------------------------------------------
def test_default_noise_model_is_noisy_positions_only():
    clean = generate_dataset("cart-pole", n_trajectories=1, duration=3.0, seed=3,
                             progress=False)
    noisy = generate_dataset("cart-pole", n_trajectories=1, duration=3.0, seed=3, noise=0.02,
                             progress=False)
    assert noisy.metadata["noise_model"] == "positions"
    assert noisy.metadata["derivatives"] == "none"
    assert not noisy.has("qd") and not noisy.has("qdd")
    a, b = clean.trajectories[0], noisy.trajectories[0]
    ratio = (b.q - a.q).std(axis=0) / a.q.std(axis=0)
    np.testing.assert_allclose(ratio, 0.02, rtol=0.1)
    np.testing.assert_array_equal(b.tau, a.tau)  # forces are not perturbed
    arguments = noisy.fit_arguments()
    assert arguments["x_dot"] is None and arguments["x_ddot"] is None  # the fit differentiates
    # the paper's model: every channel perturbed and given to the fit
    paper = generate_dataset("cart-pole", n_trajectories=1, duration=3.0, seed=3, noise=0.02,
                             noise_model="all", progress=False)
    c = paper.trajectories[0]
    assert paper.metadata["derivatives"] == "mujoco"
    for key in ("qd", "qdd", "tau"):
        ratio = (getattr(c, key) - getattr(a, key)).std(axis=0) / getattr(a, key).std(axis=0)
        assert np.all((ratio > 0.015) & (ratio < 0.025)), key
    # noise-free data keep MuJoCo's exact derivatives unless asked otherwise
    assert clean.has("qdd")
    assert not generate_dataset("cart-pole", n_trajectories=1, duration=0.1, seed=3,
                                derivatives=False, progress=False).has("qd")


def test_noise_model_errors():
    with pytest.raises(ValueError, match="noise_model"):
        noise_levels(0.1, "velocities")
    with pytest.raises(ValueError, match="noise_model='all'"):
        noise_levels({"qd": 0.1}, "positions")
    assert noise_levels({"q": 0.1, "tau": 0.05}) == {"q": 0.1, "qd": 0.0, "qdd": 0.0,
                                                     "tau": 0.05}
    with pytest.raises(ValueError, match="noise_model"):
        generate_dataset("cart-pole", duration=0.1, noise_model="sensor", progress=False)


# -- validation ----------------------------------------------------------------------------
def test_validation_force_is_the_signal_mujoco_applies():
    reference = validation_trajectory("double-pendulum", duration=1.0, seed=0, substeps=1)
    signals = SumOfSinusoids.from_dict(reference.info["signals"])
    force = actuator_force_function("double-pendulum", signals)
    # the run holds each step's signal at its midpoint; a sample at t records the forces of
    # the continuous signal at t (what the identified model is given)
    np.testing.assert_allclose(force(reference.t), reference.tau, atol=1e-12)
    gear = actuator_force_function(MJCFSystem(MODELS / "stop_pendulum.xml"),
                                   SumOfSinusoids([[5.0]], [[0.25]], [[0.0]]))
    assert gear(1.0)[0] == pytest.approx(2 * 3.0)  # ctrl clipped to its range, times the gear


def test_fine_reference_makes_an_exact_model_validate_to_rounding():
    data = generate_dataset("cart-pole", n_trajectories=1, duration=4.0, seed=0,
                            sample_every=2, progress=False)
    model = px.XLSINDy(reference_catalog("cart-pole", trig_degree=1),
                       px.ExplicitOptimizer()).fit(**data.fit_arguments())
    coarse = validation_trajectory("cart-pole", duration=4.0, seed=1, substeps=1)
    coarse.info.pop("signals")  # as before: a spline of forces sampled every 10 steps
    old = validate_model(model, "cart-pole", trajectory=coarse)
    new = validate_model(model, "cart-pole", duration=4.0, seed=1)
    assert new.valid and new.position_rmse < 1e-6
    # the exact signal beats a spline of its samples every 10 steps (samples recorded at their
    # own instant: an order of magnitude, no longer the two of samples half a step late)
    assert new.position_rmse < old.position_rmse / 10


def test_stopped_simulation_has_infinite_rmse_over_the_horizon():
    t = np.linspace(0.0, 1.0, 101)
    reference = np.column_stack([np.sin(t), np.cos(t)])
    result = compare_trajectories(t, reference, reference[:10])
    assert result.position_rmse == np.inf and not result.valid
    assert result.simulated_rmse == 0.0 and result.divergence_time == pytest.approx(0.1)
    assert np.all(np.isinf(result.position_rmse_per_coordinate))


# -- helpers of the identification layer ---------------------------------------------------
def test_unconstrained_samples_and_windows():
    active = np.zeros(20, dtype=bool)
    active[[5, 12]] = True
    keep = unconstrained_samples(active, margin=1)
    assert np.flatnonzero(~keep).tolist() == [4, 5, 6, 11, 12, 13]
    both = unconstrained_samples([active, ~active])
    assert len(both) == 2 and not both[1][0]
    # windows of 5 samples every 3 samples
    starts = np.arange(0, 16, 3)
    support = (np.arange(20)[None, :] >= starts[:, None]) & (
        np.arange(20)[None, :] < starts[:, None] + 5)
    kept = unconstrained_windows(support, active)
    expected = [not active[s:s + 5].any() for s in starts]
    assert kept.tolist() == expected and any(expected) and not all(expected)
    with pytest.raises(ValueError, match="support"):
        unconstrained_windows(support[:, :10], active)
    with pytest.raises(ValueError, match="margin"):
        unconstrained_samples(active, margin=-1)
    with pytest.raises(ValueError, match="constraint_active"):
        unconstrained_samples(np.zeros((2, 2), dtype=bool))


def test_two_link_arm_physics_against_mujoco():
    """Armature, gear ratios, ctrlrange and small damping: the identified mass matrix and
    unforced dynamics match mj_fullM and qfrc_bias (threshold of the issue: 1e-3)."""
    from pysindy_xl.mujoco import compare_physics

    system = MJCFSystem(MODELS / "two_link_arm.xml")
    data = generate_dataset(system, n_trajectories=2, duration=5.0, seed=0, sample_every=2,
                            progress=False)
    catalog = reference_catalog(system, "mixed")
    model = px.XLSINDy(catalog, px.ExplicitOptimizer(threshold=1e-3)).fit(
        **data.fit_arguments())
    coefficients = dict(zip(model.get_feature_names(), model.coefficients(), strict=True))
    assert coefficients["C_shoulder[shoulder_dot]"] == pytest.approx(0.05, rel=0.02)
    assert coefficients["C_elbow[elbow_dot]"] == pytest.approx(0.02, rel=0.02)
    physics = compare_physics(model, system)
    assert physics["mass_error"] < 1e-8 and physics["force_error"] < 1e-8
    assert physics["positive_definite"] and physics["scale"] == 1.0
    # compared with a heavier upper link (1.3 kg instead of 1.2), the model is caught
    heavier = MJCFSystem((MODELS / "two_link_arm.xml").read_text().replace(
        'mass="1.2"', 'mass="1.3"'))
    wrong = compare_physics(model, heavier)
    assert wrong["mass_error"] > 0.01 and wrong["force_error"] > 0.01


def test_validation_stops_where_the_reference_hits_a_limit(rail_cart):
    system, data, _ = rail_cart
    model, _ = fit(system, data)
    reference = validation_trajectory(system, duration=4.0, seed=3, amplitude=1.0,
                                      backoff=False)
    assert reference.constraint_active.any()
    first = reference.t[np.argmax(reference.constraint_active)]
    result = validate_model(model, system, trajectory=reference)
    assert result.constrained_at == pytest.approx(first)
    assert result.t[-1] < first and result.valid and result.position_rmse < 1e-5
    ignored = validate_model(model, system, trajectory=reference, constraints="ignore")
    assert ignored.t[-1] == pytest.approx(4.0) and ignored.position_rmse > 1e-3
