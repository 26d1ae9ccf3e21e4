"""A 7-joint arm on a real log's time stamps against the same motion resampled uniformly.

Data: the Panda-shaped servo arm of ``robot_arms.py`` simulated 21 s by MuJoCo (RK4, 0.5 ms
steps), read at the stamps of a 1 kHz log (steps jittering by 8 % about 1 ms, and at a rate of
0.3 % gaps of 2 to 9 steps: samples lost) by cubic Hermite interpolation of MuJoCo's
positions and velocities; encoder positions quantized to 1e-5 rad (after a 2e-6 rad noise),
torques with a Gaussian noise of 2 % of each joint's standard deviation. The first 14 s
identify, the last 7 s are held out.

Cases: the default fit ``XLSINDy(catalog.library())`` on the stamps as recorded (``rec``) and
on the log resampled to a uniform 1 ms grid by linear interpolation (``uni``), each with the
default residual covariance (``T``) and without it (``F``). Metric: held-out torque RMS
relative to the torques' RMS, all joints together, against the measured (noisy) torques and
against the true ones, at MuJoCo's exact held-out states (the model's own error); fit time,
and the time of the catalog (derivation and symbolic fit, once per seed, in the same process
after the imports).

Usage: ``python benchmarks/log_stamps.py [--seeds 0,1] [--cases rec-T,rec-F,uni-T,uni-F]``;
records are appended to ``benchmarks/results/log_stamps.jsonl`` (``LABEL`` in the environment
names the code measured, e.g. ``LABEL=before PYTHONPATH=old-checkout``).
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys
import time
import warnings

import numpy as np
import scipy.interpolate

RESULTS = pathlib.Path(__file__).resolve().parent / "results"


def log_stamps(duration, rng, step=1e-3, jitter=0.08, gap_rate=0.003, longest=9):
    """Stamps of a logger: jittered steps and occasional gaps of lost samples."""
    n = int(duration / step)
    steps = step * np.clip(1 + jitter * rng.standard_normal(n), 0.3, None)
    gaps = rng.random(n) < gap_rate
    steps[gaps] = step * (rng.integers(2, longest + 1, gaps.sum())
                          + jitter * rng.standard_normal(gaps.sum()))
    return np.round(0.01 + np.concatenate([[0.0], np.cumsum(steps)]), 6)


def simulate(seed):
    """The arm's MJCF and its motion at the stamps of a log: (xml, t, q, qd, qdd, tau)."""
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    from robot_arms import arm_mjcf

    from pysindy_xl.mujoco import MJCFSystem, generate_dataset

    xml = arm_mjcf("panda").replace('timestep="0.002"', 'timestep="0.0005"')
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = generate_dataset(MJCFSystem(xml), n_trajectories=1, duration=21.0, seed=seed,
                               derivatives=True, progress=False).trajectories[0]
    rng = np.random.default_rng(seed + 7)
    t = log_stamps(21.0, rng)
    t = t[t < run.t[-1] - 0.01]
    hermite = scipy.interpolate.CubicHermiteSpline
    q = hermite(run.t, run.q, run.qd)(t)
    qd = hermite(run.t, run.qd, run.qdd)(t)
    qdd = scipy.interpolate.CubicSpline(run.t, run.qdd)(t)
    tau = scipy.interpolate.CubicSpline(run.t, run.tau)(t)
    return xml, t, q, qd, qdd, tau


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", default="0")
    parser.add_argument("--cases", default="rec-T,rec-F,uni-T,uni-F")
    args = parser.parse_args()
    import pysindy_xl as px
    from pysindy_xl.mujoco import MJCFSystem, kinematic_catalog

    for seed in map(int, args.seeds.split(",")):
        xml, t, q, qd, qdd, tau_true = simulate(seed)
        rng = np.random.default_rng(seed)
        tau = tau_true + 0.02 * tau_true.std(axis=0) * rng.standard_normal(tau_true.shape)
        encoder = np.round((q + 2e-6 * rng.standard_normal(q.shape)) / 1e-5) * 1e-5
        train, test = t < 14.0, t >= 14.0
        grid = np.arange(t[0], t[train][-1], 1e-3)
        resampled = [np.column_stack([np.interp(grid, t[train], c) for c in a[train].T])
                     for a in (encoder, tau)]
        start = time.perf_counter()
        library = kinematic_catalog(MJCFSystem(xml)).library()
        library.fit()  # the derivation is cached: timed here, once, not in the fit times
        catalog_s = time.perf_counter() - start
        for case in args.cases.split(","):
            stamps, weighting = case.split("-")
            x, times, u = ((encoder[train], t[train], tau[train]) if stamps == "rec"
                           else (resampled[0], grid, resampled[1]))
            start = time.perf_counter()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                model = px.XLSINDy(library, residual_covariance=weighting == "T").fit(
                    x, times, u=u)
            fit_s = time.perf_counter() - start
            predicted = model.predict_forces(q[test], qd[test], qdd[test])
            steps = np.diff(t[train])
            record = {
                "seed": seed, "case": case, "samples": len(times),
                "catalog_s": round(catalog_s, 2), "fit_s": round(fit_s, 2),
                "load_average": os.getloadavg()[0],
                "heldout_measured": float(np.linalg.norm(predicted - tau[test])
                                          / np.linalg.norm(tau[test])),
                "heldout_true": float(np.linalg.norm(predicted - tau_true[test])
                                      / np.linalg.norm(tau_true[test])),
                "median_step": float(np.median(steps)), "max_step": float(steps.max()),
                "gaps_cut": len(model.weak_info_.get("gaps", [])),
                "code": os.environ.get("LABEL", "branch")}
            print(json.dumps(record), flush=True)
            with open(RESULTS / "log_stamps.jsonl", "a") as handle:
                handle.write(json.dumps(record) + "\n")


if __name__ == "__main__":
    main()
