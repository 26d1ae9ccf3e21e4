"""Why the flexible basis loses to a polynomial stand-in: candidate catalogs judged on a
growth's own splits.

For one case of the benchmark sets (``system:forcing:noise:seed``), the splits of
:func:`pysindy_xl.grow_catalog` are rebuilt (the default split: the last block and the region
block of each run held out; the tie judge's: every block in turn), and each candidate catalog
is fitted on each split's training pieces with the search's optimizer and test functions and
scored on the held-out blocks (the growth's criterion), then fitted on all the data with the
final fit's grouping and scored on the case's fresh test run (held-out, 2 s simulation, off the
training box; ``generic_systems.score``). Candidates:

- ``quartic``: the polynomial family to degree 4;
- ``nat K`` / ``quad K``: K natural or quadratic-end splines written as B-splines;
- ``t-nat K`` / ``t-quad K``: the same spans written one column per interior knot
  (``spline_basis="truncated"``);
- ``q-quad K``: quadratic-end splines on knots at the quantiles of each split's training
  positions (1st to 99th), written one column per knot: a basis the package does not have,
  measured by replacing the catalog's spline writer in this process;
- ``true``: the law's own potential terms in place of the splines (``sqrt(1 + x^2)`` and
  ``x^2`` for the oblique slider; ``exp(-3x)`` and ``exp(-1.5x)`` for the Morse well;
  ``log cosh 2x`` for the log-cosh well).

Usage::

    PYTHONPATH=$PWD python benchmarks/flexible_basis.py oblique_spring_slider:forced:0.01:1
"""

from __future__ import annotations

import os
import sys
import warnings

import numpy as np
import sympy as sp
from sklearn.base import clone

sys.path.insert(0, os.path.dirname(__file__))

import blind_systems as bs  # noqa: E402
import generic_systems as gs  # noqa: E402
import unseen_systems as us  # noqa: E402

import pysindy_xl as px  # noqa: E402
import pysindy_xl.catalog.automatic as automatic  # noqa: E402
import pysindy_xl.catalog.terms as terms  # noqa: E402
from pysindy_xl.catalog.floor import held_out_scores  # noqa: E402
from pysindy_xl.catalog.folds import held_out_splits  # noqa: E402
from pysindy_xl.catalog.growth_data import data_span  # noqa: E402
from pysindy_xl.catalog.moves import START  # noqa: E402
from pysindy_xl.optimizers import GroupedOptimizer  # noqa: E402

PACKAGE_WRITER = terms.spline_basis
TRUE = {"oblique_spring_slider": lambda q: [q ** 2, sp.sqrt(1 + q ** 2)],
        "morse_well": lambda q: [sp.exp(-3 * q), sp.exp(-1.5 * q)],
        "log_cosh_well": lambda q: [sp.log(sp.cosh(2 * q))]}
STATE = {"writer": None, "system": None, "train": {}}


def _plus_cubed(z):
    return ((z + sp.Abs(z)) / 2) ** 3


def _quantile_knots(q, knots):
    """Quadratic-end cubic splines on arbitrary knots, one column per knot, no constant."""
    knots = np.asarray(knots, dtype=float)
    scale = sp.Float(float(knots[-1] - knots[0]))
    s = [(q - sp.Float(float(v))) / scale for v in knots]
    z = s[0]
    return [z, z ** 2] + [_plus_cubed(s[j]) - _plus_cubed(s[-1]) for j in range(len(knots) - 1)]


def _writer(options, q, low, high, count):
    """The catalog's spline writer, replaced for the ``q-`` and ``true`` candidates."""
    if STATE["writer"] == "true":
        return TRUE[STATE["system"]](q)
    if STATE["writer"] == "quantile":
        x = STATE["train"][(low, high)]
        return _quantile_knots(q, np.quantile(x, np.linspace(0.01, 0.99, count)))
    return PACKAGE_WRITER(options, q, low, high, count)


terms.spline_basis = automatic.spline_basis = _writer  # (both callers)

CANDIDATES = {
    "quartic": (None, {"degree": 4}),
    **{f"nat{k}": (None, {"splines": k}) for k in (6, 8, 12)},
    **{f"quad{k}": (None, {"splines": k, "spline_ends": "quadratic"}) for k in (6, 8, 12, 16)},
    **{f"t-nat{k}": (None, {"splines": k, "spline_basis": "truncated"}) for k in (8, 12)},
    **{f"t-quad{k}": (None, {"splines": k, "spline_ends": "quadratic",
                             "spline_basis": "truncated"}) for k in (6, 8, 12, 16)},
    **{f"q-quad{k}": ("quantile", {"splines": k, "spline_ends": "quadratic"}) for k in (8, 12)},
    "true": ("true", {"splines": 4}),
}


