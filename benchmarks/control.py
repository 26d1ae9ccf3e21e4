"""Control with identified models: swing-ups on MuJoCo plants (issue 52's acceptance).

Every case runs the learning loop (``pysindy_xl.control.learn_to_control``): explore, identify
from positions with relative noise, swing up with sampling MPC + LQR on the model, run on the
MuJoCo plant, add the data, re-identify, until success. Methods, side by side on the same
plant, seeds and controller:

- ``automatic``: the automatic catalog (``px.grow_catalog``) grown on the loop's data from the
  coordinates and their kinds only (``pysindy_xl.control.AutomaticGrowth``);
- ``generic``: XLSINDy with a fixed catalog from the coordinates and their kinds;
- ``kinematic``: XLSINDy with the MJCF's kinematic catalog (structure given);
- ``pysindy``: PySINDy ``SINDy`` with control inputs on ``[q, qd]`` (velocities by its
  smoothed finite differences), its own libraries (polynomials of degree 2 of the velocities
  and the force, tensored with ``sin``/``cos`` of the angles), STLSQ;
- ``true``: the true equations (the upper bound: the planner's own limit).

Success: every angle within 0.2 rad of upright for 2 s, forces within the limit (clipped by
the plant), the cart within |x| <= 1.5 m. Results: one JSON line per finished case in
``benchmarks/results/control.jsonl`` (a rerun skips them), the summary in
``benchmarks/results/control.md``.

A case run again (``--rerun``, for instance after a change of the code) is appended; the
summary takes each case's latest record.

Arm tracking (``--arm``): ``benchmarks/control_arm.py`` (published 7-joint arms with torque
motors, computed-torque tracking with identified feedforward); its table is part of the summary.

Usage::

    python benchmarks/control.py --seeds 20 --tasks cartpole-10N --methods automatic true
    python benchmarks/control.py --arm --seeds 3
    python benchmarks/control.py --summary
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results"
JSONL = RESULTS / "control.jsonl"
SUMMARY = RESULTS / "control.md"

#: task name -> (system, force limit (N), noise)
TASKS = {
    "cartpole-10N": ("cart-pole", 10.0, 0.01),
    "cdp-20N": ("cart-double-pendulum", 20.0, 0.01),
    "cdp-10N": ("cart-double-pendulum", 10.0, 0.01),
    "cartpole-10N-noise5": ("cart-pole", 10.0, 0.05),
    "cdp-20N-noise5": ("cart-double-pendulum", 20.0, 0.05),
}
METHODS = ("automatic", "generic", "kinematic", "pysindy", "true")
#: STLSQ settings of the PySINDy baseline, chosen on the acceleration error of a cart-pole fit
#: from the loop's exploration data (the tuning is in the summary's notes).
PYSINDY_THRESHOLD = 2.0
PYSINDY_NORMALIZE = False
#: Interaction budget (s) of the targets.
BUDGETS = {"cartpole-10N": 8.0, "cdp-20N": 15.0}
TARGETS = {"cartpole-10N": "success >= 95 %, interaction <= 8 s, planning <= 5 ms",
           "cdp-20N": "success >= 90 %, interaction <= 15 s, planning <= 20 ms",
           "cdp-10N": "report", "cartpole-10N-noise5": "report", "cdp-20N-noise5": "report"}


def true_model(name):
    """The system's true equations ``M qdd = f(q, qd, tau)``."""
    import pysindy_xl as px
    from pysindy_xl.mujoco import get_system
    system = get_system(name)
    equations = [e - tau for e, tau in zip(system.equations_of_motion(), system.coords.tau,
                                           strict=True)]
    return px.MassMatrixDynamics(system.coords, equations)


