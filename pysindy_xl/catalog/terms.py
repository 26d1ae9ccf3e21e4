"""The candidate terms of an automatic catalog, from its checked options.

Pure functions of the options dictionary that :class:`~.automatic.AutomaticCatalog` checks
(``coords``, ``kinds``, the degrees, the interaction orders, ``differences``, ``kinetic``,
``kinetic_trig_degree``, ``gyroscopic``,
``splines``, ``spline_ends``, ``spline_basis``, ``exponentials``, ``dissipation`` and
``coulomb_scale``): the single-coordinate factors (:mod:`.bases`), their products over a few
coordinates, the kinetic, gyroscopic and potential candidates of the Lagrangian, and the
dissipation terms with the equations each enters.
"""

from __future__ import annotations

import itertools

import numpy as np
import sympy as sp

from .bases import (
    exponential_pair,
    factor_functions,
    natural_splines,
    quadratic_end_splines,
    truncated_power_splines,
)


def products(options, factors, order="interaction") -> list[tuple[sp.Expr, int, bool]]:
    """Products over at most ``options[order]`` coordinates of one factor each, as
    (expression, polynomial degree, whether it is a trigonometric polynomial)."""
    out = []
    n = len(factors)
    for size in range(1, min(options[order], n) + 1):
        for subset in itertools.combinations(range(n), size):
            for choice in itertools.product(*(factors[i] for i in subset)):
                degree = sum(c[1] for c in choice)
                if size > 1 and degree > options["degree"]:
                    continue
                out.append((sp.Mul(*(c[0] for c in choice)), degree,
                            all(c[2] for c in choice)))
    return out


def factors_of(options, degree, trig_degree, angle_degree) -> list:
    """Per coordinate: (function, polynomial degree, trigonometric polynomial) triples."""
    coords, kinds = options["coords"], options["kinds"]
    factors = []
    for q, kind in zip(coords.q, kinds, strict=True):
        own = []
        for f in factor_functions(q, kind, degree, trig_degree, angle_degree):
            trigonometric = f.has(sp.sin(q)) or f.has(sp.cos(q))
            power = 0 if trigonometric else int(sp.degree(f, q))
            own.append((f, power, kind == "linear" or trigonometric))
        factors.append(own)
    return factors


def spline_terms(options) -> list[sp.Expr]:
    """The splines of single coordinates (never multiplied by other functions),
    the last of each coordinate's left out: they sum to 1, and a constant potential has no
    Euler-Lagrange column, so all of them would be an exact dependency (which rounding
    would settle); the others span the same potentials up to a constant."""
    out = []
    for q, spline in zip(options["coords"].q, options["splines"], strict=True):
        if spline is not None:
            (low, high), count = spline
            out += spline_basis(options, q, low, high, count)
    return out


def lagrangian_candidates(options) -> tuple[list[sp.Expr], list[bool]]:
    """The Lagrangian candidates: kinetic ``kappa(q) qd_i qd_j``, gyroscopic
    ``f(q_k) qd_i``, potential ``phi(q)``, then exponentials and splines, each with whether
    it is a trigonometric polynomial (derived on arrays)."""
    coords = options["coords"]
    n = coords.n
    terms, fast = [], []
    # kinetic: kappa(q) qd_i qd_j
    kappas = [(sp.Integer(1), 0, True)]
    if options["kinetic"] == "configuration":
        factors = factors_of(options, min(options["degree"], 2),
                             options["kinetic_trig_degree"], 0)
        kappas += products(options, factors, "kinetic_interaction")
    for kappa, _, trig in kappas:
        for i, j in itertools.combinations_with_replacement(range(n), 2):
            terms.append(kappa * coords.qd[i] * coords.qd[j])
            fast.append(trig)
    # gyroscopic: f(q_k) qd_i, k != i (f(q_i) qd_i is a total time derivative)
    if options["gyroscopic"]:
        firsts = factors_of(options, 1, 1, 0)
        for i in range(n):
            for k in range(n):
                if k != i:
                    for f, _, trig in firsts[k]:
                        terms.append(f * coords.qd[i])
                        fast.append(trig)
    # potential: phi(q)
    factors = factors_of(options, options["degree"], options["trig_degree"],
                            options["angle_degree"])
    # a coordinate's splines take the place of its own powers: their span holds the
    # line, and a higher power would set the law beyond the data
    splined = {q for q, spline in zip(coords.q, options["splines"], strict=True)
               if spline is not None}
    for phi, _, trig in products(options, factors):
        if (phi.is_Symbol or (phi.is_Pow and phi.exp.is_Integer)) \
                and phi.free_symbols <= splined:
            continue
        terms.append(phi)
        fast.append(trig)
    # springs between two coordinates of one kind: powers of their difference, one column each
    for (i, qi), (j, qj) in itertools.combinations(enumerate(coords.q), 2):
        if options["kinds"][i] == options["kinds"][j]:
            for k in range(2, options.get("differences", 0) + 1):
                terms.append((qj - qi) ** k)
                fast.append(False)
    exponentials = [f for q, rate in zip(coords.q, options["exponentials"], strict=True)
                    if rate is not None for f in exponential_pair(q, rate)]
    splines = spline_terms(options)
    anchors = [f for f in options.get("anchors", ()) if f is not None]
    others = exponentials + anchors + splines
    return terms + others, fast + [False] * len(others)


def dissipation_terms(options) -> tuple[list[sp.Expr], np.ndarray]:
    """The dissipation terms and, per term, the equations it enters (a boolean mask of
    shape ``(terms, n)``)."""
    coords = options["coords"]
    terms, rows = [], []
    models = options["dissipation"]
    for model in models:
        if model == "coupled" and "viscous" in models:
            continue  # the viscous terms enter every equation
        for i, qd in enumerate(coords.qd):
            terms.append(sp.tanh(qd / sp.Float(options["coulomb_scale"][i]))
                         if model == "coulomb" else qd)
            own = np.arange(coords.n) == i
            rows.append(own if model == "coulomb" or "coupled" not in models
                        else ~own if model == "coupled" else np.ones(coords.n, dtype=bool))
    return terms, np.array(rows, dtype=bool).reshape(len(terms), coords.n)




def spline_basis(options, q, low, high, count) -> list[sp.Expr]:
    """The spline columns of one coordinate: its basis of ``options["spline_ends"]`` and
    ``options["spline_basis"]`` less the constant (a constant potential has no column; the
    B-splines sum to 1, so the last of them is left out)."""
    if options["spline_basis"] == "truncated":
        return truncated_power_splines(q, low, high, count, options["spline_ends"])[1:]
    basis = natural_splines if options["spline_ends"] == "linear" else quadratic_end_splines
    return basis(q, low, high, count)[:-1]
