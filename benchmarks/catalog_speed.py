"""Time of the automatic catalog (``px.grow_catalog``: growth plus the final fit) per system.

The data are those of ``benchmarks/generic_systems.py``: 2 runs of 10 s at 1 kHz (20,000
samples), positions only with 1 % noise (``--noise``), forced (``--forcing forced unforced``
adds the unforced data of the systems that have them). Per case it prints the wall and CPU
seconds of ``grow_catalog`` (growth and the final bagged fit on all samples), the chosen
catalog, its size and the fitted support (the names of the non-zero terms), so that two
checkouts can be compared for speed and for identical results::

    PYTHONPATH=$PWD OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 \\
        python benchmarks/catalog_speed.py [--systems duffing spring_pendulum ...] \\
        [--forcing forced unforced] [--noise 0.05] [--n-jobs 2] [--json out.json] \\
        [--profile 30]

``--n-jobs`` sets ``grow_catalog``'s processes; the workers' CPU seconds are recorded apart
(``workers_cpu_s``, with ``psutil``), and so is the 1-minute load average. ``--report
BEFORE.json AFTER.json`` (or ``--report B1.json B2.json vs A1.json A2.json``) prints a
markdown table of such runs case by case (seconds, and whether catalogs, supports and
coefficients are the same). ``--profile N`` prints the N most expensive functions
(cumulative) of a cProfile run. The package's catalog modules are imported before the clocks
start (a one-time cost of a few seconds that would fall on the first system).
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
from pysindy_xl.catalog import candidates, growth  # noqa: E402

DEFAULT = ("duffing", "spring_pendulum", "double_pendulum", "three_masses", "four_chain")


class _WorkersClock:
    """CPU seconds of this process's child processes (the growth's joblib workers) while it
    runs, sampled every 0.2 s so that a worker that exits (loky restarts a worker whose
    memory grew) still counts up to its last sample; ``restarts``: workers that exited."""

    def __enter__(self):
        import threading
        self.start, self.last, self._stop = self._sample(), {}, threading.Event()
        self.last.update(self.start)
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()
        return self

    @staticmethod
    def _sample() -> dict:
        try:
            import psutil
        except ImportError:
            return {}
        out = {}
        for child in psutil.Process().children(recursive=True):
            try:
                times = child.cpu_times()
            except psutil.Error:
                continue
            out[child.pid] = times.user + times.system
        return out

    def _run(self):
        while not self._stop.wait(0.2):
            self.last.update(self._sample())

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()
        now = self._sample()
        self.last.update(now)
        self.seconds = sum(v - self.start.get(pid, 0.0) for pid, v in self.last.items())
        self.restarts = sum(pid not in now for pid in self.last)
        return False


class _Recorded(candidates.CandidateFits):
    """``CandidateFits`` that keeps its last instance (for :func:`idle_estimate`)."""

    last = None

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        type(self).last = self


growth.CandidateFits = _Recorded


def idle_estimate(fits, main_cpu) -> float:
    """Wall seconds of the growth on idle cores (warm workers): the recorded schedule of
    ``fits`` replayed with each fit's CPU seconds (a worker's fit starts when it is submitted
    or when its worker is free; a result is waited for when it is needed), plus the calling
    process's CPU seconds outside its own fits (the final fit, the data's preparation)."""
    if fits is None:
        return float("nan")
    cpu = {key: fields["cpu_seconds"] for key, fields in fits.results.items()}
    clock, workers, finish, own = 0.0, [0.0] * max(1, fits.n_jobs - 1), {}, 0.0
    for kind, key in fits.events:
        if kind == "submit":
            free = int(np.argmin(workers))
            finish[key] = workers[free] = max(clock, workers[free]) + cpu.get(key, 0.0)
        elif kind == "local":
            clock += cpu[key]
            own += cpu[key]
        elif kind == "worker":
            clock = max(clock, finish[key])
    return clock + max(0.0, main_cpu - own)


def time_system(name, noise=0.01, seed=0, profile=0, forced=True, n_jobs=None):
    """Wall and CPU seconds of ``grow_catalog`` on one system's data, and what it chose."""
    system = gs.systems()[name]
    truth = gs.Truth(system)
    runs = gs.make_runs(system, truth, seed, forced)
    xs = gs._noisy(runs, noise, seed)
    ts = [r["t"] for r in runs]
    us = [r["u"] for r in runs] if forced else None
    profiler = cProfile.Profile() if profile else None
    _Recorded.last = None
    with _WorkersClock() as clock, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        started, cpu = time.perf_counter(), time.process_time()
        if profiler:
            profiler.enable()
        found = px.grow_catalog(xs, ts, us, coordinates=list(system["coords"].names),
                                kinds=system["kinds"], **({} if n_jobs is None
                                                          else {"n_jobs": n_jobs}))
        if profiler:
            profiler.disable()
        wall, cpu = time.perf_counter() - started, time.process_time() - cpu
    if profiler:
        pstats.Stats(profiler).sort_stats("cumulative").print_stats(profile)
    coef = found.model.coefficients()
    features = found.model.get_feature_names()
    support = [f for f, c in zip(features, coef, strict=True) if c != 0]
    return {"system": name, "n": truth.n, "forcing": "forced" if forced else "unforced",
            "noise": noise, "seed": seed, "samples": int(sum(len(t) for t in ts)),
            "wall_s": round(wall, 2), "cpu_s": round(cpu, 2),
            "workers_cpu_s": round(clock.seconds, 2), "workers_exited": clock.restarts,
            "idle_wall_estimate_s": round(idle_estimate(_Recorded.last, cpu), 2),
            "load": round(os.getloadavg()[0], 2),
            "catalog": found.catalog.describe(), "terms": found.catalog.n_terms,
            "steps": len(found.steps), "criterion": found.held_out_error,
            "path": [[s.move, s.terms, s.active, s.criterion, s.chosen, round(s.seconds, 2)]
                     for s in found.steps],
            "support": support, "coefficients": [float(c) for c in coef if c != 0]}


