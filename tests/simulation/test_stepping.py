"""Steps taken in C (``mujoco.rollout``) against ``mj_step`` called in a Python loop."""

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from pysindy_xl.mujoco import MJCFSystem  # noqa: E402
from pysindy_xl.simulation.generate import simulate_trajectory  # noqa: E402
from pysindy_xl.simulation.integration import INTEGRATORS  # noqa: E402
from pysindy_xl.simulation.stepping import (  # noqa: E402
    ROLLOUT_MIN_STEPS,
    new_runner,
    step_controls,
)

# Two links under a position servo (with a filtered activation: an actuator state carried over
# the steps) and a motor; the elbow runs into its joint limit, so that the constraint solver,
# warm-started from the last step, acts on the data.
ARM = """
<mujoco model="two_links">
  <option timestep="0.002" integrator="RK4"><flag contact="disable"/></option>
  <worldbody>
    <body name="upper" pos="0 0 0.5">
      <joint name="shoulder" axis="0 1 0" damping="0.3"/>
      <inertial pos="0.15 0 0" mass="1.0" diaginertia="0.01 0.02 0.02"/>
      <body name="lower" pos="0.3 0 0">
        <joint name="elbow" axis="0 1 0" damping="0.1" range="-0.3 0.3" limited="true"/>
        <inertial pos="0.1 0 0" mass="0.3" diaginertia="2e-3 3e-3 3e-3"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <general joint="shoulder" dyntype="filter" dynprm="0.02" gainprm="40" biastype="affine"
             biasprm="0 -40 -4"/>
    <motor joint="elbow" gear="2"/>
  </actuator>
</mujoco>
"""


def _model(substeps=3):
    model = mujoco.MjModel.from_xml_string(ARM)
    model.opt.timestep /= substeps
    return model


def _full_state(model, data):
    """Everything the next step depends on, and the warning counters."""
    state = np.empty(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_INTEGRATION))
    mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_INTEGRATION)
    return np.concatenate([state, data.warning.number])


def _loop(model, data, controls):
    for row in controls:
        data.ctrl[:] = row
        mujoco.mj_step(model, data)


@pytest.mark.parametrize("forced", [True, False])
def test_blocks_in_c_end_bit_identical_to_mj_step_in_a_loop(forced):
    model = _model()
    rng = np.random.default_rng(1)
    controls = rng.normal(0.0, 1.5, (600, model.nu)) if forced else np.zeros((600, model.nu))
    fast, slow = mujoco.MjData(model), mujoco.MjData(model)
    for data in (fast, slow):
        data.qpos[:] = [0.4, 0.25]
        data.qvel[:] = [-1.0, 2.0]
        data.qfrc_applied[:] = [0.05, -0.02]  # held inputs, besides the controls
        data.xfrc_applied[2] = [0.0, 0.0, 1.0, 0.0, 0.01, 0.0]
    runner = new_runner()
    pushed = 0
    for block in np.split(controls, [9, 40, 41, 160, 300, 450]):  # short blocks too
        step_controls(model, fast, block, runner)
        _loop(model, slow, block)
        pushed += slow.nefc > 0
        # between blocks, what a recording does: forward under another control
        for data in (fast, slow):
            data.ctrl[:] = 0.5
            mujoco.mj_forward(model, data)
        assert np.array_equal(_full_state(model, fast), _full_state(model, slow))
        assert np.array_equal(fast.qacc, slow.qacc)
    assert fast.time == pytest.approx(600 * model.opt.timestep)
    assert pushed  # the joint limit took part
    assert not np.array_equal(fast.qacc_warmstart, 0)


def test_a_block_with_a_warning_goes_on_as_mj_step_would():
    """MuJoCo's rollout stops at a warning: the block is taken again one step at a time, so
    the bad accelerations and MuJoCo's reset happen as in the loop."""
    model = _model(substeps=1)
    controls = np.full((40, model.nu), 0.3)
    controls[17, 1] = 1e9  # |qacc| > mjMAXVAL: mjWARN_BADQACC, the data reset
    fast, slow = mujoco.MjData(model), mujoco.MjData(model)
    step_controls(model, fast, controls)
    _loop(model, slow, controls)
    bad = int(mujoco.mjtWarning.mjWARN_BADQACC)
    assert slow.warning.number[bad] == 1
    assert np.array_equal(_full_state(model, fast), _full_state(model, slow))


