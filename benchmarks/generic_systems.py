"""Systems nobody described: the automatic catalog (grown on the data) on 13 designed systems.

Each system is a sympy Lagrangian with viscous damping; its equations come from sympy's
Euler-Lagrange derivation, its trajectories from scipy's DOP853 at rtol = atol = 1e-10. Training
data: 2 runs of 10 s at 1 kHz (20,000 samples), positions only, Gaussian noise of 0, 1 or 5 %
of each coordinate's standard deviation; forced by sums of sines (every system) or free from
random initial states (five systems). Per case:

- ``held_out``: relative RMS of the generalized forces the model needs on a fresh forced run,
  with the true velocities and accelerations (unforced: of the accelerations it predicts);
- ``simulation``: a 2 s simulation of the fresh run from its initial state under its forces,
  RMS error over the coordinates' standard deviation;
- ``off_box``: the held-out figure on 2,000 random states (positions, velocities, accelerations)
  in the box of the training data widened by 20 %;
- ``right``: held_out <= 2 %, simulation <= 5 %, off_box <= 5 % (the issue's definition);
- ``hand``: the same figures of a correct hand-built catalog (an AutomaticCatalog with the
  families the system needs) on the same data, fitted with XLSINDy's defaults, and ``ratio``
  = held_out / hand held_out; ``hand_same`` and ``ratio_same``: the same catalog fitted with
  the test functions of the automatic catalog's final fit (the search's), so that the two fits
  differ by their catalogs alone;
- baselines on the same data and scores: PySINDy ``SINDy`` on the first-order state
  ``[q, qd]`` with a polynomial library (degree 3), plus a Fourier library of the angles, with
  the input ``u`` (its accelerations against the truth, and its 2 s simulation), in the strong
  form (smoothed derivatives) and in the weak form (``WeakPDELibrary``: no derivative of the
  smoothed state is estimated), each with the STLSQ threshold of :data:`THRESHOLDS` that
  predicts the training runs' last fifth best when fitted on the first four fifths (its
  off-box figure: the accelerations under no force); and a scikit-learn MLP inverse-dynamics
  regressor ``(q, qd, qdd) -> u`` on smoothed derivatives (no simulation).

Results are appended to a JSONL file (finished cases are skipped when the script is run again);
``--reuse FILE`` takes the catalogs' figures of the cases ``FILE`` holds and runs only the
baselines on them; ``--report`` writes the markdown summary. Usage::

    python benchmarks/generic_systems.py --noise 0.01 0.05 --seeds 0 [--systems duffing ...]
    python benchmarks/generic_systems.py --report benchmarks/results/generic_systems.md
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

import pysindy_xl as px

RESULTS = os.path.join(os.path.dirname(__file__), "results", "generic_systems_grid.jsonl")
G = 9.81


def _system(name, names, kinds, lagrangian, damping, amplitude, frequency, q0, hand,
            unforced=False, center=None):
    coords = px.Coordinates(names)
    return {"name": name, "coords": coords, "kinds": kinds,
            "L": lagrangian(coords.q, coords.qd), "damping": np.asarray(damping, float),
            "amplitude": np.asarray(amplitude, float), "frequency": frequency,
            "q0": np.asarray(q0, float), "hand": hand, "unforced": unforced,
            "center": np.zeros(len(names)) if center is None else np.asarray(center, float)}


def systems():
    """The 13 designed systems (name -> description)."""
    out = [
        _system("spring_line", ["x"], ["linear"],
                lambda q, v: 0.75 * v[0] ** 2 - 2 * q[0] ** 2, [0.2], [3], (0.1, 1.0), [0.5],
                {"kinetic": "constant"}),
        _system("duffing", ["x"], ["linear"],
                lambda q, v: 0.5 * v[0] ** 2 - q[0] ** 2 - 0.375 * q[0] ** 4, [0.1], [3],
                (0.1, 1.0), [0.8], {"degree": 4, "kinetic": "constant"}, unforced=True),
        _system("gravity_torsion", ["theta"], ["angle"],
                lambda q, v: 0.16 * v[0] ** 2 + 3.924 * sp.cos(q[0]) - 1.5 * q[0] ** 2, [0.05],
                [2], (0.1, 1.0), [1.0], {"angle_degree": 2, "kinetic": "constant"},
                unforced=True),
        _system("torsion_quartic", ["phi"], ["angle"],
                lambda q, v: 0.1 * v[0] ** 2 - q[0] ** 2 - 0.5 * q[0] ** 4, [0.05], [1.5],
                (0.1, 1.0), [0.8], {"angle_degree": 4, "trig_degree": 0, "kinetic": "constant"}),
        _system("bead_on_hoop", ["theta"], ["angle"],
                lambda q, v: 0.125 * v[0] ** 2 + 4.5 * sp.sin(q[0]) ** 2 + 4.905 * sp.cos(q[0]),
                [0.02], [1.0], (0.1, 1.0), [1.0], {"trig_degree": 2, "kinetic": "constant"}),
        _system("log_cosh_well", ["x"], ["linear"],
                lambda q, v: 0.5 * v[0] ** 2 - 2 * sp.log(sp.cosh(2 * q[0])), [0.1], [3],
                (0.1, 1.0), [1.0], {"splines": 8, "kinetic": "constant"}),
        _system("spring_pendulum", ["r", "theta"], ["linear", "angle"],
                lambda q, v: 0.5 * (v[0] ** 2 + q[0] ** 2 * v[1] ** 2) + G * q[0] * sp.cos(q[1])
                - 10 * (q[0] - 1) ** 2, [0.1, 0.05], [3, 2], (0.2, 1.5), [0.3, 0.5],
                {"interaction": 2}, unforced=True, center=[1.5, 0.0]),
        _system("coupled_oscillators", ["x1", "x2"], ["linear", "linear"],
                lambda q, v: 0.5 * v[0] ** 2 + 0.75 * v[1] ** 2 - q[0] ** 2 - 1.5 * q[1] ** 2
                - 0.8 * (q[0] - q[1]) ** 2, [0.1, 0.1], [2, 2], (0.1, 1.0), [0.5, 0.5],
                {"interaction": 2, "kinetic": "constant"}, unforced=True),
        _system("rotating_frame", ["x", "y"], ["linear", "linear"],
                lambda q, v: 0.5 * ((v[0] - 1.5 * q[1]) ** 2 + (v[1] + 1.5 * q[0]) ** 2)
                - 2.5 * (q[0] ** 2 + q[1] ** 2), [0.1, 0.1], [2, 2], (0.1, 1.0), [0.3, 0.3],
                {"gyroscopic": True, "kinetic": "constant"}, unforced=True),
        _system("double_pendulum", ["a", "b"], ["angle", "angle"],
                lambda q, v: 0.25 * v[0] ** 2 + 0.125 * v[1] ** 2
                + 0.25 * v[0] * v[1] * sp.cos(q[0] - q[1]) + 2 * G * 0.5 * sp.cos(q[0])
                + G * 0.5 * sp.cos(q[1]), [0.05, 0.05], [2, 1], (0.1, 1.0), [0.6, 0.6],
                {"interaction": 2}),
        _system("cart_spring_pendulum", ["x", "theta"], ["linear", "angle"],
                lambda q, v: 0.75 * v[0] ** 2 + 0.3 * v[0] * v[1] * sp.cos(q[1])
                + 0.09 * v[1] ** 2 - 2.5 * q[0] ** 2 + 0.5 * G * 0.6 * sp.cos(q[1]),
                [0.2, 0.05], [3, 1], (0.1, 1.0), [0.3, 0.5], {"interaction": 2}),
        _system("three_masses", ["x1", "x2", "x3"], ["linear"] * 3,
                lambda q, v: 0.5 * (v[0] ** 2 + v[1] ** 2 + v[2] ** 2) - 1.5 * q[0] ** 2
                - 0.5 * q[0] ** 4 - (q[1] - q[0]) ** 2 - (q[2] - q[1]) ** 2, [0.1] * 3, [2] * 3,
                (0.1, 1.0), [0.3] * 3, {"degree": 4, "interaction": 2, "kinetic": "constant"}),
        _system("four_chain", ["x1", "x2", "x3", "x4"], ["linear"] * 4,
                lambda q, v: 0.5 * sum(vi ** 2 for vi in v) - q[0] ** 2 - q[3] ** 2
                - sum((q[i + 1] - q[i]) ** 2 for i in range(3)), [0.1] * 4, [2] * 4,
                (0.1, 1.0), [0.3] * 4, {"interaction": 2, "kinetic": "constant"}),
    ]
    return {s["name"]: s for s in out}


class Truth:
    """Equations ``M(q) qdd = f(q, qd) + u`` of a system, derived from its Lagrangian."""

    def __init__(self, system):
        coords = system["coords"]
        n = coords.n
        lagrangian = system["L"]
        rows = []
        for i in range(n):
            momentum = sp.diff(lagrangian, coords.qd[i])
            rows.append(sum(sp.diff(momentum, coords.q[k]) * coords.qd[k]
                            + sp.diff(momentum, coords.qd[k]) * coords.qdd[k] for k in range(n))
                        - sp.diff(lagrangian, coords.q[i]) + system["damping"][i] * coords.qd[i])
        mass = sp.Matrix(n, n, lambda i, j: sp.diff(rows[i], coords.qdd[j]))
        rest = sp.Matrix([rows[i].subs({a: 0 for a in coords.qdd}) for i in range(n)])
        args = (*coords.q, *coords.qd)
        self.n = n
        self._mass = [[sp.lambdify(args, mass[i, j]) for j in range(n)] for i in range(n)]
        self._rest = [sp.lambdify(args, rest[i]) for i in range(n)]
        # one call per step for the integrator
        self._mass_matrix = sp.lambdify(args, mass, "numpy")
        self._rest_vector = sp.lambdify(args, list(rest), "numpy")

    def _parts(self, q, qd):
        args = (*np.atleast_2d(q).T, *np.atleast_2d(qd).T)
        k = np.atleast_2d(q).shape[0]
        mass = np.array([[np.broadcast_to(f(*args), (k,)) for f in row] for row in self._mass])
        rest = np.array([np.broadcast_to(f(*args), (k,)) for f in self._rest])
        return np.moveaxis(mass, 2, 0), rest.T

    def forces(self, q, qd, qdd):
        mass, rest = self._parts(q, qd)
        return np.einsum("kij,kj->ki", mass, qdd) + rest

    def accelerations(self, q, qd, u):
        mass, rest = self._parts(q, qd)
        return np.linalg.solve(mass, (u - rest)[..., None])[..., 0]

    def simulate(self, x0, t, force):
        n = self.n

        def rhs(time, y):
            mass = np.asarray(self._mass_matrix(*y), dtype=float)
            rest = np.asarray(self._rest_vector(*y), dtype=float)
            return np.concatenate([y[n:], np.linalg.solve(mass, force(time) - rest)])

        solution = solve_ivp(rhs, (t[0], t[-1]), x0, t_eval=t, method="DOP853", rtol=1e-10,
                             atol=1e-10)
        if not solution.success or solution.y.shape[1] != len(t):
            raise RuntimeError(f"truth integration failed: {solution.message}")
        return solution.y.T


def _forcing(system, rng, forced=True):
    n = system["coords"].n
    low, high = system["frequency"]
    frequencies = rng.uniform(low, high, (5, n))
    phases = rng.uniform(0, 2 * np.pi, (5, n))
    amplitude = system["amplitude"] if forced else np.zeros(n)

    def force(time):
        return amplitude * np.sin(2 * np.pi * frequencies * time + phases).sum(axis=0) / 2.5

    return force


def make_runs(system, truth, seed, forced, n_runs=2, duration=10.0, rate=1000.0):
    """Runs of (t, q, qd, qdd, u) from the truth."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, 1.0 / rate)
    runs = []
    for _ in range(n_runs):
        force = _forcing(system, rng, forced)
        q0 = system["center"] + system["q0"] * rng.uniform(-1, 1, truth.n) * (1 if forced
                                                                                else 1.5)
        qd0 = rng.uniform(-0.5, 0.5, truth.n) * (1 if forced else 2)
        y = truth.simulate(np.r_[q0, qd0], t, force)
        u = np.array([force(time) for time in t])
        q, qd = y[:, :truth.n], y[:, truth.n:]
        runs.append({"t": t, "q": q, "qd": qd, "qdd": truth.accelerations(q, qd, u), "u": u,
                     "force": force})
    return runs


