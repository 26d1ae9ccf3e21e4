"""A second blind set: six more systems the automatic catalog was never run on.

Written after the development set (``generic_systems.py``), the validation set
(``unseen_systems.py``) and the first blind set (``blind_systems.py``), each different from
their 27 systems, and run once with no change to the method: their right rate is a blind
estimate. The systems are the kind a robotics or mechanics researcher brings with a CSV:

- ``offset_spring_pendulum``: a pendulum whose bob is held by a spring (rest length 0.3)
  anchored off the pivot; the spring's potential ``k/2 (d(theta) - l0)^2`` with
  ``d = sqrt(1.05 - 0.4 sin(theta) - 0.8 cos(theta))`` is a ``sqrt`` of sines and cosines that
  no trigonometric family states (only the splines of ``theta`` do);
- ``bead_rotating_parabola``: a bead on a parabolic wire ``z = c r^2`` spun at a fixed rate
  about its axis (inertia ``1 + 4 c^2 r^2``, centrifugal and gravity potentials in ``r^2``);
- ``cart_stiffening_pendulum``: a pendulum hanging from a cart held by a stiffening spring
  (``k x^2 / 2 + k3 x^4 / 4``);
- ``ball_rotating_dish``: a ball sliding in a parabolic dish on a turntable, recorded in the
  turntable's frame (Coriolis terms ``x y_dot``, inertia ``(x x_dot + y y_dot)^2``);
- ``three_link_arm``: a planar three-link arm of uniform rods in a vertical plane, relative
  joint angles (as encoders give them), gravity and viscous joint friction: inertia in
  ``cos(b)``, ``cos(c)``, ``cos(b + c)``, gravity in ``cos(a + b + c)`` (a product of three
  coordinates' functions);
- ``half_car``: a half-car model: body heave ``z`` and pitch ``theta``, front and rear wheel
  hops, suspension springs to the body's ends (``z +- l sin(theta)``) and tyre springs.

Everything else is ``generic_systems.py``'s and ``unseen_systems.py``'s, imported: the truth
(sympy Euler-Lagrange, scipy DOP853 at rtol = atol = 1e-10), the data (2 runs of 10 s at 1 kHz,
positions with 0, 1 or 5 % noise, seeded by the case), the scores, the hand-built reference
(``hand``: AutomaticCatalog parameters that contain the law), the grid, the report and
``--explain``. Usage::

    PYTHONPATH=$PWD python benchmarks/blind2_systems.py --seeds 0 1 2 --no-baselines \\
        --out benchmarks/results/blind2_systems_<commit>.jsonl
    python benchmarks/blind2_systems.py --out benchmarks/results/blind2_systems_<commit>.jsonl \\
        --report benchmarks/results/blind2_systems.md
    PYTHONPATH=$PWD python benchmarks/blind2_systems.py --explain half_car:forced:0.05:0
"""

from __future__ import annotations

import os
import sys

import sympy as sp

sys.path.insert(0, os.path.dirname(__file__))

import generic_systems as gs  # noqa: E402 - the benchmark's machinery
import unseen_systems as us  # noqa: E402

RESULTS = os.path.join(os.path.dirname(__file__), "results", "blind2_systems.jsonl")
G = gs.G


def offset_spring_pendulum_lagrangian(q, v, mass=0.5, length=0.5, anchor=(0.4, -0.8),
                                      stiffness=6.0, rest=0.3):
    """Pendulum (bob ``mass`` at ``length``, angle from the downward vertical) with a spring of
    ``stiffness`` and rest length ``rest`` from the bob to the fixed point ``anchor``."""
    bob = sp.Matrix([length * sp.sin(q[0]), -length * sp.cos(q[0])])
    d = sp.sqrt(sp.expand((bob - sp.Matrix(anchor)).dot(bob - sp.Matrix(anchor))))
    return (0.5 * mass * length ** 2 * v[0] ** 2 + mass * G * length * sp.cos(q[0])
            - 0.5 * stiffness * (d - rest) ** 2)


def bead_rotating_parabola_lagrangian(q, v, mass=1.0, shape=0.8, rate=2.5):
    """Bead of ``mass`` on the wire ``z = shape r^2`` turning at ``rate`` about its axis."""
    r, rd = q[0], v[0]
    return (0.5 * mass * (rd ** 2 + (2 * shape * r * rd) ** 2 + rate ** 2 * r ** 2)
            - mass * G * shape * r ** 2)


def cart_stiffening_pendulum_lagrangian(q, v, cart=0.8, mass=0.4, length=0.6, stiffness=6.0,
                                        hardening=20.0):
    """Cart on a spring ``stiffness x^2 / 2 + hardening x^4 / 4`` with a pendulum hung from
    it (bob ``mass`` at ``length``)."""
    x, theta, xd, thetad = q[0], q[1], v[0], v[1]
    return (0.5 * (cart + mass) * xd ** 2 + mass * length * xd * thetad * sp.cos(theta)
            + 0.5 * mass * length ** 2 * thetad ** 2 + mass * G * length * sp.cos(theta)
            - 0.5 * stiffness * x ** 2 - 0.25 * hardening * x ** 4)


