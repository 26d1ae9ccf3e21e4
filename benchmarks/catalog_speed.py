"""Time of the automatic catalog (``px.grow_catalog``: growth plus the final fit) per system.

The data are those of ``benchmarks/generic_systems.py``: 2 forced runs of 10 s at 1 kHz (20,000
samples), positions only with 1 % noise. Per system it prints the wall and CPU seconds of
``grow_catalog`` (growth and the final bagged fit on all samples), the chosen catalog, its
size and the fitted support (the names of the non-zero terms), so that two checkouts can be
compared for speed and for identical results::

    PYTHONPATH=$PWD OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 \\
        python benchmarks/catalog_speed.py [--systems duffing spring_pendulum ...] \\
        [--json out.json] [--profile 30]

``--report BEFORE.json AFTER.json`` prints a markdown table of two such runs (seconds, and
whether catalogs, supports and coefficients are the same). ``--profile N`` prints the N most
expensive functions (cumulative) of a cProfile run. The package's catalog modules are imported
before the clocks start (a one-time cost of a few seconds that would fall on the first system).
"""

from __future__ import annotations

import argparse
import cProfile
import json
import os
import pstats
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import generic_systems as gs  # noqa: E402 - the benchmark's systems and data

import pysindy_xl as px  # noqa: E402
import pysindy_xl.catalog  # noqa: E402, F401 - imported before the clocks start

DEFAULT = ("duffing", "spring_pendulum", "double_pendulum", "three_masses", "four_chain")


def _workers_cpu() -> float:
    """CPU seconds of this process's child processes so far (the growth's joblib workers)."""
    try:
        import psutil
    except ImportError:
        return 0.0
    total = 0.0
    for child in psutil.Process().children(recursive=True):
        try:
            times = child.cpu_times()
        except psutil.Error:
            continue
        total += times.user + times.system
    return total


def time_system(name, noise=0.01, seed=0, profile=0, forced=True, n_jobs=None):
    """Wall and CPU seconds of ``grow_catalog`` on one system's data, and what it chose."""
    system = gs.systems()[name]
    truth = gs.Truth(system)
    runs = gs.make_runs(system, truth, seed, forced)
    xs = gs._noisy(runs, noise, seed)
    ts = [r["t"] for r in runs]
    us = [r["u"] for r in runs] if forced else None
    profiler = cProfile.Profile() if profile else None
    workers = _workers_cpu()
    started, cpu = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if profiler:
            profiler.enable()
        found = px.grow_catalog(xs, ts, us, coordinates=list(system["coords"].names),
                                kinds=system["kinds"], **({} if n_jobs is None
                                                          else {"n_jobs": n_jobs}))
        if profiler:
            profiler.disable()
    wall, cpu = time.perf_counter() - started, time.process_time() - cpu
    workers = _workers_cpu() - workers
    if profiler:
        pstats.Stats(profiler).sort_stats("cumulative").print_stats(profile)
    coef = found.model.coefficients()
    features = found.model.get_feature_names()
    support = [f for f, c in zip(features, coef, strict=True) if c != 0]
    return {"system": name, "n": truth.n, "forcing": "forced" if forced else "unforced",
            "noise": noise, "seed": seed, "samples": int(sum(len(t) for t in ts)),
            "wall_s": round(wall, 2), "cpu_s": round(cpu, 2),
            "workers_cpu_s": round(workers, 2), "load": round(os.getloadavg()[0], 2),
            "catalog": found.catalog.describe(), "terms": found.catalog.n_terms,
            "steps": len(found.steps), "criterion": found.held_out_error,
            "path": [[s.move, s.terms, s.active, s.criterion, s.chosen, round(s.seconds, 2)]
                     for s in found.steps],
            "support": support, "coefficients": [float(c) for c in coef if c != 0]}


def report(before_path, after_path) -> str:
    """Markdown table comparing two ``--json`` runs system by system."""
    with open(before_path) as handle:
        before = {r["system"]: r for r in json.load(handle)}
    with open(after_path) as handle:
        after = {r["system"]: r for r in json.load(handle)}
    lines = ["| system | coordinates | before: wall s (CPU s) | after: wall s (CPU s) | CPU "
             "speed-up | catalog, support, coefficients |", "|---|---|---|---|---|---|"]
    for name, old in before.items():
        new = after.get(name)
        if new is None:
            continue
        if old["catalog"] != new["catalog"] or old["support"] != new["support"]:
            verdict = "DIFFERENT catalog or support"
        elif old["coefficients"] == new["coefficients"]:
            verdict = "identical"
        else:
            a, b = np.asarray(old["coefficients"]), np.asarray(new["coefficients"])
            verdict = (f"same catalog and support, coefficients within "
                       f"{np.max(np.abs(a - b) / np.abs(a)):.1e} (relative)")
        lines.append(f"| {name} | {old['n']} | {old['wall_s']:.1f} ({old['cpu_s']:.1f}) | "
                     f"{new['wall_s']:.1f} ({new['cpu_s']:.1f}) | "
                     f"{old['cpu_s'] / new['cpu_s']:.2f}x | {verdict} |")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--systems", nargs="+", default=list(DEFAULT))
    parser.add_argument("--noise", type=float, default=0.01)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--forcing", nargs="+", default=["forced"],
                        choices=["forced", "unforced"],
                        help="forced and/or unforced data (unforced: the systems that have it)")
    parser.add_argument("--n-jobs", type=int, default=None,
                        help="grow_catalog's n_jobs (default: its own default)")
    parser.add_argument("--json", default=None, help="write the records to this file")
    parser.add_argument("--profile", type=int, default=0)
    parser.add_argument("--report", nargs=2, metavar=("BEFORE", "AFTER"), default=None,
                        help="print a markdown comparison of two --json files and exit")
    args = parser.parse_args(argv)
    if args.report:
        print(report(*args.report))
        return None
    records = []
    table = gs.systems()
    for forcing in args.forcing:
        for name in args.systems:
            if forcing == "unforced" and not table[name]["unforced"]:
                continue
            record = time_system(name, args.noise, args.seed, args.profile,
                                 forcing == "forced", args.n_jobs)
            records.append(record)
            print(json.dumps({k: record[k] for k in ("system", "n", "forcing", "wall_s",
                                                     "cpu_s", "workers_cpu_s", "load", "terms",
                                                     "steps", "catalog")}),
                  flush=True)
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(records, handle, indent=1)
    return records


if __name__ == "__main__":
    main()