def _relative(a, b):
    norm = np.linalg.norm(b)
    return float(np.linalg.norm(a - b) / norm) if norm > 0 else float("inf")


def _widened_box(runs, n, samples=2000, widen=1.2):
    """States drawn uniformly from the runs' box of (q, qd, qdd), widened by ``widen``."""
    rng = np.random.default_rng(99)
    box = {}
    for key in ("q", "qd", "qdd"):
        values = np.vstack([r[key] for r in runs])
        low, high = values.min(axis=0), values.max(axis=0)
        middle, half = (low + high) / 2, (high - low) / 2 * widen
        box[key] = rng.uniform(middle - half, middle + half, (samples, n))
    return box


def score(predict_forces, predict_accelerations, simulate, system, truth, test, train_runs,
          forced):
    """held_out, simulation, off_box of a model given as functions."""
    out = {}
    try:
        if forced:
            out["held_out"] = _relative(predict_forces(test["q"], test["qd"], test["qdd"]),
                                        test["u"])
        else:
            out["held_out"] = _relative(predict_accelerations(test["q"], test["qd"], test["u"]),
                                        test["qdd"])
    except Exception as error:  # noqa: BLE001 - a failed prediction is a failed case
        out["held_out"], out["error"] = float("inf"), repr(error)[:200]
    try:
        horizon = test["t"] <= 2.0
        y = simulate(np.r_[test["q"][0], test["qd"][0]], test["t"][horizon], test["force"])
        err = np.sqrt(np.mean((y[:, :truth.n] - test["q"][horizon]) ** 2, axis=0))
        out["simulation"] = float(np.max(err / test["q"].std(axis=0)))
    except Exception as error:  # noqa: BLE001
        out["simulation"], out["simulation_error"] = float("inf"), repr(error)[:200]
    box = _widened_box(train_runs, truth.n)
    try:
        if forced:
            out["off_box"] = _relative(predict_forces(box["q"], box["qd"], box["qdd"]),
                                       truth.forces(box["q"], box["qd"], box["qdd"]))
        else:
            zero = np.zeros_like(box["q"])
            out["off_box"] = _relative(predict_accelerations(box["q"], box["qd"], zero),
                                       truth.accelerations(box["q"], box["qd"], zero))
    except Exception as error:  # noqa: BLE001
        out["off_box"], out["off_box_error"] = float("inf"), repr(error)[:200]
    out["right"] = bool(out["held_out"] <= 0.02 and out["simulation"] <= 0.05
                        and out["off_box"] <= 0.05)
    return out


