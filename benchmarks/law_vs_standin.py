"""Why a catalog that holds the law can score worse than a stand-in on the growth's blocks.

Takes one unseen case (default: the elastic double pendulum, forced, 1 % noise, seed 2, whose
growth keeps ``4.2 cos(a - b)`` and ``sin^2`` products for the joint spring ``-1.5 (a - b)^2``)
and the search split that :func:`pysindy_xl.grow_catalog` builds for it (intercepted where
the growth hands it to its candidate fits, so the split is the growth's own), and prints:

1. the sparse fits of the stand-in's catalog and of the law's catalog (the growth's search
   fits): criterion, block errors and coefficients;
2. least-squares fits of the law's own terms (the catalog's nine: ``a^2, a b, b^2`` for the
   spring; and seven, with ``(a - b)^2`` as one term) and of the stand-in's twelve, on the
   noisy and on the noise-free training positions, scored on the noisy and noise-free held-out
   blocks; and the exact law (true coefficients) on the same blocks;
3. the error of each run's held-out piece, the states' reach in and out of the fit, and the
   terms whose coefficient errors make the law's error on the worst piece;
4. the same least-squares fits on fresh noise draws of the same runs (the criterion's spread);
5. the cross-validated blocks and the fold of the extreme states (``region="extremes"``).

Usage::

    PYTHONPATH=$PWD python benchmarks/law_vs_standin.py [--draws 6]
"""

import argparse
import os
import pickle
import sys
import warnings

import numpy as np
import sympy as sp
from sklearn.base import clone

import pysindy_xl as px
from pysindy_xl.catalog import growth
from pysindy_xl.catalog.automatic import AutomaticCatalog
from pysindy_xl.catalog.candidates import CandidateFits, evaluate_candidate
from pysindy_xl.catalog.floor import held_out_scores
from pysindy_xl.catalog.moves import START

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import generic_systems as gs  # noqa: E402
import growth_cases as gc  # noqa: E402
import unseen_systems as us  # noqa: E402

KEY = "elastic_double_pendulum:forced:0.01:2"
STAND_IN = dict(START, trig_degree=2, interaction=2, kinetic="configuration")
LAW = dict(START, trig_degree=1, angle_degree=2, interaction=2, kinetic="configuration")
TRUE = {"F[tau]": -1.0, "L[a_dot**2]": 0.3, "L[b_dot**2]": 0.1,
        "L[a_dot*b_dot*sin(a)*sin(b)]": 0.2, "L[a_dot*b_dot*cos(a)*cos(b)]": 0.2,
        "L[cos(a)]": 5.886, "L[cos(b)]": 1.962, "L[a**2]": -1.5, "L[b**2]": -1.5,
        "L[a*b]": 3.0, "C_a[a_dot]": 0.05, "C_b[b_dot]": 0.05}


class _Captured(Exception):
    """Raised by the intercepting CandidateFits once it holds the search's data."""


def search_of(key, **options):
    """The case's data and the SearchData that ``grow_catalog(**options)`` builds for it."""
    system, truth, forced, (runs, test, xs, ts, u) = gs.case_of(key, us.systems())
    held = {}

    class Intercept(CandidateFits):
        def __init__(self, search, n_jobs=None):  # noqa: D107 - stops the growth
            held["search"] = search
            raise _Captured

    growth.CandidateFits = Intercept
    try:
        gc.grow(system, xs, ts, u, **options)
    except _Captured:
        pass
    finally:
        growth.CandidateFits = CandidateFits
    return runs, xs, ts, held["search"]


def clean_of(pieces, runs, xs, stride):
    """The noise-free positions of noisy pieces (found by their first sample)."""
    out = []
    for piece in pieces:
        for k, xk in enumerate(xs):
            hit = np.flatnonzero(np.all(xk == piece[0], axis=1))
            if len(hit):
                out.append(runs[k]["q"][hit[0]:hit[0] + len(piece) * stride:stride])
                break
    return out


def law_library(terms):
    """Forces, the Lagrangian ``terms`` and a viscous force per coordinate."""
    c = px.Coordinates(["a", "b"])
    return px.CatalogRepartition([px.ExternalForces(c), px.LagrangeLibrary(c, terms(c)),
                                  px.ClassicalLibrary(c, list(c.qd), mask=np.eye(2))])


