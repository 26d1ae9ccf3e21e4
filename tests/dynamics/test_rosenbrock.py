"""ROS2, the linearly implicit path of MassMatrixDynamics.simulate: stiff closed loops."""

import numpy as np
import pytest
import sympy as sp

import pysindy_xl as px
from pysindy_xl.dynamics import SimulationError


def _stiff_servo_pair():
    """Two coupled links, the second light (1e-3) under a stiff servo: |lambda| ~ 2e3 1/s."""
    c = px.Coordinates(["a", "b"])
    a, b = c.q
    (ad, bd), (add, bdd) = c.qd, c.qdd
    equations = [
        0.5 * add + 0.01 * sp.cos(a - b) * bdd + 0.2 * ad + 3.0 * sp.sin(a)
        - c.tau[0],
        0.01 * sp.cos(a - b) * add + 1e-3 * bdd + 0.01 * bd - c.tau[1],
    ]
    dynamics = px.MassMatrixDynamics(c, equations)

    def servo(t, q, qd):
        reference = np.array([0.5 * np.sin(2 * t), 0.3 * np.sin(3 * t)])
        rate = np.array([np.cos(2 * t), 0.9 * np.cos(3 * t)])
        return np.array([40.0, 5.0]) * (reference - q) + np.array([4.0, 2.0]) * (rate - qd)

    return dynamics, servo


def test_ros2_agrees_with_dop853_in_a_stiff_closed_loop():
    dynamics, servo = _stiff_servo_pair()
    t = np.linspace(0.0, 1.0, 101)
    accurate = dynamics.simulate([0.0, 0.0, 1.0, 0.9], t, feedback=servo)
    fast = dynamics.simulate([0.0, 0.0, 1.0, 0.9], t, feedback=servo, method="ROS2",
                             step=2e-3)
    assert np.abs(fast[:, :2] - accurate[:, :2]).max() < 1e-4
    assert np.abs(fast[:, 2:] - accurate[:, 2:]).max() < 5e-3  # local error 1e-3


def test_ros2_reports_divergence_with_the_valid_part():
    c = px.Coordinates(["x"])
    unstable = px.MassMatrixDynamics(c, [c.qdd[0] - 100.0 * c.q[0]])  # x'' = 100 x
    t = np.linspace(0.0, 5.0, 51)
    with pytest.raises(SimulationError, match="diverged") as caught:
        unstable.simulate([1.0, 0.0], t, method="ROS2", divergence_bound=1e6)
    assert 1 <= len(caught.value.states) < len(t)
    with pytest.raises(ValueError, match="step"):
        unstable.simulate([1.0, 0.0], t, method="ROS2", step=-1.0)