def ball_rotating_dish_lagrangian(q, v, mass=1.0, shape=0.5, rate=1.5):
    """Ball of ``mass`` sliding in the dish ``z = shape (x^2 + y^2)`` turning at ``rate``,
    in the dish's frame."""
    x, y, xd, yd = q[0], q[1], v[0], v[1]
    zd = 2 * shape * (x * xd + y * yd)
    return (0.5 * mass * ((xd - rate * y) ** 2 + (yd + rate * x) ** 2 + zd ** 2)
            - mass * G * shape * (x ** 2 + y ** 2))


def three_link_arm_lagrangian(q, v, masses=(1.0, 0.7, 0.4), lengths=(0.5, 0.4, 0.3)):
    """Three uniform rods in a vertical plane, joined at relative joint angles (the first
    from the downward vertical)."""
    angles = [q[0], q[0] + q[1], q[0] + q[1] + q[2]]
    rates = [v[0], v[0] + v[1], v[0] + v[1] + v[2]]
    kinetic, potential = 0, 0
    joint_y, joint_xd, joint_yd = 0, 0, 0
    for mass, length, angle, rate in zip(masses, lengths, angles, rates, strict=True):
        y = joint_y - length / 2 * sp.cos(angle)
        xd = joint_xd + length / 2 * sp.cos(angle) * rate
        yd = joint_yd + length / 2 * sp.sin(angle) * rate
        kinetic += 0.5 * mass * (xd ** 2 + yd ** 2) + 0.5 * mass * length ** 2 / 12 * rate ** 2
        potential += mass * G * y
        joint_y -= length * sp.cos(angle)
        joint_xd += length * sp.cos(angle) * rate
        joint_yd += length * sp.sin(angle) * rate
    return sp.expand(sp.expand_trig(kinetic - potential))


def half_car_lagrangian(q, v, body=1.0, pitch_inertia=0.4, wheel=0.15, front=0.6, rear=0.5,
                        spring_front=12.0, spring_rear=10.0, tyre=60.0):
    """Half-car: body heave ``z`` and pitch ``theta`` (mass ``body``, inertia
    ``pitch_inertia``), wheels of mass ``wheel`` at ``front`` and ``rear`` of the centre,
    suspension and tyre springs (about the static equilibrium)."""
    z, theta, zf, zr = q
    return (0.5 * body * v[0] ** 2 + 0.5 * pitch_inertia * v[1] ** 2
            + 0.5 * wheel * (v[2] ** 2 + v[3] ** 2)
            - 0.5 * spring_front * (z + front * sp.sin(theta) - zf) ** 2
            - 0.5 * spring_rear * (z - rear * sp.sin(theta) - zr) ** 2
            - 0.5 * tyre * (zf ** 2 + zr ** 2))


def systems():
    """The second blind set (name -> record of ``generic_systems._system``)."""
    system = gs._system
    out = [
        system("offset_spring_pendulum", ["theta"], ["angle"], offset_spring_pendulum_lagrangian,
               [0.05], [0.8], (0.1, 1.0), [0.8],
               {"splines": 8, "spline_ends": "quadratic", "kinetic": "constant"}),
        system("bead_rotating_parabola", ["r"], ["linear"], bead_rotating_parabola_lagrangian,
               [0.1], [3.0], (0.1, 1.0), [0.5], {}, unforced=True),
        system("cart_stiffening_pendulum", ["x", "theta"], ["linear", "angle"],
               cart_stiffening_pendulum_lagrangian, [0.2, 0.1], [3.0, 0.3], (0.1, 1.0),
               [0.4, 0.5], {"degree": 4}, unforced=True),
        system("ball_rotating_dish", ["x", "y"], ["linear", "linear"],
               ball_rotating_dish_lagrangian, [0.1, 0.1], [3.0, 3.0], (0.1, 1.0), [0.4, 0.4],
               {"gyroscopic": True, "interaction": 2}, unforced=True),
        system("three_link_arm", ["a", "b", "c"], ["angle", "angle", "angle"],
               three_link_arm_lagrangian, [0.2, 0.1, 0.1], [2.5, 1.0, 0.2], (0.1, 1.0),
               [0.5, 0.5, 0.5], {"interaction": 3, "kinetic_interaction": 2}),
        system("half_car", ["z", "theta", "zf", "zr"], ["linear", "angle", "linear", "linear"],
               half_car_lagrangian, [0.5, 0.5, 0.3, 0.3], [3.0, 0.25, 3.0, 3.0], (0.1, 1.0),
               [0.1, 0.1, 0.05, 0.05], {"trig_degree": 2, "interaction": 2,
                                         "kinetic": "constant"}, unforced=True),
    ]
    return {s["name"]: s for s in out}


if __name__ == "__main__":
    sys.exit(us.main(table=systems, results=RESULTS, script="blind2_systems.py",
                     title="Systems the automatic catalog was run on blind, second set"))