def _law9(c):
    (a, b), (ad, bd) = c.q, c.qd
    return [ad ** 2, bd ** 2, ad * bd * sp.sin(a) * sp.sin(b), ad * bd * sp.cos(a) * sp.cos(b),
            sp.cos(a), sp.cos(b), a ** 2, b ** 2, a * b]


def _law7(c):
    (a, b), (ad, bd) = c.q, c.qd
    return [ad ** 2, bd ** 2, ad * bd * sp.cos(a - b), sp.cos(a), sp.cos(b), (a - b) ** 2]


def _stand_in12(c):
    (a, b), (ad, bd) = c.q, c.qd
    s, k = (sp.sin(a), sp.sin(b)), (sp.cos(a), sp.cos(b))
    return [ad ** 2, bd ** 2, ad * bd * s[0] * s[1], ad * bd * k[0] * k[1], k[0], k[1],
            s[0] ** 2, s[1] ** 2, s[0] * s[1], k[0] * k[1], s[0] ** 2 * s[1] ** 2,
            s[0] * s[1] * k[0] * k[1]]


LIBRARIES = {"law, 9 terms": _law9, "law, 7 terms": _law7, "stand-in, 12 terms": _stand_in12}


def fitted(search, split, train, library=None, parameters=None):
    """The search's model fitted on ``train``: a catalog's sparse fit (``parameters``) or a
    least-squares fit of ``library``'s terms."""
    model = clone(search.template)
    if parameters is not None:
        model.set_params(feature_library=AutomaticCatalog(**split.fixed, **parameters))
    else:
        model.set_params(feature_library=library,
                         optimizer=px.ExplicitOptimizer(threshold=1e-9))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(**train)
    return model


def errors(model, blocks):
    """Held-out error of each block."""
    return [held_out_scores(model, block, True, floor=False)[0] for block in blocks]


def rms(values):
    return float(np.sqrt(np.mean(np.square(values))))


def pct(values):
    return " ".join(f"{100 * v:.2f}" for v in values)


