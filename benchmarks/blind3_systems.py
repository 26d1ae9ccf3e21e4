"""A third blind set: six more systems the automatic catalog was never run on.

Written after the development set (``generic_systems.py``), the validation set
(``unseen_systems.py``) and the first two blind sets (``blind_systems.py``,
``blind2_systems.py``), each different from their 33 systems (and from the cart double
pendulum of the control benchmarks), and run once with no change to the method: their right
rate is a blind estimate. The systems are the kind a robotics or mechanics researcher brings
with a CSV:

- ``magnetic_spring``: a magnet sliding between two fixed magnets that repel it (a magnetic
  spring); the repulsion's potential ``c / (d - x) + c / (d + x) = 2 c d / (d^2 - x^2)``
  is rational, outside the power, trigonometric and exponential families (its series in
  ``(x / d)^2`` converges at the swings here, ``|x| / d <= 0.4``: the hand-built reference is
  the polynomial of degree 6, the splines' being wrong where the test run leaves the training
  range);
- ``rocking_half_disk``: a solid half-disk rocking without slipping on a flat floor; its
  inertia about the contact point is ``m (3 r^2 / 2 - 2 r a cos(theta))`` (``a`` the centre
  of mass's distance from the centre of the rim), its potential ``-m g a cos(theta)``;
- ``furuta_pendulum``: a rotary (Furuta) pendulum: an arm turning in the horizontal plane
  (held by a return spring) carrying a rod swinging in the plane normal to the arm; the arm's
  inertia has ``sin(b)^2`` (the rod's distance from the axis), the coupling ``cos(b) a_dot
  b_dot``; the catalog's kinetic coefficients have sines and cosines of degree 1 only, so no
  catalog states ``sin(b)^2 a_dot^2``: the hand-built reference (``cos(b)`` in its place) is
  the nearest catalog, not the law;
- ``flexible_joint_arm``: a motor driving a link under gravity through an elastic joint (the
  textbook series-elastic / flexible-joint robot): motor and link angles, joint spring
  ``k (l - m)^2 / 2``;
- ``ball_on_beam``: a ball rolling on a beam pivoted at its centre, the beam held by a torsion
  spring (a soft servo), the ball by a centring spring: inertia ``m r^2 b_dot^2``, gravity
  ``m g (r sin(b) + rho cos(b))``, a constant coupling ``r_dot b_dot`` from the ball's rolling;
- ``elastic_crane``: an overhead crane: a trolley on a track (held by a soft position servo,
  a spring) with a payload hung on a coil spring: trolley position, hanger length and swing
  angle
  (kinetic terms ``r cos(theta) x_dot theta_dot``, ``sin(theta) x_dot r_dot``,
  ``r^2 theta_dot^2``; potential ``-m g r cos(theta)`` and the cable's spring).

Everything else is ``generic_systems.py``'s and ``unseen_systems.py``'s, imported: the truth
(sympy Euler-Lagrange, scipy DOP853 at rtol = atol = 1e-10), the data (2 runs of 10 s at 1 kHz,
positions with 0, 1 or 5 % noise, seeded by the case), the scores, the hand-built reference
(``hand``: AutomaticCatalog parameters that contain the law, but for the two systems above),
the grid, the report and ``--explain``. Usage::

    PYTHONPATH=$PWD python benchmarks/blind3_systems.py --seeds 0 1 2 --no-baselines \\
        --out benchmarks/results/blind3_systems_<commit>.jsonl
    python benchmarks/blind3_systems.py --out benchmarks/results/blind3_systems_<commit>.jsonl \\
        --report benchmarks/results/blind3_systems.md
    PYTHONPATH=$PWD python benchmarks/blind3_systems.py --explain elastic_crane:forced:0.05:0
"""

from __future__ import annotations

import math
import os
import sys

import sympy as sp

sys.path.insert(0, os.path.dirname(__file__))

import generic_systems as gs  # noqa: E402 - the benchmark's machinery
import unseen_systems as us  # noqa: E402

RESULTS = os.path.join(os.path.dirname(__file__), "results", "blind3_systems.jsonl")
G = gs.G


def magnetic_spring_lagrangian(q, v, mass=0.5, strength=3.5, gap=2.0):
    """Magnet of ``mass`` between two fixed magnets at ``+-gap`` repelling it with the force
    ``strength / distance^2`` each."""
    x = q[0]
    return 0.5 * mass * v[0] ** 2 - strength * (1 / (gap - x) + 1 / (gap + x))


def rocking_half_disk_lagrangian(q, v, mass=1.0, radius=0.3):
    """Solid half-disk of ``mass`` and ``radius`` rocking without slipping on a floor
    (``theta``: its tilt; the centre of mass ``4 r / (3 pi)`` below the rim's centre)."""
    offset = 4 * radius / (3 * math.pi)
    inertia = mass * (1.5 * radius ** 2 - 2 * radius * offset * sp.cos(q[0]))
    return 0.5 * inertia * v[0] ** 2 + mass * G * offset * sp.cos(q[0])


