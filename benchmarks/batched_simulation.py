"""Time per simulation step of an identified double pendulum (the paper's Table 2).

The double pendulum of :mod:`pysindy_xl.mujoco` is identified from MuJoCo data (mixed
catalog, explicit optimizer); the identified model is then stepped with fixed-step RK4 at
MuJoCo's own time step (1 ms) by

* NumPy, sequential (batch 1): ``model.dynamics_.state_derivative`` in a Python RK4 loop;
* JAX, sequential (batch 1): a jitted RK4 step called from Python, and the whole
  trajectory in one ``lax.scan`` (:func:`pysindy_xl.export.jax_dynamics.simulate`);
* JAX, batched (default 10,000 trajectories): :func:`pysindy_xl.export.jax_dynamics.simulate_batch`
  in float32 and float64, storing every state or only the final one;

and, as the reference a user would otherwise pick, MuJoCo stepping the same MJCF system
(RK4, 1 ms): ``mj_step`` in a Python loop, and ``mujoco.rollout`` (C loop) for one
trajectory and for the whole batch on a thread pool.

Every figure is the wall time of a run divided by (trajectories x steps), in microseconds:
best and median of ``--repeat`` runs (the machine may be shared). All trajectories get
random initial states and random sum-of-sines joint torques, held over each step as MuJoCo
does (``interpolation="zoh"``). As a check that both simulate the same system, the batched
JAX trajectories are compared with MuJoCo's.

Usage: ``python benchmarks/batched_simulation.py [--batch 10000] [--steps 500] [--repeat 5]``
"""

import argparse
import os
import platform
import statistics
import time

import jax
import jax.numpy as jnp
import mujoco
import mujoco.rollout
import numpy as np

import pysindy_xl as px
from pysindy_xl import mujoco as pxm
from pysindy_xl.export.jax_dynamics import rk4_step, simulate, simulate_batch

PAPER = {  # Table 2 of the paper, microseconds per step
    "NumPy (sequential)": 150.0,
    "JAX (sequential)": 160.0,
    "JAX (parallelized, GPU)": 0.2,
}
TARGET_US = 0.2


def identify(system):
    """Identify the double pendulum from MuJoCo data; returns the fitted XLSINDy."""
    data = pxm.generate_dataset(
        system, n_trajectories=2, duration=8.0, seed=0, sample_every=5, progress=False
    )
    model = px.XLSINDy(pxm.reference_catalog(system, "mixed"), px.ExplicitOptimizer())
    return model.fit(**data.fit_arguments("tau"))


def joint_torques(rng, n_batch, n_steps, dt, amplitudes):
    """Random sums of 3 sinusoids per joint, shape (n_batch, n_steps, 2)."""
    t = dt * np.arange(n_steps)
    omega = rng.uniform(1.0, 8.0, (n_batch, 1, 2, 3))
    phase = rng.uniform(0.0, 2 * np.pi, (n_batch, 1, 2, 3))
    waves = np.sin(omega * t[None, :, None, None] + phase).mean(axis=-1)
    return waves * np.asarray(amplitudes)


def timed(function, repeat):
    """Run ``function`` once to warm up, then ``repeat`` times.

    Returns the wall times and the CPU times of this process (all threads together: on a
    shared machine, the CPU time shows the work done whatever the other users take).
    """
    function()
    wall, cpu = [], []
    for _ in range(repeat):
        start, start_cpu = time.perf_counter(), time.process_time()
        function()
        wall.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return wall, cpu


def numpy_rk4(dynamics, x0, tau, dt):
    """One trajectory with the model's single-state NumPy derivative, RK4 in Python."""
    derivative = dynamics.state_derivative
    state = np.array(x0, dtype=float)
    for k in range(len(tau)):
        k1 = derivative(state, tau[k])
        k2 = derivative(state + 0.5 * dt * k1, tau[k])
        k3 = derivative(state + 0.5 * dt * k2, tau[k])
        k4 = derivative(state + dt * k3, tau[k])
        state = state + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return state


