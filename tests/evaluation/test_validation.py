"""Validation against MuJoCo: metrics, failures, the cart-pole acceptance case, a user MJCF."""

import numpy as np
import pytest

import pysindy_xl as px
from pysindy_xl.dynamics import SimulationError
from pysindy_xl.mujoco import (
    MJCFSystem,
    compare_trajectories,
    generate_dataset,
    plot_validation,
    reference_catalog,
    true_coefficients,
    validate_model,
    validation_trajectory,
)


@pytest.fixture(scope="module")
def cart_pole_model():
    data = generate_dataset("cart-pole", n_trajectories=2, duration=10.0, seed=0,
                            sample_every=2, progress=False)
    return px.XLSINDy(reference_catalog("cart-pole"), px.ExplicitOptimizer()).fit(
        **data.fit_arguments())


def test_noise_free_explicit_cart_pole_is_valid_over_10_s(cart_pole_model):
    result = validate_model(cart_pole_model, "cart-pole", duration=10.0, seed=123)
    assert result.valid and result.failure is None and result.divergence_time is None
    assert result.position_rmse < 0.01
    assert result.t[-1] == pytest.approx(10.0)
    assert result.prediction.shape == result.reference.shape == (1001, 4)
    summary = result.to_dict()
    assert summary["valid"] is True and set(summary["position_rmse_per_coordinate"]) == {
        "x", "theta"}


def test_validation_under_mixed_forcing_and_joint_forces(cart_pole_model):
    reference = validation_trajectory("cart-pole", duration=3.0, forcing="mixed", seed=4)
    assert np.all(reference.u[:, 1] == 0)
    result = validate_model(cart_pole_model, "cart-pole", trajectory=reference)
    assert result.valid and result.position_rmse < 1e-3
    with pytest.raises(ValueError, match="force_input"):
        validate_model(cart_pole_model, trajectory=reference, force_input="ctrl")
    with pytest.raises(ValueError, match="system"):
        validate_model(cart_pole_model)


def test_metrics_on_known_trajectories():
    t = np.linspace(0, 10, 1001)
    reference = np.column_stack([np.sin(t), np.cos(t)])  # ptp of q = 2 -> bound 0.2 * 2
    prediction = reference + np.column_stack([0.1 * t, 0 * t])
    result = compare_trajectories(t, reference, prediction, coordinate_names=["a"])
    assert not result.valid and result.failure is None
    assert result.divergence_time == pytest.approx(4.0, abs=0.011)
    assert result.position_rmse == pytest.approx(np.sqrt(np.mean((0.1 * t) ** 2)))
    close = compare_trajectories(t, reference, reference + [0.05, 3.0])  # velocity errors ignored
    assert close.valid and close.position_rmse == pytest.approx(0.05)
    # a small motion uses the absolute floor of 1 (rad or m): 0.15 < 0.2 stays valid
    still = np.zeros((len(t), 2))
    assert compare_trajectories(t, still, still + [0.15, 0]).valid
    assert not compare_trajectories(t, still, still + [0.25, 0]).valid
    # non-finite states end the prediction
    broken = prediction.copy()
    broken[500:] = np.nan
    cut = compare_trajectories(t, reference, broken)
    assert len(cut.prediction) == 500 and cut.failure == "non-finite state"
    with pytest.raises(ValueError, match="prediction"):
        compare_trajectories(t, reference, np.zeros((5, 3)))
    with pytest.raises(ValueError, match="divergence_bound"):
        compare_trajectories(t, reference, reference, divergence_bound=0)


class BlowingUpModel:
    """Stands for an identified model whose simulation fails at t = 2."""

    def simulate(self, x0, t, u=None, **options):
        k = int(np.searchsorted(t, 2.0))
        states = np.tile(x0, (k, 1))
        raise SimulationError("stopped", 2.0, t[:k], states, "diverged")


def test_failed_simulation_is_invalid():
    reference = validation_trajectory("cart-pole", duration=3.0, seed=1)
    result = validate_model(BlowingUpModel(), "cart-pole", trajectory=reference)
    assert not result.valid and result.failure == "diverged"
    assert result.divergence_time <= 2.0 + 1e-9
    assert 0.6 < result.simulated_fraction < 0.7


