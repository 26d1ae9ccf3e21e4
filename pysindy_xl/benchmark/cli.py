"""Command line of the benchmark: ``pysindy-xl benchmark`` and ``benchmarks/table1.py``.

::

    pysindy-xl benchmark --quick                       # the small grid, all cores
    pysindy-xl benchmark --full --jobs 32 --out results/full
    pysindy-xl benchmark --quick --retry error timeout  # rerun the failed runs only
    pysindy-xl benchmark --quick --report-only          # rebuild the table from the records
    pysindy-xl benchmark --quick --fresh                # start over (old records kept aside)

    # a Dask cluster (pip install "dask[distributed]"):
    dask scheduler &  dask worker tcp://HOST:8786 --nworkers 16 --nthreads 1 &
    pysindy-xl benchmark --full --backend dask --address tcp://HOST:8786 --jobs -1

    # a Ray cluster (pip install "ray[default]"):
    ray start --head  # then `ray start --address HOST:6379` on the other machines
    pysindy-xl benchmark --full --backend ray --address auto --jobs -1
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

from .._validation import argument_type
from .grid import (
    CATALOGS,
    FORCINGS,
    PRESETS,
    SOLVERS,
    SYSTEM_NAMES,
    all_configurations,
    config_label,
)
from .isolation import ISOLATIONS
from .records import STATUSES

__all__ = ["add_parser", "build_parser", "main", "run_benchmark"]

BACKENDS = ("loky", "multiprocessing", "dask", "ray")
#: The help's layout: the module docstring's examples as its epilog.
_LAYOUT = {"formatter_class": argparse.RawDescriptionHelpFormatter,
           "epilog": __doc__.split("::", 1)[1]}


_positive_float = argument_type("real", low=0, low_open=True)
_non_negative_float = argument_type("real", low=0)


def _configuration(text):
    """``CATALOG:SOLVER`` (or ``sindy`` for the pysindy baseline)."""
    if text.strip().lower() in ("sindy", "pysindy", "classical:pysindy"):
        return ("classical", "pysindy")
    catalog, _, solver = text.partition(":")
    if catalog not in CATALOGS or solver not in SOLVERS:
        raise argparse.ArgumentTypeError(f"expected CATALOG:SOLVER with CATALOG in {CATALOGS} "
                                         f"and SOLVER in {SOLVERS}, or 'sindy', got {text!r}")
    return (catalog, solver)


def add_arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Add the benchmark options to ``parser``; returns it.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The parser to extend.

    Returns
    -------
    argparse.ArgumentParser
        The same parser.
    """
    preset = parser.add_mutually_exclusive_group()
    preset.add_argument("--quick", dest="preset", action="store_const", const="quick",
                        help="small grid, short trajectories (default)")
    preset.add_argument("--full", dest="preset", action="store_const", const="full",
                        help="the paper's scale, 1 h time limit per run")
    parser.set_defaults(preset="quick")
    parser.add_argument("--out", metavar="DIR", default=None,
                        help="directory of records.jsonl and the table files (default: "
                             "./pysindy-xl-benchmark/PRESET)")
    parser.add_argument("-j", "--jobs", type=int, default=-1,
                        help="parallel processes; -1 = all cores (default: -1)")
    parser.add_argument("--backend", choices=BACKENDS, default="loky",
                        help="joblib backend: local processes (loky, default), or a Dask / Ray "
                             "cluster (see --address)")
    parser.add_argument("--address", default=None,
                        help="scheduler address for --backend dask (tcp://HOST:8786) or ray "
                             "('auto' or HOST:6379)")
    parser.add_argument("--blas-threads", type=_blas_threads, default="auto", metavar="N",
                        help="BLAS threads inside each run: auto (1 when runs go in parallel, "
                             "default), none (no limit) or a number")
    parser.add_argument("--timeout", type=_positive_float, default=None,
                        help="seconds per run (default: the preset's: 90 quick, 3600 full)")
    parser.add_argument("--systems", nargs="+", choices=SYSTEM_NAMES, default=None)
    parser.add_argument("--forcing", nargs="+", choices=FORCINGS, default=None)
    parser.add_argument("--friction", nargs="+", type=_non_negative_float, default=None,
                        help="friction levels (multipliers of the default joint damping)")
    parser.add_argument("--noise", nargs="+", type=_non_negative_float, default=None,
                        help="relative noise levels on every channel (the paper's model)")
    parser.add_argument("--position-noise", nargs="*", type=_non_negative_float, default=None,
                        help="relative noise levels on the positions only, no derivative given "
                        "(default: the preset's; none to leave them out)")
    parser.add_argument("--seeds", nargs="+", type=int, default=None)
    parser.add_argument("--configs", nargs="+", type=_configuration, default=None,
                        metavar="CATALOG:SOLVER",
                        help="configurations to run, e.g. mixed:mixed lagrange:explicit sindy "
                             "(default: all, and the pysindy baseline)")
    parser.add_argument("--no-baseline", action="store_true",
                        help="leave out the pysindy.SINDy row")
    parser.add_argument("--retry", nargs="+", choices=STATUSES, default=(),
                        help="run again the runs whose recorded status is one of these")
    parser.add_argument("--limit", type=int, default=None,
                        help="run at most this many pending runs, then stop")
    parser.add_argument("--isolation", choices=ISOLATIONS, default="auto",
                        help="how the time limit is enforced (default: a forked process per run)")
    parser.add_argument("--fresh", action="store_true",
                        help="start over: existing records are renamed records.TIME.jsonl "
                             "(kept), then every run is done again")
    parser.add_argument("--report-only", action="store_true",
                        help="do not run anything: rebuild the table from the records")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    return parser


