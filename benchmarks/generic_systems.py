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

# (the scores, baselines and reports live in their own modules; their names stay importable
# from here, where the other grids and the tests look for them)
from grid_baselines import THRESHOLDS, _derivatives, baseline_scores  # noqa: E402,F401
from grid_report import (  # noqa: E402,F401
    BASELINE_METHODS,
    _finite,
    _pct,
    _rate,
    baselines_section,
    write_report,
)
from grid_scores import (  # noqa: E402,F401
    _relative,
    _widened_box,
    _xlsindy_functions,
    outside_share,
    score,
)
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


def grid_cases(table, systems=None, forcing=("forced", "unforced"), noise=(0.0, 0.01, 0.05),
               seeds=(0, 1, 2)):
    """The grid's cases ``(system, forcing, noise, seed)`` of the systems ``table``: each seed,
    noise level, forcing and system (``systems``; None or empty: all of ``table``), in that
    nesting, unforced only for the systems with free runs (``table[name]["unforced"]``).
    :func:`case_key` makes the key of one."""
    chosen = systems or list(table)
    return [(name, kind, level, seed) for seed in seeds for level in noise for kind in forcing
            for name in chosen if kind == "forced" or table[name]["unforced"]]


def case_key(case) -> str:
    """The key ``"system:forcing:noise:seed"`` of a case of :func:`grid_cases` (:func:`case_of`
    reads it)."""
    return ":".join(map(str, case))


def run_case(system, truth, noise, seed, forced, baselines=True, region="block", extra_moves=(),
             hand=True):
    runs, test, xs, ts, us = case_data(system, truth, noise, seed, forced)
    names = list(system["coords"].names)
    record = {"system": system["name"], "n": truth.n, "noise": noise, "seed": seed,
              "forcing": "forced" if forced else "unforced", "samples": sum(len(t) for t in ts),
              "test_outside": outside_share(test, runs)}
    started, cpu = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            lines = []
            found = px.grow_catalog(xs, ts, us, coordinates=names, kinds=system["kinds"],
                                    region=region, progress=lines.append,
                                    **_moves(extra_moves))
            # what the search's end did besides climbing: settled ends refused for their
            # final fit, a physical alternative answering, judged terms restored
            record["end_notes"] = [line for line in lines
                                   if line.split(" ", 1)[0] in ("refused", "answer", "restored")]
            record["seconds"] = time.perf_counter() - started
            record["cpu_seconds"] = time.process_time() - cpu
            record["catalog"] = found.catalog.describe()
            record["terms"] = found.catalog.n_terms
            record["kept"] = int(np.count_nonzero(found.model.coefficients()))
            record["steps"] = len(found.steps)
            record["work"] = found.work  # (the search's work, grow_catalog's work_budget)
            record["own_runs"] = found.own_runs  # (unforced: where the model leaves its runs)
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
        if hand:  # the correct hand-built catalog, same data (skipped in a rerun of the
            # automatic catalog alone, whose hand-built figures are known)
            try:  # the splines' end knots where grow_catalog puts them
                from pysindy_xl.catalog.growth_data import END_PERCENTILE
                low, high = np.percentile(np.vstack(xs), [END_PERCENTILE, 100 - END_PERCENTILE],
                                          axis=0)
                bounds = [(float(a), float(b)) for a, b in zip(low, high, strict=True)]
                catalog = px.AutomaticCatalog(names, kinds=system["kinds"], bounds=bounds,
                                              **system["hand"])
                fitted = px.XLSINDy(catalog).fit(xs, ts, u=us)
                record["hand"] = score(*_xlsindy_functions(fitted), system, truth, test, runs,
                                       forced)
            except Exception as error:  # noqa: BLE001
                record["hand"] = {"right": False, "held_out": float("inf"),
                                  "error": repr(error)[:300]}
            if "auto" in record and "error" not in record["auto"]:
                # the same catalog fitted with the test functions of the automatic catalog's
                # final fit (grow_catalog's search's): the two fits then differ by their
                # catalogs alone
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
    if "hand" in record:
        record["ratio"] = (record["auto"]["held_out"] / record["hand"]["held_out"]
                           if record["hand"].get("held_out", 0) > 0 else None)
    if "hand_same" in record:
        record["ratio_same"] = (record["auto"]["held_out"] / record["hand_same"]["held_out"]
                                if record["hand_same"].get("held_out", 0) > 0 else None)
    return record


def _moves(extra_moves) -> dict:
    """grow_catalog's ``moves`` with ``extra_moves`` (some of ``MORE_MOVES``) added; empty
    (the default moves) without them."""
    if not extra_moves:
        return {}
    from pysindy_xl.catalog.moves import MOVES
    return {"moves": tuple(MOVES) + tuple(m for m in extra_moves if m not in MOVES)}


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


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--systems", nargs="*", default=None)
    parser.add_argument("--noise", nargs="*", type=float, default=[0.0, 0.01, 0.05])
    parser.add_argument("--seeds", nargs="*", type=int, default=[0, 1, 2])
    parser.add_argument("--forcing", nargs="*", default=["forced", "unforced"])
    parser.add_argument("--out", default=RESULTS)
    parser.add_argument("--no-baselines", action="store_true")
    parser.add_argument("--no-hand", action="store_true",
                        help="skip the hand-built catalog's fits (with --no-baselines: the "
                        "automatic catalog alone, for a rerun whose other figures are known)")
    parser.add_argument("--reuse", default=None, metavar="FILE.jsonl",
                        help="take the catalogs' figures of the cases this file holds; run "
                             "only the baselines on them")
    parser.add_argument("--report", default=None, metavar="FILE.md")
    parser.add_argument("--region", default="block",
                        help="grow_catalog's region (default: block)")
    parser.add_argument("--extra-moves", nargs="*", default=[],
                        help="moves of MORE_MOVES added to grow_catalog's default moves")
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
    cases = grid_cases(table, args.systems, args.forcing, args.noise, args.seeds)
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
                              baselines=not args.no_baselines, region=region,
                              extra_moves=getattr(args, "extra_moves", ()),
                              hand=not getattr(args, "no_hand", False))
            if getattr(args, "extra_moves", ()):
                record["extra_moves"] = list(args.extra_moves)
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