def pysindy_identify(system, data, threshold=PYSINDY_THRESHOLD, normalize=PYSINDY_NORMALIZE):
    """PySINDy with control from noisy positions: a JAX ``f(state, tau)`` of the fitted model
    (STLSQ ``threshold``, ``normalize_columns=normalize``)."""
    import jax.numpy as jnp
    import pysindy as ps
    import sympy as sp
    n = system.n
    angles = list(system.angle_coordinates)
    others = [i for i in range(n) if i not in angles]
    names = [f"q{i}" for i in range(n)] + [f"v{i}" for i in range(n)] + ["u"]
    smoother = ps.SmoothedFiniteDifference(smoother_kws={"window_length": 41, "polyorder": 3})
    states, forces, times = [], [], []
    for q, t, tau in data:
        step = 10  # 100 Hz: the smoother's window spans 0.4 s of the 1 kHz record
        qd = np.asarray(smoother(q, t))
        states.append(np.c_[q, qd][::step])
        forces.append(tau[::step, :1])
        times.append(t[::step])
    del others  # the cart's position enters no equation of a cart system
    polynomial_inputs = [n + i for i in range(n)] + [2 * n]
    library = ps.GeneralizedLibrary(
        [ps.PolynomialLibrary(degree=2), ps.FourierLibrary(n_frequencies=1)],
        tensor_array=[[1, 1]],
        inputs_per_library=[polynomial_inputs, angles])
    model = ps.SINDy(optimizer=ps.STLSQ(threshold=threshold, alpha=1e-3,
                                        normalize_columns=normalize),
                     feature_library=library,
                     differentiation_method=ps.SmoothedFiniteDifference(
                         smoother_kws={"window_length": 9, "polyorder": 3}))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(states, t=times, u=forces, feature_names=names)
    symbols = sp.symbols(names)
    features = [sp.sympify(name.replace(" ", "*").replace("^", "**"),
                           locals={s.name: s for s in symbols})
                for name in model.get_feature_names()]
    coefficients = model.coefficients()  # (2n, F)
    rows = [sp.Add(*(float(c) * feat for c, feat in zip(row, features, strict=True) if c))
            for row in coefficients]
    evaluate = sp.lambdify(symbols, rows, modules="jax")

    def f(state, tau):
        values = [state[..., i] for i in range(2 * n)] + [tau[..., 0]]
        out = [jnp.broadcast_to(jnp.asarray(v, dtype=state.dtype), state.shape[:-1])
               for v in evaluate(*values)]
        return jnp.stack(out, axis=-1)

    f.n_coordinates = n
    f.equations = [f"d{names[i]}/dt = {sp.N(r, 4)}" for i, r in enumerate(rows)]
    return f


def run_case(task, method, seed, max_episodes=None, n_jobs=None):
    """One case: the loop's JSON report, with the wall time (``max_episodes``: the loop's cap
    on episodes, default its own; ``n_jobs``: processes of the automatic catalog's growth,
    which do not change the result)."""
    from pysindy_xl.control.loop import learn_to_control
    system, force_limit, noise = TASKS[task]
    options = {"seed": seed, "force_limit": force_limit, "noise": noise,
               "log": lambda m: print(f"    {m}", file=sys.stderr, flush=True)}
    if method == "true":
        options.update(model=true_model(system), max_episodes=1)
    elif method == "pysindy":
        from pysindy_xl.mujoco import get_system
        # no physical check: a first-order SINDy model gets every attempt
        options.update(identify=lambda s, d: pysindy_identify(get_system(system), d),
                       check_model=False)
    elif method == "automatic" and n_jobs is not None:
        from pysindy_xl.control import AutomaticGrowth
        options.update(catalog=AutomaticGrowth(n_jobs=n_jobs))
    else:
        options.update(catalog=method)
    if max_episodes is not None and method != "true":
        options.update(max_episodes=max_episodes)
    start = time.perf_counter()
    result = learn_to_control(system, **options).to_dict()
    result["wall_s"] = time.perf_counter() - start
    result.update(task_name=task, method=method if max_episodes is None
                  else f"{method}-max{max_episodes}ep")
    if method == "pysindy" and not result["equations"]:
        result["equations"] = []
    return result


NOTES_PATH = RESULTS / "control_notes.md"
# the arm-tracking benchmark lives in its own script (benchmarks/control_arm.py)
from control_arm import arm_summary  # noqa: E402  (a sibling script, not a package)


