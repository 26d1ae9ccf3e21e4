"""Catalog size, build time and accuracy: kinematic catalog vs the paper-style catalog.

Systems: the three shipped ones and the MJCF models of the tests (a 3-link planar arm with
off-axis centres of mass and full inertias, a 4-hinge spatial arm with tilted axes, armature and
damping, a cart carrying a 2-link pendulum with a spring), plus optional generic serial arms.

For each system and catalog (``kinematic``: :func:`pysindy_xl.kinematic_catalog`; ``mixed``:
the paper's velocity x trigonometric monomials of degree 2 plus viscous friction):

* ``columns``: features of the catalog (force column included);
* ``derive_s``: kinematic derivation and base-parameter reduction (cold cache);
* ``library_s``: symbolic Euler-Lagrange columns and compilation (``library.fit()``);
* ``span_residual``: least-squares fit of ``Theta_rest xi = tau`` on one noise-free MuJoCo
  trajectory (forced on every joint), relative residual on another: round-off when the true
  model is in the catalog's span (held out, so that a large catalog cannot overfit);
* ``fit_s``: ``XLSINDy.fit`` (explicit) with the kinematic catalog;
* for the kinematic catalog, ``mass_error`` and ``gravity_error``: relative error of ``M(q)``
  and the gravity torque identified by ``XLSINDy`` (explicit, noise-free) at 20 random states.

Usage: ``python benchmarks/kinematic_catalog.py [--robots 6 7] [--arms 5 6]``;
writes ``benchmarks/results/kinematic_catalog.{json,md}``.
"""

import argparse
import json
import os
import platform
import sys
import time

import numpy as np

os.environ["PYSINDY_XL_CACHE"] = "off"  # derivation times: no on-disk cache

import pysindy_xl as px
from pysindy_xl.feature_library import stack_variables
from pysindy_xl.mujoco import MJCFSystem, generate_dataset, get_system, reference_catalog
from pysindy_xl.mujoco.catalogs import kinematic as kinematic_module

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
import kinematic_models  # noqa: E402

RESULTS = os.path.join(os.path.dirname(__file__), "results")


def systems(arms, robots):
    out = {name: get_system(name) for name in
           ("cart-pole", "double-pendulum", "cart-double-pendulum")}
    out["planar-arm"] = MJCFSystem(kinematic_models.PLANAR_ARM, force_amplitude=4.0)
    out["spatial-arm"] = MJCFSystem(kinematic_models.SPATIAL_ARM, force_amplitude=3.0)
    out["cart-two-link"] = MJCFSystem(kinematic_models.CART_DOUBLE_PENDULUM,
                                      force_amplitude=3.0)
    for n in robots:
        out[f"robot-arm-{n}"] = MJCFSystem(kinematic_models.robot_arm(n), force_amplitude=1.0)
    for n in arms:
        out[f"serial-arm-{n}"] = MJCFSystem(kinematic_models.serial_arm(n), force_amplitude=3.0)
    return out


def span_residual(library, data):
    """Least-squares fit on the first trajectory, relative residual on the second one."""
    parts = []
    for tr in data.trajectories[:2]:
        theta = library.transform(stack_variables(tr.q, tr.qd, tr.qdd, tr.tau))
        force = theta[:, library.force_columns_].sum(axis=1)
        parts.append((np.delete(theta, library.force_columns_, axis=1), force))
    (train, train_force), (test, test_force) = parts
    scale = np.sqrt(np.mean(train**2, axis=0))
    scale[scale == 0] = 1.0
    solution = np.linalg.lstsq(train / scale, train_force, rcond=None)[0]
    return float(np.linalg.norm(test / scale @ solution - test_force)
                 / np.linalg.norm(test_force))