def _xlsindy_functions(model):
    def simulate(x0, t, force):
        return model.simulate(x0, t, u=force)
    return (model.predict_forces, lambda q, qd, u: model.predict(q, qd, u), simulate)


def _noisy(runs, noise, seed):
    rng = np.random.default_rng(seed + 1000)
    return [r["q"] + noise * r["q"].std(axis=0) * rng.normal(size=r["q"].shape) for r in runs]


def case_data(system, truth, noise, seed, forced):
    """One case's data: ``(runs, test, xs, ts, us)``, the training runs, the fresh test run
    (seed + 500), the noisy positions, the times and the forces (None unforced)."""
    runs = make_runs(system, truth, seed, forced)
    test = make_runs(system, truth, seed + 500, forced, n_runs=1)[0]
    return (runs, test, _noisy(runs, noise, seed), [r["t"] for r in runs],
            [r["u"] for r in runs] if forced else None)


def case_of(key, table=None):
    """The case ``"system:forcing:noise:seed"`` of the systems ``table`` (default
    :func:`systems`): ``(system, truth, forced, data)``, ``data`` as :func:`case_data` gives."""
    name, forcing, noise, seed = key.split(":")
    system = (table or systems())[name]
    truth, forced = Truth(system), forcing == "forced"
    return system, truth, forced, case_data(system, truth, float(noise), int(seed), forced)