def jax_python_loop(step, x0, tau):
    state = jnp.asarray(x0)
    for k in range(len(tau)):
        state = step(state, tau[k])
    return state.block_until_ready()


def mujoco_states(model, data, qpos, qvel):
    """Full-physics state vectors of several (qpos, qvel), shape (B, nstate)."""
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    states = np.empty((len(qpos), mujoco.mj_stateSize(model, spec)))
    for k in range(len(qpos)):
        mujoco.mj_resetData(model, data)
        data.qpos[:], data.qvel[:] = qpos[k], qvel[k]
        mujoco.mj_getState(model, data, states[k], spec)
    return states


def mj_step_loop(model, data, qpos, qvel, controls):
    mujoco.mj_resetData(model, data)
    data.qpos[:], data.qvel[:] = qpos, qvel
    for k in range(len(controls)):
        data.ctrl[:] = controls[k]
        mujoco.mj_step(model, data)
    return data.qpos.copy()


def report(rows, n_cores):
    print()
    print(f"{'implementation':<44} {'batch':>6} {'best us':>9} {'median us':>9} {'cpu us':>8}")
    print("-" * 80)
    for name, batch, (wall, cpu) in rows:
        print(
            f"{name:<44} {batch:>6} {min(wall):>9.4f} {statistics.median(wall):>9.4f} "
            f"{min(cpu):>8.4f}"
        )
    print("-" * 80)
    print(
        f"microseconds per trajectory-step: wall time (best, median) and process CPU time "
        f"(best, all threads); {n_cores} CPU cores. Paper: "
        + ", ".join(f"{k} {v:g}" for k, v in PAPER.items())
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch", type=int, default=10_000)
    parser.add_argument("--steps", type=int, default=500, help="steps per trajectory")
    parser.add_argument(
        "--sequential-steps", type=int, default=200, help="steps of the slow Python loops"
    )
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument(
        "--mujoco-batch",
        type=int,
        default=1000,
        help="trajectories of the threaded MuJoCo rollout (its cost per "
        "trajectory-step does not depend on the batch; 10,000 takes minutes)",
    )
    parser.add_argument(
        "--threads",
        type=int,
        default=None,
        help="threads of mujoco.rollout (default: available cores)",
    )
    args = parser.parse_args()
    n_cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    threads = args.threads or n_cores
    print(
        f"{platform.processor() or platform.machine()}, {n_cores} cores, jax {jax.__version__}"
        f" on {jax.devices()[0].platform}, mujoco {mujoco.__version__}"
    )

    system = pxm.get_system("double-pendulum")
    start = time.perf_counter()
    model = identify(system)
    print(f"identified in {time.perf_counter() - start:.1f} s:")
    model.print()
    f = model.to_jax()
    print(f"mass-matrix solve: {f.solver}")

    mj_model = system.mj_model()
    mj_data = mujoco.MjData(mj_model)
    dt = float(mj_model.opt.timestep)
    rng = np.random.default_rng(0)
    n_batch, n_steps = args.batch, args.steps
    q0 = rng.uniform(-1.0, 1.0, (n_batch, 2))
    qd0 = rng.uniform(-1.0, 1.0, (n_batch, 2))
    x0 = np.hstack([q0, qd0])
    amplitudes = [system.force_amplitudes[j] for j in system.joint_names]
    torques = joint_torques(rng, n_batch, n_steps, dt, amplitudes)  # MuJoCo joint torques u
    tau = torques @ system.force_matrix().T  # generalized forces on the model's coordinates
    # one force sample per step: the JAX input has n_steps + 1 samples (the last one unused)
    tau_jax = np.concatenate([tau, tau[:, -1:]], axis=1)
    to_joints = np.linalg.inv(system.joint_to_coordinates)
    qpos0, qvel0 = q0 @ to_joints.T, qd0 @ to_joints.T

    rows = []

    def per(times, n_traj, n_step):
        return tuple([1e6 * s / (n_traj * n_step) for s in series] for series in times)

    # -- sequential, batch 1 ----------------------------------------------------------
    m = args.sequential_steps
    times = timed(lambda: numpy_rk4(model.dynamics_, x0[0], tau[0, :m], dt), args.repeat)
    rows.append(("NumPy RK4, Python loop", 1, per(times, 1, m)))

    step = jax.jit(lambda state, u: rk4_step(f, state, 0.0, dt, u))
    tau0 = [jnp.asarray(u, dtype=jnp.float32) for u in tau[0, :m]]
    times = timed(lambda: jax_python_loop(step, x0[0], tau0), args.repeat)
    rows.append(("JAX RK4 step jitted, Python loop", 1, per(times, 1, m)))

    for x64 in (False, True):
        with jax.enable_x64(x64):
            label = "float64" if x64 else "float32"
            times = timed(
                lambda: simulate(f, x0[0], tau_jax[0], dt).states.block_until_ready(),
                args.repeat,
            )
            rows.append((f"JAX RK4 lax.scan, one trajectory, {label}", 1, per(times, 1, n_steps)))

    times = timed(
        lambda: mj_step_loop(mj_model, mj_data, qpos0[0], qvel0[0], torques[0, :m]), args.repeat
    )
    rows.append(("MuJoCo mj_step, Python loop", 1, per(times, 1, m)))

    states0 = mujoco_states(
        mj_model, mj_data, qpos0[: args.mujoco_batch], qvel0[: args.mujoco_batch]
    )
    datas = [mujoco.MjData(mj_model) for _ in range(threads)]
    times = timed(
        lambda: mujoco.rollout.rollout(mj_model, datas[0], states0[:1], torques[:1]), args.repeat
    )
    rows.append(("MuJoCo rollout, one trajectory", 1, per(times, 1, n_steps)))

    # -- batched ----------------------------------------------------------------------
    n_mj = min(args.mujoco_batch, n_batch)
    with mujoco.rollout.Rollout(nthread=threads) as rollout:
        times = timed(
            lambda: rollout.rollout(mj_model, datas, states0[:n_mj], torques[:n_mj]), args.repeat
        )
        rows.append((f"MuJoCo rollout, {threads} threads", n_mj, per(times, n_mj, n_steps)))
        mj_state, _ = rollout.rollout(mj_model, datas, states0[:n_mj], torques[:n_mj])

    jax_results = {}
    for x64 in (False, True):
        with jax.enable_x64(x64):
            label = "float64" if x64 else "float32"
            for final_only in (False, True):

                def run(final_only=final_only):
                    result = simulate_batch(f, x0, tau_jax, dt, final_only=final_only)
                    return result.states.block_until_ready()

                times = timed(run, args.repeat)
                what = "final state" if final_only else "all states"
                rows.append(
                    (f"JAX RK4 vmap, {label}, {what}", n_batch, per(times, n_batch, n_steps))
                )
            jax_results[label] = simulate_batch(f, x0, tau_jax, dt)

    report(rows, n_cores)

    # -- same system? ------------------------------------------------------------------
    mj_q = mj_state[:, -1, 1:3] @ system.joint_to_coordinates.T
    for label, result in jax_results.items():
        jax_q = np.asarray(result.states[:n_mj, -1, :2], dtype=float)
        gap = np.abs(jax_q - mj_q)
        print(
            f"JAX ({label}) vs MuJoCo after {n_steps * dt:g} s: max |q| gap {gap.max():.2e} "
            f"rad, median {np.median(gap):.2e}; diverged: {int(np.sum(result.diverged))}"
        )
    best = {name: min(wall) for name, _, (wall, _) in rows}
    jax_best = min(
        best["JAX RK4 vmap, float32, all states"], best["JAX RK4 vmap, float64, all states"]
    )
    mj_best = best[f"MuJoCo rollout, {threads} threads"]
    print(
        f"target JAX batched < {TARGET_US} us/trajectory-step: best {jax_best:.3f} us -> "
        f"{'met' if jax_best < TARGET_US else 'NOT met'}; MuJoCo rollout {mj_best:.3f} us -> "
        f"JAX {mj_best / jax_best:.1f}x {'faster' if jax_best < mj_best else 'slower'}"
    )


if __name__ == "__main__":
    main()
