"""Excitation trajectories: optimized against random Fourier series under the same limits.

Arms: the three servo arms of ``robot_arms.py`` (shaped like a UR5, a Franka Panda and a KUKA
iiwa; position servos with armature, damping and limits). Limits: the MJCF's joint ranges
within the servos' control ranges less 5 % at each end (the default), 1.5 rad/s, 5 rad/s^2 and
the torque limits of the real arms (:data:`TORQUE_LIMITS`, checked on the MJCF's nominal
inertials). Series: 5 harmonics, period 10 s, starting and ending at rest.

* ``optimized``: :func:`pysindy_xl.mujoco.excitation_trajectory` (3 random starts, seed 0);
* ``random``: random Fourier series under the same limits (``optimize=False``, seeds 1-5:
  coefficients drawn, each joint scaled to touch its tightest limit, then all joints together
  under the torque limits).

Metrics: the condition number of the identification regressor (the kinematic catalog's
columns: base parameters, viscous and smooth Coulomb friction) along one period of the planned
trajectory, and along the run MuJoCo's position servos actually make of it; then a simulated
identification: :func:`~pysindy_xl.mujoco.generate_dataset` plays the trajectory through the
servos for two periods (``reference=``), recorded at 250 Hz, 1 % Gaussian noise on the
positions (3 noise seeds), ``XLSINDy(catalog.library())`` with its defaults; mass-matrix error as
in ``robot_arms.py`` (mean over 200 random joint states of ``|M_id - M|_F / |M|_F``) and
torque error on a fresh random-signal run (worst joint, relative RMS).

Usage: ``python benchmarks/excitation.py [--arms ur5,panda,iiwa] [--randoms 5] [--seeds 3]``;
records appended to ``results/excitation.jsonl``, summary in ``results/excitation.md``.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from robot_arms import arm_mjcf  # noqa: E402

RESULTS = pathlib.Path(__file__).resolve().parent / "results"
#: Per-joint torque limits (N m) of the real arms the models are shaped like.
TORQUE_LIMITS = {"ur5": [150, 150, 150, 28, 28, 28],
                 "panda": [87, 87, 87, 87, 12, 12, 12],
                 "iiwa": [176, 176, 110, 110, 110, 40, 40]}
LIMITS = dict(velocity_limits=1.5, acceleration_limits=5.0, n_harmonics=5, period=10.0)


def regressor_condition(library, q, qd, qdd):
    from pysindy_xl import stack_variables

    theta = library.transform(stack_variables(q, qd, qdd))
    return float(np.linalg.cond(np.delete(theta, library.force_columns_, axis=1)))


def identify(system, catalog, trajectory, seed, fresh):
    """Mass-matrix and torque errors of the default fit on two periods played by the servos."""
    import pysindy_xl as px
    from pysindy_xl.mujoco import generate_dataset

    library = catalog.library().fit()
    kwargs = dict(n_trajectories=1, duration=2 * trajectory.period, sample_every=2,
                  progress=False, reference=trajectory, seed=seed)
    clean = generate_dataset(system, **kwargs).trajectories[0]
    data = generate_dataset(system, noise=0.01, **kwargs)
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = px.XLSINDy(library).fit(**data.fit_arguments(forces="tau"))
    fit_s = time.perf_counter() - start
    coef = model.coefficients()
    coef = -coef / coef[library.force_columns_[0]]
    beta = coef[[j for j, c in enumerate(library.categories_) if c == "lagrange"]]
    limits = system.mj_model().jnt_range
    q = np.random.default_rng(0).uniform(limits[:, 0], limits[:, 1], size=(200, system.n))
    mass, mass_id = catalog.mass_matrix(q), catalog.mass_matrix(q, beta)
    theta = library.transform(px.stack_variables(fresh.q, fresh.qd, fresh.qdd)).reshape(
        system.n, len(fresh.t), -1)
    rest = np.setdiff1d(np.arange(theta.shape[-1]), library.force_columns_)
    predicted = (theta[:, :, rest] @ coef[rest]).T
    torque = np.sqrt(np.mean((predicted - fresh.tau) ** 2, axis=0) / np.mean(fresh.tau**2,
                                                                             axis=0))
    half = len(clean.t) // 2  # the second period: the servos' start transient is over
    return dict(
        mass_error=float(np.mean(np.linalg.norm(mass_id - mass, axis=(1, 2))
                                 / np.linalg.norm(mass, axis=(1, 2)))),
        torque_error=float(torque.max()), fit_s=fit_s,
        realized_condition=regressor_condition(library, clean.q[half:], clean.qd[half:],
                                               clean.qdd[half:]),
        tracking_error=float(np.max(np.abs(clean.q - trajectory.q(clean.t)))),
        constrained=float(clean.constraint_active.mean()))


def run_arm(arm, n_random, n_seeds, out, restarts=3, max_iter=100):
    from pysindy_xl.mujoco import (
        MJCFSystem,
        excitation_trajectory,
        generate_dataset,
        kinematic_catalog,
    )

    system = MJCFSystem(arm_mjcf(arm))
    catalog = kinematic_catalog(system)
    fresh = generate_dataset(system, n_trajectories=1, duration=5.0, seed=1000, sample_every=2,
                             progress=False).trajectories[0]
    limits = LIMITS | {"torque_limits": TORQUE_LIMITS[arm]}
    designs = []
    start = time.perf_counter()
    best = excitation_trajectory(system, restarts=restarts, seed=0, max_iter=max_iter, **limits)
    designs.append(("optimized", 0, best, time.perf_counter() - start))
    for seed in range(1, n_random + 1):
        start = time.perf_counter()
        designs.append(("random", seed, excitation_trajectory(system, optimize=False, seed=seed,
                                                              restarts=1, **limits),
                        time.perf_counter() - start))
    records = []
    for kind, seed, trajectory, design_s in designs:
        for noise_seed in range(n_seeds):
            record = dict(arm=arm, kind=kind, design_seed=seed, noise_seed=noise_seed,
                          condition=trajectory.condition_number, design_s=design_s,
                          restarts=trajectory.info["restarts"])
            record.update(identify(system, catalog, trajectory, noise_seed, fresh))
            print(json.dumps({k: v for k, v in record.items() if k != "restarts"}), flush=True)
            with out.open("a") as handle:
                handle.write(json.dumps(record) + "\n")
            records.append(record)
    return records


def summarize(records) -> str:
    lines = ["| arm | trajectory | condition number (planned) | condition number (as the servos "
             "ran it) | mass-matrix error at 1 % noise (median / worst) | torque error "
             "(median) | servo tracking error (rad, median) | design (s) |",
             "|---|---|---|---|---|---|---|---|"]
    verdicts = []
    for arm in dict.fromkeys(r["arm"] for r in records):
        rows = {kind: [r for r in records if r["arm"] == arm and r["kind"] == kind]
                for kind in ("optimized", "random")}
        if not rows["optimized"] or not rows["random"]:
            continue
        for kind, rs in rows.items():
            conditions = sorted({r["design_seed"]: r["condition"] for r in rs}.values())
            realized = [r["realized_condition"] for r in rs]
            mass = [r["mass_error"] for r in rs]
            lines.append(
                f"| {arm} | {kind} ({len(conditions)}) | {np.median(conditions):.1f}"
                f"{'' if len(conditions) == 1 else f' ({conditions[0]:.0f}-{conditions[-1]:.0f})'}"
                f" | {np.median(realized):.1f} | {np.median(mass):.3%} / {np.max(mass):.3%} | "
                f"{np.median([r['torque_error'] for r in rs]):.2%} | "
                f"{np.median([r['tracking_error'] for r in rs]):.2f} | "
                f"{np.median([r['design_s'] for r in rs]):.0f} |")
        ratio = rows["optimized"][0]["condition"] / np.median(
            list({r["design_seed"]: r["condition"] for r in rows["random"]}.values()))
        better = np.median([r["mass_error"] for r in rows["optimized"]]) <= np.median(
            [r["mass_error"] for r in rows["random"]])
        verdicts.append(f"- {arm}: condition number ratio optimized / median random "
                        f"{ratio:.2f} ({'<=' if ratio <= 0.5 else '>'} 0.5); mass-matrix error "
                        f"{'at most' if better else 'above'} the random trajectories' median")
    return ("Optimized excitation against random Fourier series under the same limits (see "
            "excitation.py for the setup; times are wall clock on a shared 2-core machine)\n\n"
            + "\n".join(lines) + "\n\n" + "\n".join(verdicts) + "\n\n" + NOTE)


#: What the table does not say by itself.
NOTE = ("The arms' position servos are soft (``kp = 200 / (k + 1)``): they follow a reference "
        "with errors of tenths of a radian, so the run is not the planned trajectory. Where they "
        "distort it most (iiwa: condition number 45 planned, 150 as run, against 85 for the "
        "random series as run) the optimized design's gain in accuracy is small; a controller "
        "that tracks its reference keeps the planned conditioning.\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arms", default="ur5,panda,iiwa")
    parser.add_argument("--randoms", type=int, default=5)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--restarts", type=int, default=3)
    parser.add_argument("--max-iter", type=int, default=100)
    parser.add_argument("--out", default=str(RESULTS))
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "excitation.jsonl"
    for arm in args.arms.split(","):
        run_arm(arm, args.randoms, args.seeds, path, args.restarts, args.max_iter)
    records = [json.loads(line) for line in path.read_text().splitlines()]
    (out / "excitation.md").write_text(summarize(records))
    print(summarize(records))


if __name__ == "__main__":
    main()