def _blas_threads(text):
    if text in ("auto", "none"):
        return None if text == "none" else "auto"
    try:
        value = int(text)
    except ValueError:
        message = f"expected auto, none or an integer, got {text!r}"
        raise argparse.ArgumentTypeError(message) from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}")
    return value


def add_parser(subparsers):
    """Register ``benchmark`` on argparse subparsers (the ``pysindy-xl`` command); the parsed
    namespace's ``func(args)`` runs it and returns the exit status.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The subparsers of the ``pysindy-xl`` parser.

    Returns
    -------
    argparse.ArgumentParser
        The ``benchmark`` subparser.
    """
    parser = subparsers.add_parser(
        "benchmark", help="reproduce the paper's Table 1 (parallel, resumable)",
        description="Run the grid of the paper's Table 1 (systems x friction x forcing x noise "
                    "x seeds x configurations), rank the configurations per trajectory and "
                    "write the table (Markdown, CSV, PNG). Interrupted grids resume.", **_LAYOUT)
    add_arguments(parser)
    parser.set_defaults(func=run_benchmark)
    return parser


def build_parser() -> argparse.ArgumentParser:
    """A standalone parser (``benchmarks/table1.py``).

    Returns
    -------
    argparse.ArgumentParser
        The parser of the benchmark options.
    """
    parser = argparse.ArgumentParser(
        prog="table1.py", description="Reproduce the paper's Table 1 with pysindy-xl.", **_LAYOUT)
    return add_arguments(parser)


def settings_from_args(args):
    """The :class:`GridSettings` described by parsed arguments.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments of the benchmark options.

    Returns
    -------
    GridSettings
        The preset with the options' changes.
    """
    settings = PRESETS[args.preset]
    configurations = args.configs or all_configurations(include_baseline=True)
    if args.no_baseline:
        configurations = [c for c in configurations if c != ("classical", "pysindy")]
    return settings.with_options(
        systems=tuple(args.systems) if args.systems else None,
        forcings=tuple(args.forcing) if args.forcing else None,
        friction_levels=tuple(args.friction) if args.friction else None,
        noise_levels=tuple(args.noise) if args.noise else None,
        position_noise_levels=(None if args.position_noise is None
                               else tuple(args.position_noise)),
        seeds=tuple(args.seeds) if args.seeds else None,
        configurations=tuple(dict.fromkeys(configurations)),
        timeout=args.timeout,
    )


