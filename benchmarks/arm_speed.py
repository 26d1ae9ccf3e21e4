"""Time a robot arm end to end: catalog, fit, validation, simulation step.

The acceptance of the robot-arm work: 10,000 samples of a 7-joint servo arm (the Panda-like arm
of ``robot_arms.py``: armature, damping, limits, position servos) with 1 % noise on the
positions only, identified with ``XLSINDy``'s defaults (weak form, bagged selection). Steps:

* ``catalog``: :func:`~pysindy_xl.mujoco.kinematic_catalog` and the library's derivation (the
  Euler-Lagrange columns of the base parameters);
* ``fit``: ``XLSINDy(library).fit`` on the noisy positions and recorded torques;
* ``validation``: :func:`~pysindy_xl.mujoco.validate_model` over ``--validation`` seconds
  (a fresh MuJoCo run, the MJCF's servos driving the identified model in closed loop);
* ``step``: one evaluation of the identified dynamics at a state (``state_derivative``, the
  cost a simulator pays per right-hand side) against one ``mujoco.mj_step`` of the MJCF;
* ``identified MJCF``: one ``mujoco.mj_step`` of the identified arm exported by
  :meth:`~pysindy_xl.XLSINDy.to_mjcf` (the MJCF with the identified, physically consistent
  inertials, armature and friction; ``residual`` is how far its inertials are from
  reproducing the identified base parameters);
* ``jax``: one fixed step (RK4, the MJCF's timestep, float64) of ``XLSINDy.to_jax`` rolled
  out with :func:`~pysindy_xl.export.jax_dynamics.simulate` (one trajectory) and
  :func:`~pysindy_xl.export.jax_dynamics.simulate_batch` (per trajectory of 256), compiled
  beforehand; skipped without JAX.

Each step is timed in a fresh process state except the catalog derivation, which later fits of
the same arm reuse (it is cached); ``catalog (cached)`` reports that reuse.

Usage: ``python benchmarks/arm_speed.py [--arm panda] [--samples 10000] [--validation 5]``;
writes ``benchmarks/results/arm_speed.json`` and prints the figures.
"""

import argparse
import json
import pathlib
import platform
import sys
import tempfile
import time
import warnings

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from robot_arms import arm_mjcf  # noqa: E402


def timed(function):
    start = time.perf_counter()
    value = function()
    return value, time.perf_counter() - start


def best_of(function, repeats=3) -> float:
    """The shortest of ``repeats`` timings: microsecond loops on a shared machine."""
    return min(timed(function)[1] for _ in range(repeats))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arm", default="panda")
    parser.add_argument("--samples", type=int, default=10_000)
    parser.add_argument("--noise", type=float, default=0.01)
    parser.add_argument("--validation", type=float, default=5.0)
    parser.add_argument("--out", default=str(HERE / "results" / "arm_speed.json"))
    args = parser.parse_args()

    import mujoco

    import pysindy_xl as px
    from pysindy_xl.mujoco import (
        MJCFSystem,
        generate_dataset,
        kinematic_catalog,
        validate_model,
    )

    system = MJCFSystem(arm_mjcf(args.arm))
    n_trajectories, sample_every, timestep = 2, 2, system.mj_model().opt.timestep
    duration = args.samples / n_trajectories * sample_every * timestep
    data = generate_dataset(system, n_trajectories=n_trajectories, duration=duration,
                            noise=args.noise, seed=0, sample_every=sample_every,
                            progress=False)
    n_samples = sum(len(tr.t) for tr in data.trajectories)
    library, catalog_s = timed(lambda: kinematic_catalog(system).library().fit())
    _, cached_s = timed(lambda: kinematic_catalog(system).library().fit())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model, fit_s = timed(lambda: px.XLSINDy(library).fit(
            **data.fit_arguments(forces="tau")))
        result, validation_s = timed(lambda: validate_model(
            model, system, duration=args.validation, seed=1))
    state = result.reference[len(result.reference) // 2]  # a clean state of the arm
    dynamics = model.dynamics_
    dynamics.state_derivative(state)
    repeats = 200
    _, step_s = timed(lambda: [dynamics.state_derivative(state) for _ in range(repeats)])
    mj_model = system.mj_model()
    mj_data = mujoco.MjData(mj_model)
    mujoco_s = best_of(lambda: [mujoco.mj_step(mj_model, mj_data) for _ in range(10_000)])
    # the identified arm exported (physically consistent inertials) and stepped by MuJoCo
    with tempfile.TemporaryDirectory() as folder:
        path = pathlib.Path(folder) / "identified.xml"
        residual = model.to_mjcf(path, template=system)["residual"]
        identified = mujoco.MjModel.from_xml_path(str(path))
    identified_data = mujoco.MjData(identified)
    identified_s = best_of(lambda: [mujoco.mj_step(identified, identified_data)
                                    for _ in range(10_000)])
    jax_figures = jax_steps(model, state, timestep)
    figures = {
        "arm": args.arm, "joints": system.n, "samples": n_samples, "noise": args.noise,
        "catalog_s": catalog_s, "catalog_cached_s": cached_s, "fit_s": fit_s,
        "validation_s": validation_s, "validation_horizon_s": args.validation,
        "validation_drive": result.drive, "validation_valid": bool(result.valid),
        "total_s": catalog_s + fit_s + validation_s,
        "rhs_ms": step_s / repeats * 1e3, "mujoco_step_ms": mujoco_s / 10_000 * 1e3,
        "identified_mjcf_step_ms": identified_s / 10_000 * 1e3,
        "identified_mjcf_residual": residual,
        **jax_figures,
        "machine": {"python": platform.python_version(), "processor": platform.processor(),
                    "cpus": __import__("os").cpu_count()},
    }
    pathlib.Path(args.out).write_text(json.dumps(figures, indent=2) + "\n")
    for key, value in figures.items():
        print(f"{key}: {value:.3g}" if isinstance(value, float) else f"{key}: {value}")


def jax_steps(model, state, timestep, n_steps=2000, batch=256) -> dict:
    """Milliseconds per RK4 step of the identified arm rolled out in JAX (float64)."""
    try:
        import jax
    except ImportError:
        return {}
    import numpy as np

    from pysindy_xl.export.jax_dynamics import simulate, simulate_batch

    with jax.enable_x64(True):
        function = model.to_jax()
        n = len(state) // 2
        forces = np.zeros((n_steps + 1, n))
        states = np.tile(state, (batch, 1))
        batch_forces = np.zeros((batch, n_steps + 1, n))

        def one():
            return simulate(function, state, forces, timestep).states.block_until_ready()

        def many():
            return simulate_batch(function, states, batch_forces,
                                  timestep).states.block_until_ready()

        one(), many()  # compile
        _, one_s = timed(one)
        _, many_s = timed(many)
    return {"jax_rk4_step_ms": one_s / n_steps * 1e3,
            "jax_batch_rk4_step_ms": many_s / n_steps / batch * 1e3}


if __name__ == "__main__":
    main()