def test_short_blocks_and_bad_controls():
    model = _model()
    fast, slow = mujoco.MjData(model), mujoco.MjData(model)
    controls = np.ones((ROLLOUT_MIN_STEPS - 1, model.nu))
    step_controls(model, fast, controls, runner=None)
    _loop(model, slow, controls)
    assert np.array_equal(_full_state(model, fast), _full_state(model, slow))
    with pytest.raises(ValueError, match="controls"):
        step_controls(model, fast, np.ones((10, model.nu + 1)))


def test_without_mujoco_rollout_the_steps_are_taken_in_python(monkeypatch):
    import mujoco.rollout

    monkeypatch.delattr(mujoco.rollout, "Rollout")
    assert new_runner() is None
    model = _model()
    fast, slow = mujoco.MjData(model), mujoco.MjData(model)
    controls = np.linspace(-1.0, 1.0, 2 * ROLLOUT_MIN_STEPS)[:, None].repeat(model.nu, axis=1)
    step_controls(model, fast, controls)
    _loop(model, slow, controls)
    assert np.array_equal(_full_state(model, fast), _full_state(model, slow))


def test_a_model_without_actuators():
    model = mujoco.MjModel.from_xml_string(ARM.split("<actuator>")[0] + "</mujoco>")
    assert model.nu == 0
    fast, slow = mujoco.MjData(model), mujoco.MjData(model)
    for data in (fast, slow):
        data.qpos[:] = [1.0, 0.2]
    step_controls(model, fast, np.zeros((300, 0)))
    _loop(model, slow, np.zeros((300, 0)))
    assert np.array_equal(_full_state(model, fast), _full_state(model, slow))
    assert slow.qpos[0] != 1.0


def _reference_run(system, duration, signals, q0, qd0, sample_every, substeps, forced):
    """The recording of :func:`simulate_trajectory`, written out with ``mj_step``."""
    model = system.mj_model()
    dt = model.opt.timestep
    model.opt.timestep = dt / substeps
    model.opt.integrator = INTEGRATORS["RK4"]
    if not forced:
        model.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = q0, qd0
    n_fine = int(round(duration / dt)) * substeps
    times = np.arange(n_fine + 1) * (dt / substeps)
    record_every = sample_every * substeps
    recorded = np.arange(0, n_fine + 1, record_every)
    zero = np.zeros((n_fine + 1, model.nu))
    at_samples = signals(times[recorded]) if forced else zero
    stepped = signals(times[:n_fine] + dt / substeps / 2) if forced else zero
    rows = []
    for k in range(n_fine + 1):
        if k % record_every == 0:
            data.ctrl[:] = at_samples[k // record_every]
            mujoco.mj_forward(model, data)
            rows.append(np.concatenate([data.qpos, data.qvel, data.qacc, data.qfrc_actuator,
                                        data.qfrc_constraint]))
        if k < n_fine:
            data.ctrl[:] = stepped[k]
            mujoco.mj_step(model, data)
    return times[recorded], np.array(rows)


@pytest.mark.parametrize("forced", [True, False])
def test_simulated_trajectories_are_those_of_mj_step_in_a_loop(forced):
    system = MJCFSystem(ARM)
    n = system.n

    def signals(t):  # a plain function: evaluated on the same times as the reference
        t = np.asarray(t, dtype=float)
        return np.stack([0.4 * np.sin(7.0 * t), 1.2 * np.cos(11.0 * t + 0.3)], axis=1)

    q0, qd0 = np.array([0.3, 0.2]), np.array([0.5, -1.5])
    # 151 model steps, a sample every 2: the run ends one step after its last sample
    trajectory = simulate_trajectory(system, 0.302, signals if forced else None, q0, qd0,
                                     sample_every=2, substeps=3, control_at="midpoint",
                                     integrator="RK4")
    t, rows = _reference_run(system, 0.302, signals, q0, qd0, 2, 3, forced)
    assert trajectory.info["substeps"] == 3
    assert np.array_equal(trajectory.t, t)
    for name, column in (("q", 0), ("qd", n), ("qdd", 2 * n), ("u", 3 * n),
                         ("u_constraint", 4 * n)):
        assert np.array_equal(getattr(trajectory, name), rows[:, column:column + n]), name
    assert trajectory.constraint_active.any()  # the elbow's limit acted
    if forced:
        assert np.abs(trajectory.u).max() > 0.1


def test_the_progress_bar_counts_every_model_step():
    class Bar:
        total = 0

        def update(self, n):
            Bar.total += n

    system = MJCFSystem(ARM)
    # 2600 model steps in blocks of 3 x 7 internal steps: the thousands fall inside blocks
    simulate_trajectory(system, 5.2, None, sample_every=7, substeps=3, integrator="RK4",
                        progress=Bar())
    assert Bar.total == 2601
