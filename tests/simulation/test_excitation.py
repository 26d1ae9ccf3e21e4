"""Excitation trajectories: the Fourier series, its limits, its conditioning, its files.

Ground truth: sympy's derivatives of the series, finite differences, MuJoCo's inverse
dynamics (``mj_inverse``) for the torques of the MJCF, MuJoCo's actuator law for the servo
controls.
"""

import mujoco
import numpy as np
import pytest
import sympy as sp

from pysindy_xl.data.tables import read_csv
from pysindy_xl.mujoco import (
    FourierTrajectory,
    MJCFSystem,
    actuator_law,
    excitation_trajectory,
    generate_dataset,
    kinematic_catalog,
)

# Two pitch joints in gravity with limits, armature, damping and position servos.
SERVO_ARM = """<mujoco model="servo_arm"><compiler angle="radian"/>
<option timestep="0.001" integrator="RK4" gravity="0 0 -9.81"><flag contact="disable"/></option>
<worldbody><body name="upper"><joint name="shoulder" axis="0 1 0" range="-1.5 1.5"
  armature="0.02" damping="0.2"/><inertial pos="0.15 0 -0.02" mass="1.5"
  fullinertia="0.01 0.012 0.008 0.001 -0.0005 0.0007"/>
 <body name="fore" pos="0.3 0 0"><joint name="elbow" axis="0 1 0" range="-2 2" armature="0.01"
  damping="0.1"/><inertial pos="0.1 0.01 0.01" mass="0.8" diaginertia="0.004 0.005 0.003"/>
 </body></body></worldbody>
<actuator><position joint="shoulder" kp="400" kv="20" ctrlrange="-1.4 1.4"/>
<position joint="elbow" kp="200" kv="8" ctrlrange="-1.8 1.8"/></actuator></mujoco>"""

LIMITS = dict(velocity_limits=[2.0, 2.5], acceleration_limits=[6.0, 8.0],
              torque_limits=[6.0, 2.0])


@pytest.fixture(scope="module")
def system():
    return MJCFSystem(SERVO_ARM)


@pytest.fixture(scope="module")
def designs(system):
    kwargs = dict(n_harmonics=3, period=4.0, restarts=1, seed=3, **LIMITS)
    return (excitation_trajectory(system, **kwargs),
            [excitation_trajectory(system, optimize=False, **(kwargs | {"seed": s}))
             for s in range(3)])


def random_series(seed=0, n=2, harmonics=3, period=2.5):
    rng = np.random.default_rng(seed)
    return FourierTrajectory(rng.normal(size=n), rng.normal(size=(n, harmonics)),
                             rng.normal(size=(n, harmonics)), period, names=["x", "y"][:n])


def test_the_series_and_its_derivatives_are_swevers_and_exact():
    trajectory = random_series()
    t = sp.Symbol("t")
    w = 2 * sp.pi / sp.nsimplify(trajectory.period)
    times = np.linspace(-1.0, 7.0, 9)
    for j in range(2):
        q = trajectory.q0[j] + sum(
            trajectory.a[j, l] / (w * (l + 1)) * sp.sin(w * (l + 1) * t)
            - trajectory.b[j, l] / (w * (l + 1)) * sp.cos(w * (l + 1) * t) for l in range(3))
        for order, method in enumerate((trajectory.q, trajectory.qd, trajectory.qdd)):
            exact = sp.lambdify(t, sp.diff(q, t, order))(times)
            np.testing.assert_allclose(method(times)[:, j], exact, rtol=1e-12, atol=1e-12)
    h = 1e-5  # and against finite differences of the method above
    np.testing.assert_allclose((trajectory.q(times + h) - trajectory.q(times - h)) / (2 * h),
                               trajectory.qd(times), rtol=1e-7, atol=1e-8)
    np.testing.assert_allclose((trajectory.qd(times + h) - trajectory.qd(times - h)) / (2 * h),
                               trajectory.qdd(times), rtol=1e-7, atol=1e-8)
    for method in (trajectory.q, trajectory.qd, trajectory.qdd):  # periodic
        np.testing.assert_allclose(method(times + trajectory.period), method(times),
                                   atol=1e-12)
        assert method(0.3).shape == (2,)


