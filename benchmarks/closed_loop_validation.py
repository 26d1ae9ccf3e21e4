"""Closed-loop validation time on a 7-joint arm: MuJoCo stepping the identified model against
integrating its equations (scipy's DOP853, the ROS2 path).

Identifies a stripped Menagerie arm of ``benchmarks/models/menagerie`` (default the Franka
FR3: stiff position servos, kv 200-450) from one noise-free trajectory, then validates it in
closed loop against the same fresh MuJoCo reference three times: ``simulator="mujoco"`` (the
identified parameters in MuJoCo under the MJCF's own actuators, the default where MJCF can
state the model), and the identified equations integrated by ``DOP853`` (adaptive, rtol 1e-8;
the default before) and by ``method="ROS2"`` (L-stable Rosenbrock, local error 1e-3). Prints
the wall time of each, the number of evaluations of the identified equations, the metrics and
how far the paths are apart; writes ``benchmarks/results/closed_loop_validation.json``.

Usage::

    python benchmarks/closed_loop_validation.py [--arm fr3] [--horizon 2.0] [--duration 4.0]
        [--skip-dop853]
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def main(argv=None):
    import pysindy_xl as px
    from pysindy_xl.evaluation.validation import validate_model, validation_trajectory
    from pysindy_xl.mujoco import MJCFSystem, generate_dataset, kinematic_catalog

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--horizon", type=float, default=2.0)
    parser.add_argument("--duration", type=float, default=4.0)
    parser.add_argument("--arm", default="fr3")
    parser.add_argument("--skip-dop853", action="store_true")
    args = parser.parse_args(argv)
    system = MJCFSystem(os.path.join(HERE, "models", "menagerie", f"{args.arm}.xml"))
    data = generate_dataset(system, n_trajectories=1, duration=args.duration, seed=0,
                            sample_every=2, progress=False)
    model = px.XLSINDy(kinematic_catalog(system).library(), px.ExplicitOptimizer())
    model.fit(**data.fit_arguments(forces="tau"))
    reference = validation_trajectory(system, args.horizon, seed=10_000)
    dynamics = model.dynamics_
    counted = {"n": 0}
    evaluate = dynamics._evaluate_scalar

    def counting(*values):
        counted["n"] += 1
        return evaluate(*values)

    dynamics._evaluate_scalar = counting
    runs = {}
    paths = [("MuJoCo", {"simulator": "mujoco"}),
             ("DOP853", {"simulator": "model"}),
             ("ROS2", {"simulator": "model", "method": "ROS2"})]
    if args.skip_dop853:
        paths.pop(1)
    for label, options in paths:
        counted["n"] = 0
        start = time.perf_counter()
        result = validate_model(model, system, trajectory=reference, timeout=3600, **options)
        runs[label] = {"time_s": time.perf_counter() - start, "evaluations": counted["n"],
                       "valid": bool(result.valid), "force_error": result.force_error,
                       "position_rmse": result.position_rmse, "prediction": result.prediction}
        print(f"{label:7s} {runs[label]['time_s']:7.2f} s  {counted['n']:6d} evaluations  "
              f"force error {result.force_error:.4f}  position RMSE "
              f"{result.position_rmse:.2e}  {'VALID' if result.valid else 'INVALID'}",
              flush=True)
    n = system.n
    predictions = {label: run.pop("prediction") for label, run in runs.items()}
    fast = predictions["MuJoCo"]
    gaps, speedups = {}, {}
    for label in runs:
        if label == "MuJoCo":
            continue
        other = predictions[label]
        k = min(len(fast), len(other))
        gaps[label] = {"max_position_gap": float(np.abs(fast[:k, :n] - other[:k, :n]).max()),
                       "max_velocity_gap": float(np.abs(fast[:k, n:] - other[:k, n:]).max())}
        speedups[label] = runs[label]["time_s"] / runs["MuJoCo"]["time_s"]
        print(f"MuJoCo against {label}: {speedups[label]:.1f}x faster; largest gaps: "
              f"positions {gaps[label]['max_position_gap']:.2e} rad, velocities "
              f"{gaps[label]['max_velocity_gap']:.2e} rad/s")
    load = os.getloadavg() if hasattr(os, "getloadavg") else None
    record = {"system": f"{args.arm} (stripped Menagerie)", "horizon_s": args.horizon,
              "training_duration_s": args.duration,
              "reference_integration": {"integrator": reference.info.get("integrator"),
                                        "substeps": reference.info.get("substeps")},
              "runs": runs, "speedup_over": speedups, "gaps_to_mujoco": gaps,
              "load_average": load, "cpus": os.cpu_count(),
              "note": "wall times on the machine of the run (shared; see load_average); "
                      "compare within one record"}
    os.makedirs(os.path.join(HERE, "results"), exist_ok=True)
    name = "closed_loop_validation" + ("" if args.arm == "fr3" else f"_{args.arm}")
    with open(os.path.join(HERE, "results", f"{name}.json"), "w",
              encoding="utf-8") as handle:
        json.dump(record, handle, indent=2)


if __name__ == "__main__":
    main()
