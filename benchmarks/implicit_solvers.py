"""Implicit (SINDy-PI) solvers: fast batched FISTA vs the cvxpy formulation vs pysindy's SINDyPI.

All three solve the same problem on the same matrices,

    min_X 1/2 ||Theta~ X - Theta~||_F^2 + alpha ||X||_1   s.t.  diag(X) = 0,

with ``Theta~`` the column-normalized regression matrix of the unforced double pendulum on a
cart with friction (sympy ground truth of ``tests/ground_truth.py``, three trajectories of 10 s
at 100 Hz), for catalogs of about 25, 50, 100 and 200 columns: the true Lagrangian terms and
friction plus seeded random candidate terms (velocity monomials times trigonometric monomials),
exact identities dropped on random probe points as :class:`pysindy_xl.XLSINDy` does.

* ``fast``: :class:`pysindy_xl.optimizers.implicit.ImplicitOptimizer` (default solver).
* ``cvxpy``: the same class with ``solver="cvxpy"`` (one joint conic problem on the triangular
  factor ``R`` of ``Theta~``, default cvxpy solver).
* ``pysindy``: ``pysindy.optimizers.SINDyPI`` (one cvxpy problem per column), given ``R`` as its
  data matrix: the same least-squares objective as ``Theta~`` with F rows instead of 3 N, which
  only helps it. Its weight is ``2 alpha`` (it does not halve the squared loss). Its solution
  matrix goes through the same homothetic clustering as the others.

For each solver and size the script prints the wall time and whether the extracted law has the
true support. Every solver run happens in a child process with a time limit (``--timeout``).

``--systems cart-pole double-pendulum`` times instead the clean implicit fits of the paper's
systems (MuJoCo, unforced, damping as in Table 1, three trajectories of 10 s every 1 ms, the
``mixed`` reference catalog), in this process, BLAS on one thread, the timings of one system
interleaved so that they share the load, the garbage collected before each:

* ``fit``: ``XLSINDy(catalog, ImplicitOptimizer()).fit`` end to end, on a fresh catalog each
  time (its symbolic fit, the rows, the problem, the solve, the wrap);
* ``optimizer``: ``ImplicitOptimizer().fit_problem`` on the problem that fit builds (exact
  identities dropped; the coordinate blocks balanced, the columns normalized and factored, the
  batched solver, the law extraction);
* ``SINDyPI``: ``pysindy.optimizers.SINDyPI`` alone on the triangular factor ``R`` of the same
  reduced, balanced, normalized columns (the project's factorization is not counted in its
  time); its solution matrix then goes through the same law extraction, to say whether it
  finds the same law.

Results (medians of ``--repeats``, the load average) go to
``benchmarks/results/implicit_systems.json`` under ``--label`` and the table of every label to
``implicit_systems.md``.

Usage: ``python benchmarks/implicit_solvers.py [--sizes 25 50 100 200] [--alpha auto]
[--timeout 600] [--solvers fast cvxpy pysindy]``;
``python benchmarks/implicit_solvers.py --systems cart-pole double-pendulum [--repeats 7]
[--label after]``
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import io
import json
import multiprocessing as mp
import os
import pathlib
import platform
import sys
import time
import warnings

import numpy as np
import sympy as sp

import pysindy_xl as px
from pysindy_xl.feature_library import stack_variables
from pysindy_xl.optimizers._base import independent_columns
from pysindy_xl.optimizers._sparse import column_norms, triangular_factor
from pysindy_xl.optimizers.implicit import ImplicitOptimizer

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tests"))
import ground_truth as gt  # noqa: E402


def regression_matrix(n_columns: int, seed: int = 0):
    """Stacked matrix of the unforced cart double pendulum with ``n_columns`` catalog columns.

    Returns ``(theta, true_coefficients, names)``; the true support is always included.
    """
    system = gt.cart_double_pendulum()
    coords = system.coords
    trig = [f(q) for q in coords.q[1:] for f in (sp.cos, sp.sin)]
    velocities = px.monomials(coords.qd, 2)
    true_terms = [m for m in sp.expand(system.lagrangian).as_coefficients_dict() if m != 1]
    degree = 3 if n_columns > 120 else 2
    pool = px.products(velocities, [1, *px.monomials(trig, degree)]) + px.monomials(trig, 3)
    pool = [t for t in pool if t not in true_terms]
    pool = [pool[i] for i in np.random.default_rng(seed).permutation(len(pool))]
    classical = [*coords.qd, *[sp.sin(q) for q in coords.q[1:]], *px.monomials(coords.qd, 2)]

    t = np.arange(0.0, 10.0, 0.01)
    runs = [system.simulate(gt.random_initial_state(system, s), t) for s in (0, 1, 2)]
    data = [stack_variables(r["q"], r["qd"], r["qdd"], r["tau"], t) for r in runs]
    probe = np.random.default_rng(1).uniform(-2, 2, size=(3000, data[0].shape[1]))
    n = coords.n
    for extra in range(0, len(pool) + 1, max(2, n_columns // 8)):
        library = px.CatalogRepartition([
            px.LagrangeLibrary(coords, true_terms + pool[:extra]),
            px.ClassicalLibrary(coords, classical),
        ]).fit()
        keep, _ = independent_columns(library.transform(probe), library.column_priority())
        keep = np.setdiff1d(keep, library.force_columns_)
        if len(keep) >= n_columns:
            break
    else:
        raise ValueError(f"n_columns: the candidate pool yields only {len(keep)} columns")
    friction = {(coords.qd[i], i): c for i, c in enumerate(system.friction)}
    truth = library.ideal_coefficients(lagrangian=system.lagrangian, classical=friction,
                                       forces=0.0)
    true_columns = np.flatnonzero(truth)
    others = np.setdiff1d(keep, true_columns)
    keep = np.union1d(true_columns, others[: n_columns - true_columns.size])
    thetas = [library.transform(z).reshape(n, len(t), -1) for z in data]
    theta = np.concatenate(thetas, axis=1).reshape(n * len(t) * len(data), -1)
    names = library.get_feature_names()
    return theta[:, keep], truth[keep], [names[k] for k in keep]


def sindy_pi(r_factor, alpha):
    """pysindy's SINDyPI solution matrix of problem (1) on ``r_factor``, zero diagonal."""
    import pysindy as ps

    solver = ps.SINDyPI(reg_weight_lam=2 * alpha, tol=1e-8, max_iter=100_000)
    with contextlib.redirect_stdout(io.StringIO()):  # SINDyPI prints one line per column
        solver.fit(r_factor, r_factor)
    solution = np.asarray(solver.coef_, dtype=float).T
    np.fill_diagonal(solution, 0.0)
    return solution


