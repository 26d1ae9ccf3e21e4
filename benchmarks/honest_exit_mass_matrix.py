"""The honest exit of ``pysindy-xl identify`` and the fit's mass-matrix check, case by case.

Each case goes through the command line (``pysindy_xl.cli.main``) on a CSV of positions (and
forces where forced), as a user would run it; the script records the exit status, the fit
quality R^2 and the model's ``mass_matrix_check_`` (fraction of the checked training states
where the identified mass matrix is positive definite).

* ``generic``: ``generic_systems.py``'s systems (sympy Lagrangians integrated by scipy),
  ``NAME:forced|unforced:NOISE:SEED``, with the automatic catalog (the default);
* ``paper``: the paper's MuJoCo systems, ``paper:NAME:CATALOG``: ``pysindy-xl generate NAME``
  (2 runs of 5 s, 1 % position noise, seed 1), then ``identify`` with the kinematic or the
  paper's (mixed) catalog;
* ``vanishing inertia``: the hanging spring ``m xdd = m g - k x - c xd`` (scipy, 1e-10, two
  free 10 s runs at 200 Hz) fitted with a catalog whose kinetic coefficient may change sign
  (``x_dot^2``, ``x x_dot^2``, ``x``, viscous), strong form on exact derivatives and weak form on
  positions; and the same with the spring ``x^2`` (the law). The CLI's catalogs cannot state
  these, so the reference catalog is replaced by them; the fit path is the CLI's.

Usage::

    PYTHONPATH=$PWD python benchmarks/honest_exit_mass_matrix.py [CASE ...] [--out FILE.jsonl]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import sys
import tempfile
import time
import warnings

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, os.path.dirname(__file__))

import generic_systems as gs  # noqa: E402

import pysindy_xl as px  # noqa: E402
import pysindy_xl.cli.commands as commands  # noqa: E402
import pysindy_xl.mujoco.catalogs.reference as reference  # noqa: E402
from pysindy_xl.cli import main as cli  # noqa: E402

DEFAULT = ["spring_pendulum:forced:0.01:0", "spring_pendulum:unforced:0.01:0",
           "spring_pendulum:forced:0.05:0", "spring_pendulum:unforced:0.05:2",
           "spring_line:forced:0.05:0", "duffing:unforced:0.05:1",
           "gravity_torsion:unforced:0.05:0", "bead_on_hoop:forced:0.05:0",
           "log_cosh_well:forced:0.01:0", "double_pendulum:forced:0.05:0",
           "cart_spring_pendulum:forced:0.05:1", "coupled_oscillators:unforced:0.05:0",
           "rotating_frame:unforced:0.01:0", "three_masses:forced:0.01:0",
           "paper:cart-pole:kinematic", "paper:cart-pole:mixed",
           "paper:double-pendulum:kinematic", "paper:double-pendulum:mixed",
           "paper:cart-double-pendulum:kinematic", "paper:cart-double-pendulum:mixed"]


def _run(argv):
    """Exit status, R^2 and mass-matrix check of ``pysindy-xl identify argv``."""
    seen = {}
    original = commands.fit_quality

    def recording(model, arguments):
        quality = original(model, arguments)
        seen.update(check=model.mass_matrix_check_, r2=quality["r2"])
        return quality

    commands.fit_quality = recording
    err = io.StringIO()
    try:
        with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()), \
                contextlib.redirect_stderr(err):
            warnings.simplefilter("ignore")
            status = cli(argv)
    finally:
        commands.fit_quality = original
    message = [line for line in err.getvalue().splitlines() if "error:" in line]
    return {"status": status, "r2": seen.get("r2"),
            "definite": (seen.get("check") or {}).get("positive_definite_fraction"),
            "message": message[0][:160] if message else ""}


def generic_case(spec, folder):
    name, forcing, noise, seed = spec.split(":")
    forced, noise, seed = forcing == "forced", float(noise), int(seed)
    system = gs.systems()[name]
    truth = gs.Truth(system)
    runs = gs.make_runs(system, truth, seed, forced)
    positions = gs._noisy(runs, noise, seed)
    names = list(system["coords"].names)
    header = ["t", *names, *([f"tau_{n}" for n in names] if forced else []), "trajectory"]
    rows = [np.column_stack([r["t"], q, *([r["u"]] if forced else []), np.full(len(q), k)])
            for k, (r, q) in enumerate(zip(runs, positions, strict=True))]
    path = os.path.join(folder, f"{name}.csv")
    np.savetxt(path, np.vstack(rows), delimiter=",", header=",".join(header), comments="")
    angles = [n for n, kind in zip(names, system["kinds"], strict=True) if kind == "angle"]
    argv = ["identify", path, "--coordinates", ",".join(names), "--quiet"]
    return _run(argv + (["--angles", ",".join(angles)] if angles else []))


def paper_case(spec, folder):
    _, name, catalog = spec.split(":")
    path = os.path.join(folder, f"{name}.npz")
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        cli(["generate", name, path, "--duration", "5", "--trajectories", "2", "--noise",
             "0.01", "--seed", "1"])
    return _run(["identify", path, "--catalog", catalog, "--quiet"])


def _hanging_spring_csv(folder, derivatives):
    g, k, c = 9.81, 4.0, 0.1
    t = np.arange(0.0, 10.0, 0.005)
    columns = []
    for run, y0 in enumerate(([2.0, 0.3], [2.9, -0.4])):
        y = solve_ivp(lambda _, s: [s[1], g - k * s[0] - c * s[1]], (0, t[-1]), y0, t_eval=t,
                      method="DOP853", rtol=1e-10, atol=1e-10).y
        columns.append(np.column_stack([t, y[0], *([y[1], g - k * y[0] - c * y[1]]
                                                   if derivatives else []),
                                        np.full(len(t), run)]))
    header = ["t", "x", *(["x_dot", "x_ddot"] if derivatives else []), "trajectory"]
    path = os.path.join(folder, f"hanging_{derivatives}.csv")
    np.savetxt(path, np.vstack(columns), delimiter=",", header=",".join(header), comments="")
    return path


def hanging_spring_case(spring, derivatives, folder):
    coords = px.Coordinates(["x"])
    (x,), (xd,) = coords.q, coords.qd
    terms = [xd**2, x, x**2] if spring else [xd**2, x * xd**2, x]
    catalog = px.LagrangeLibrary(coords, terms) + px.ClassicalLibrary(coords, [xd])
    original = reference.reference_catalog
    reference.reference_catalog = lambda *a, **k: catalog
    try:
        return _run(["identify", _hanging_spring_csv(folder, derivatives), "--coordinates", "x",
                     "--catalog", "lagrange", "--quiet"])
    finally:
        reference.reference_catalog = original


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="*", default=DEFAULT)
    parser.add_argument("--out", default=None)
    args = parser.parse_args(argv)
    records = []
    with tempfile.TemporaryDirectory() as folder:
        jobs = [(f"hanging spring, {'law' if spring else 'kinetic a + b x, no spring'}, "
                 f"{'strong' if derivatives else 'weak'}",
                 lambda s=spring, d=derivatives: hanging_spring_case(s, d, folder))
                for spring in (False, True) for derivatives in (True, False)]
        jobs += [(spec, lambda s=spec: (paper_case if s.startswith("paper:") else
                                        generic_case)(s, folder)) for spec in args.cases]
        print("| case | exit | R^2 | M positive definite on | message |")
        print("|---|---|---|---|---|")
        for label, job in jobs:
            started = time.perf_counter()
            record = {"case": label, **job(), "seconds": time.perf_counter() - started}
            records.append(record)
            definite = record["definite"]
            print(f"| {label} | {record['status']} | {record['r2']:.4f} | "
                  f"{'-' if definite is None else f'{100 * definite:.2f} %'} | "
                  f"{record['message']} |", flush=True)
    if args.out:
        with open(args.out, "w", encoding="utf-8") as handle:
            handle.writelines(json.dumps(record) + "\n" for record in records)


if __name__ == "__main__":
    main()
