"""The growth's final fit with the search's test functions against the default ones, case by case.

``grow_catalog`` judges each catalog by fits with the search's weak-form test functions (one
half-width: the default width of the longest run, at most a third of the shortest run's time
block) and fits the chosen catalog on all the data with the same test functions. This script
grows the catalog once per case of ``generic_systems.py`` (same data: two 10 s runs at 1 kHz,
positions with Gaussian noise) and scores three models on the benchmark's fresh test run:

- ``search``: the growth's model (the search's test functions);
- ``default``: the chosen catalog fitted on all the data with XLSINDy's default test functions
  (wider; unforced data: three widths), the same optimizer otherwise;
- ``hand``: the correct hand-built catalog, fitted by XLSINDy's defaults (the benchmark's
  reference); ``--hand-search`` adds ``hand_search``: the same catalog fitted with the
  search's test functions (the reference fitted as the growth's model is).

Each case appends one JSON line; cases already in the file are skipped. ``--report`` prints
the markdown summary of a file. Usage::

    PYTHONPATH=$PWD python benchmarks/final_fit_consistency.py out.jsonl duffing:forced:0.05:0
    python benchmarks/final_fit_consistency.py --report out.jsonl
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

import generic_systems as gs  # noqa: E402

import pysindy_xl as px  # noqa: E402

#: Held-out errors below this are round-off (noise-free data): their ratios mean nothing.
ROUND_OFF = 1e-8


def run_case(case: str, hand_search: bool = False) -> dict:
    """Grow once and score the models of one case (see the module docstring)."""
    from sklearn.base import clone

    from pysindy_xl.catalog.growth_data import END_PERCENTILE
    system, truth, forced, (runs, test, xs, ts, us) = gs.case_of(case)
    names = list(system["coords"].names)
    record = {"case": case}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cpu = time.process_time()
        found = px.grow_catalog(xs, ts, us, coordinates=names, kinds=system["kinds"])
        record["cpu_growth"] = time.process_time() - cpu
        record["catalog"] = found.catalog.describe()
        models = {"search": found.model}
        cpu = time.process_time()
        models["default"] = clone(found.model).set_params(test_functions=None).fit(xs, ts, u=us)
        record["cpu_default_fit"] = time.process_time() - cpu
        low, high = np.percentile(np.vstack(xs), [END_PERCENTILE, 100 - END_PERCENTILE], axis=0)
        bounds = [(float(a), float(b)) for a, b in zip(low, high, strict=True)]
        catalog = px.AutomaticCatalog(names, kinds=system["kinds"], bounds=bounds,
                                      **system["hand"])
        cpu = time.process_time()
        models["hand"] = px.XLSINDy(catalog).fit(xs, ts, u=us)
        record["cpu_hand_fit"] = time.process_time() - cpu
        if hand_search:
            models["hand_search"] = px.XLSINDy(
                catalog, test_functions=found.model.test_functions).fit(xs, ts, u=us)
        for key, model in models.items():
            record[key] = gs.score(*gs._xlsindy_functions(model), system, truth, test, runs,
                                   forced)
            record[key]["kept"] = int(np.count_nonzero(model.coef_))
    return record


def _ratio(record, key):
    hand = record["hand"]["held_out"]
    return record[key]["held_out"] / hand if hand > 0 else float("inf")


def report(path: str) -> str:
    """The markdown summary of the records in ``path``."""
    with open(path) as f:
        records = [r for r in map(json.loads, f) if "error" not in r]
    lines = ["| cases | model | right 0-1 % | right 5 % | within 1.5x of hand | "
             "within 1.5x, noisy | median held-out % |", "|---|---|---|---|---|---|---|"]
    groups = {"benchmark grid": [r for r in records
                                 if not r["case"].startswith("log_cosh_well:unforced")],
              "log_cosh_well unforced": [r for r in records
                                         if r["case"].startswith("log_cosh_well:unforced")]}
    for label, group in groups.items():
        if not group:
            continue
        low = [r for r in group if float(r["case"].split(":")[2]) <= 0.01]
        high = [r for r in group if float(r["case"].split(":")[2]) > 0.01]
        noisy = [r for r in group if r["hand"]["held_out"] > ROUND_OFF]
        for key in ("default", "search", "hand"):
            within = "-" if key == "hand" else (
                f"{sum(_ratio(r, key) <= 1.5 for r in group)}/{len(group)}")
            within_noisy = "-" if key == "hand" else (
                f"{sum(_ratio(r, key) <= 1.5 for r in noisy)}/{len(noisy)}")
            lines.append(f"| {label} ({len(group)}) | {key} | "
                         f"{sum(r[key]['right'] for r in low)}/{len(low)} | "
                         f"{sum(r[key]['right'] for r in high)}/{len(high)} | {within} | "
                         f"{within_noisy} | "
                         f"{100 * np.median([r[key]['held_out'] for r in group]):.3g} |")
    alike = [r for r in groups["benchmark grid"] if "hand_search" in r]
    if alike:  # the hand-built catalog fitted with the test functions of the model it judges
        within = sum(r["search"]["held_out"] <= 1.5 * r["hand_search"]["held_out"]
                     for r in alike)
        lines += ["", f"Benchmark grid, the hand-built catalog fitted with the search's test "
                  f"functions too (``hand_search``): the growth's model within 1.5x of it in "
                  f"{within}/{len(alike)} cases; right "
                  f"{sum(r['hand_search']['right'] for r in alike)}/{len(alike)}."]
    changed = [r for r in records if r["default"]["right"] != r["search"]["right"]
               or (max(r["default"]["held_out"], r["search"]["held_out"]) > ROUND_OFF
                   and abs(np.log(r["search"]["held_out"] / r["default"]["held_out"]))
                   > np.log(1.1))]
    lines += ["", "Cases whose held-out error moved by more than 10 % (above round-off), or "
              "whose verdict changed (default -> search's test functions; % of the truth):", "",
              "| case | catalog | held-out % | / hand's | 2 s sim % | off-box % | right | kept |",
              "|---|---|---|---|---|---|---|---|"]
    for r in changed:
        a, b = r["default"], r["search"]
        lines.append(
            f"| {r['case']} | {r['catalog']} | {100 * a['held_out']:.3g} -> "
            f"{100 * b['held_out']:.3g} | {_ratio(r, 'default'):.2f} -> "
            f"{_ratio(r, 'search'):.2f} | {100 * a['simulation']:.3g} -> "
            f"{100 * b['simulation']:.3g} | {100 * a['off_box']:.3g} -> "
            f"{100 * b['off_box']:.3g} | {'Y' if a['right'] else 'n'} -> "
            f"{'Y' if b['right'] else 'n'} | {a['kept']} -> {b['kept']} |")
    moved = [np.log(r["search"]["held_out"] / r["default"]["held_out"]) for r in records
             if min(r["default"]["held_out"], r["search"]["held_out"]) > ROUND_OFF]
    if moved:
        lines += ["", f"Above round-off ({len(moved)} cases): geometric mean of search / "
                  f"default held-out error {np.exp(np.mean(moved)):.3f}; lower by more than "
                  f"10 % in {sum(m < -np.log(1.1) for m in moved)}, higher by more than 10 % "
                  f"in {sum(m > np.log(1.1) for m in moved)}."]
    fits = {"cpu_growth": "the growth (its final fit included)",
            "cpu_default_fit": "a fit on all the data with the default test functions",
            "cpu_search_fit": "a fit on all the data with the search's test functions",
            "cpu_hand_fit": "the hand-built catalog's fit"}
    lines += ["", "CPU s (median): " + "; ".join(
        f"{text} {np.median([r[key] for r in records]):.2f}" for key, text in fits.items()
        if all(key in r for r in records)) + "."]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", help="JSONL file the records are appended to")
    parser.add_argument("cases", nargs="*", help="system:forcing:noise:seed")
    parser.add_argument("--report", metavar="JSONL")
    parser.add_argument("--hand-search", action="store_true",
                        help="also fit the hand-built catalog with the search's test functions")
    args = parser.parse_intermixed_args(argv)
    if args.report:
        print(report(args.report))
        return
    done = gs.recorded(args.out, lambda record: record["case"])
    for case in args.cases:
        if case in done:
            continue
        try:
            record = run_case(case, args.hand_search)
        except Exception as error:  # noqa: BLE001 - a failed case is recorded
            record = {"case": case, "error": repr(error)[:300]}
        with open(args.out, "a") as f:
            f.write(json.dumps(record) + "\n")
        print(case, {k: record[k]["held_out"] for k in ("default", "search", "hand")
                     if k in record}, flush=True)


if __name__ == "__main__":
    main()