def run_case(system, truth, noise, seed, forced, baselines=True, region="block"):
    runs, test, xs, ts, us = case_data(system, truth, noise, seed, forced)
    names = list(system["coords"].names)
    record = {"system": system["name"], "n": truth.n, "noise": noise, "seed": seed,
              "forcing": "forced" if forced else "unforced", "samples": sum(len(t) for t in ts)}
    started, cpu = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            found = px.grow_catalog(xs, ts, us, coordinates=names, kinds=system["kinds"],
                                    region=region)
            record["seconds"] = time.perf_counter() - started
            record["cpu_seconds"] = time.process_time() - cpu
            record["catalog"] = found.catalog.describe()
            record["terms"] = found.catalog.n_terms
            record["kept"] = int(np.count_nonzero(found.model.coefficients()))
            record["steps"] = len(found.steps)
            record["criterion"] = found.held_out_error
            # the near ties judged again on every block (move, terms, criterion, that
            # cross-validation, chosen)
            record["ties"] = [[s.move, s.terms, s.criterion, s.tie_error, s.chosen]
                              for s in found.steps if np.isfinite(s.tie_error)]
            if region != "block":  # the path, with the second fold's verdicts
                record["region"] = region
                record["path"] = [[s.move, s.terms, s.criterion, s.second_error, s.chosen]
                                  for s in found.steps]
                record["second_cpu_seconds"] = sum(s.second_cpu_seconds for s in found.steps)
                record["steps_cpu_seconds"] = sum(s.cpu_seconds for s in found.steps)
            record["auto"] = score(*_xlsindy_functions(found.model), system, truth, test, runs,
                                   forced)
            record["lagrangian"] = str(found.model.lagrangian())[:400]
        except Exception as error:  # noqa: BLE001 - recorded as a failed case
            record["seconds"] = time.perf_counter() - started
            record["cpu_seconds"] = time.process_time() - cpu
            record["auto"] = {"right": False, "held_out": float("inf"), "simulation": float("inf"),
                              "off_box": float("inf"), "error": repr(error)[:300]}
        try:  # the correct hand-built catalog, same data
            # the splines' end knots where grow_catalog puts them
            from pysindy_xl.catalog.growth_data import END_PERCENTILE
            low, high = np.percentile(np.vstack(xs), [END_PERCENTILE, 100 - END_PERCENTILE],
                                      axis=0)
            bounds = [(float(a), float(b)) for a, b in zip(low, high, strict=True)]
            catalog = px.AutomaticCatalog(names, kinds=system["kinds"], bounds=bounds,
                                          **system["hand"])
            hand = px.XLSINDy(catalog).fit(xs, ts, u=us)
            record["hand"] = score(*_xlsindy_functions(hand), system, truth, test, runs, forced)
        except Exception as error:  # noqa: BLE001
            record["hand"] = {"right": False, "held_out": float("inf"), "error": repr(error)[:300]}
        if "auto" in record and "error" not in record["auto"]:
            # the same catalog fitted with the test functions of the automatic catalog's final
            # fit (grow_catalog's search's): the two fits then differ by their catalogs alone
            try:
                same = px.XLSINDy(catalog, test_functions=found.model.test_functions).fit(
                    xs, ts, u=us)
                record["hand_same"] = score(*_xlsindy_functions(same), system, truth, test,
                                            runs, forced)
            except Exception as error:  # noqa: BLE001
                record["hand_same"] = {"right": False, "held_out": float("inf"),
                                       "error": repr(error)[:300]}
        if baselines:
            record.update(baseline_scores(system, truth, forced, (runs, test, xs, ts, us)))
    record["ratio"] = (record["auto"]["held_out"] / record["hand"]["held_out"]
                       if record["hand"].get("held_out", 0) > 0 else None)
    if "hand_same" in record:
        record["ratio_same"] = (record["auto"]["held_out"] / record["hand_same"]["held_out"]
                                if record["hand_same"].get("held_out", 0) > 0 else None)
    return record


def baseline_scores(system, truth, forced, data):
    """The baselines' figures on one case's ``data`` (``(runs, test, xs, ts, us)``, as
    :func:`case_data` gives): ``{"sindy": ..., "weak_sindy": ..., "mlp": ...}`` (no ``"mlp"``
    unforced: the inverse-dynamics regressor needs the forces)."""
    runs, test, xs, ts, us = data
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = {"sindy": _sindy_baseline(system, truth, xs, ts, us, test, runs, forced),
               "weak_sindy": _sindy_baseline(system, truth, xs, ts, us, test, runs, forced,
                                             weak=True)}
        if forced:
            out["mlp"] = _mlp_baseline(truth, xs, ts, us, test, runs)
    return out


def _derivatives(xs, ts):
    from pysindy_xl.held_out import scoring_derivatives
    return [scoring_derivatives(t, x) for x, t in zip(xs, ts, strict=True)]