def setup(case):
    """The case's data, the search's template model and its two kinds of splits."""
    table = {**gs.systems(), **us.systems(), **bs.systems()}
    system, truth, forced, data = gs.case_of(case, table)
    runs, test, xs, ts, forces = data
    xs = [np.asarray(x, dtype=float).reshape(len(x), -1) for x in xs]
    n_blocks, stride = 5, max(1, int(np.ceil(sum(len(t) for t in ts) / 6000)))
    arrays = {"x": xs, "t": ts, "u": forces, "x_dot": None, "x_ddot": None}
    from pysindy_xl.fit import RememberedSmoother
    from pysindy_xl.weak import BumpTestFunctions
    block = min(len(t) for t in ts) // n_blocks
    longest = int(np.argmax([len(t) for t in ts]))
    width = min(BumpTestFunctions().half_width(ts[longest], xs[longest]),
                min(t[block - 1] - t[0] for t in ts) / 3)
    if not forced:
        raise ValueError("case: forced cases only")
    template = px.XLSINDy(optimizer=px.ExplicitOptimizer(),
                          test_functions=BumpTestFunctions(width=width),
                          smoother=RememberedSmoother())
    default = held_out_splits(arrays, n_blocks, stride, False, "block", margin=width)[0]
    every = held_out_splits(arrays, n_blocks, stride, True, "block", margin=width)[0]
    fixed = {"coordinates": list(system["coords"].names), "kinds": list(system["kinds"]),
             "max_terms": 400}
    return system, truth, (runs, test, xs, ts, forces), template, default, every, fixed


def _remember(xs, bounds):
    for bound, values in zip(bounds, np.vstack(xs).T, strict=True):
        STATE["train"][bound] = values


def criterion(template, splits, fixed, parameters):
    """Held-out errors of each split's blocks (the search's fits)."""
    errors = []
    for train, blocks in splits:
        bounds = data_span(train["x"])
        _remember(train["x"], bounds)
        model = clone(template).set_params(feature_library=px.AutomaticCatalog(
            **fixed, bounds=bounds, **parameters))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model.fit(**train)
        errors += [held_out_scores(model, held, True, False)[0] for held in blocks]
    return errors


def final(system, truth, data, template, fixed, parameters):
    """The scores of the candidate fitted on all the data as the growth's final fit is."""
    runs, test, xs, ts, forces = data
    bounds = data_span(xs)
    _remember(xs, bounds)
    catalog = px.AutomaticCatalog(**fixed, bounds=bounds, **parameters)
    optimizer = GroupedOptimizer(px.optimizers.default_optimizer(
        np.any(np.vstack(forces) != 0, axis=0), True), groups=catalog.spline_columns())
    model = clone(template).set_params(feature_library=catalog, smoother=None,
                                       optimizer=optimizer)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(xs, ts, u=forces)
        return gs.score(*gs._xlsindy_functions(model), system, truth, test, runs, True)


def main(case, names=None):
    STATE["system"] = case.split(":")[0]
    system, truth, data, template, default, every, fixed = setup(case)
    train = np.vstack(data[2])
    print(f"{case}: training range {train.min():.2f} .. {train.max():.2f}, test run "
          f"{data[1]['q'].min():.2f} .. {data[1]['q'].max():.2f}")
    for train_pieces, blocks in default:
        low, high = data_span(train_pieces["x"])[0]
        print(f"  default split: splines' end knots {low:.2f} .. {high:.2f}; held out " + ", ".join(
            f"{np.vstack(b['x']).min():.2f} .. {np.vstack(b['x']).max():.2f}" for b in blocks))
    print("| candidate | time block | region block | criterion | every block (5) | their RMS "
          "| test held-out | simulation | off-box | right |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name in names or CANDIDATES:
        writer, parameters = CANDIDATES[name]
        STATE["writer"] = writer
        automatic._TERMS.clear()  # (terms cached by parameters, not by writer)
        parameters = dict(START, kinetic="constant", **parameters)
        errors = criterion(template, default, fixed, parameters)
        blocks = criterion(template, every, fixed, parameters)
        scores = final(system, truth, data, template, fixed, parameters)
        print(f"| {name} | {100 * errors[0]:.2f} | {100 * errors[1]:.2f} | "
              f"{100 * np.sqrt(np.mean(np.square(errors))):.2f} | "
              + " ".join(f"{100 * e:.1f}" for e in blocks)
              + f" | {100 * np.sqrt(np.mean(np.square(blocks))):.2f} | "
              f"{100 * scores['held_out']:.2f} | {100 * scores['simulation']:.2f} | "
              f"{100 * scores['off_box']:.2f} | {scores['right']} |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2].split(",") if len(sys.argv) > 2 else None)
