"""Computed-torque tracking on the MuJoCo double pendulum (both joints driven by motors):
the model's inverse dynamics as feedforward cut the PD law's tracking error many times over.

Ground truth: MuJoCo is the plant; the model is the system's Lagrangian equations (sympy)."""

import numpy as np
import pytest

import pysindy_xl as px
from pysindy_xl.control.computed_torque import ComputedTorque
from pysindy_xl.control.plant import MuJoCoPlant
from pysindy_xl.mujoco import get_system


def _reference(t):
    w = np.array([2.0 * np.pi * 0.8, 2.0 * np.pi * 1.1])
    a = np.array([0.8, 0.6])
    return a * np.sin(w * t), a * w * np.cos(w * t), -a * w ** 2 * np.sin(w * t)


def _rms_error(controller):
    plant = MuJoCoPlant("double-pendulum", ["theta1", "theta2"], force_limit=200.0,
                        control_dt=0.002)
    q0, qd0, _ = _reference(0.0)
    plant.reset(q0, qd0)
    episode = plant.run(controller, 3.0)
    q_ref = np.stack([_reference(t)[0] for t in episode.t])
    return float(np.sqrt(np.mean((episode.q - q_ref) ** 2)))


@pytest.fixture(scope="module")
def true_model():
    system = get_system("double-pendulum")
    return px.MassMatrixDynamics(system.coords, [
        e - tau for e, tau in zip(system.equations_of_motion(), system.coords.tau, strict=True)])


@pytest.mark.parametrize("mode", ["feedforward", "computed-torque"])
def test_identified_feedforward_beats_pd_alone(true_model, mode):
    kp, kd = (30.0, 3.0) if mode == "feedforward" else (100.0, 20.0)
    pd = _rms_error(ComputedTorque(None, _reference, kp=30.0, kd=3.0, n=2))
    model = _rms_error(ComputedTorque(true_model, _reference, kp=kp, kd=kd, n=2, mode=mode))
    assert model < pd / 5


def test_tabulated_feedforward_matches_the_model_along_the_reference(true_model):
    times = np.linspace(0.0, 1.0, 501)
    tabulated = ComputedTorque(true_model, _reference, kp=5.0, kd=1.0, n=2,
                               feedforward_times=times)
    direct = ComputedTorque(true_model, _reference, kp=5.0, kd=1.0, n=2)
    state = np.array([0.1, -0.2, 0.3, 0.0])
    for t in (0.0, 0.5, 0.998):  # on the grid
        np.testing.assert_allclose(tabulated(state, t), direct(state, t), rtol=1e-9)


def test_bad_gains_and_modes_are_refused(true_model):
    with pytest.raises(ValueError, match="kp: expected a gain >= 0 or 2"):
        ComputedTorque(true_model, _reference, kp=[1.0, 2.0, 3.0], kd=1.0, n=2)
    with pytest.raises(ValueError, match="mode: expected one of"):
        ComputedTorque(true_model, _reference, kp=1.0, kd=1.0, n=2, mode="pid")
    with pytest.raises(TypeError, match="model: expected a fitted model"):
        ComputedTorque(object(), _reference, kp=1.0, kd=1.0, n=2)