def test_the_design_keeps_every_limit(system, designs):
    best, randoms = designs
    limits = best.info["limits"]
    t = np.linspace(0.0, best.period, 4001)
    for trajectory in (best, *randoms):
        q, qd, qdd = trajectory.q(t), trajectory.qd(t), trajectory.qdd(t)
        low, high = np.array(limits["position"]).T
        assert np.all(q >= low - 1e-9) and np.all(q <= high + 1e-9)
        assert np.all(np.abs(qd) <= np.array(LIMITS["velocity_limits"]) * (1 + 1e-3))
        assert np.all(np.abs(qdd) <= np.array(LIMITS["acceleration_limits"]) * (1 + 1e-3))
        # MuJoCo's inverse dynamics of the MJCF: the torques the servos must give
        model = system.mj_model()
        data = mujoco.MjData(model)
        torques = np.empty_like(q)
        for k in range(0, len(t), 10):
            data.qpos[:], data.qvel[:], data.qacc[:] = q[k], qd[k], qdd[k]
            mujoco.mj_inverse(model, data)
            torques[k] = data.qfrc_inverse
        assert np.all(np.abs(torques[::10]) <= np.array(LIMITS["torque_limits"]) * (1 + 1e-3))
        # the random series touch a limit (they are scaled to them): a fair baseline
        assert trajectory.info["optimized"] or max(
            np.abs(torques[::10]).max(axis=0) / LIMITS["torque_limits"]) > 0.99 or max(
            np.abs(qd).max(axis=0) / LIMITS["velocity_limits"]) > 0.99 or max(
            np.abs(qdd).max(axis=0) / LIMITS["acceleration_limits"]) > 0.99 or np.any(
            np.isclose(q, low, atol=1e-3) | np.isclose(q, high, atol=1e-3))
    # the default position limits: the joint ranges within the servos' control ranges, 5 %
    np.testing.assert_allclose(limits["position"], [[-1.26, 1.26], [-1.62, 1.62]])
    # starts and ends at rest
    np.testing.assert_allclose(best.qd(0.0), 0.0, atol=1e-9)
    np.testing.assert_allclose(best.qdd(best.period), 0.0, atol=1e-9)


def test_the_optimized_regressor_is_better_conditioned(system, designs):
    best, randoms = designs
    conditions = [r.condition_number for r in randoms]
    assert best.condition_number < min(0.6 * np.median(conditions), min(conditions))
    # the reported number is that of the catalog's regressor along the trajectory
    library = kinematic_catalog(system).library().fit()
    t = np.linspace(0.0, best.period, 301)[:-1]
    from pysindy_xl import stack_variables

    theta = library.transform(stack_variables(best.q(t), best.qd(t), best.qdd(t)))
    theta = np.delete(theta, library.force_columns_, axis=1)
    assert np.linalg.cond(theta) == pytest.approx(best.condition_number, rel=1e-3)
    # deterministic
    again = excitation_trajectory(system, n_harmonics=3, period=4.0, restarts=1, seed=3,
                                  **LIMITS)
    np.testing.assert_array_equal(again.a, best.a)


def test_the_progress_bar_counts_iterations_and_changes_nothing(system, designs, capsys):
    """The bar advances by every start's share of iterations (stopping early counts the
    rest) and shows the best condition number; the design is the one made without it."""
    kwargs = dict(n_harmonics=3, period=4.0, restarts=1, seed=3, **LIMITS)
    shown = excitation_trajectory(system, progress=True, **kwargs)
    np.testing.assert_array_equal(shown.a, designs[0].a)
    np.testing.assert_array_equal(shown.b, designs[0].b)
    err = capsys.readouterr().err
    assert "excitation design" in err and "100/100" in err
    assert f"condition={shown.condition_number:.3g}" in err