def run_benchmark(args) -> int:
    """Run (or, with ``--report-only``, only report) the benchmark of parsed arguments.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments of the benchmark options.

    Returns
    -------
    int
        The exit status: 0 on success (failed runs are recorded, not errors), 1 when the grid
        cannot run or, with ``--report-only``, has no records, 2 on invalid options.
    """
    from .records import GridBusyError, RecordStore
    from .report import load_average, machine_description, write_report
    from .runner import run_grid
    try:
        settings = settings_from_args(args)
    except (ValueError, TypeError) as error:
        print(f"benchmark: error: {error}", file=sys.stderr)
        return 2
    out = args.out or os.path.join("pysindy-xl-benchmark", settings.name)
    records_path = os.path.join(out, "records.jsonl")
    machine_path = os.path.join(out, "machine.json")
    if args.report_only:
        if not os.path.exists(records_path):
            print(f"benchmark: error: no records at {records_path}", file=sys.stderr)
            return 1
        machine = None
        if os.path.exists(machine_path):
            with open(machine_path, encoding="utf-8") as handle:
                machine = json.load(handle)
    else:
        if args.fresh and os.path.exists(records_path):
            kept = os.path.join(out, time.strftime("records.%Y%m%d-%H%M%S.jsonl"))
            os.replace(records_path, kept)
            print(f"previous records kept as {kept}")
        tasks = settings.tasks()
        print(f"benchmark {settings.name}: {len(tasks)} runs on "
              f"{len(settings.trajectories())} trajectories, {settings.timeout:g} s limit per "
              f"run, records in {records_path}", flush=True)
        load_at_start = load_average()
        try:
            outcome = run_grid(settings, records_path, n_jobs=args.jobs, backend=args.backend,
                               address=args.address, retry=args.retry,
                               isolation=args.isolation,
                               progress=False if args.no_progress else None, limit=args.limit,
                               blas_threads=args.blas_threads)
        except (ImportError, ValueError, GridBusyError) as error:
            print(f"benchmark: error: {error}", file=sys.stderr)
            return 1
        print(f"ran {outcome['ran']} runs in {outcome['seconds']:.0f} s "
              f"({outcome['skipped']} already recorded): {outcome['statuses']}", flush=True)
        machine = machine_description(n_jobs=_effective_jobs(args.jobs), backend=args.backend)
        machine["wall_time_s"] = round(outcome["seconds"], 1)
        machine["runs_this_session"] = outcome["ran"]
        machine["load_average_at_start"] = load_at_start
    records = RecordStore(records_path).records()
    wanted = {t.run_id for t in settings.tasks()}
    records = [r for r in records if r["run_id"] in wanted]  # other grids' records stay out
    configs = [config_label(c, s) for c, s in settings.configurations]
    report = write_report(records, out, settings, machine, configs)
    print()
    print(f"Table 1 ({len(records)} of {len(wanted)} runs recorded)")
    print(report["text"])
    print()
    print("written: " + ", ".join(sorted(report["files"].values())))
    return 0


def _effective_jobs(n_jobs):
    import joblib
    try:
        return joblib.effective_n_jobs(n_jobs)
    except Exception:
        return n_jobs


def main(argv=None) -> int:
    """Entry point of ``benchmarks/table1.py``; returns the exit status.

    Parameters
    ----------
    argv : list of str, default=None
        The arguments; None: ``sys.argv[1:]``.

    Returns
    -------
    int
        The exit status.

    Examples
    --------
    Reporting a grid that never ran is an error (exit status 1):

    >>> import contextlib, os, sys, tempfile
    >>> with contextlib.redirect_stderr(sys.stdout):
    ...     status = main(["--report-only", "--out", os.path.join(tempfile.mkdtemp(), "none")])
    benchmark: error: no records at .../none/records.jsonl
    >>> status
    1
    """
    args = build_parser().parse_args(argv)
    return run_benchmark(args)