def furuta_pendulum_lagrangian(q, v, arm_inertia=0.1, arm=0.2, mass=1.0, rod=0.3, spring=1.0):
    """Rotary pendulum: arm (inertia ``arm_inertia`` about the vertical axis, length ``arm``,
    return ``spring``) at angle ``a``; uniform rod of ``mass`` and length ``rod`` at its tip,
    angle ``b`` from the downward vertical in the plane normal to the arm."""
    a_dot, b_dot, b = v[0], v[1], q[1]
    half = rod / 2
    rod_inertia = mass * half ** 2 + mass * rod ** 2 / 12  # about the rod's pivot
    return (0.5 * (arm_inertia + mass * arm ** 2 + rod_inertia * sp.sin(b) ** 2) * a_dot ** 2
            + mass * arm * half * sp.cos(b) * a_dot * b_dot + 0.5 * rod_inertia * b_dot ** 2
            + mass * G * half * sp.cos(b) - 0.5 * spring * q[0] ** 2)


def flexible_joint_arm_lagrangian(q, v, motor=0.05, link=0.1, weight=1.4715, stiffness=5.0):
    """Motor (inertia ``motor``, angle ``m``) driving through a joint spring of ``stiffness``
    a link (inertia ``link`` about the joint, ``weight`` = mass g times the centre of mass's
    distance; angle ``l`` from the downward vertical)."""
    return (0.5 * motor * v[0] ** 2 + 0.5 * link * v[1] ** 2
            - 0.5 * stiffness * (q[1] - q[0]) ** 2 + weight * sp.cos(q[1]))


def ball_on_beam_lagrangian(q, v, beam=0.1, mass=0.2, ball=0.02, torsion=4.0, centring=4.0):
    """Solid ball (``mass``, radius ``ball``) rolling on a beam (inertia ``beam`` about its
    centre pivot, torsion spring ``torsion``) at distance ``r`` from the pivot, held by a
    centring spring; ``b`` the beam's tilt."""
    r, b, r_dot, b_dot = q[0], q[1], v[0], v[1]
    spin = 0.4 * mass * ball ** 2
    kinetic = (0.5 * (beam + mass * (r ** 2 + ball ** 2) + spin) * b_dot ** 2
               + 0.5 * (mass + spin / ball ** 2) * r_dot ** 2
               - (mass * ball + spin / ball) * r_dot * b_dot)
    return (kinetic - mass * G * (r * sp.sin(b) + ball * sp.cos(b))
            - 0.5 * torsion * b ** 2 - 0.5 * centring * r ** 2)


def elastic_crane_lagrangian(q, v, trolley=1.0, payload=0.5, servo=4.0, cable=50.0, rest=0.8):
    """Trolley of mass ``trolley`` at ``x`` (held by a ``servo`` spring) carrying a
    ``payload`` on a coil spring (stiffness ``cable``, rest length ``rest``) of length ``r`` at
    angle ``theta`` from the downward vertical."""
    x, r, theta = q
    xd, rd, thd = v
    return (0.5 * (trolley + payload) * xd ** 2
            + 0.5 * payload * (rd ** 2 + r ** 2 * thd ** 2)
            + payload * xd * (rd * sp.sin(theta) + r * thd * sp.cos(theta))
            + payload * G * r * sp.cos(theta)
            - 0.5 * servo * x ** 2 - 0.5 * cable * (r - rest) ** 2)


def systems():
    """The third blind set (name -> record of ``generic_systems._system``)."""
    system = gs._system
    out = [
        system("magnetic_spring", ["x"], ["linear"], magnetic_spring_lagrangian,
               [0.1], [0.5], (0.1, 1.0), [0.6], {"degree": 6, "kinetic": "constant"},
               unforced=True),
        system("rocking_half_disk", ["theta"], ["angle"], rocking_half_disk_lagrangian,
               [0.02], [0.16], (0.1, 1.0), [0.8], {}, unforced=True),
        system("furuta_pendulum", ["a", "b"], ["angle", "angle"], furuta_pendulum_lagrangian,
               [0.05, 0.005], [0.4, 0.1], (0.1, 1.0), [0.5, 0.5],
               {"angle_degree": 2}),
        system("flexible_joint_arm", ["m", "l"], ["angle", "angle"],
               flexible_joint_arm_lagrangian, [0.05, 0.05], [0.4, 0.15], (0.1, 1.0), [0.5, 0.5],
               {"angle_degree": 2, "interaction": 2, "kinetic": "constant"}, unforced=True),
        system("ball_on_beam", ["r", "b"], ["linear", "angle"], ball_on_beam_lagrangian,
               [0.1, 0.05], [0.2, 0.4], (0.1, 1.0), [0.2, 0.3],
               {"interaction": 2, "angle_degree": 2}),
        system("elastic_crane", ["x", "r", "theta"], ["linear", "linear", "angle"],
               elastic_crane_lagrangian, [0.3, 0.3, 0.02], [2.0, 1.0, 0.3], (0.1, 1.0),
               [0.3, 0.05, 0.4], {"interaction": 2}, center=[0.0, 0.8 + 0.5 * G / 50.0, 0.0]),
    ]
    return {s["name"]: s for s in out}


if __name__ == "__main__":
    sys.exit(us.main(table=systems, results=RESULTS, script="blind3_systems.py",
                     title="Systems the automatic catalog was run on blind, third set"))
