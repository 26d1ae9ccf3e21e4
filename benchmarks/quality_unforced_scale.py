"""The fit-quality R^2 of unforced fits over each equation's kinetic part, against the former
figure over the largest single term, on right and wrong laws of one case.

The case is ``generic_systems.py``'s spring pendulum, unforced, 5 % noise, seed 2 (two 10 s runs
at 1 kHz), where the growth judged over the largest term kept a wrong law with splines. Models:

* ``law (growth)``: :func:`~pysindy_xl.grow_catalog` as it is (the polynomial law);
* ``splines (growth, largest-term criterion)``: the growth with its former held-out criterion
  (each equation over its largest term ``max_j ||Theta_j xi_j||``), which keeps the splines;
* ``hand law`` and ``hand, no spring``: a hand-built catalog of the law (``r_dot^2``,
  ``r^2 theta_dot^2``, ``r cos(theta)``, ``r``, ``r^2``, viscous damping), and the same without
  the spring's ``r`` and ``r^2`` (no restoring force on ``r``);
* ``law, spring zeroed``: the growth's law with its coefficients on the potentials of ``r``
  alone (``L[r]``, ``L[r**2]``) set to zero;
* ``law, kinetic part x 0.5`` and ``x 0.25``: the growth's law with its coefficients on the
  columns that carry inertia scaled (accelerations 2 and 4 times the law's).

For each: R^2 overall and per coordinate, over the kinetic part (:func:`fit_quality`) and over
the largest term (the former figure, computed here), and the truth: the relative error of the
accelerations the model predicts on a fresh run. Usage::

    PYTHONPATH=$PWD python benchmarks/quality_unforced_scale.py [--out results.json]
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import sys
import warnings

import numpy as np
import sympy as sp

sys.path.insert(0, os.path.dirname(__file__))

import generic_systems as gs  # noqa: E402

import pysindy_xl as px  # noqa: E402
from pysindy_xl.catalog import candidates  # noqa: E402
from pysindy_xl.fit.kinetic_scale import inertial_columns  # noqa: E402
from pysindy_xl.fit.wrap import catalog_dynamics  # noqa: E402
from pysindy_xl.quality import fit_quality  # noqa: E402


def largest_term_r2(model, arguments) -> dict:
    """The former unforced figure: ``1 - ||r||^2 / ||Theta_j xi_j||^2``, ``j`` the largest
    single term over all the rows; per coordinate the same column on its block."""
    problem = model.regression(**{key: arguments.get(key) for key in ("x", "t")})
    theta, columns = problem.theta, problem.catalog_map.columns
    coef = model.coef_[columns]
    residual = theta @ coef
    j = int(np.argmax(np.linalg.norm(theta * coef, axis=0)))
    target = theta[:, j] * coef[j]
    n = problem.n_coordinates

    def r2(r, b):
        return float(1 - (r @ r) / (b @ b)) if b @ b > 0 else float("nan")
    return {"r2": r2(residual, target), "term": model.get_feature_names()[columns[j]],
            "per": [r2(r, b) for r, b in zip(residual.reshape(n, -1), target.reshape(n, -1),
                                             strict=True)]}


def _largest_term_error(model, held, forced) -> float:
    """The growth's former held-out criterion (each equation over its largest term)."""
    if forced:
        return _current_error(model, held, forced)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        problem = model.regression(held["x"], held["t"], u=held["u"], formulation="weak",
                                   propagate_noise=False)
        if not len(problem.theta):
            problem = model.regression(held["x"], held["t"], u=held["u"], formulation="strong")
    theta, coef = problem.theta, model.coef_[problem.catalog_map.columns]
    residual = theta @ coef
    errors = []
    for rows in np.array_split(np.arange(len(theta)), problem.n_coordinates):
        norm = float(np.linalg.norm(theta[rows] * coef, axis=0).max(initial=0.0))
        errors.append(np.linalg.norm(residual[rows]) / norm if norm > 0 else np.inf)
    return float(np.sqrt(np.mean(np.square(errors))))