def planning_timing(system_name: str, catalog: str, seed: int = 0, calls: int = 200) -> dict:
    """Planning time of one control period (ms) on a model identified from one exploration:
    the compiled sampling planner called ``calls`` times from states along a swing-up."""
    import jax

    from pysindy_xl.control import (
        MuJoCoPlant,
        PredictiveController,
        catalog_identifier,
        continuous_dynamics,
        discrete_dynamics,
        exploration_policy,
        get_task,
        noisy_positions,
        swing_up_cost,
    )
    from pysindy_xl.control.loop import EXPLORE_S, PLANNER_SETTINGS
    from pysindy_xl.mujoco import get_system
    system = get_system(system_name)
    task = get_task(system_name)
    settings = dict(PLANNER_SETTINGS[system_name])
    plant = MuJoCoPlant(system, task.actuated, task.force_limit, settings.pop("control_dt"))
    rng = np.random.default_rng(seed)
    plant.reset()
    episode = plant.run(exploration_policy(task.force_limit, rng), EXPLORE_S[system_name])
    model, _ = catalog_identifier(catalog)[1](
        system, [(noisy_positions(episode, 0.01, rng), episode.t, episode.tau)])
    step = discrete_dynamics(continuous_dynamics(model), plant.control_dt, plant.actuation,
                             settings.pop("substeps"))
    cost = swing_up_cost(system.n, task.angles(system), track_limit=task.track_limit,
                         force_limit=task.force_limit)
    controller = PredictiveController(step, cost, task.force_limit, settings.pop("horizon"),
                                      goal=None, angles=task.angles(system), **settings)
    states = episode.states[:: max(1, len(episode.states) // calls)][:calls]
    for state in states:
        controller(state)
    jax.block_until_ready(controller._plan)
    times = np.array(controller.planning_ms)
    return {"system": system_name, "catalog": catalog, "median_ms": float(np.median(times)),
            "p10_ms": float(np.percentile(times, 10)), "p90_ms": float(np.percentile(times, 90)),
            "load_average": os.getloadavg()[0], "terms": int(np.count_nonzero(
                model.coefficients()))}


def to_jax_speed(system_name: str, repeats: int = 20) -> dict:
    """512 rollouts of 60 RK4 steps (float64) of a kinematic-catalog model: ``to_jax()``, the
    rigid-body kernel with LU (the path ``to_jax()`` took before), and the model's own
    mass-matrix and forcing expressions (``MassMatrixDynamics`` of its equations)."""
    import jax

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    import pysindy_xl as px
    from pysindy_xl.export.jax_dynamics import dynamics_function, simulate_batch
    from pysindy_xl.mujoco import generate_dataset, get_system, reference_catalog
    system = get_system(system_name)
    data = generate_dataset(system, n_trajectories=2, duration=4.0, seed=0, noise=0.01,
                            progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = px.XLSINDy(reference_catalog(system, "kinematic"))
        model.fit(**data.fit_arguments(forces="tau"))
    dynamics = model.dynamics_
    n = dynamics.coords.n
    rng = np.random.default_rng(0)
    x0 = jnp.asarray(np.c_[rng.uniform(-1, 1, (512, n)), rng.uniform(-1, 1, (512, n))])
    u = jnp.asarray(rng.uniform(-1, 1, (512, 60, n)))
    paths = {"kernel_lu": dynamics_function(dynamics, solver="lu"), "to_jax": model.to_jax(),
             "expressions": dynamics_function(px.MassMatrixDynamics(dynamics.coords,
                                                                    dynamics.equations))}
    record = {"system": system_name}
    states = {name: np.asarray(simulate_batch(f, x0, u, 0.01).states)
              for name, f in paths.items()}
    times = {name: [] for name in paths}
    for k in range(repeats):  # interleaved: the machine's load falls on both fast paths alike
        for name, f in paths.items():
            if name == "kernel_lu" and k >= 3:
                continue  # the slow path apart, a few times
            start = time.perf_counter()
            jax.block_until_ready(simulate_batch(f, x0, u, 0.01).states)
            times[name].append(time.perf_counter() - start)
    for name in paths:
        record[f"{name}_ms"] = 1e3 * min(times[name])
        record[f"{name}_median_ms"] = 1e3 * float(np.median(times[name]))
    record["max_difference"] = float(np.nanmax(np.abs(states["to_jax"] - states["kernel_lu"])))
    record["load_average"] = os.getloadavg()[0]
    return record


def to_jax_summary():
    path = RESULTS / "control_to_jax.jsonl"
    if not path.exists():
        return ""
    records = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    lines = ["| system | to_jax() ms: min (median) | own expressions ms: min (median) | rigid "
             "kernel + LU ms (the path before) | max difference to the kernel | load average |",
             "|---|---|---|---|---|---|"]
    for r in records:
        lines.append(f"| {r['system']} | {r['to_jax_ms']:.1f} ({r['to_jax_median_ms']:.1f}) | "
                     f"{r['expressions_ms']:.1f} ({r['expressions_median_ms']:.1f}) | "
                     f"{r['kernel_lu_ms']:.0f} | {r['max_difference']:.1e} | "
                     f"{r['load_average']:.1f} |")
    return "\n".join(lines) + "\n"


def timing_summary():
    path = RESULTS / "control_timing.jsonl"
    if not path.exists():
        return ""
    latest = {}
    for line in path.read_text().splitlines():
        if line.strip():
            record = json.loads(line)
            latest[(record["system"], record["catalog"])] = record  # the last run of each
    records = list(latest.values())
    lines = ["| system | catalog | model terms | planning ms: median (p10, p90) | target | "
             "load average |", "|---|---|---|---|---|---|"]
    for r in records:
        target = "5" if r["system"] == "cart-pole" else "20"
        lines.append(f"| {r['system']} | {r['catalog']} | {r['terms']} | {r['median_ms']:.1f} "
                     f"({r['p10_ms']:.1f}, {r['p90_ms']:.1f}) | <= {target} ms | "
                     f"{r['load_average']:.1f} |")
    return "\n".join(lines) + "\n"


HEADER = """# Control with identified models (benchmarks/control.py)

Learning loop on MuJoCo plants: explore within the force limit, identify from positions only
(relative noise as in the task name: 1 %, or 5 % for `-noise5`), swing up with sampling MPC
(MPPI, 60 periods of 20 ms) + LQR near the top planned on the identified model, run on MuJoCo,
add the data, re-identify until success. Success: every angle within 0.2 rad of upright for 2 s
in a row, force within the limit (clipped by the plant), cart within |x| <= 1.5 m; attempts last
at most 6 s, at most 6 episodes. "within budget": success with at most 8 s (cart-pole) / 15 s
(cart double pendulum) of plant interaction in total, the successful attempt included.

Methods: `automatic` = the automatic catalog (`px.grow_catalog`) grown on the loop's data from
the coordinates' names and kinds only (hinges angles, slides linear; no MJCF structure), the
catalog's size capped by the data (`AutomaticGrowth`: 150 equations per candidate);
`automatic-max2ep` = the same loop capped at two episodes (one exploration, one attempt: on the
cart double pendulum, whose first exploration is 8 s, this decides success within 15 s);
`generic` = XLSINDy with a fixed catalog from the coordinates and their kinds (the stand-in
used before the automatic catalog); `kinematic` = XLSINDy with the MJCF's kinematic catalog
(structure given); `pysindy` = PySINDy SINDy with control from the same data; `true` = the
true equations (upper bound, no exploration). Same controller, plant and seeds for all.

Machine: 2 cores shared with ~5 other jobs (load average 9-11 during the runs): every planning
time below is inflated by the load; the `--timing` table measures the planning step alone.
"""


def _append(path, line: str) -> None:
    """Append ``line`` to ``path`` in one write (runs in parallel append whole lines)."""
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        os.write(fd, line.encode("utf-8"))
    finally:
        os.close(fd)


@functools.cache
def _commit() -> str | None:
    """The checkout's commit when the first case ends (recorded with each case), or None
    outside a git checkout."""
    import subprocess
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=Path(__file__).parent,
                              capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None


def write_summary(notes: str = "") -> str:
    text = (HEADER + "\n## Swing-up\n\n" + summarize() + "\n## Arm tracking\n\n"
            + arm_summary() + "\n## Planning step\n\n" + timing_summary()
            + "\n## to_jax() of kinematic-catalog models (512 rollouts x 60 RK4 steps, float64)"
            "\n\n" + to_jax_summary() + "\n" + notes)
    SUMMARY.write_text(text, encoding="utf-8")
    return text


def finished():
    if not JSONL.exists():
        return set()
    done = set()
    for line in JSONL.read_text().splitlines():
        if line.strip():
            record = json.loads(line)
            done.add((record["task_name"], record["method"], record["seed"]))
    return done


def summarize():
    """Markdown table of every finished case (``control.md``)."""
    if not JSONL.exists():
        return "no results yet\n"
    records = [json.loads(line) for line in JSONL.read_text().splitlines() if line.strip()]
    # a case run again (--rerun) is summarized by its latest record; the earlier stay on file
    latest = {(r["task_name"], r["method"], r["seed"]): r for r in records}
    records = list(latest.values())
    lines = ["| task | method | cases | success | within budget | interaction s (median, max) "
             "| episodes (median) | identification s (median, max) | planning ms (median) "
             "| target |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for task in TASKS:
        labels = list(METHODS) + sorted({r["method"] for r in records} - set(METHODS))
        for method in labels:
            group = [r for r in records if r["task_name"] == task and r["method"] == method]
            if not group:
                continue
            success = np.mean([r["success"] for r in group])
            interaction = [r["interaction_s"] for r in group if r["success"]]
            inter = (f"{np.median(interaction):.1f}, {np.max(interaction):.1f}" if interaction
                     else "-")
            steps = [r["mpc_step_ms"] for r in group if r["mpc_step_ms"] is not None]
            budget = BUDGETS.get(task.replace("-noise5", ""), np.inf)
            within = np.mean([bool(r["success"]) and r["interaction_s"] <= budget
                              for r in group])
            step = f"{np.median(steps):.1f}" if steps else "-"
            fits = [s for r in group for s in r.get("identify_s") or []]
            fit = f"{np.median(fits):.0f}, {np.max(fits):.0f}" if fits else "-"
            lines.append(f"| {task} | {method} | {len(group)} | {100 * success:.0f} % | "
                         f"{100 * within:.0f} % | {inter} "
                         f"| {np.median([r['episodes'] for r in group]):.0f} | {fit} | "
                         f"{step} | {TARGETS[task]} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", nargs="+", choices=list(TASKS), default=list(TASKS))
    parser.add_argument("--methods", nargs="+", choices=METHODS, default=list(METHODS))
    parser.add_argument("--seeds", type=int, default=20, help="seeds 0..N-1 (default 20)")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--summary", action="store_true", help="only print the summary")
    parser.add_argument("--max-episodes", type=int, default=None,
                        help="cap the loop's episodes (recorded as METHOD-maxNep); 2 = one "
                             "exploration and one attempt: enough to tell success within the "
                             "cart double pendulum's 15 s budget after an 8 s exploration")
    parser.add_argument("--rerun", action="store_true",
                        help="run finished cases again (the summary takes each case's latest "
                             "record)")
    parser.add_argument("--n-jobs", type=int, default=None,
                        help="processes of the automatic catalog's growth (the result does "
                             "not depend on it)")
    parser.add_argument("--arm", action="store_true", help="run the arm-tracking cases")
    parser.add_argument("--to-jax", action="store_true",
                        help="time to_jax() against the rigid-body kernel and the expressions")
    parser.add_argument("--timing", action="store_true",
                        help="time the planning step on identified models")
    args = parser.parse_args(argv)
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    RESULTS.mkdir(parents=True, exist_ok=True)
    if args.to_jax:
        for system_name in ("cart-pole", "cart-double-pendulum"):
            record = to_jax_speed(system_name)
            print(json.dumps(record), flush=True)
            with (RESULTS / "control_to_jax.jsonl").open("a") as handle:
                handle.write(json.dumps(record) + "\n")
        return 0
    if args.timing:
        for system_name in ("cart-pole", "cart-double-pendulum"):
            for catalog in ("kinematic", "automatic"):
                record = planning_timing(system_name, catalog)
                print(json.dumps(record), flush=True)
                with (RESULTS / "control_timing.jsonl").open("a") as handle:
                    handle.write(json.dumps(record) + "\n")
        return 0
    if args.arm and not args.summary:
        import control_arm
        control_arm.main(["--seeds", str(args.seeds), "--first-seed", str(args.first_seed)])
        print(write_summary(NOTES_PATH.read_text() if NOTES_PATH.exists() else ""))
        return 0
    if not args.summary:
        done = set() if args.rerun else finished()
        label = (lambda m: m) if args.max_episodes is None else \
            (lambda m: f"{m}-max{args.max_episodes}ep")
        cases = [(task, method, seed) for task in args.tasks for method in args.methods
                 for seed in range(args.first_seed, args.first_seed + args.seeds)
                 if (task, label(method), seed) not in done]
        print(f"{len(cases)} cases to run ({len(done)} finished before)", file=sys.stderr)
        for k, (task, method, seed) in enumerate(cases, 1):
            print(f"[{k}/{len(cases)}] {task} {method} seed {seed}", file=sys.stderr,
                  flush=True)
            try:
                record = run_case(task, method, seed, args.max_episodes, args.n_jobs)
            except (ValueError, TypeError, ArithmeticError, RuntimeError) as error:  # recorded
                record = {"task_name": task, "method": label(method), "seed": seed,
                          "success": False,
                          "interaction_s": None, "episodes": 0, "mpc_step_ms": None,
                          "error": f"{type(error).__name__}: {error}"}
            record["code"] = _commit()
            _append(JSONL, json.dumps(record, default=float) + "\n")
            print(f"    -> success {record['success']}, interaction "
                  f"{record['interaction_s']}", file=sys.stderr, flush=True)
    print(write_summary(NOTES_PATH.read_text() if NOTES_PATH.exists() else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