class _GivenSolution(ImplicitOptimizer):
    """ImplicitOptimizer whose solution matrix comes from elsewhere (pysindy's SINDyPI)."""

    def _sindy_pi_matrix(self, r_factor):
        self.alpha_ = self._resolve_alpha(r_factor)
        self.n_iter_ = 0
        self.converged_ = True
        self._column_converged = np.ones(r_factor.shape[1], dtype=bool)
        return sindy_pi(r_factor, self.alpha_)


def _run(solver, theta, alpha, queue):
    """Child process: fit, report (seconds, support, converged, iterations) or the error."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    warnings.simplefilter("ignore")
    if solver == "pysindy":
        optimizer = _GivenSolution(alpha=alpha)
    else:
        optimizer = ImplicitOptimizer(alpha=alpha, solver="fista" if solver == "fast" else solver)
    start = time.perf_counter()
    try:
        optimizer.fit_catalog(theta, 3, [])
    except Exception as error:  # reported in the table, not raised
        queue.put((time.perf_counter() - start, None, False, 0, f"{type(error).__name__}"))
        return
    queue.put((time.perf_counter() - start, optimizer.coef_ != 0, optimizer.converged_,
               optimizer.n_iter_, ""))


def timed(solver, theta, alpha, timeout):
    """Run one solver in a child process with a time limit."""
    queue = mp.get_context("spawn").Queue()
    process = mp.get_context("spawn").Process(target=_run, args=(solver, theta, alpha, queue))
    process.start()
    process.join(timeout)
    if process.is_alive():
        process.terminate()
        process.join()
        return None
    return queue.get() if not queue.empty() else None


RESULTS = pathlib.Path(__file__).resolve().parent / "results" / "implicit_systems"


def system_fit(system, catalog="mixed"):
    """Clean unforced data of a paper system: ``(new_model, fit_arguments, problem)``, the
    problem as ``XLSINDy.fit`` builds it (``new_model()`` gives an unfitted estimator with a
    fresh catalog)."""
    from pysindy_xl.benchmark.grid import TrajectorySpec
    from pysindy_xl.benchmark.runner import system_for, trajectory_data
    from pysindy_xl.fit import build_problem, check_fit
    from pysindy_xl.mujoco.catalogs.reference import reference_catalog

    spec = TrajectorySpec(system=system, friction=1.0, forcing="implicit", noise=0.0, seed=0)
    dataset = trajectory_data(spec, 3, 10.0, 1, 1.0)[0]
    mechanics = system_for(spec)
    arguments = dataset.fit_arguments(forces=None)

    def new_model():
        return px.XLSINDy(reference_catalog(mechanics, catalog), ImplicitOptimizer())

    model = new_model()
    library, data, formulation = check_fit(model, arguments["x"], arguments["t"],
                                           arguments["x_dot"], arguments["x_ddot"], None, None)
    problem = build_problem(library, data, formulation, hold_still=model.hold_still,
                            drop_dependent=model.drop_dependent)
    return new_model, arguments, problem


def reduced_factor(problem):
    """``R`` of the balanced, non-zero, unit-norm columns that ImplicitOptimizer solves on."""
    theta = problem.balanced().theta
    norms, nonzero = column_norms(theta)
    return triangular_factor(theta[:, nonzero] / norms[nonzero])


def time_system(system, repeats, label, catalog="mixed"):
    """Median times of the end-to-end fit, the optimizer and SINDyPI (module docstring)."""
    import threadpoolctl

    new_model, arguments, problem = system_fit(system, catalog)
    r_factor = reduced_factor(problem)
    alpha = ImplicitOptimizer()._resolve_alpha(r_factor)
    runs = {  # (untimed set-up, timed run)
        "fit": (new_model, lambda model: model.fit(**arguments)),
        "optimizer": (ImplicitOptimizer, lambda optimizer: optimizer.fit_problem(problem)),
        "SINDyPI": (lambda: None, lambda _: sindy_pi(r_factor, alpha)),
    }
    times = {name: [] for name in runs}
    load = [os.getloadavg()[0]]
    with threadpoolctl.threadpool_limits(1, "blas"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ours = ImplicitOptimizer().fit_problem(problem)
        theirs = _GivenSolution().fit_problem(problem)
        for _ in range(repeats):
            for name, (set_up, run) in runs.items():
                subject = set_up()
                gc.collect()  # no run pays for the garbage of another (cvxpy leaves much)
                start = time.perf_counter()
                run(subject)
                times[name].append(time.perf_counter() - start)
    load.append(os.getloadavg()[0])
    median = {name: float(np.median(t)) for name, t in times.items()}
    row = {
        "label": label, "system": system, "catalog": catalog,
        "rows": int(problem.theta.shape[0]), "columns": int(r_factor.shape[1]),
        "alpha": alpha, "repeats": repeats, "load_average": load,
        "median_s": median, "times_s": times,
        "SINDyPI_over_optimizer": median["SINDyPI"] / median["optimizer"],
        "SINDyPI_over_fit": median["SINDyPI"] / median["fit"],
        "same_law": bool(np.array_equal(ours.coef_ != 0, theirs.coef_ != 0)),
        "law_terms": int(np.count_nonzero(ours.coef_)),
    }
    print(f"{system}: {row['columns']} columns, fit {median['fit']:.3f} s, optimizer "
          f"{median['optimizer']:.3f} s, SINDyPI {median['SINDyPI']:.3f} s (x"
          f"{row['SINDyPI_over_optimizer']:.1f} / x{row['SINDyPI_over_fit']:.1f}), same law: "
          f"{row['same_law']}, load {load[0]:.1f}-{load[1]:.1f}", flush=True)
    return row


def write_systems(rows):
    """Merge ``rows`` into the results (replacing those of the same label and system) and
    write the table of every label."""
    json_path = RESULTS.with_suffix(".json")
    old = json.loads(json_path.read_text())["runs"] if json_path.exists() else []
    done = {(r["label"], r["system"]) for r in rows}
    runs = [r for r in old if (r["label"], r["system"]) not in done] + rows
    machine = f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores"
    json_path.write_text(json.dumps({"machine": machine, "runs": runs}, indent=1) + "\n")
    lines = [f"# Clean implicit fits of the paper's systems against pysindy's SINDyPI ({machine})",
             "", "Median wall times (s), BLAS on one thread, the three timings of a system "
             "interleaved; `benchmarks/implicit_solvers.py --systems` (its docstring says "
             "what each time covers). Load average: 1-min, before / after the system's "
             "timings.", "",
             "| label | system | rows x columns | fit | optimizer | SINDyPI | SINDyPI / "
             "optimizer | SINDyPI / fit | same law | load |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in runs:
        m = r["median_s"]
        lines.append(f"| {r['label']} | {r['system']} | {r['rows']} x {r['columns']} | "
                     f"{m['fit']:.3f} | {m['optimizer']:.3f} | {m['SINDyPI']:.3f} | "
                     f"{r['SINDyPI_over_optimizer']:.1f} | {r['SINDyPI_over_fit']:.1f} | "
                     f"{'yes' if r['same_law'] else 'NO'} | "
                     f"{r['load_average'][0]:.1f} / {r['load_average'][1]:.1f} |")
    md_path = RESULTS.with_suffix(".md")
    old_md = md_path.read_text() if md_path.exists() else ""
    notes = old_md[old_md.index("\n## Notes"):] if "\n## Notes" in old_md else ""  # kept
    md_path.write_text("\n".join(lines) + "\n" + notes)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--systems", nargs="+", choices=["cart-pole", "double-pendulum"],
                        help="time the clean implicit fits of these paper systems instead")
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--label", default="current")
    parser.add_argument("--sizes", type=int, nargs="+", default=[25, 50, 100, 200])
    parser.add_argument("--alpha", default="auto",
                        help="L1 weight, or 'auto' (ImplicitOptimizer's rule, per matrix)")
    parser.add_argument("--timeout", type=float, default=600.0)
    parser.add_argument("--solvers", nargs="+", default=["fast", "cvxpy", "pysindy"],
                        choices=["fast", "cvxpy", "pysindy"])
    args = parser.parse_args(argv)
    if args.systems:
        write_systems([time_system(system, args.repeats, args.label)
                       for system in args.systems])
        return

    print(f"# implicit solvers, alpha={args.alpha}, {platform.processor() or platform.machine()}"
          f", {os.cpu_count()} cores, timeout {args.timeout:g} s")
    print(f"{'columns':>7} {'rows':>6} {'cond':>8} {'alpha':>8} {'solver':>8} {'time_s':>9} "
          f"{'support':>8} {'converged':>9} {'iters':>6} {'vs_fast':>8}")
    for size in args.sizes:
        theta, truth, _ = regression_matrix(size)
        norms, _ = column_norms(theta)
        r_factor = triangular_factor(theta / norms)
        singular = np.linalg.svd(r_factor, compute_uv=False)
        alpha = (ImplicitOptimizer()._resolve_alpha(r_factor) if args.alpha == "auto"
                 else float(args.alpha))
        # Conditioning apart from the law itself: second smallest singular value.
        cond = singular[0] / singular[-2]
        fast_time = None
        for solver in args.solvers:
            result = timed(solver, theta, alpha, args.timeout)
            head = f"{size:>7} {theta.shape[0]:>6} {cond:>8.1e} {alpha:>8.1e} {solver:>8}"
            if result is None:
                print(f"{head} "
                      f"{'>' + format(args.timeout, 'g'):>9} {'timeout':>8}", flush=True)
                continue
            seconds, support, converged, iters, error = result
            if solver == "fast":
                fast_time = seconds
            ok = error or ("yes" if np.array_equal(support, truth != 0) else "NO")
            ratio = f"{seconds / fast_time:.1f}x" if fast_time else ""
            print(f"{head} {seconds:>9.2f} {ok:>8} {converged!s:>9} {iters:>6} {ratio:>8}",
                  flush=True)


if __name__ == "__main__":
    main()
