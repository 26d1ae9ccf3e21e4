"""Systems whose inertia has an angle's second trigonometric degree: ``sin(b)^2`` in a kinetic
coefficient (the catalog's ``kinetic_trig_degree``; the growth's move of that name).

- ``spherical_pendulum``: a point mass on a rigid massless rod (``m = 1``, ``l = 1``) on a
  two-axis gimbal whose outer axis is horizontal: ``phi`` turns the gimbal about that axis
  (from the downward vertical), ``theta`` is the rod's angle from it (the polar angle about a
  horizontal polar axis):
  ``L = (theta_dot^2 + sin(theta)^2 phi_dot^2) / 2 + g sin(theta) cos(phi)``, viscous damping
  on both angles; forced by torques on both axes, unforced from wider initial states. The
  chart's poles (``sin(theta) = 0``) lie on the horizontal axis, far from the hanging state
  (``theta = pi/2``, ``phi = 0``), so no run passes near them (in the chart about the vertical
  axis every run with little angular momentum about it passes near the pole: the azimuth
  whips round, and its noise, relative to its spread, swamps the data). The law needs
  ``sin(theta)^2`` in a kinetic coefficient and a potential over two angles' functions
  (interaction 2).

The blind set's ``furuta_pendulum`` (:mod:`blind3_systems`) is the other such system; run it
there. Everything else is ``generic_systems.py``'s and ``unseen_systems.py``'s (the truth, the
data, the scores, the hand-built reference, the grid, the report). Usage::

    PYTHONPATH=$PWD python benchmarks/kinetic_trig_systems.py --seeds 0 1 2 --no-baselines \\
        --out benchmarks/results/kinetic_trig_systems_<commit>.jsonl
"""

from __future__ import annotations

import inspect
import math
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
    """Point ``mass`` on a rod of ``length``: polar angle ``theta`` from a horizontal polar
    axis, ``phi`` the turn about that axis from the downward vertical."""
    theta, phi = q
    return (0.5 * mass * length ** 2 * (v[0] ** 2 + sp.sin(theta) ** 2 * v[1] ** 2)
            + mass * G * length * sp.sin(theta) * sp.cos(phi))


def systems():
    """The systems (name -> record of ``generic_systems._system``); the hand-built catalog
    states ``sin(theta)^2`` where the package offers ``kinetic_trig_degree``."""
    offered = "kinetic_trig_degree" in inspect.signature(px.AutomaticCatalog).parameters
    hand = dict({"kinetic_trig_degree": 2} if offered else {}, interaction=2)
    out = [
        gs._system("spherical_pendulum", ["theta", "phi"], ["angle", "angle"],
                   spherical_pendulum_lagrangian, [0.05, 0.05], [1.0, 0.8], (0.1, 1.0),
                   [0.4, 0.5], hand, unforced=True, center=[math.pi / 2, 0.0]),
    ]
    return {s["name"]: s for s in out}


if __name__ == "__main__":
    sys.exit(us.main(table=systems, results=RESULTS, script="kinetic_trig_systems.py",
                     title="Systems with sin^2 in a kinetic coefficient"))
