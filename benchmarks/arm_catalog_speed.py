"""Time of a 7-joint arm's kinematic catalog and of catalog + fit, wall and CPU.

Arms (``--arm``): ``panda``, the panda-like arm of ``benchmarks/robot_arms.py``, fitted on two
MuJoCo trajectories of ``--samples`` samples each; ``kinova-gen3``, the real Kinova Gen3
URDF (joint frames not aligned with the axes: ten times the monomials of the panda's
columns), fitted on the training part of its real log (``benchmarks/real_robots.py``);
``ur10e``, the 6-joint UR10e URDF on its identification run (5,375 samples, jittered stamps).
Steps: ``kinematic_catalog`` from a cold cache (``catalog``; the on-disk cache of derivations
is turned off, ``PYSINDY_XL_CACHE=off``, for every step but ``catalog_disk``: the catalog read
back from that cache, the in-memory one cleared), ``catalog.library().fit()``
(``library``), and ``kinematic_catalog`` + ``XLSINDy(catalog.library()).fit(q, t, u=tau)``,
every cache cleared first (``catalog_fit``), the same with the in-memory caches cleared and
the on-disk one warm (``catalog_fit_disk``: a first fit in a new process of a machine that
has derived this arm's catalog before), then the same again with the caches it filled
(``refit``: the regression alone, so that ``catalog_fit - refit`` is what deriving the
catalog costs a first fit, measured in the same conditions). Each is repeated; the
record gives the best and the median, wall and process CPU time. Run the same command
before and after a change in the same conditions (``PYTHONPATH`` pointing at each version)
and compare.

Usage: ``python benchmarks/arm_catalog_speed.py --label after [--arm kinova-gen3
[--log-samples 15000]] [--repeats 3]`` (``--log-samples``: the real log repeated as separate
runs to that many samples; each copy after the first carries its own dither of 1e-6 rad,
below the encoders' resolution, so that no copy shares the evaluations of another, as the
runs of a real long log would not); appends to ``benchmarks/results/arm_catalog_speed.json``.
"""

import argparse
import json
import os
import platform
import statistics
import sys
import tempfile
import time
import warnings

import numpy as np

import pysindy_xl as px
from pysindy_xl.feature_library import _base, polynomial_lagrange, repartition
from pysindy_xl.mujoco import MJCFSystem, generate_dataset
from pysindy_xl.mujoco.catalogs import kinematic as kinematic_module

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from robot_arms import arm_mjcf  # noqa: E402

RESULTS = os.path.join(HERE, "results", "arm_catalog_speed.json")


def clear_caches():
    kinematic_module._CACHE.clear()
    polynomial_lagrange._DERIVATIONS.clear()
    _base._DERIVED.clear()
    getattr(repartition, "_MERGED", {}).clear()


def timed(function):
    wall, cpu = time.perf_counter(), time.process_time()
    out = function()
    return out, time.perf_counter() - wall, time.process_time() - cpu


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--label", required=True, help="e.g. before or after")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--samples", type=int, default=3000, help="per trajectory (two)")
    parser.add_argument("--arm", choices=("panda", "kinova-gen3", "ur10e"), default="panda")
    parser.add_argument("--log-samples", type=int, default=None,
                        help="real arms: samples in all, the training log repeated as runs "
                             "(default: the log once)")
    args = parser.parse_args()
    warnings.simplefilter("ignore")  # the Kinova URDF's impossible inertias, balanced
    if args.arm == "panda":
        system = MJCFSystem(arm_mjcf("panda"), force_amplitude=1.0)
        step = system.mj_model().opt.timestep
        data = generate_dataset(system, n_trajectories=2, duration=args.samples * step,
                                seed=0, progress=False)
        fit_arguments = data.fit_arguments(forces="tau")
        samples = int(sum(len(t) for t in fit_arguments["t"]))
    else:
        import real_robots

        (t, q, tau), _, urdf = (real_robots.kinova() if args.arm == "kinova-gen3"
                                else real_robots.ur10e())
        system = real_robots.mjcf_system(urdf)
        # the log as separate runs: whole copies, then its start, to --log-samples in all
        total = args.log_samples or len(t)
        pieces = [slice(0, len(t))] * (total // len(t)) + (
            [slice(0, total % len(t))] if total % len(t) else [])
        dither = np.random.default_rng(0)
        fit_arguments = {"x": [q[k] + (1e-6 * dither.uniform(-1, 1, q[k].shape) if i else 0.0)
                               for i, k in enumerate(pieces)], "t": [t[k] for k in pieces],
                         "u": [tau[k] for k in pieces]}
        samples = total
    load = os.getloadavg()
    times = {"catalog": [], "catalog_disk": [], "library": [], "catalog_fit": [],
             "catalog_fit_disk": [], "refit": []}
    disk = tempfile.mkdtemp(prefix="arm_catalog_speed")
    for _ in range(args.repeats):
        os.environ["PYSINDY_XL_CACHE"] = disk
        clear_caches()
        px.kinematic_catalog(system)  # written to the disk cache (where the code has one)
        clear_caches()
        _, wall, cpu = timed(lambda: px.kinematic_catalog(system))
        times["catalog_disk"].append((wall, cpu))
        os.environ["PYSINDY_XL_CACHE"] = "off"
        clear_caches()
        catalog, wall, cpu = timed(lambda: px.kinematic_catalog(system))
        times["catalog"].append((wall, cpu))
        clear_caches()
        _, wall, cpu = timed(lambda catalog=catalog: catalog.library().fit())
        times["library"].append((wall, cpu))
        clear_caches()
        model, wall, cpu = timed(lambda: px.XLSINDy(px.kinematic_catalog(system).library())
                                 .fit(**fit_arguments))
        times["catalog_fit"].append((wall, cpu))
        _, wall, cpu = timed(lambda: px.XLSINDy(px.kinematic_catalog(system).library())
                             .fit(**fit_arguments))
        times["refit"].append((wall, cpu))
        os.environ["PYSINDY_XL_CACHE"] = disk  # (filled with the plans by a first fit)
        clear_caches()
        px.XLSINDy(px.kinematic_catalog(system).library()).fit(**fit_arguments)
        clear_caches()
        _, wall, cpu = timed(lambda: px.XLSINDy(px.kinematic_catalog(system).library())
                             .fit(**fit_arguments))
        times["catalog_fit_disk"].append((wall, cpu))
        os.environ["PYSINDY_XL_CACHE"] = "off"
    record = {
        "label": args.label, "pysindy_xl": os.path.dirname(px.__file__),
        "machine": {"python": platform.python_version(), "cpus": os.cpu_count(),
                    "load_average": load, "load_average_end": os.getloadavg()},
        "arm": args.arm, "joints": system.n, "samples": samples,
        "coefficients_checksum": float(np.sum(np.abs(model.coefficients()))),
    }
    for key, values in times.items():
        walls, cpus = [v[0] for v in values], [v[1] for v in values]
        record[key] = {"wall_best": round(min(walls), 3), "wall_median": round(
            statistics.median(walls), 3), "cpu_best": round(min(cpus), 3),
            "cpu_median": round(statistics.median(cpus), 3)}
    print(json.dumps(record))
    os.makedirs(os.path.dirname(RESULTS), exist_ok=True)
    records = []
    if os.path.exists(RESULTS):
        with open(RESULTS, encoding="utf-8") as f:
            records = json.load(f)
    records.append(record)
    with open(RESULTS, "w", encoding="utf-8") as f:
        json.dump(records, f, indent=1)


if __name__ == "__main__":
    main()
