"""Closed-loop validation time on a 7-joint arm: scipy's DOP853 against the ROS2 path.

Identifies the stripped Franka FR3 of ``benchmarks/models/menagerie`` (stiff position
servos, kv 200-450) from one noise-free trajectory, then validates it in closed loop against
the same fresh MuJoCo reference twice: with the default ``DOP853`` (adaptive, rtol 1e-8) and
with ``method="ROS2"`` (L-stable Rosenbrock, local error 1e-3, steps of at most the model's
2 ms). Prints the wall time of each, the number of evaluations of the identified dynamics,
the metrics and how far the two paths are apart; writes
``benchmarks/results/closed_loop_validation.json``.

Usage::

    python benchmarks/closed_loop_validation.py [--horizon 2.0] [--duration 4.0]
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
    from pysindy_xl.mujoco import MJCFSystem, generate_dataset, kinematic_catalog
    from pysindy_xl.mujoco.evaluation.validation import validate_model, validation_trajectory

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--horizon", type=float, default=2.0)
    parser.add_argument("--duration", type=float, default=4.0)
    args = parser.parse_args(argv)
    system = MJCFSystem(os.path.join(HERE, "models", "menagerie", "fr3.xml"))
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
    for label, options in (("DOP853", {}), ("ROS2", {"method": "ROS2"})):
        counted["n"] = 0
        start = time.perf_counter()
        result = validate_model(model, system, trajectory=reference, timeout=3600, **options)
        runs[label] = {"time_s": time.perf_counter() - start, "evaluations": counted["n"],
                       "valid": bool(result.valid), "force_error": result.force_error,
                       "position_rmse": result.position_rmse, "prediction": result.prediction}
        print(f"{label:7s} {runs[label]['time_s']:7.2f} s  {counted['n']:6d} evaluations  "
              f"force error {result.force_error:.4f}  position RMSE "
              f"{result.position_rmse:.2e}  {'VALID' if result.valid else 'INVALID'}")
    n = system.n
    a, b = runs["DOP853"].pop("prediction"), runs["ROS2"].pop("prediction")
    k = min(len(a), len(b))
    gap = {"max_position_gap": float(np.abs(a[:k, :n] - b[:k, :n]).max()),
           "max_velocity_gap": float(np.abs(a[:k, n:] - b[:k, n:]).max())}
    speedup = runs["DOP853"]["time_s"] / runs["ROS2"]["time_s"]
    print(f"ROS2 against DOP853: {speedup:.1f}x faster; largest gaps: positions "
          f"{gap['max_position_gap']:.2e} rad, velocities {gap['max_velocity_gap']:.2e} rad/s")
    record = {"system": "fr3 (stripped Menagerie)", "horizon_s": args.horizon,
              "training_duration_s": args.duration, "runs": runs, "speedup": speedup, **gap,
              "note": "wall times on the machine of the run; compare within one record"}
    os.makedirs(os.path.join(HERE, "results"), exist_ok=True)
    with open(os.path.join(HERE, "results", "closed_loop_validation.json"), "w",
              encoding="utf-8") as handle:
        json.dump(record, handle, indent=2)


if __name__ == "__main__":
    main()
