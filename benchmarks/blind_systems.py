"""Systems the automatic catalog was never run on before its rates were recorded: a blind set.

``generic_systems.py`` is the development set of :func:`pysindy_xl.grow_catalog`, and
``unseen_systems.py`` became partly seen once fixes were made after reading its failures. The
systems below were written afterwards, each different from the 21 systems of those two sets,
and their grid was run once, with no change to the method: their right rate is a blind
estimate. One and two linear or angular coordinates, and one system of three:

- ``helmholtz_oscillator``: a mass on a spring with a softening quadratic force (potential
  ``x^2 - 0.15 x^3``, asymmetric; the amplitudes stay well inside the well);
- ``oblique_spring_slider``: a slider on a rod, held by a spring anchored at distance ``a``
  from the rod, potential ``k/2 (sqrt(a^2 + x^2) - l0)^2``: a ``sqrt`` that no polynomial states
  (the splines' case);
- ``vertical_pivot_pendulum``: a pendulum whose pivot slides on a vertical spring-loaded rail
  (inertia coupling ``y_dot theta_dot sin(theta)``, gravity on ``y`` and ``theta``);
- ``two_link_arm``: a planar two-link arm in a horizontal plane, relative joint angles, a
  torsion spring at each joint (inertia ``cos(b)``, potential ``a^2``, ``b^2``);
- ``quartic_coupled_well``: a particle in a 2-D well with a quartic coupling ``x^2 y^2``;
- ``cart_torsion_pendulum_cart``: a sprung cart carrying a pendulum with a torsion spring at
  its pivot, coupled to a second cart by a spring (two linear coordinates and an angle).

Everything else is ``generic_systems.py``'s and ``unseen_systems.py``'s, imported: the truth,
the data, the scores, the hand-built reference, the grid, the report and ``--explain``.
Usage::

    PYTHONPATH=$PWD python benchmarks/blind_systems.py --seeds 0 1 --no-baselines
    python benchmarks/blind_systems.py --report benchmarks/results/blind_systems.md
    PYTHONPATH=$PWD python benchmarks/blind_systems.py --explain two_link_arm:forced:0.05:0
"""

from __future__ import annotations

import os
import sys

import sympy as sp

sys.path.insert(0, os.path.dirname(__file__))

import generic_systems as gs  # noqa: E402 - the benchmark's machinery
import unseen_systems as us  # noqa: E402

RESULTS = os.path.join(os.path.dirname(__file__), "results", "blind_systems.jsonl")
G = gs.G


def systems():
    """The blind systems (name -> record of ``generic_systems._system``)."""
    system = gs._system
    out = [
        # softening quadratic spring force: V = x^2 - 0.15 x^3 (the well's rim is at x = 4.4)
        system("helmholtz_oscillator", ["x"], ["linear"],
               lambda q, v: 0.5 * v[0] ** 2 - q[0] ** 2 + 0.15 * q[0] ** 3, [0.1], [0.6],
               (0.1, 1.0), [0.5], {"degree": 3, "kinetic": "constant"}, unforced=True),
        # slider on a rod, spring (k = 4, rest length 0.5) anchored 1 from the rod
        system("oblique_spring_slider", ["x"], ["linear"],
               lambda q, v: 0.5 * v[0] ** 2 - 2.0 * (sp.sqrt(1 + q[0] ** 2) - 0.5) ** 2, [0.1],
               [2.0], (0.1, 1.0), [0.8],
               {"splines": 8, "spline_ends": "quadratic", "kinetic": "constant"}),
        # pivot (mass 1) on a vertical rail with a spring (k = 20), bob 0.3 at length 0.5
        system("vertical_pivot_pendulum", ["y", "theta"], ["linear", "angle"],
               lambda q, v: 0.5 * 1.3 * v[0] ** 2 + 0.3 * 0.5 * v[0] * v[1] * sp.sin(q[1])
               + 0.5 * 0.3 * 0.25 * v[1] ** 2 - 1.3 * G * q[0] + 0.3 * G * 0.5 * sp.cos(q[1])
               - 10.0 * q[0] ** 2, [0.2, 0.02], [3.0, 0.25], (0.1, 1.0), [0.1, 0.5], {},
               unforced=True, center=[-1.3 * G / 20.0, 0.0]),
        # horizontal two-link arm, relative joint angles, joint torsion springs 2 and 1
        system("two_link_arm", ["a", "b"], ["angle", "angle"],
               lambda q, v: 0.5 * (0.23 + 0.08 * sp.cos(q[1])) * v[0] ** 2
               + (0.05 + 0.04 * sp.cos(q[1])) * v[0] * v[1] + 0.5 * 0.05 * v[1] ** 2
               - 1.0 * q[0] ** 2 - 0.5 * q[1] ** 2, [0.05, 0.03], [1.2, 0.6], (0.1, 1.0),
               [0.5, 0.5], {"angle_degree": 2}),
        # particle in a 2-D well with a quartic coupling x^2 y^2
        system("quartic_coupled_well", ["x", "y"], ["linear", "linear"],
               lambda q, v: 0.5 * v[0] ** 2 + 0.5 * v[1] ** 2 - q[0] ** 2 - 1.5 * q[1] ** 2
               - 0.5 * q[0] ** 2 * q[1] ** 2, [0.1, 0.1], [2.5, 2.5], (0.1, 1.0), [0.6, 0.6],
               {"degree": 4, "interaction": 2, "kinetic": "constant"}),
        # sprung cart (1) with a pendulum (0.3 at 0.5) and a torsion spring at its pivot,
        # coupled by a spring to a second cart (0.8)
        system("cart_torsion_pendulum_cart", ["x1", "x2", "theta"],
               ["linear", "linear", "angle"],
               lambda q, v: 0.5 * 1.3 * v[0] ** 2 + 0.3 * 0.5 * v[0] * v[2] * sp.cos(q[2])
               + 0.5 * 0.3 * 0.25 * v[2] ** 2 + 0.3 * G * 0.5 * sp.cos(q[2])
               - 0.5 * q[2] ** 2 + 0.5 * 0.8 * v[1] ** 2 - 1.5 * q[0] ** 2
               - 1.0 * (q[1] - q[0]) ** 2, [0.2, 0.1, 0.03], [2.0, 1.5, 0.3], (0.1, 1.0),
               [0.3, 0.3, 0.4], {"interaction": 2, "angle_degree": 2}),
    ]
    return {s["name"]: s for s in out}


if __name__ == "__main__":
    sys.exit(us.main(table=systems, results=RESULTS, script="blind_systems.py",
                     title="Systems the automatic catalog was run on blind"))
