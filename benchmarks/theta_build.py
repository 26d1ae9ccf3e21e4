"""Time the build of the regression matrix of a ~290-term mixed catalog, strong and weak.

System: double pendulum on a cart, coordinates (x, theta1, theta2). Catalog:

* Lagrange: velocity monomials (degree <= 2) x trigonometric monomials of the angles
  (degree <= 2): 149 terms;
* classical: velocity monomials (degree <= 2) x {1, sin, cos of each angle}, entering every
  equation: 45 terms x 3 equations;
* the force column.

pysindy-xl derives all columns symbolically once, decomposes every non-zero entry into
coefficients times products of atom powers, and evaluates each distinct atom and product once
for the whole catalog, writing entries in place (see ``pysindy_xl/feature_library/_compile.py``).
The naive baseline does what a direct implementation would: one ``sympy.lambdify`` per non-zero
entry, evaluated entry by entry. Both are vectorized over samples; the symbolic derivation is
shared and reported apart.

Then the whole weak fit of that catalog (issue 10's target: under 10 s): ``XLSINDy`` with its
defaults on 100 s of the forced double pendulum on a cart with friction at 1 kHz (ground truth
from ``sympy.physics.mechanics``, scipy DOP853 at 1e-10, ``tests/ground_truth.py``), 1 % noise
on the positions only; and with ``residual_covariance=False``. Each fit's support is checked
against the true law.

Usage: ``python benchmarks/theta_build.py [--samples 100000] [--repeat 3] [--no-fit]``;
writes ``benchmarks/results/theta_build.json``.
"""

import argparse
import json
import pathlib
import platform
import sys
import time

import numpy as np
import sympy as sp

import pysindy_xl as px

HERE = pathlib.Path(__file__).resolve().parent


def mixed_catalog() -> px.CatalogRepartition:
    coords = px.Coordinates(["x", "theta1", "theta2"])
    trig = [f(coords.q[i]) for i in (1, 2) for f in (sp.sin, sp.cos)]
    velocity = px.monomials(coords.qd, 2)
    lagrange_terms = [t for t in px.products([1, *px.monomials(trig, 2)], [1, *velocity])
                      if t.free_symbols]
    classical_terms = px.products([1, *trig], velocity)
    return px.CatalogRepartition([
        px.ExternalForces(coords),
        px.LagrangeLibrary(coords, lagrange_terms),
        px.ClassicalLibrary(coords, classical_terms),
    ])