def pieces_of(blocks):
    """Each run's piece of each block, as a block of its own."""
    return [{"x": [b["x"][k]], "t": [b["t"][k]], "u": [b["u"][k]]}
            for b in blocks for k in range(len(b["x"]))]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=6, help="fresh noise draws (part 4)")
    args = parser.parse_args()
    runs, xs, ts, search = search_of(KEY)
    split = search.splits[0]
    stride = max(1, int(np.ceil(sum(len(t) for t in ts) / 6000)))
    clean_blocks = [dict(b, x=clean_of(b["x"], runs, xs, 1)) for b in split.blocks]
    clean_train = dict(split.train, x=clean_of(split.train["x"], runs, xs, stride))

    print(f"== 1. search fits ({KEY}; blocks: time, region; errors in %)")
    models = {}
    for label, parameters in (("stand-in catalog", STAND_IN), ("law's catalog", LAW)):
        step = evaluate_candidate(search, parameters)
        models[label] = fitted(search, split, split.train, parameters=parameters)
        kept = {n: round(float(v), 4) for n, v in zip(models[label].get_feature_names(),
                                                      models[label].coefficients(),
                                                      strict=True) if v}
        print(f"{label} ({step['terms']} terms): criterion {100 * step['criterion']:.3f}, "
              f"blocks {pct(step['block_errors'])}\n  {kept}")

    print("\n== 2. the law's own terms, least squares (noisy blocks | noise-free blocks)")
    exact = pickle.loads(pickle.dumps(models["law's catalog"]))
    exact.coef_ = np.array([TRUE.get(n, 0.0) for n in exact.get_feature_names()])
    exact._build_dynamics()
    e = errors(exact, split.blocks)
    print(f"exact law (true coefficients): {pct(e)} (criterion {100 * rms(e):.3f}) | "
          f"{pct(errors(exact, clean_blocks))}")
    for label, terms in LIBRARIES.items():
        for data, train in (("noisy", split.train), ("noise-free", clean_train)):
            model = fitted(search, split, train, law_library(terms))
            e = errors(model, split.blocks)
            print(f"{label}, fitted on {data} positions: {pct(e)} (criterion "
                  f"{100 * rms(e):.3f}) | {pct(errors(model, clean_blocks))}")
            models[f"{label} {data}"] = model

    print("\n== 3. per run (time block run 0, run 1; region block run 0, run 1)")
    pieces = pieces_of(split.blocks)
    print("largest |angle| fitted:", [round(float(np.abs(x).max()), 2)
                                      for x in split.train["x"]],
          " held out:", [round(float(np.abs(p["x"][0]).max()), 2) for p in pieces])
    for label in ("stand-in catalog", "law's catalog", "law, 9 terms noisy",
                  "stand-in, 12 terms noisy"):
        print(f"{label}: {pct(errors(models[label], pieces))}")
    worst = pieces[0]
    for label in ("law's catalog", "law, 9 terms noisy"):
        model = models[label]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            problem = model.regression(worst["x"], worst["t"], u=worst["u"],
                                       formulation="weak", propagate_noise=False)
        names = np.array(model.get_feature_names())[problem.catalog_map.columns]
        coef = model.coef_[problem.catalog_map.columns]
        truth = np.array([TRUE.get(n, 0.0) for n in names])
        theta, forces = problem.theta, problem.force_columns
        scale = np.linalg.norm(theta[:, forces] @ coef[forces])
        parts = sorted(((np.linalg.norm(theta[:, j] * (coef[j] - truth[j])) / scale,
                         names[j], coef[j] - truth[j]) for j in range(len(names))),
                       reverse=True)[:5]
        print(f"{label} on the time block of run 0: fitted "
              f"{100 * np.linalg.norm(theta @ coef) / scale:.2f}, exact "
              f"{100 * np.linalg.norm(theta @ truth) / scale:.2f}; largest parts of "
              "Theta (xi - xi_true): " + ", ".join(f"{n} {d:+.4f} -> {100 * v:.2f}"
                                                   for v, n, d in parts))

    print(f"\n== 4. fresh noise draws on the same runs ({args.draws}): mean criterion | "
          "mean noise-free blocks")
    sd = np.std(np.vstack(split.train["x"]) - np.vstack(clean_train["x"]), axis=0)
    found = {label: [] for label in [*LIBRARIES, "stand-in catalog, sparse",
                                     "law's catalog, sparse"]}
    for draw in range(args.draws):
        rng = np.random.default_rng(100 + draw)
        train = dict(clean_train, x=[x + rng.normal(size=x.shape) * sd
                                     for x in clean_train["x"]])
        for label, terms in LIBRARIES.items():
            model = fitted(search, split, train, law_library(terms))
            found[label].append((rms(errors(model, split.blocks)),
                                 rms(errors(model, clean_blocks))))
        for label, parameters in (("stand-in catalog, sparse", STAND_IN),
                                  ("law's catalog, sparse", LAW)):
            model = fitted(search, split, train, parameters=parameters)
            found[label].append((rms(errors(model, split.blocks)),
                                 rms(errors(model, clean_blocks))))
    for label, values in found.items():
        values = np.array(values)
        print(f"{label}: {pct(values[:, 0])} -> mean {100 * values[:, 0].mean():.3f} | "
              f"mean {100 * values[:, 1].mean():.3f}")

    print("\n== 5. other folds (block errors; criterion)")
    for options in ({"cross_validate": True}, {"cross_validate": True, "n_blocks": 8},
                    {"region": "extremes"}, {"region": "both"}):
        other = search_of(KEY, **options)[3]
        for label, parameters in (("stand-in catalog", STAND_IN), ("law's catalog", LAW)):
            step = evaluate_candidate(other, parameters)
            print(f"{options}: {label}: {pct(step['block_errors'])}; "
                  f"{100 * step['criterion']:.3f}")

    print("\n== 6. the search fits on the benchmark's widened box, by |a - b| (force error)")
    system, truth = gs.case_of(KEY, us.systems())[:2]
    box = gs._widened_box(runs, 2)
    apart = np.abs(box["q"][:, 0] - box["q"][:, 1])
    recorded = float(max(np.abs(r["q"][:, 0] - r["q"][:, 1]).max() for r in runs))
    true_forces = truth.forces(box["q"], box["qd"], box["qdd"])
    print(f"recorded |a - b| <= {recorded:.2f} rad; box states beyond it: "
          f"{100 * np.mean(apart > recorded):.0f} %, largest {apart.max():.1f} rad")
    for label in ("stand-in catalog", "law's catalog"):
        forces = models[label].predict_forces(box["q"], box["qd"], box["qdd"])
        parts = [np.linalg.norm(forces[m] - true_forces[m]) / np.linalg.norm(true_forces[m])
                 for m in (apart <= recorded, apart > recorded)]
        print(f"{label}: within {100 * parts[0]:.2f}, beyond {100 * parts[1]:.2f}")


if __name__ == "__main__":
    main()
