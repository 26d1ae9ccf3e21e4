"""Why the growth misses three forced rows of the offset spring pendulum (second blind set).

Per case ``system:forcing:noise:seed`` of the five sets (forced only):

- the grown model's held-out force error on the fresh test run, split into the samples inside
  the training runs' range of positions and those outside it (``inside`` and ``outside`` add
  in squares to ``held_out``);
- the same split for the benchmark's hand-built catalog, fitted three ways: XLSINDy's defaults
  (the benchmark's ``hand``), the growth's test functions (``hand_same``), and these with each
  coordinate's splines kept whole (the growth's final fit, :func:`_grouped_optimizer`);
- with ``--anchor``: the law's own family for a spring anchored off a coordinate's path, fitted
  by variable projection on the training runs (strong form, derivatives of
  :func:`~pysindy_xl.held_out.scoring_derivatives`; a sketch, not the package's weak form):
  the length ``sqrt(1 - e cos(theta - phi))`` of an angle (``e``, ``phi`` fitted) or
  ``sqrt((x - c)^2 + h^2)`` of a linear coordinate (``c``, ``h``), beside the first
  catalog's force columns (inertia, viscous friction, ``sin``/``cos`` or ``1``/``x``).

Usage (one process; ``benchmarks/results/offset_spring_trace.md`` reports it)::

    PYTHONPATH=$PWD python benchmarks/offset_spring_trace.py \\
        offset_spring_pendulum:forced:0.0:2 --anchor \\
        --out benchmarks/results/offset_spring_trace.jsonl
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings

import numpy as np
from scipy.optimize import minimize

sys.path.insert(0, os.path.dirname(__file__))

import blind2_systems as b2  # noqa: E402
import blind3_systems as b3  # noqa: E402
import blind_systems as b1  # noqa: E402
import generic_systems as gs  # noqa: E402
import unseen_systems as us_  # noqa: E402

import pysindy_xl as px  # noqa: E402
from pysindy_xl.catalog.final_fit import _grouped_optimizer  # noqa: E402
from pysindy_xl.catalog.growth_data import END_PERCENTILE  # noqa: E402
from pysindy_xl.held_out import scoring_derivatives  # noqa: E402


def split_error(model, test, outside):
    """held_out, inside, outside of ``model`` on the test run (relative to its forces' norm)."""
    error = model.predict_forces(test["q"], test["qd"], test["qdd"]) - test["u"]
    norm = np.sum(test["u"] ** 2)
    return {"held_out": float(np.sqrt(np.sum(error ** 2) / norm)),
            "inside": float(np.sqrt(np.sum(error[~outside] ** 2) / norm)),
            "outside": float(np.sqrt(np.sum(error[outside] ** 2) / norm)),
            "kept": int(np.count_nonzero(model.coefficients()))}


def _anchor_columns(q, qd, qdd, p, kind):
    x, v, a = q[:, 0], qd[:, 0], qdd[:, 0]
    if kind == "angle":  # the force of -sqrt(1 - e cos(x - phi)), then the first catalog's
        e, phi = p
        length = e * np.sin(x - phi) / (2 * np.sqrt(1 - e * np.cos(x - phi)))
        return np.column_stack([a, v, np.cos(x), np.sin(x), length])
    c, h = p
    return np.column_stack([a, v, np.ones_like(x), x, (x - c) / np.sqrt((x - c) ** 2 + h ** 2)])


def anchor_fit(xs, ts, us, test, kind):
    """The anchored spring's length fitted by variable projection (grid, then Nelder-Mead)."""
    smooth = [scoring_derivatives(t, x) for x, t in zip(xs, ts, strict=True)]
    cut = [slice(200, len(t) - 200) for t in ts]  # (the smoother's ends left out)
    q, qd, qdd = (np.vstack([d[k][s] for d, s in zip(smooth, cut, strict=True)])
                  for k in range(3))
    u = np.vstack([f[s] for f, s in zip(us, cut, strict=True)])[:, 0]

    def residual(p):
        if (kind == "angle" and not 0 < p[0] < 1) or (kind != "angle" and p[1] <= 0):
            return 1e9
        columns = _anchor_columns(q, qd, qdd, p, kind)
        coef = np.linalg.lstsq(columns, u, rcond=None)[0]
        return float(np.linalg.norm(columns @ coef - u) / np.linalg.norm(u))

    grid = ([(e, p) for e in np.linspace(0.05, 0.99, 48) for p in np.linspace(-np.pi, np.pi, 61)]
            if kind == "angle" else
            [(c, h) for c in np.linspace(-2, 2, 41) for h in np.geomspace(0.05, 5, 41)])
    start = min(grid, key=residual)
    found = minimize(residual, start, method="Nelder-Mead",
                     options={"xatol": 1e-5, "fatol": 1e-10})
    columns = _anchor_columns(q, qd, qdd, found.x, kind)
    coef = np.linalg.lstsq(columns, u, rcond=None)[0]
    predicted = _anchor_columns(test["q"], test["qd"], test["qdd"], found.x, kind) @ coef
    return {"parameters": [float(p) for p in found.x], "train_residual": float(found.fun),
            "held_out": float(np.linalg.norm(predicted - test["u"][:, 0])
                              / np.linalg.norm(test["u"][:, 0])),
            "inertia": float(coef[0]), "damping": float(coef[1])}


def trace(key, anchor=False):
    """The record of one case (see the module's docstring)."""
    table = {**gs.systems(), **us_.systems(), **b1.systems(), **b2.systems(), **b3.systems()}
    system, truth, forced, (runs, test, xs, ts, us) = gs.case_of(key, table)
    names = list(system["coords"].names)
    q = np.vstack([r["q"] for r in runs])
    low, high = q.min(axis=0), q.max(axis=0)
    outside = np.any((test["q"] < low) | (test["q"] > high), axis=1)
    record = {"case": key, "train_range": [low.tolist(), high.tolist()],
              "test_range": [test["q"].min(axis=0).tolist(), test["q"].max(axis=0).tolist()],
              "outside_share": float(outside.mean())}
    cpu = time.process_time()
    found = px.grow_catalog(xs, ts, us, coordinates=names, kinds=system["kinds"])
    record["cpu_seconds"] = time.process_time() - cpu
    record["catalog"] = found.catalog.describe()
    record["criterion"] = found.held_out_error
    record["auto"] = split_error(found.model, test, outside)
    ends = np.percentile(np.vstack(xs), [END_PERCENTILE, 100 - END_PERCENTILE], axis=0)
    bounds = [(float(a), float(b)) for a, b in zip(*ends, strict=True)]
    catalog = px.AutomaticCatalog(names, kinds=system["kinds"], bounds=bounds, **system["hand"])
    functions = found.model.test_functions
    record["hand"] = split_error(px.XLSINDy(catalog).fit(xs, ts, u=us), test, outside)
    record["hand_same"] = split_error(
        px.XLSINDy(catalog, test_functions=functions).fit(xs, ts, u=us), test, outside)
    whole = _grouped_optimizer(None, catalog.fit(), np.ones(len(names), bool), True)
    record["hand_whole"] = split_error(
        px.XLSINDy(catalog, test_functions=functions, optimizer=whole).fit(xs, ts, u=us),
        test, outside)
    if anchor and len(names) == 1:
        record["anchor"] = anchor_fit(xs, ts, us, test, system["kinds"][0])
    return record


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="+", metavar="SYSTEM:forced:NOISE:SEED")
    parser.add_argument("--anchor", action="store_true",
                        help="also fit the anchored spring's family (one-coordinate systems)")
    parser.add_argument("--out", default=None, help="JSONL file the records are appended to")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    for key in args.cases:
        record = trace(key, args.anchor)
        line = json.dumps(record)
        print(line, flush=True)
        if args.out:
            with open(args.out, "a", encoding="utf-8") as handle:
                handle.write(line + "\n")


if __name__ == "__main__":
    main()