def _bounded_simulation(rhs, x0, t, max_evaluations=20000):
    """RK45 of ``rhs`` over ``t``; stops (RuntimeError) on blow-up or after too many steps."""
    count = [0]
    scale = 1e3 * (1 + np.abs(x0).max())

    def guarded(time, x):
        count[0] += 1
        if count[0] > max_evaluations:
            raise RuntimeError("simulation: too many steps (stiff or diverging)")
        return rhs(time, x)

    def blow_up(time, x):
        return scale - np.abs(x).max()

    blow_up.terminal = True
    solution = solve_ivp(guarded, (t[0], t[-1]), x0, t_eval=t, rtol=1e-6, atol=1e-8,
                         events=blow_up)
    if solution.y.shape[1] != len(t):
        raise RuntimeError("simulation: diverged")
    return solution.y.T


#: STLSQ thresholds tried by the PySINDy baselines (chosen on the training runs' last fifth).
THRESHOLDS = (0.005, 0.02, 0.05, 0.2, 0.5)


def _sindy_library(system):
    import pysindy as ps
    library = ps.PolynomialLibrary(degree=3)
    if "angle" in system["kinds"]:
        library = library + ps.FourierLibrary(n_frequencies=2)
    return library


def _sindy_fit(system, states, derivatives, ts, us, threshold, weak):
    """PySINDy on ``[q, qd]``: the strong form (smoothed derivatives) or the weak form (no
    derivative of the state; the state itself is the smoothed ``[q, qd]``). Returns
    ``accelerations(q, qd, u)`` of the model (strong-form evaluation of its coefficients)."""
    import pysindy as ps
    n = states[0].shape[1] // 2
    library = _sindy_library(system)
    optimizer = ps.STLSQ(threshold=threshold)
    if weak:
        grid = ts[0]
        if any(len(t) != len(grid) or not np.allclose(t, grid) for t in ts):
            raise ValueError("the weak baseline needs runs on one time grid")
        weak_library = ps.WeakPDELibrary(function_library=library, spatiotemporal_grid=grid,
                                         K=WEAK_WINDOWS, H_xt=WEAK_HALF_WIDTH)
        model = ps.SINDy(feature_library=weak_library, optimizer=optimizer)
        model.fit(states, t=ts, u=us)
        coef = model.coefficients()
        strong = _sindy_library(system).fit(np.c_[states[0], us[0]] if us else states[0])

        def rates(x, u):
            return strong.transform(np.c_[x, u] if us else x) @ coef.T
    else:
        model = ps.SINDy(feature_library=library, optimizer=optimizer)
        model.fit(states, t=ts, x_dot=derivatives, u=us)

        def rates(x, u):
            return model.predict(x, u=u if us else None)

    def accelerations(q, qd, u):
        return np.asarray(rates(np.c_[q, qd], u))[:, n:]

    return accelerations, rates


#: Test windows and their half width (s) of the weak-form PySINDy baseline.
WEAK_WINDOWS, WEAK_HALF_WIDTH = 400, 0.1


def _sindy_baseline(system, truth, xs, ts, us, test, runs, forced, weak=False):
    """PySINDy ``SINDy`` on [q, qd] with polynomial (+ Fourier of the angles) library, strong or
    weak form; the STLSQ threshold is the one of :data:`THRESHOLDS` whose model predicts the
    accelerations of the training runs' last fifth best when fitted on the first four fifths."""
    n = truth.n
    smooth = _derivatives(xs, ts)
    states = [np.c_[q, qd] for q, qd, _ in smooth]
    derivatives = [np.c_[qd, qdd] for _, qd, qdd in smooth]
    controls = us if forced else None
    started = time.perf_counter()
    try:
        cut = [int(0.8 * len(t)) for t in ts]
        validation = []
        for threshold in THRESHOLDS:
            try:
                accelerations, _ = _sindy_fit(
                    system, [s[:c] for s, c in zip(states, cut, strict=True)],
                    [d[:c] for d, c in zip(derivatives, cut, strict=True)],
                    [t[:c] for t, c in zip(ts, cut, strict=True)],
                    None if controls is None else [u[:c] for u, c in zip(controls, cut,
                                                                         strict=True)],
                    threshold, weak)
                predicted = np.vstack([accelerations(s[c:, :n], s[c:, n:],
                                                     None if controls is None else u[c:])
                                       for s, c, u in zip(states, cut, controls or states,
                                                          strict=True)])
                target = np.vstack([d[c:, n:] for d, c in zip(derivatives, cut, strict=True)])
                error = _relative(predicted, target)
            except Exception:  # noqa: BLE001 - a threshold that fails loses
                error = float("inf")
            validation.append(error if np.isfinite(error) else float("inf"))
        threshold = THRESHOLDS[int(np.argmin(validation))]
        accelerations, rates = _sindy_fit(system, states, derivatives, ts, controls, threshold,
                                          weak)

        def simulate(x0, t, force):
            return _bounded_simulation(
                lambda time, x: rates(x[None], force(time)[None] if forced else None)[0], x0, t)

        scores = {"threshold": threshold,
                  "held_out_accelerations": _relative(accelerations(test["q"], test["qd"],
                                                                    test["u"]), test["qdd"])}
        full = score(None, accelerations, simulate, system, truth, test, runs, False)
        # off the box: the accelerations under no force (forced runs too; a failed
        # prediction is recorded as None)
        scores.update({"simulation": full["simulation"],
                       "off_box_accelerations": full["off_box"], "off_box_under": "no force"})
    except Exception as error:  # noqa: BLE001
        scores = {"error": repr(error)[:200]}
    scores["seconds"] = time.perf_counter() - started
    return scores


