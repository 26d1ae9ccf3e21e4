"""Systems whose inertia has an angle's second trigonometric degree: ``sin(b)^2`` in a kinetic
coefficient (the catalog's ``kinetic_trig_degree``; the growth's move of that name).

- ``spherical_pendulum``: a point mass on a rigid massless rod (``m = 1``, ``l = 1``), polar
  angle ``theta`` from the downward vertical and azimuth ``phi``:
  ``L = (theta_dot^2 + sin(theta)^2 phi_dot^2) / 2 + g cos(theta)``, viscous damping on both
  angles; forced by torques on both (``u_phi`` about the vertical axis), unforced from wider
  initial states.

The blind set's ``furuta_pendulum`` (:mod:`blind3_systems`) is the other such system; run it
there. Everything else is ``generic_systems.py``'s and ``unseen_systems.py``'s (the truth, the
data, the scores, the hand-built reference, the grid, the report). Usage::

    PYTHONPATH=$PWD python benchmarks/kinetic_trig_systems.py --seeds 0 1 2 --no-baselines \\
        --out benchmarks/results/kinetic_trig_systems_<commit>.jsonl
"""

from __future__ import annotations

import inspect
import os
import sys

import sympy as sp

sys.path.insert(0, os.path.dirname(__file__))

import generic_systems as gs  # noqa: E402 - the benchmark's machinery
import unseen_systems as us  # noqa: E402

import pysindy_xl as px  # noqa: E402

RESULTS = os.path.join(os.path.dirname(__file__), "results", "kinetic_trig_systems.jsonl")
G = gs.G


def spherical_pendulum_lagrangian(q, v, mass=1.0, length=1.0):
    """Point ``mass`` on a rod of ``length``: polar angle ``theta`` from the downward vertical,
    azimuth ``phi``."""
    theta = q[0]
    return (0.5 * mass * length ** 2 * (v[0] ** 2 + sp.sin(theta) ** 2 * v[1] ** 2)
            + mass * G * length * sp.cos(theta))


def systems():
    """The systems (name -> record of ``generic_systems._system``); the hand-built catalog
    states ``sin(theta)^2`` where the package offers ``kinetic_trig_degree``."""
    offered = "kinetic_trig_degree" in inspect.signature(px.AutomaticCatalog).parameters
    hand = {"kinetic_trig_degree": 2} if offered else {}
    out = [
        gs._system("spherical_pendulum", ["theta", "phi"], ["angle", "angle"],
                   spherical_pendulum_lagrangian, [0.05, 0.02], [2.0, 0.6], (0.1, 1.0),
                   [0.3, 0.5], hand, unforced=True, center=[1.0, 0.0]),
    ]
    return {s["name"]: s for s in out}


if __name__ == "__main__":
    sys.exit(us.main(table=systems, results=RESULTS, script="kinetic_trig_systems.py",
                     title="Systems with sin^2 in a kinetic coefficient"))
