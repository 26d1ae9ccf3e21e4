"""Identification from noisy positions: weak form vs strong form vs plain pysindy SINDy.

Systems (ground truth from ``sympy.physics.mechanics``, trajectories by scipy DOP853 at
1e-10 tolerance; see ``tests/ground_truth.py``): the forced cart-pole, double pendulum,
double pendulum on a cart and three-link pendulum, with viscous friction, paper-style
catalogs (velocity monomials x trigonometric monomials, plus friction). Each run: a random
initial state and sum-of-sines forces on every coordinate, 30 s at 100 Hz; Gaussian noise of
``level`` times each coordinate's standard deviation added to the positions only; nothing
else is given to the methods.

Methods:

* ``weak``: ``XLSINDy(catalog)`` with its defaults: weak form, smoother and test functions
  chosen from the data, and, every coordinate being forced, the bagged explicit fit
  ``EnsembleOptimizer(ExplicitOptimizer())`` (20 cross-validated fits on 70 % subsamples,
  terms included in at least half of them, median coefficients); also records the smallest
  inclusion probability of a true term, the largest of a false term, and whether every
  true coefficient lies in its 95 % interval (issue 13's acceptance cell);
* ``weak_ols``: as ``weak`` but ``residual_covariance=False``: the rows fitted as they are,
  not whitened by the covariance of the pilot law's residual (the default before that
  reweighting);
* ``single``: the weak form with one cross-validated fit, ``ExplicitOptimizer()`` (the
  default before bagging);
* ``pairs``: the weak form bagged over complementary pairs of halves,
  ``EnsembleOptimizer(sampling="complementary_pairs")`` (10 pairs; a term is included by a
  pair when both halves keep it), with the same uncertainty metrics as ``weak``;
* ``mixed``: the weak form on data forced on the first coordinate only (the cart, or the
  first link), the others free: :class:`~pysindy_xl.MixedOptimizer`, chosen by default (its
  explicit part bagged as the fully forced fit is);
* ``implicit``: the weak form on unforced data (no ``u``): :class:`~pysindy_xl.ImplicitOptimizer`,
  chosen by default (laws selected by their noise ratio); support and error up to the law's
  scale. Three trajectories of 10 s from different initial states instead of one of 30 s: a
  single unforced trajectory stays on one (slowly decaying) energy level, where other
  Lagrangians give the same motion (Jacobi-Maupertuis: ``(E - V) T`` is a purely kinetic
  one), so no method can single out the true law from it;
* ``implicit_gls``: as ``implicit`` with ``residual_covariance=True`` (off by default on
  unforced data: measured here, it finds fewer exact laws on the double pendulum);
* ``bagged_implicit``: the same unforced runs, ``EnsembleOptimizer(ImplicitOptimizer())``
  (20 fits on 70 % subsamples; the law refit on the terms most fits keep, with all the data);
* ``strong``: ``XLSINDy(catalog, formulation="strong")``: pointwise Euler-Lagrange columns,
  derivatives by the package's default differentiation (Savitzky-Golay smoothed finite
  differences), same sparsity selection;
* ``sindy``: plain ``pysindy.SINDy`` (STLSQ) on the second-order problem ``[q, qd]``, with
  velocities and accelerations from the package's smoother, on the classical terms of the
  catalog's Euler-Lagrange expansion (no exact-support metric: another parametrization).

Metrics per cell: exact support (every true term and no other), median relative coefficient
error, valid (5 s validation from a fresh state and forcing: position RMSE below 10 % of the
range of every coordinate); for unforced fits also the number of rival laws the fit reports
(``undetermined_``: the data hold them as well; a wrong law that reports none is a confident
wrong law). Writes ``benchmarks/results/noise_sweep.{jsonl,md,png}`` (``--out`` elsewhere).

Usage: ``python benchmarks/noise_sweep.py [--seeds 10] [--first-seed 0]
[--levels 0,0.001,0.01,0.03,0.05,0.1] [--methods weak,single,strong,sindy]
[--systems cart_pole,...] [--jobs -1] [--append]``
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
import time

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

SYSTEMS = {"cart_pole": [1], "double_pendulum": [0, 1], "cart_double_pendulum": [1, 2],
           "triple_pendulum": [0, 1, 2]}
METHODS = ["weak", "weak_ols", "single", "pairs", "mixed", "implicit", "implicit_gls",
           "bagged_implicit", "strong", "sindy"]
#: Forced coordinates of the methods that do not force every coordinate.
FORCED = {"mixed": [0], "implicit": [], "implicit_gls": [], "bagged_implicit": []}


def _setup(name):
    import ground_truth
    from support.paper import paper_catalog, true_coefficients

    system = getattr(ground_truth, name)()
    library = paper_catalog(system.coords, SYSTEMS[name])
    return system, library, true_coefficients(system, library.fit())


def _force(system, seed, method):
    """The forcing of a run: every coordinate, some, or none (None)."""
    from ground_truth import random_force

    active = FORCED.get(method)
    return None if active == [] else random_force(system, seed, active=active)


def _validates(simulate, system, seed, method):
    from ground_truth import random_initial_state

    t = np.arange(0.0, 5.0, 0.01)
    force = _force(system, seed, method)
    x0 = random_initial_state(system, seed)
    truth = system.simulate(x0, t, force)
    try:
        sim = simulate(x0, t, force)
    except Exception:  # diverged, singular mass matrix: not valid
        return False
    rmse = np.sqrt(np.mean((sim[:, : system.n] - truth["q"]) ** 2, axis=0))
    return bool(np.all(rmse < 0.1 * np.ptp(truth["q"], axis=0)))


def _sindy(system, library, t, noisy, tau):
    import sympy as sp

    import pysindy_xl as px
    from pysindy_xl.benchmark.baseline import SINDyBaseline

    coords = system.coords
    accelerations = set(coords.qdd)
    terms = []
    for column in np.asarray(library.symbolic_matrix_).T:
        for entry in column:
            for term in sp.Add.make_args(sp.expand(entry)):
                core = term.as_coeff_Mul()[1]
                if core != 1 and not core.free_symbols & accelerations and not \
                        core.free_symbols & set(coords.tau) and core not in terms:
                    terms.append(core)
    terms += [q for q in coords.qd if q not in terms]
    q, qd, qdd = px.WhittakerSmoother().smooth(t, noisy)
    return SINDyBaseline(coords, terms).fit([q], [t], [qd], [qdd], [tau])


def run(name, level, seed, method):
    from ground_truth import random_initial_state

    import pysindy_xl as px

    system, library, true = _setup(name)
    unforced = FORCED.get(method) == []
    pieces = 3 if unforced else 1  # unforced: several energy levels (see above)
    t = np.arange(0.0, 30.0 / pieces, 0.01)
    runs = [system.simulate(random_initial_state(system, seed + 1000 * k), t,
                            _force(system, seed, method)) for k in range(pieces)]
    if unforced:  # no force: the law holds up to a factor, force column unused
        true = true.copy()
        true[library.force_columns_] = 0.0
    rng = np.random.default_rng(10_000 + seed)
    noisy = [r["q"] + level * r["q"].std(axis=0) * rng.normal(size=r["q"].shape) for r in runs]
    data = runs[0]
    if pieces == 1:
        noisy = noisy[0]
    else:
        t = [t] * pieces
    record = {"system": name, "level": level, "seed": seed, "method": method}
    start = time.perf_counter()
    try:
        if method == "sindy":
            model = _sindy(system, library, t, noisy, data["tau"])
            record.update(exact=None, error=None)
        else:
            formulation = "strong" if method == "strong" else "weak"
            optimizer = {"single": px.ExplicitOptimizer(),
                         "pairs": px.EnsembleOptimizer(sampling="complementary_pairs"),
                         "bagged_implicit": px.EnsembleOptimizer(px.ImplicitOptimizer()),
                         }.get(method)
            model = px.XLSINDy(library, optimizer, formulation=formulation,
                               residual_covariance={"weak_ols": False, "implicit_gls": True}
                               .get(method, "auto")).fit(
                noisy, t, u=None if unforced else data["tau"])
            coef, support = model.coefficients(), true != 0
            if unforced and np.any(coef[support]):  # compare up to the scale
                coef = coef * (coef[support] @ true[support]) / (coef[support] @ coef[support])
            record["exact"] = bool(np.array_equal(coef != 0, support))
            record["error"] = float(np.median(np.abs(coef[support] - true[support])
                                              / np.abs(true[support])))
            record["terms"] = int(np.count_nonzero(coef))
            # rival laws the fit reports (unforced noise-ratio selection): an honest fit flags
            # the data that do not determine the law
            record["undetermined"] = len(getattr(model.optimizer_, "undetermined_", ()))
            if model.coef_interval_ is not None:  # a bagged fit
                low, high = model.coef_interval_
                probability = model.inclusion_probability_
                record.update(
                    true_inclusion=float(probability[support].min()),
                    false_inclusion=float(probability[~support].max(initial=0.0)),
                    covered=bool(np.all((low[support] <= true[support])
                                        & (true[support] <= high[support]))),
                    interval_width=float(np.median((high[support] - low[support])
                                                   / np.abs(true[support]))))
        record["fit_s"] = time.perf_counter() - start
        record["valid"] = _validates(lambda x0, tt, u: model.simulate(x0, tt, u=u), system,
                                     500 + seed, method)
        record["status"] = "ok"
    except Exception as err:  # a failed fit counts as a failure, with its reason
        record.update(status="error", message=f"{type(err).__name__}: {err}"[:300],
                      exact=False, valid=False, fit_s=time.perf_counter() - start)
    return record


def _key(record) -> tuple:
    return (record["system"], record["level"], record["seed"], record["method"])


def summarize(records) -> str:
    rows = ["| system | noise | method | exact support | median coef. error | valid | "
            "median fit (s) |", "|---|---|---|---|---|---|---|"]
    keys = sorted({(r["system"], r["level"], r["method"]) for r in records},
                  key=lambda k: (k[0], k[1], METHODS.index(k[2])))
    for system, level, method in keys:
        cell = [r for r in records if (r["system"], r["level"], r["method"]) == (system, level,
                                                                                  method)]
        errors = [r["error"] for r in cell if r.get("error") is not None]
        exact = "-" if method == "sindy" else f"{sum(bool(r['exact']) for r in cell)}/{len(cell)}"
        error = f"{np.median(errors):.2%}" if errors else "-"
        rows.append(f"| {system} | {level:.1%} | {method} | {exact} | {error} | "
                    f"{sum(bool(r['valid']) for r in cell)}/{len(cell)} | "
                    f"{np.median([r['fit_s'] for r in cell]):.1f} |")
    flagged = [r for r in records if "undetermined" in r and FORCED.get(r["method"]) == []]
    if flagged:
        rows += ["", "Unforced fits that report rival laws (``undetermined_``, with an "
                 "``UndeterminedLawWarning``): wrong laws flagged / not flagged, exact laws "
                 "flagged", "", "| system | noise | method | wrong, flagged | wrong, not flagged "
                 "| exact, flagged |", "|---|---|---|---|---|---|"]
        for system, level, method in sorted({(r["system"], r["level"], r["method"])
                                             for r in flagged}):
            cell = [r for r in flagged
                    if (r["system"], r["level"], r["method"]) == (system, level, method)]
            wrong = [r for r in cell if not r["exact"]]
            rows.append(f"| {system} | {level:.1%} | {method} | "
                        f"{sum(r['undetermined'] > 0 for r in wrong)}/{len(wrong)} | "
                        f"{sum(r['undetermined'] == 0 for r in wrong)}/{len(wrong)} | "
                        f"{sum(r['undetermined'] > 0 for r in cell if r['exact'])}/"
                        f"{len(cell) - len(wrong)} |")
    ensemble = [r for r in records if r["method"] in ("weak", "pairs") and "covered" in r]
    if ensemble:
        rows += ["", "Uncertainty of the bagged fits, the default (weak: 70 % subsamples) and "
                 "complementary pairs (per seed: every true term with inclusion >= 0.9, every "
                 "false term <= 0.2, every true coefficient inside its 95 % interval)",
                 "", "| system | noise | method | true >= 0.9 | false <= 0.2 | covered | "
                 "median interval width (relative) |", "|---|---|---|---|---|---|---|"]
        for system, level, method in sorted({(r["system"], r["level"], r["method"])
                                             for r in ensemble}):
            cell = [r for r in ensemble
                    if (r["system"], r["level"], r["method"]) == (system, level, method)]
            counts = [sum(r["true_inclusion"] >= 0.9 for r in cell),
                      sum(r["false_inclusion"] <= 0.2 for r in cell),
                      sum(r["covered"] for r in cell)]
            widths = [r["interval_width"] for r in cell if "interval_width" in r]
            width = f"{np.median(widths):.2%}" if widths else "-"
            rows.append(f"| {system} | {level:.1%} | {method} | "
                        + " | ".join(f"{c}/{len(cell)}" for c in counts) + f" | {width} |")
    return "\n".join(rows)


def plot(records, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(SYSTEMS), figsize=(5 * len(SYSTEMS), 3.5), sharey=True)
    for ax, system in zip(np.atleast_1d(axes), SYSTEMS, strict=True):
        for method, style in (("weak", "o-"), ("single", "D-"), ("pairs", "P-"), ("mixed", "v-"),
                              ("implicit", "x-"), ("bagged_implicit", "X--"), ("strong", "s--"),
                              ("sindy", "^:")):
            levels = sorted({r["level"] for r in records if r["system"] == system})
            rate = [np.mean([bool(r["valid"]) and (method == "sindy" or bool(r["exact"]))
                             for r in records if (r["system"], r["level"], r["method"]) ==
                             (system, lv, method)] or [np.nan]) for lv in levels]
            if np.all(np.isnan(rate)):
                continue
            ax.plot([100 * lv for lv in levels], rate, style, label=method)
        ax.set_xscale("symlog", linthresh=0.1)
        ax.set_ylim(-0.05, 1.05)
        ax.set_title(system)
        ax.set_xlabel("position noise (% of std)")
    np.atleast_1d(axes)[0].set_ylabel("success (exact support and valid)")
    np.atleast_1d(axes)[0].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--first-seed", type=int, default=0,
                        help="seeds first-seed .. first-seed + seeds - 1 (fresh seeds check a "
                             "choice made on the usual ones)")
    parser.add_argument("--levels", default="0,0.001,0.01,0.03,0.05,0.1")
    parser.add_argument("--methods", default="weak,single,strong,sindy",
                        help=f"comma-separated, among {METHODS}")
    parser.add_argument("--systems", default=",".join(SYSTEMS),
                        help=f"comma-separated, among {list(SYSTEMS)}")
    parser.add_argument("--jobs", type=int, default=-1)
    parser.add_argument("--out", default=str(HERE / "results"))
    parser.add_argument("--append", action="store_true",
                        help="add these runs to the existing records (other methods/levels)")
    args = parser.parse_args()
    from joblib import Parallel, delayed

    levels = [float(v) for v in args.levels.split(",")]
    tasks = [(name, level, seed, method) for name in args.systems.split(",") for level in levels
             for seed in range(args.first_seed, args.first_seed + args.seeds)
             for method in args.methods.split(",")]
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "noise_sweep.jsonl"
    # every finished run is appended here at once: an interrupted sweep resumes from it
    partial = out / "noise_sweep.partial.jsonl"
    finished = {}
    if partial.exists():
        for line in partial.read_text().splitlines():
            try:
                record = json.loads(line)
                finished[_key(record)] = record
            except (json.JSONDecodeError, KeyError):  # a line cut by the interruption
                continue
    records = [finished[task] for task in tasks if task in finished]
    todo = [task for task in tasks if task not in finished]
    if records:
        print(f"resuming: {len(records)} of {len(tasks)} runs already done ({partial})")
    start = time.perf_counter()
    with open(partial, "a") as log:
        for record in Parallel(n_jobs=args.jobs, verbose=5, return_as="generator_unordered")(
                delayed(run)(*task) for task in todo):
            log.write(json.dumps(record) + "\n")
            log.flush()
            records.append(record)
    records.sort(key=lambda r: tasks.index(_key(r)))
    if args.append and path.exists():
        done = {_key(r) for r in records}
        previous = [json.loads(line) for line in path.read_text().splitlines() if line]
        records = [r for r in previous if _key(r) not in done] + records
    with open(path, "w") as f:
        f.writelines(json.dumps(record) + "\n" for record in records)
    partial.unlink()
    table = summarize(records)
    (out / "noise_sweep.md").write_text(
        f"{len(records)} runs (last invocation: {time.perf_counter() - start:.0f} s wall on "
        f"{args.jobs} jobs)\n\n{table}\n")
    plot(records, out / "noise_sweep.png")
    print(table)


if __name__ == "__main__":
    main()