def _mlp_baseline(truth, xs, ts, us, test, runs):
    """scikit-learn MLP inverse dynamics (q, qd, qdd) -> u on smoothed derivatives."""
    from sklearn.neural_network import MLPRegressor
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    smooth = _derivatives(xs, ts)
    features = np.vstack([np.c_[q, qd, qdd] for q, qd, qdd in smooth])[::4]
    targets = np.vstack(us)[::4]
    started = time.perf_counter()
    regressor = MLPRegressor(hidden_layer_sizes=(64, 64), max_iter=300, random_state=0,
                             early_stopping=True)
    model = make_pipeline(StandardScaler(), regressor)
    model.fit(features, targets if targets.shape[1] > 1 else targets[:, 0])

    def forces(q, qd, qdd):
        return model.predict(np.c_[q, qd, qdd]).reshape(len(q), -1)

    held = _relative(forces(test["q"], test["qd"], test["qdd"]), test["u"])
    box = _widened_box(runs, truth.n)
    off = _relative(forces(box["q"], box["qd"], box["qdd"]),
                    truth.forces(box["q"], box["qd"], box["qdd"]))
    return {"held_out": held, "off_box": off, "seconds": time.perf_counter() - started}


def recorded(path, key):
    """``key(record)`` of every record already in the JSONL file ``path`` (the cases a rerun
    skips; empty when the file does not exist)."""
    if not path or not os.path.exists(path):
        return set()
    with open(path, encoding="utf-8") as handle:
        return {key(json.loads(line)) for line in handle if line.strip()}


def _rows(path):
    """The records of the JSONL file ``path`` by case ``(system, forcing, noise, seed)``
    (empty for None)."""
    if not path:
        return {}
    with open(path, encoding="utf-8") as handle:
        records = [json.loads(line) for line in handle if line.strip()]
    return {(r["system"], r["forcing"], r["noise"], r["seed"]): r for r in records}


def _done(path):
    return recorded(path, lambda r: (r["system"], r["forcing"], r["noise"], r["seed"]))


def _finite(value):
    if isinstance(value, float) and not np.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    return value


def _pct(value):
    return "-" if value is None else f"{100 * value:.2f}"


def _rate(records, key="auto"):
    if not records:
        return "-"
    right = sum(bool(r[key].get("right")) for r in records)
    return f"{right}/{len(records)} ({100 * right / len(records):.0f} %)"


def _off_box_unscored(record, key):
    """Whether the baseline ``key`` of ``record`` has no off-box figure by design: SINDy rows
    of forced runs written before the baselines scored off the box under no force (no
    ``"off_box_under"``)."""
    scores = record.get(key, {})
    return (key in ("sindy", "weak_sindy") and record["forcing"] == "forced"
            and "error" not in scores and "off_box_under" not in scores)


def _baseline_right(scores, held_out, simulation, off_box):
    """True/False by the issue's definition of "right" on a baseline's ``scores`` (no
    simulation figure when ``simulation`` is None); a missing figure is a failed prediction."""
    if "error" in scores:
        return False
    keys = (held_out, off_box) if simulation is None else (held_out, simulation, off_box)
    limits = (0.02, 0.05) if simulation is None else (0.02, 0.05, 0.05)
    figures = [scores.get(k) for k in keys]
    return all(f is not None and f <= limit for f, limit in zip(figures, limits, strict=True))


def _baseline_rate(verdicts):
    judged = [v for v in verdicts if v is not None]
    if not judged:
        return "-"
    text = f"{sum(judged)}/{len(judged)} ({100 * sum(judged) / len(judged):.0f} %)"
    missing = len(verdicts) - len(judged)
    return text + (f" ({missing} more without an off-box figure)" if missing else "")


def _median_pct(values):
    """The median of ``values`` in percent, a missing figure (a failed prediction) counted as
    infinite; "-" for none."""
    values = [v if v is not None else float("inf") for v in values]
    return _pct(float(np.median(values))) if values else "-"


#: The methods of the baselines section: label, record key, held-out, simulation, off-box keys.
BASELINE_METHODS = (
    ("XLSINDy, automatic catalog", "auto", "held_out", "simulation", "off_box"),
    ("XLSINDy, hand-built catalog", "hand", "held_out", "simulation", "off_box"),
    ("PySINDy SINDy", "sindy", "held_out_accelerations", "simulation",
     "off_box_accelerations"),
    ("PySINDy weak SINDy", "weak_sindy", "held_out_accelerations", "simulation",
     "off_box_accelerations"),
    ("MLP inverse dynamics (forced)", "mlp", "held_out", None, "off_box"),
)


