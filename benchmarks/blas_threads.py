"""Effect of limiting BLAS threads (threadpoolctl) on small identification problems.

Measured side by side, best of ``--repeat``:

1. **one fit** (cart-pole, reference ``mixed`` catalog, explicit solver, MuJoCo data) in this
   process, with the default BLAS thread count and with one thread;
2. **two fits in parallel** in two forked processes (no automatic limit, like Dask or Ray
   workers), default BLAS threads against one thread per process;
3. **the benchmark grid** (``run_grid``) on a Dask ``LocalCluster`` of threads (the back end
   where nothing else limits BLAS): ``blas_threads=None`` against the default ``"auto"`` (one
   thread per run), when ``dask.distributed`` is installed.

Usage: ``python benchmarks/blas_threads.py [--repeat 3] [--out FILE.json]``
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import tempfile
import time

from threadpoolctl import threadpool_info, threadpool_limits

_DATA = {}


def _problem(duration):
    from pysindy_xl.mujoco import generate_dataset, reference_catalog

    if duration not in _DATA:
        data = generate_dataset("cart-pole", n_trajectories=2, duration=duration, seed=0,
                                progress=False)
        _DATA[duration] = data.fit_arguments()
    return reference_catalog, _DATA[duration]


def fit_once(duration=4.0) -> float:
    import pysindy_xl as px

    reference_catalog, arguments = _problem(duration)
    model = px.XLSINDy(reference_catalog("cart-pole", "mixed"), px.ExplicitOptimizer())
    start = time.perf_counter()
    model.fit(**arguments)
    return time.perf_counter() - start


def _worker(args):
    threads, duration, fits = args
    if threads is not None:
        threadpool_limits(limits=threads, user_api="blas")
    return sum(fit_once(duration) for _ in range(fits))


def parallel_fits(threads, duration, fits=2) -> float:
    _problem(duration)  # simulated once, inherited by the forked workers
    fit_once(duration)  # warm caches (compiled catalogs) before forking
    context = multiprocessing.get_context("fork")
    start = time.perf_counter()
    with context.Pool(2) as pool:
        pool.map(_worker, [(threads, duration, fits)] * 2)
    return time.perf_counter() - start


def grid_on_dask(blas_threads) -> float | None:
    try:
        from dask.distributed import LocalCluster
    except ImportError:
        return None
    from pysindy_xl.benchmark.grid import GridSettings
    from pysindy_xl.benchmark.runner import run_grid

    settings = GridSettings(systems=("cart-pole",), forcings=("explicit",),
                            configurations=(("mixed", "explicit"), ("lagrange", "explicit"),
                                            ("classical", "explicit"), ("mixed", "mixed")),
                            n_trajectories=2, duration=2.0, validation_duration=1.0,
                            timeout=300.0, name="threads")
    with tempfile.TemporaryDirectory() as tmp, LocalCluster(
            n_workers=1, threads_per_worker=2, processes=False,
            dashboard_address=None) as cluster:
        start = time.perf_counter()
        run_grid(settings, os.path.join(tmp, "records.jsonl"), backend="dask",
                 address=cluster.scheduler_address, n_jobs=2, progress=False,
                 isolation="none", blas_threads=blas_threads)
        return time.perf_counter() - start


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--duration", type=float, default=4.0,
                        help="seconds per training trajectory (2 trajectories, 2 ms steps)")
    parser.add_argument("--no-grid", action="store_true", help="skip the Dask grid timing")
    parser.add_argument("--out", default=None)
    args = parser.parse_args(argv)
    import logging

    logging.getLogger("distributed").setLevel(logging.ERROR)
    fit_once(args.duration)  # warm-up: data, compiled catalog, BLAS loaded
    blas = [(p["internal_api"], p["num_threads"]) for p in threadpool_info()
            if p["user_api"] == "blas"]
    default_threads = max(n for _, n in blas) if blas else None
    print(f"BLAS: {blas}, {os.cpu_count()} cores; best of {args.repeat}, the two settings "
          "alternated")
    results = {"blas": blas, "cpu_count": os.cpu_count(), "repeat": args.repeat,
               "duration": args.duration}

    def one_fit(threads):
        with threadpool_limits(limits=threads, user_api="blas"):
            return fit_once(args.duration)

    cases = [("one fit", one_fit),
             ("two fits in 2 processes", lambda threads: parallel_fits(threads, args.duration))]
    if not args.no_grid and grid_on_dask(1) is not None:  # warm-up: simulated data cached
        cases.append(("grid, 4 runs, Dask 2 threads",
                      lambda threads: grid_on_dask(None if threads is None else "auto")))
    for label, run in cases:
        times = {None: [], 1: []}
        for _ in range(args.repeat):
            for threads in (None, 1):
                times[threads].append(run(threads))
        row = {"default": min(times[None]), "1 thread": min(times[1]),
               "runs_default": times[None], "runs_1_thread": times[1]}
        row["speedup"] = row["default"] / row["1 thread"]
        results[label] = row
        print(f"  {label:<30} default ({default_threads} BLAS threads) {row['default']:.3f} s, "
              f"1 thread {row['1 thread']:.3f} s: x{row['speedup']:.2f}")
    if args.out:
        with open(args.out, "w", encoding="utf-8") as handle:
            json.dump(results, handle, indent=2)
        print(f"wrote {args.out}")
    return results


if __name__ == "__main__":
    main()
