"""Cost of an RK4 substep in implicitfast steps, and the integration of forced arm runs.

For each stripped MuJoCo Menagerie arm of ``benchmarks/models/menagerie/``, the model a forced
``generate_dataset`` run integrates (plain torque motors wrapped in their tracking servo,
:func:`~pysindy_xl.simulation.signals.motor_tracking`), and for it:

- the substeps RK4 needs under a held control (``h |lambda| <= RK4_HELD_BOUND``) and those
  the implicit step needs (inertia bias ``h max D_ii <= BIAS_TOLERANCE max |M_ij|``, stable);
- the time of one internal step of each integrator (µs) in the loop of
  :func:`~pysindy_xl.simulation.generate.simulate_trajectory` (set the control, ``mj_step``),
  best of ``--repeats`` runs of ``--steps`` steps, and their ratio: what ``RK4_COST`` prices;
- the integration :func:`~pysindy_xl.simulation.integration.choose_integration` picks
  (``held_control=True``) and the time of one model step with it (ms).

The two integrators are timed alternately on the same model, so the machine's load moves both.
Writes ``benchmarks/results/integration_cost.md`` (``--out``).

Usage::

    python benchmarks/integration_cost.py [ARM ...] [--steps 3000] [--repeats 3]
"""

from __future__ import annotations

import argparse
import copy
import math
import os
import time
import warnings

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
MODELS = os.path.join(HERE, "models", "menagerie")
ARMS = ("fr3", "xarm7", "ur10e", "sawyer", "z1", "lite6", "m1013", "piper", "arx_l5")


def forced_model(arm: str):
    """The MuJoCo model a forced ``generate_dataset`` run of the arm integrates."""
    from pysindy_xl.mujoco import get_system
    from pysindy_xl.mujoco.systems.tracking import tracked_model
    from pysindy_xl.simulation.signals import motor_tracking
    system = get_system(os.path.join(MODELS, f"{arm}.xml"))
    model = system.mj_model()
    controller = motor_tracking(system, model)
    return model if controller is None else tracked_model(model, controller)


def step_time(model, integrator: str, substeps: int, steps: int, repeats: int) -> float:
    """Seconds per internal step of ``integrator`` at ``timestep / substeps``."""
    import mujoco

    from pysindy_xl.simulation.integration import INTEGRATORS
    model = copy.deepcopy(model)
    model.opt.integrator = INTEGRATORS[integrator]
    model.opt.timestep = model.opt.timestep / substeps
    data = mujoco.MjData(model)
    ctrl = np.tile(data.ctrl, (steps, 1))
    best = math.inf
    for _ in range(repeats):
        mujoco.mj_resetData(model, data)
        start = time.perf_counter()
        for k in range(steps):
            data.ctrl[:] = ctrl[k]
            mujoco.mj_step(model, data)
        best = min(best, (time.perf_counter() - start) / steps)
    return best


def measure(arm: str, steps: int, repeats: int) -> dict:
    """One arm's row (see the module docstring)."""
    from pysindy_xl.simulation import integration as integ
    model = forced_model(arm)
    choice = integ.choose_integration(model, held_control=True)
    timestep = float(model.opt.timestep)
    rk4 = math.ceil(timestep * choice.rate / integ.RK4_HELD_BOUND)
    saved = integ.RK4_HELD_MAX_SUBSTEPS, integ.RK4_COST
    try:  # the implicit step choose_integration would take where RK4 were never kept
        integ.RK4_HELD_MAX_SUBSTEPS, integ.RK4_COST = 0, math.inf
        implicit = integ.choose_integration(model, held_control=True).substeps
    finally:
        integ.RK4_HELD_MAX_SUBSTEPS, integ.RK4_COST = saved
    rk4_s = implicit_s = math.inf
    for _ in range(2):  # alternate: the load moves both
        rk4_s = min(rk4_s, step_time(model, "RK4", min(rk4, 1000), steps, repeats))
        implicit_s = min(implicit_s, step_time(model, "implicitfast", implicit, steps, repeats))
    chosen_s = rk4_s if choice.integrator == "RK4" else implicit_s
    return {"arm": arm, "nv": model.nv, "rk4": rk4, "implicit": implicit,
            "rk4_us": rk4_s * 1e6, "implicit_us": implicit_s * 1e6, "ratio": rk4_s / implicit_s,
            "integrator": choice.integrator, "substeps": choice.substeps,
            "model_step_ms": chosen_s * choice.substeps * 1e3}


def table(rows) -> str:
    lines = ["| arm | nv | RK4 substeps (held) | implicit substeps | RK4 step (µs) | "
             "implicitfast step (µs) | ratio | chosen | model step (ms) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['arm']} | {r['nv']} | {r['rk4']} | {r['implicit']} | "
                     f"{r['rk4_us']:.1f} | {r['implicit_us']:.1f} | {r['ratio']:.2f} | "
                     f"{r['integrator']} {r['substeps']} | {r['model_step_ms']:.2f} |")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("arms", nargs="*", default=list(ARMS))
    parser.add_argument("--steps", type=int, default=3000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", default=os.path.join(HERE, "results", "integration_cost.md"))
    args = parser.parse_args(argv)
    rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for arm in args.arms:
            rows.append(measure(arm, args.steps, args.repeats))
            print(table(rows[-1:]).splitlines()[-1], flush=True)
    ratios = np.array([r["ratio"] for r in rows])
    text = (table(rows) + f"\n\nRK4 / implicitfast step: {ratios.min():.2f}-{ratios.max():.2f}, "
            f"median {np.median(ratios):.2f}.\n")
    print(text)
    with open(args.out, "w", encoding="utf-8") as handle:
        handle.write("# Cost of an RK4 substep in implicitfast steps (`integration_cost.py`)\n\n"
                     f"{args.steps} steps, best of {args.repeats} runs, two alternations; "
                     f"{os.cpu_count()} cores shared with other jobs (load average "
                     f"{os.getloadavg()[0]:.1f} at the end).\n\n" + text)


if __name__ == "__main__":
    main()