def baselines_section(records):
    """The markdown lines of the report's section "Baselines on the same data" on the JSONL
    ``records`` that hold baselines (``"sindy"``): the methods' rates of "right" and median
    figures per noise level, side by side with both XLSINDy catalogs on the same cases, then
    every case. Empty when no record holds baselines."""
    records = [r for r in records if "sindy" in r]
    if not records:
        return []
    lines = ["", "## Baselines on the same data", "",
             "PySINDy `SINDy` (polynomial degree 3, + Fourier of the angles, input u; strong "
             "form on smoothed derivatives, and weak form with `WeakPDELibrary`, "
             f"{WEAK_WINDOWS} windows of half width {WEAK_HALF_WIDTH} s; STLSQ threshold "
             f"chosen among {list(THRESHOLDS)} on the training runs' last fifth) predicts "
             "accelerations: its figure is the held-out relative error of the "
             "accelerations (forced runs: under the recorded forces). The MLP predicts forces "
             "from smoothed (q, qd, qdd).", "",
             f"Cases with baselines: {len(records)}. \"right\" as above (held-out <= 2 %, "
             "simulation <= 5 %, off-box <= 5 %); for SINDy the held-out and off-box figures "
             "are acceleration errors (off the box: under no force), for XLSINDy on forced "
             "runs force errors. The MLP, an inverse-dynamics map, has no simulation: its "
             "\"right\" counts held-out and off-box alone. A failed fit or simulation counts "
             "as an infinite error in the medians.", "",
             "| noise | method | right | median held-out % | median sim % | "
             "median off-box % |",
             "| --- | --- | --- | --- | --- | --- |"]
    for level in sorted({r["noise"] for r in records}):
        group = [r for r in records if r["noise"] == level]
        for label, key, held, sim, off in BASELINE_METHODS:
            scored = [r[key] for r in group if key in r]
            if not scored:
                continue
            judged = [r[key] for r in group if key in r and not _off_box_unscored(r, key)]
            verdicts = ([bool(s.get("right")) for s in scored] if key in ("auto", "hand")
                        else [_baseline_right(s, held, sim, off) for s in judged])
            verdicts += [None] * (len(scored) - len(judged))
            lines.append(
                f"| {100 * level:g} % | {label} | {_baseline_rate(verdicts)} | "
                f"{_median_pct([s.get(held) for s in scored])} | "
                f"{'-' if sim is None else _median_pct([s.get(sim) for s in scored])} | "
                f"{_median_pct([s.get(off) for s in judged])} |")
    header = ["| system | forcing | noise | seed | XLSINDy auto held-out % | SINDy acc. % | "
              "SINDy sim % | weak SINDy acc. % | weak SINDy sim % | MLP held-out % | "
              "MLP off-box % |",
              "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    lines += ["", "Medians over the cases (held-out relative error; SINDy: of the accelerations, "
              "XLSINDy unforced: of the accelerations, forced: of the forces):", "",
              "| noise | XLSINDy auto | SINDy | weak SINDy | MLP (forced) |",
              "| --- | --- | --- | --- | --- |"]
    for level in sorted({r["noise"] for r in records}):
        group = [r for r in records if r["noise"] == level]
        lines.append(
            f"| {100 * level:g} % | {_median_pct([r['auto'].get('held_out') for r in group])} | "
            f"{_median_pct([r['sindy'].get('held_out_accelerations') for r in group])} | "
            f"{_median_pct([r.get('weak_sindy', {}).get('held_out_accelerations') for r in group])}"
            f" | {_median_pct([r['mlp'].get('held_out') for r in group if 'mlp' in r])} |")
    lines += ["", "Per case:", "", *header]
    for r in records:
        sindy, weak, mlp = r.get("sindy", {}), r.get("weak_sindy", {}), r.get("mlp", {})
        lines.append(
            f"| {r['system']} | {r['forcing']} | {r['noise']:g} | {r['seed']} | "
            f"{_pct(r['auto'].get('held_out'))} | "
            f"{_pct(sindy.get('held_out_accelerations'))} | {_pct(sindy.get('simulation'))} | "
            f"{_pct(weak.get('held_out_accelerations'))} | {_pct(weak.get('simulation'))} | "
            f"{_pct(mlp.get('held_out'))} | {_pct(mlp.get('off_box'))} |")
    return lines


def write_report(path, out):
    """The markdown summary of the JSONL results ``path``, written to ``out``."""
    with open(path, encoding="utf-8") as handle:
        records = [json.loads(line) for line in handle if line.strip()]
    low = [r for r in records if r["noise"] <= 0.01]
    high = [r for r in records if r["noise"] > 0.01]
    ratios = [r["ratio"] for r in records if r.get("ratio") is not None]
    lines = ["# Systems nobody described: the automatic catalog", "",
             "`python benchmarks/generic_systems.py` (see its docstring for the systems, data and "
             "scores; `--report` writes this file). \"right\" = held-out error <= 2 %, 2 s "
             "simulation within 5 %, error off the training box (widened 20 %) <= 5 %.", "",
             f"Cases run: {len(records)} ({', '.join(sorted({str(r['noise']) for r in records}))} "
             f"noise; seeds {sorted({r['seed'] for r in records})}; "
             f"{sum(r['forcing'] == 'forced' for r in records)} forced, "
             f"{sum(r['forcing'] == 'unforced' for r in records)} unforced).", "",
             "| target | automatic catalog | hand-built catalog | issue target |",
             "| --- | --- | --- | --- |",
             f"| right at 0-1 % noise | {_rate(low)} | {_rate(low, 'hand')} | >= 95 % |",
             f"| right at 5 % noise | {_rate(high)} | {_rate(high, 'hand')} | >= 85 % |"]
    for level in sorted({r["noise"] for r in records}):
        group = [r for r in records if r["noise"] == level]
        lines.append(f"| (right at {100 * level:g} % noise) | {_rate(group)} | "
                     f"{_rate(group, 'hand')} | |")
    if ratios:
        within = sum(ratio <= 1.5 for ratio in ratios)
        lines.append(f"| held-out error / hand-built's (median, max; cases <= 1.5) | "
                     f"{np.median(ratios):.2f}, {np.max(ratios):.2f}; {within}/{len(ratios)} "
                     f"({100 * within / len(ratios):.0f} %) | 1 | <= 1.5 |")
    same = [r["ratio_same"] for r in records if r.get("ratio_same") is not None]
    if same:
        within = sum(ratio <= 1.5 for ratio in same)
        lines.append(f"| (the same, the hand-built catalog fitted with the final fit's test "
                     f"functions) | {np.median(same):.2f}, {np.max(same):.2f}; "
                     f"{within}/{len(same)} ({100 * within / len(same):.0f} %) | 1 | |")
    for n in sorted({r["n"] for r in records}):
        group = [r for r in records if r["n"] == n]
        lines.append(f"| catalog + fit, {n} coordinate(s), 20,000 samples: wall s (CPU s), "
                     f"median | {np.median([r['seconds'] for r in group]):.1f} "
                     f"({np.median([r['cpu_seconds'] for r in group]):.1f}) | - | <= 10 s |")
    lines += ["", "Wall times are on a shared 2-core machine with other jobs running (CPU "
              "seconds are this process's own).", "",
              "## Every case", "",
              "| system | n | forcing | noise | seed | right | held-out % | sim % | off-box % | "
              "hand held-out % | ratio | ratio, same fit | wall s | CPU s | kept / terms | "
              "catalog |",
              "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | "
              "--- | --- | --- |"]
    for r in records:
        a, h = r["auto"], r["hand"]
        mark = " (*)" if r.get("early") else ""
        lines.append(
            f"| {r['system']}{mark} | {r['n']} | {r['forcing']} | {r['noise']:g} | {r['seed']} | "
            f"{'yes' if a.get('right') else 'no'} | {_pct(a.get('held_out'))} | "
            f"{_pct(a.get('simulation'))} | {_pct(a.get('off_box'))} | {_pct(h.get('held_out'))} | "
            f"{'-' if r.get('ratio') is None else format(r['ratio'], '.2f')} | "
            f"{'-' if r.get('ratio_same') is None else format(r['ratio_same'], '.2f')} | "
            f"{r['seconds']:.1f} | {r['cpu_seconds']:.1f} | {r.get('kept', '-')} / "
            f"{r.get('terms', '-')} | {r.get('catalog', a.get('error', ''))} |")
    lines += baselines_section(records)
    with open(out, "w", encoding="utf-8") as handle:
        handle.write("\n".join(lines) + "\n")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--systems", nargs="*", default=None)
    parser.add_argument("--noise", nargs="*", type=float, default=[0.0, 0.01, 0.05])
    parser.add_argument("--seeds", nargs="*", type=int, default=[0, 1, 2])
    parser.add_argument("--forcing", nargs="*", default=["forced", "unforced"])
    parser.add_argument("--out", default=RESULTS)
    parser.add_argument("--no-baselines", action="store_true")
    parser.add_argument("--reuse", default=None, metavar="FILE.jsonl",
                        help="take the catalogs' figures of the cases this file holds; run "
                             "only the baselines on them")
    parser.add_argument("--report", default=None, metavar="FILE.md")
    parser.add_argument("--region", default="block",
                        help="grow_catalog's region (default: block)")
    args = parser.parse_args(argv)
    if args.report:
        write_report(args.out, args.report)
        return 0
    return run_grid(systems(), args, region=args.region)


def run_grid(table, args, region="block") -> int:
    """Run the cases of ``args`` (``systems``, ``noise``, ``seeds``, ``forcing``) of the systems
    ``table`` that ``args.out`` does not hold yet, each appended to it as one JSON line (a run
    killed and restarted resumes), with a progress line per case; returns 0. A case of the JSONL
    file ``args.reuse`` (optional) keeps that file's catalog figures and runs the baselines
    alone (its record then names the file in ``reused_from``)."""
    chosen = args.systems or list(table)
    cases = [(name, forcing, noise, seed) for seed in args.seeds for noise in args.noise
             for forcing in args.forcing for name in chosen
             if forcing == "forced" or table[name]["unforced"]]
    done = _done(args.out)
    todo = [c for c in cases if c not in done]
    print(f"{len(cases)} cases, {len(cases) - len(todo)} already in {args.out}", flush=True)
    reuse = _rows(getattr(args, "reuse", None))
    if reuse and args.no_baselines:
        raise ValueError("reuse: the baselines are what a reused row is run for; "
                         "drop --no-baselines")
    truths = {}
    for k, (name, forcing, noise, seed) in enumerate(todo):
        system = table[name]
        truth = truths.setdefault(name, Truth(system))
        started = time.perf_counter()
        if (name, forcing, noise, seed) in reuse:
            # the catalogs' figures of an earlier run of the same case (same data: the case's
            # seeds fix it), the baselines run here on that data
            record = dict(reuse[name, forcing, noise, seed])
            record["reused_from"] = os.path.basename(args.reuse)
            record.update(baseline_scores(system, truth, forcing == "forced",
                                          case_data(system, truth, noise, seed,
                                                    forcing == "forced")))
        else:
            record = run_case(system, truth, noise, seed, forcing == "forced",
                              baselines=not args.no_baselines, region=region)
        with open(args.out, "a", encoding="utf-8") as handle:
            handle.write(json.dumps(_finite(record)) + "\n")
        auto = record["auto"]
        print(f"[{k + 1}/{len(todo)}] {name} {forcing} noise {noise:g} seed {seed}: right "
              f"{auto['right']}, held-out {auto.get('held_out')}, sim {auto.get('simulation')}, "
              f"off-box {auto.get('off_box')}, cpu {record['cpu_seconds']:.1f} s "
              f"({time.perf_counter() - started:.0f} s in all)", flush=True)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(__file__))
    sys.exit(main())
