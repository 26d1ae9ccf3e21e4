"""Unforced identification from noisy positions with kinematic catalogs: SINDy-PI path vs
errors-in-variables total least squares.

Each run: a MuJoCo system (``pysindy_xl.mujoco``), three unforced 10 s trajectories from random
initial states (``generate_dataset(forcing="implicit")``, 10 ms samples), Gaussian noise of
``level`` times each coordinate's standard deviation on the positions only; the kinematic
catalog (``kinematic_catalog(system, coulomb=False)``). Methods:

* ``implicit``: ``ImplicitOptimizer()`` (noise-ratio selection of the support);
* ``tls``: the default for a complete catalog, ``TotalLeastSquaresOptimizer()`` (every
  column, errors-in-variables law).

Metrics: the largest relative error of the Lagrangian base parameters after scaling the law
on the dominant one (``params <= 2 %``), the same for the friction terms, the number of
undetermined directions reported, fit time, and validation (``validate_model``: a fresh 5 s
unforced MuJoCo trajectory).

Usage: ``python benchmarks/unforced_kinematic.py [--seeds 10] [--levels 0.01,0.03,0.05,0.1]
[--systems cart-pole,double-pendulum,cart-double-pendulum,triple-pendulum]``
"""

from __future__ import annotations

import argparse
import json
import pathlib
import time
import warnings

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent


def run(name, level, seed, method):
    import pysindy_xl as px
    from pysindy_xl.evaluation.validation import validate_model
    from pysindy_xl.mujoco import generate_dataset, get_system
    from pysindy_xl.mujoco.catalogs.kinematic import kinematic_catalog

    system = get_system(name)
    catalog = kinematic_catalog(system, coulomb=False)
    library = catalog.library()
    forces = library.fit().force_columns_
    names = library.get_feature_names()
    truth = catalog.true_coefficients().copy()
    truth[forces] = 0.0
    lagrange = np.array([n.startswith("L[") for n in names]) & (truth != 0)
    friction = np.array([n.startswith("C") for n in names]) & (truth != 0)
    data = generate_dataset(system, n_trajectories=3, duration=10.0, seed=seed, sample_every=10,
                            forcing="implicit", noise=level, noise_model="positions",
                            progress=False)
    arguments = {k: v for k, v in data.fit_arguments(forces=None).items() if k != "u"}
    optimizer = {"implicit": px.ImplicitOptimizer(), "tls": None}[method]
    record = {"system": name, "level": level, "seed": seed, "method": method}
    start = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = px.XLSINDy(library, optimizer).fit(**arguments)
        record["fit_s"] = time.perf_counter() - start
        coef = model.coefficients()
        ref = np.flatnonzero(lagrange)[np.argmax(np.abs(truth[lagrange]))]
        scaled = coef * truth[ref] / coef[ref] if coef[ref] else coef * np.nan
        error = np.abs(scaled - truth) / np.abs(np.where(truth != 0, truth, 1.0))
        record["param_error"] = float(np.nanmax(np.where(lagrange, error, 0.0)))
        record["friction_error"] = float(np.nanmax(np.where(friction, error, 0.0)))
        record["undetermined"] = len(getattr(model.optimizer_, "undetermined_", []))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            record["valid"] = bool(validate_model(model, system, duration=5.0,
                                                  forcing="implicit", seed=seed + 500).valid)
        record["status"] = "ok"
    except Exception as err:  # a failed fit counts as a failure, with its reason
        record.update(status="error", message=f"{type(err).__name__}: {err}"[:300],
                      param_error=np.inf, friction_error=np.inf, valid=False,
                      fit_s=time.perf_counter() - start)
    return record


def summarize(records) -> str:
    rows = ["| system | noise | method | params within 2 % | median param. error | "
            "median friction error | valid | median fit (s) |", "|---|---|---|---|---|---|---|---|"]
    for key in sorted({(r["system"], r["level"], r["method"]) for r in records}):
        cell = [r for r in records if (r["system"], r["level"], r["method"]) == key]
        within = sum(r["param_error"] <= 0.02 for r in cell)
        rows.append(f"| {key[0]} | {key[1]:.1%} | {key[2]} | {within}/{len(cell)} | "
                    f"{np.median([r['param_error'] for r in cell]):.2%} | "
                    f"{np.median([r['friction_error'] for r in cell]):.1%} | "
                    f"{sum(r['valid'] for r in cell)}/{len(cell)} | "
                    f"{np.median([r['fit_s'] for r in cell]):.1f} |")
    return "\n".join(rows)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--levels", default="0.01,0.03,0.05,0.1")
    parser.add_argument("--systems",
                        default="cart-pole,double-pendulum,cart-double-pendulum,triple-pendulum")
    parser.add_argument("--methods", default="implicit,tls")
    parser.add_argument("--jobs", type=int, default=1)
    args = parser.parse_args()
    from joblib import Parallel, delayed

    tasks = [(s, float(lv), seed, m) for s in args.systems.split(",")
             for lv in args.levels.split(",") for seed in range(args.seeds)
             for m in args.methods.split(",")]
    start = time.perf_counter()
    records = list(Parallel(n_jobs=args.jobs, verbose=5)(delayed(run)(*t) for t in tasks))
    out = HERE / "results"
    with open(out / "unforced_kinematic.jsonl", "w") as f:
        f.writelines(json.dumps(r) + "\n" for r in records)
    table = summarize(records)
    (out / "unforced_kinematic.md").write_text(
        f"{len(records)} runs, {args.seeds} seeds per cell (command: python "
        f"benchmarks/unforced_kinematic.py --seeds {args.seeds} --levels {args.levels} "
        f"--systems {args.systems}; {time.perf_counter() - start:.0f} s wall)\n\n{table}\n")
    print(table)


if __name__ == "__main__":
    main()