def _records(paths) -> dict:
    """Records of ``--json`` files by (system, forcing, noise); older files: forced, 1 %."""
    out = {}
    for path in paths:
        with open(path) as handle:
            for r in json.load(handle):
                out[(r["system"], r.get("forcing", "forced"), r.get("noise", 0.01))] = r
    return out


def report(before_paths, after_paths) -> str:
    """Markdown table comparing ``--json`` runs case by case (several files per side).

    CPU s: the calling process's; the workers' CPU seconds (``--n-jobs``) are added after a
    ``+``. The idle-core estimate is :func:`idle_estimate` (the CPU seconds where no workers
    ran). The load is the 1-minute load average at the end of the case.
    """
    before, after = _records(before_paths), _records(after_paths)
    lines = ["| system | n | forcing | noise | steps | before: wall s (CPU s) | after: wall s "
             "(CPU s + workers') | after: idle-core estimate s | load after | catalog, "
             "support, coefficients |", "|---|---|---|---|---|---|---|---|---|---|"]
    for key, old in before.items():
        new = after.get(key)
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
        workers = new.get("workers_cpu_s", 0.0)
        lines.append(f"| {key[0]} | {old['n']} | {key[1]} | {100 * key[2]:g} % | "
                     f"{new['steps']} | {old['wall_s']:.1f} ({old['cpu_s']:.1f}) | "
                     f"{new['wall_s']:.1f} ({new['cpu_s']:.1f}"
                     + (f" + {workers:.1f}" if workers else "") + ") | "
                     f"{new.get('idle_wall_estimate_s', new['cpu_s']):.1f} | "
                     f"{new.get('load', float('nan')):.1f} | {verdict} |")
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
    parser.add_argument("--report", nargs="+", default=None, metavar="JSON",
                        help="BEFORE... vs AFTER... (or BEFORE AFTER): print a markdown "
                             "comparison of --json files and exit")
    args = parser.parse_args(argv)
    if args.report:
        if "vs" in args.report:
            split = args.report.index("vs")
            before, after = args.report[:split], args.report[split + 1:]
        else:
            before, after = args.report[:1], args.report[1:]
        print(report(before, after))
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
            print(json.dumps({k: record[k] for k in (
                "system", "n", "forcing", "wall_s", "cpu_s", "workers_cpu_s",
                "idle_wall_estimate_s", "load", "terms", "steps", "catalog")}),
                  flush=True)
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(records, handle, indent=1)
    return records


if __name__ == "__main__":
    main()