def benchmark(name, system, paper, fit):
    data = generate_dataset(system, n_trajectories=2, duration=2.0, seed=0, sample_every=5,
                            progress=False)
    records = []
    kinematic_module._CACHE.clear()
    start = time.perf_counter()
    catalog = px.kinematic_catalog(system)
    derive = time.perf_counter() - start
    start = time.perf_counter()
    library = catalog.library().fit()
    library_seconds = time.perf_counter() - start
    record = {
        "system": name, "catalog": "kinematic", "columns": library.n_output_features_,
        "lagrange_columns": len(catalog.lagrange_terms),
        "candidate_functions": catalog.n_candidates,
        "derive_s": round(derive, 3), "library_s": round(library_seconds, 3),
        "span_residual": span_residual(library, data),
    }
    if not fit:
        records.append(record)
        return records
    model = px.XLSINDy(catalog.library(), optimizer=px.ExplicitOptimizer(threshold=1e-8))
    start = time.perf_counter()
    try:
        model.fit(**data.fit_arguments(forces="tau"))
    except (RecursionError, ValueError, RuntimeError) as error:
        # large catalogs: the model's symbolic mass-matrix form may exceed Python's limits
        record["fit_error"] = f"{type(error).__name__}: {str(error)[:80]}"
    else:
        record["fit_s"] = round(time.perf_counter() - start, 3)
        identified = catalog.lagrange_coefficients(model)
        rng = np.random.default_rng(5)
        q = np.array([system.random_initial_state(rng)[0] for _ in range(20)])
        mass_true, gravity_true = catalog.mass_matrix(q), catalog.gravity_torque(q)
        record["mass_error"] = float(np.abs(catalog.mass_matrix(q, identified) - mass_true).max()
                                     / np.abs(mass_true).max())
        record["gravity_error"] = float(
            np.abs(catalog.gravity_torque(q, identified) - gravity_true).max()
            / np.abs(gravity_true).max())
    records.append(record)
    if paper:
        start = time.perf_counter()
        library = reference_catalog(system, "mixed").fit()
        library_seconds = time.perf_counter() - start
        records.append({
            "system": name, "catalog": "mixed (paper)", "columns": library.n_output_features_,
            "lagrange_columns": sum(c == "lagrange" for c in library.categories_),
            "derive_s": 0.0, "library_s": round(library_seconds, 3),
            "span_residual": span_residual(library, data),
        })
    return records


def markdown(records, machine):
    head = ("| system | catalog | columns | Lagrange | derive (s) | library (s) "
            "| held-out residual | XLSINDy fit (s) | M(q) error | gravity error |\n"
            "|---|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for r in records:
        def fmt(key, r=r):
            return f"{r[key]:.1e}" if key in r else "-"
        lines.append(f"| {r['system']} | {r['catalog']} | {r['columns']} | "
                     f"{r['lagrange_columns']} | {r['derive_s']} | {r['library_s']} | "
                     f"{fmt('span_residual')} | {r.get('fit_s', r.get('fit_error', '-'))} | "
                     f"{fmt('mass_error')} | {fmt('gravity_error')} |")
    return (f"Kinematic vs paper-style catalogs ({machine['processor'] or machine['machine']}, "
            f"Python {machine['python']})\n\n" + head + "\n".join(lines) + "\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arms", type=int, nargs="*", default=[],
                        help="also benchmark generic serial arms (every axis tilted) with these "
                             "joint counts")
    parser.add_argument("--robots", type=int, nargs="*", default=[],
                        help="also benchmark robot-like arms (axes along the link frames) with "
                             "these joint counts (at most 7)")
    parser.add_argument("--fit-max-joints", type=int, default=4,
                        help="run XLSINDy only up to this many joints (its symbolic mass-matrix "
                             "form is slow on the large terms of longer arms) (default: 4)")
    parser.add_argument("--skip-paper-for", nargs="*", default=[],
                        help="systems whose paper-style catalog is not built (too large)")
    args = parser.parse_args()
    machine = {"python": platform.python_version(), "machine": platform.machine(),
               "processor": platform.processor(), "cpus": os.cpu_count()}
    records = []
    for name, system in systems(args.arms, args.robots).items():
        paper = name not in args.skip_paper_for and not name.startswith(("serial", "robot"))
        fit = system.n <= args.fit_max_joints
        for record in benchmark(name, system, paper, fit):
            print(json.dumps(record), flush=True)
            records.append(record)
    os.makedirs(RESULTS, exist_ok=True)
    with open(os.path.join(RESULTS, "kinematic_catalog.json"), "w", encoding="utf-8") as f:
        json.dump({"machine": machine, "records": records}, f, indent=1)
    with open(os.path.join(RESULTS, "kinematic_catalog.md"), "w", encoding="utf-8") as f:
        f.write(markdown(records, machine))
    print(markdown(records, machine))


if __name__ == "__main__":
    main()