def naive_build(library: px.CatalogRepartition, z: np.ndarray) -> tuple[np.ndarray, float, float]:
    """Per-entry lambdify, then per-entry evaluation. Returns (theta, compile_s, eval_s)."""
    matrix, variables = library.symbolic_matrix_, library.coords.variables
    n, n_features = matrix.shape
    start = time.perf_counter()
    functions = [(c, j, sp.lambdify(variables, matrix[c, j], modules="numpy"))
                 for c in range(n) for j in range(n_features) if matrix[c, j] != 0]
    compiled = time.perf_counter()
    n_samples = z.shape[0]
    theta = np.zeros((n * n_samples, n_features))
    columns = z.T
    for c, j, f in functions:
        theta[c * n_samples:(c + 1) * n_samples, j] = f(*columns)
    return theta, compiled - start, time.perf_counter() - compiled


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=100_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--no-fit", action="store_true", help="only time the matrix builds")
    args = parser.parse_args()

    rng = np.random.default_rng(0)
    library = mixed_catalog()
    start = time.perf_counter()
    library._fit_symbolic()
    derive = time.perf_counter() - start
    start = time.perf_counter()
    library._compile()
    compile_s = time.perf_counter() - start
    n_entries = len(library._entry_index)
    z = rng.uniform(-2, 2, size=(args.samples, len(library.coords.variables)))

    evaluate = min(_timed(lambda: library.transform(z)) for _ in range(args.repeat))
    theta = library.transform(z)
    naive = [naive_build(library, z) for _ in range(args.repeat)]
    naive_compile = min(r[1] for r in naive)
    naive_eval = min(r[2] for r in naive)
    assert np.allclose(theta, naive[0][0], rtol=1e-10, atol=1e-10), "the two builds disagree"

    # weak matrix of the same catalog and samples (one trajectory at 1 kHz): symbolic split
    # E = d/dt P - Q, compile, evaluate P and Q, contract with the test-function matrices
    t = np.arange(args.samples) * 1e-3
    start = time.perf_counter()
    library.weak_matrices()
    weak_derive = time.perf_counter() - start
    phi, dphi, _ = px.BumpTestFunctions(width=0.5).matrices(t)
    start = time.perf_counter()
    library.weak_transform(z, phi, dphi)  # first call compiles P and Q
    weak_first = time.perf_counter() - start
    weak_eval = min(_timed(lambda: library.weak_transform(z, phi, dphi))
                    for _ in range(args.repeat))
    weak_compile = weak_first - weak_eval
    weak_shape = library.weak_transform(z, phi, dphi).shape

    ours = compile_s + evaluate
    baseline = naive_compile + naive_eval
    print(f"machine: {platform.processor() or platform.machine()}, numpy {np.__version__}, "
          f"sympy {sp.__version__}")
    print(f"catalog: {library.n_output_features_} columns, {n_entries} non-zero symbolic entries;"
          f" {args.samples} samples -> Theta {theta.shape[0]} x {theta.shape[1]}")
    print(f"symbolic derivation (shared by both)  : {derive:8.3f} s")
    print(f"{'':38s}  {'pysindy-xl':>10s}  {'naive':>10s}")
    print(f"{'compile':38s}  {compile_s:9.3f}s  {naive_compile:9.3f}s")
    print(f"{'numeric evaluation':38s}  {evaluate:9.3f}s  {naive_eval:9.3f}s")
    print(f"{'total without derivation':38s}  {ours:9.3f}s  {baseline:9.3f}s"
          f"   speed-up x{baseline / ours:.1f}")
    print(f"{'total with derivation':38s}  {ours + derive:9.3f}s  {baseline + derive:9.3f}s"
          f"   speed-up x{(baseline + derive) / (ours + derive):.1f}")

    print(f"weak form: {phi.shape[0]} test functions (half-width 0.5 s) -> Theta "
          f"{weak_shape[0]} x {weak_shape[1]}")
    print(f"{'':38s}  {'strong':>10s}  {'weak':>10s}")
    print(f"{'symbolic derivation':38s}  {derive:9.3f}s  {weak_derive:9.3f}s   (weak: extra)")
    print(f"{'compile':38s}  {compile_s:9.3f}s  {weak_compile:9.3f}s")
    print(f"{'numeric evaluation':38s}  {evaluate:9.3f}s  {weak_eval:9.3f}s")
    weak_total = derive + weak_derive + weak_compile + weak_eval
    print(f"{'total':38s}  {derive + ours:9.3f}s  {weak_total:9.3f}s"
          f"   weak / strong x{weak_total / (derive + ours):.2f}")
    record = {"machine": platform.processor() or platform.machine(), "samples": args.samples,
              "columns": int(library.n_output_features_), "strong_build_s": derive + ours,
              "weak_build_s": weak_total, "naive_build_s": baseline + derive}
    if not args.no_fit:
        record["fits"] = weak_fits(args.samples)
    path = HERE / "results" / "theta_build.json"
    path.write_text(json.dumps(record, indent=1) + "\n")
    print(f"written: {path}")


def weak_fits(n_samples: int, level: float = 0.01) -> list[dict]:
    """Time ``XLSINDy(mixed_catalog()).fit`` on noisy positions of the double pendulum on a
    cart (1 kHz), defaults and unweighted rows; support checked against the true law."""
    sys.path.insert(0, str(HERE.parent / "tests"))
    from ground_truth import cart_double_pendulum, random_force, random_initial_state
    from support.paper import true_coefficients

    system = cart_double_pendulum()
    t = np.arange(n_samples) * 1e-3
    data = system.simulate(random_initial_state(system, 0), t, random_force(system, 0))
    rng = np.random.default_rng(1)
    noisy = data["q"] + level * data["q"].std(axis=0) * rng.normal(size=data["q"].shape)
    library = mixed_catalog()
    true = true_coefficients(system, library.fit())
    print(f"weak fit: {n_samples} samples ({t[-1]:.0f} s at 1 kHz), {level:.0%} noise on the "
          f"positions, {library.n_output_features_} columns")
    fits = []
    for setting in ("auto", False):
        start = time.perf_counter()
        model = px.XLSINDy(library, residual_covariance=setting).fit(noisy, t, u=data["tau"])
        elapsed = time.perf_counter() - start
        coef, support = model.coefficients(), true != 0
        fits.append({"residual_covariance": setting, "fit_s": elapsed,
                     "exact": bool(np.array_equal(coef != 0, support)),
                     "error": float(np.median(np.abs(coef[support] - true[support])
                                              / np.abs(true[support])))})
        print(f"  residual_covariance={setting!s:5s}: {elapsed:6.2f} s, exact support "
              f"{fits[-1]['exact']}, median coefficient error {fits[-1]['error']:.3%}")
    return fits


def _timed(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


if __name__ == "__main__":
    main()