USER_PENDULUM = """
<mujoco model="user_pendulum">
  <option timestep="0.001" integrator="RK4"><flag contact="disable"/></option>
  <worldbody>
    <body name="arm">
      <joint name="swing" type="hinge" axis="0 1 0" damping="0.2"/>
      <inertial pos="0 0 -0.6" mass="0.7" diaginertia="1e-8 1e-8 1e-8"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.6" size="0.02"/>
    </body>
  </worldbody>
  <actuator><motor joint="swing" gear="2"/></actuator>
</mujoco>
"""


def test_user_mjcf_hinge_simulated_identified_and_validated(tmp_path):
    path = tmp_path / "pendulum.xml"
    path.write_text(USER_PENDULUM)
    system = MJCFSystem(path)
    data = generate_dataset(system, n_trajectories=2, duration=5.0, seed=0, sample_every=2,
                            progress=False)
    catalog = reference_catalog(system, "mixed")
    model = px.XLSINDy(catalog, px.ExplicitOptimizer()).fit(**data.fit_arguments())
    names = model.get_feature_names()
    coef = dict(zip(names, model.coefficients(), strict=True))
    m, l, g = 0.7, 0.6, 9.81
    assert coef["L[swing_dot**2]"] == pytest.approx(m * l**2 / 2, rel=1e-6)
    assert coef["L[cos(swing)]"] == pytest.approx(m * g * l, rel=1e-6)
    assert coef["C_swing[swing_dot]"] == pytest.approx(0.2, rel=1e-6)
    assert np.count_nonzero(model.coefficients()) == 4  # with the force column
    result = validate_model(model, system, duration=5.0, seed=9)
    assert result.valid and result.position_rmse < 1e-3
    with pytest.raises(ValueError, match="no known true model"):
        true_coefficients(system, catalog)


def test_plot_written_as_png(cart_pole_model, tmp_path):
    result = validate_model(cart_pole_model, "cart-pole", duration=2.0, seed=5)
    truth, _ = true_coefficients("cart-pole", cart_pole_model.feature_library_)
    path = tmp_path / "figure.png"
    figure = plot_validation(result, path, cart_pole_model.get_feature_names(),
                             cart_pole_model.coefficients(), truth, title="cart-pole")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and path.stat().st_size > 10_000
    assert len(figure.axes) == 2 * 2 + 1
    bars = figure.axes[-1]
    assert len(bars.patches) == 2 * 7  # identified and true bars of the 7 active features
    with pytest.raises(ValueError, match="feature_names"):
        plot_validation(result, None, ["a"], cart_pole_model.coefficients())


CONTACT_PENDULUM = """
<mujoco><compiler angle="radian"/><option timestep="0.001" integrator="RK4"/>
  <worldbody>
    <geom name="wall" type="box" pos="0.6 0 0.5" size="0.05 0.5 0.6"/>
    <body pos="0 0 1">
      <joint name="swing" axis="0 1 0" damping="0.2" range="-1.5 1.5"/>
      <inertial pos="0 0 -0.6" mass="0.7" diaginertia="1e-4 1e-4 1e-4"/>
      <geom type="sphere" pos="0 0 -0.6" size="0.05" mass="0"/>
    </body>
  </worldbody>
  <actuator><motor joint="swing"/></actuator>
</mujoco>
"""


def test_compare_physics_skips_states_in_contact():
    from pysindy_xl.mujoco import compare_physics

    free = MJCFSystem(CONTACT_PENDULUM.replace('<option timestep="0.001" integrator="RK4"/>',
                                               '<option timestep="0.001" integrator="RK4">'
                                               '<flag contact="disable"/></option>'))
    data = generate_dataset(free, n_trajectories=1, duration=2.0, seed=0, sample_every=2,
                            progress=False)
    model = px.XLSINDy(reference_catalog(free, "mixed"), px.ExplicitOptimizer()).fit(
        **data.fit_arguments())
    walled = MJCFSystem(CONTACT_PENDULUM)  # the bob touches the wall beyond about 0.9 rad
    physics = compare_physics(model, walled, n_states=10, scale=1.0)
    assert physics["contact_states_skipped"] > 0
    assert physics["force_error"] < 1e-6 and physics["mass_error"] < 1e-6
    assert compare_physics(model, free, n_states=10, scale=1.0)["contact_states_skipped"] == 0