_current_error = candidates.held_out_error


def _hand_catalog(coords, spring=True):
    (r, th), (rd, thd) = coords.q, coords.qd
    terms = [rd**2, r**2 * thd**2, r * sp.cos(th)]
    if spring:
        terms += [r, r**2]
    return px.LagrangeLibrary(coords, terms) + px.ClassicalLibrary(
        coords, [rd, thd], mask=np.eye(2))


def _edited(model, columns, factor):
    """A copy of ``model`` with its coefficients on ``columns`` multiplied by ``factor``."""
    edited = copy.deepcopy(model)
    edited.coef_[columns] *= factor
    edited.dynamics_ = catalog_dynamics(edited.feature_library_, edited.coef_,
                                        np.zeros(edited.n_coordinates_, dtype=bool))
    return edited


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="write the figures as JSON")
    args = parser.parse_args(argv)
    system = gs.systems()["spring_pendulum"]
    truth = gs.Truth(system)
    runs = gs.make_runs(system, truth, 2, False)
    test = gs.make_runs(system, truth, 502, False, n_runs=1)[0]
    xs, ts = gs._noisy(runs, 0.05, 2), [r["t"] for r in runs]
    names, kinds = list(system["coords"].names), system["kinds"]
    arguments = {"x": xs, "t": ts}
    models = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        law = px.grow_catalog(xs, ts, coordinates=names, kinds=kinds, n_jobs=1)
        models["law (growth)"] = (law.model, law.catalog.describe())
        candidates.held_out_error = _largest_term_error
        try:
            old = px.grow_catalog(xs, ts, coordinates=names, kinds=kinds, n_jobs=1)
        finally:
            candidates.held_out_error = _current_error
        models["splines (growth, largest-term criterion)"] = (old.model, old.catalog.describe())
        coords = px.Coordinates(names)
        for label, spring in (("hand law", True), ("hand, no spring", False)):
            models[label] = (px.XLSINDy(_hand_catalog(coords, spring)).fit(xs, ts), "hand")
        feature_names = law.model.get_feature_names()
        spring = [feature_names.index(name) for name in ("L[r]", "L[r**2]")]
        models["law, spring zeroed"] = (_edited(law.model, spring, 0.0), law.catalog.describe())
        problem = law.model.regression(xs, ts, propagate_noise=False)
        kinetic = problem.catalog_map.columns[inertial_columns(law.model, problem)]
        for factor in (0.5, 0.25):
            models[f"law, kinetic part x {factor}"] = (_edited(law.model, kinetic, factor),
                                                       law.catalog.describe())
        rows = []
        for label, (model, catalog) in models.items():
            predicted = model.predict(test["q"], test["qd"])
            error = float(np.linalg.norm(predicted - test["qdd"]) / np.linalg.norm(test["qdd"]))
            new = fit_quality(model, arguments)
            former = largest_term_r2(model, arguments)
            rows.append({"model": label, "catalog": catalog, "accelerations": error,
                         "r2_kinetic": new["r2"],
                         "r2_kinetic_per": list(new["r2_per_coordinate"].values()),
                         "r2_largest": former["r2"], "r2_largest_per": former["per"],
                         "largest_term": former["term"]})
    print("| model | accelerations (fresh run) | R^2 over the largest term (r, theta) | "
          "R^2 over the kinetic part (r, theta) | largest term |")
    print("|---|---|---|---|---|")
    for row in rows:
        print(f"| {row['model']} | {100 * row['accelerations']:.2f} % | {row['r2_largest']:.4f} "
              f"({', '.join(f'{v:.4f}' for v in row['r2_largest_per'])}) | "
              f"{row['r2_kinetic']:.4f} ({', '.join(f'{v:.4f}' for v in row['r2_kinetic_per'])})"
              f" | `{row['largest_term']}` |")
    for row in rows:
        print(f"{row['model']}: {row['catalog']}")
    if args.out:
        with open(args.out, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