def test_the_csv_and_the_json_round_trip(tmp_path):
    trajectory = random_series(1)
    path = tmp_path / "excitation.csv"
    trajectory.to_csv(path, rate=200.0, periods=2)
    data = read_csv(path).trajectories[0]
    t = np.arange(int(2 * 2.5 * 200) + 1) / 200.0
    np.testing.assert_allclose(data.t, t, rtol=0, atol=1e-12)
    for read, method in ((data.q, trajectory.q), (data.qd, trajectory.qd),
                         (data.qdd, trajectory.qdd)):
        np.testing.assert_allclose(read, method(t), rtol=1e-15, atol=1e-15)
    assert list(read_csv(path).coordinate_names) == ["x", "y"]
    copy = FourierTrajectory.from_dict(trajectory.to_dict())
    np.testing.assert_array_equal(copy.q(t), trajectory.q(t))


def test_the_servos_follow_the_reference(system, designs):
    best = designs[0]
    # MuJoCo's actuator law under the controls: the position term vanishes on the reference
    # (a position servo's kv damps the velocity, not the velocity error)
    law = actuator_law(system, best.controls(system))
    t = np.linspace(0.0, 2 * best.period, 50)
    np.testing.assert_allclose(law(t, best.q(t), np.zeros((50, 2))), 0.0, atol=1e-9)
    # generate_dataset plays it through the servos
    data = generate_dataset(system, n_trajectories=1, duration=best.period, seed=0,
                            reference=best, sample_every=10, progress=False)
    trajectory = data.trajectories[0]
    # the run starts on the reference; the recording once the servos' stiff modes settled
    np.testing.assert_allclose(trajectory.info["q0"], best.q(0.0), atol=1e-9)
    assert trajectory.t[0] == pytest.approx(trajectory.info["settle"]) and trajectory.t[0] > 0
    error = np.abs(trajectory.q - best.q(trajectory.t)).max(axis=0)
    assert np.all(error < 0.2 * np.ptp(best.q(trajectory.t), axis=0))
    assert FourierTrajectory.from_dict(data.metadata["reference"]).condition_number == (
        best.condition_number)


def test_bad_inputs_are_named(system, tmp_path):
    def raises(error, match, call):
        with pytest.raises(error, match=match):
            call()

    raises(ValueError, "period", lambda: FourierTrajectory([0.0], [[1.0]], [[0.0]], -1.0))
    raises(ValueError, "a, b", lambda: FourierTrajectory([0.0, 1.0], [[1.0]], [[0.0]], 1.0))
    raises(ValueError, "q0", lambda: FourierTrajectory([np.nan], [[1.0]], [[0.0]], 1.0))
    raises(ValueError, "names", lambda: FourierTrajectory([0.0], [[1.0]], [[0.0]], 1.0,
                                                          names=["a", "b"]))
    raises(ValueError, "rate", lambda: random_series().to_csv(tmp_path / "x.csv", rate=0))
    raises(ValueError, "data", lambda: FourierTrajectory.from_dict({"q0": [0.0]}))
    raises(ValueError, "n_harmonics", lambda: excitation_trajectory(system, n_harmonics=0))
    raises(ValueError, "period", lambda: excitation_trajectory(system, period="10"))
    raises(ValueError, "velocity_limits",
           lambda: excitation_trajectory(system, velocity_limits=[1.0, -1.0]))
    raises(ValueError, "position_limits",
           lambda: excitation_trajectory(system, position_limits=[[1.0, -1.0], [0, 1]]))
    raises(ValueError, "torque_limits",  # cannot even hold the arm up
           lambda: excitation_trajectory(system, n_harmonics=1, torque_limits=0.1))
    raises(TypeError, "seed", lambda: excitation_trajectory(system, seed=1.5))
    motors = MJCFSystem(SERVO_ARM.replace('<position joint="shoulder" kp="400" kv="20"',
                                          '<motor joint="shoulder"'))
    raises(ValueError, "reference.*'actuator0'.*position servo",
           lambda: random_series().controls(motors))
    unlimited = MJCFSystem(SERVO_ARM.replace(' range="-2 2"', ""))
    raises(ValueError, "position_limits.*elbow", lambda: excitation_trajectory(unlimited))
    raises(TypeError, "reference", lambda: generate_dataset(system, reference=[0.0]))
