"""The second blind set of ``benchmarks/blind2_systems.py``: its Lagrangians against an
independent derivation from the bodies' positions in an inertial frame (time derivatives by
sympy, the rotating frames turned explicitly), its truth's equations against energy
conservation (undamped, unforced, scipy at tight tolerance), and each hand-built catalog right
on noise-free data (the reference that makes the benchmark's "right" reachable)."""

import pathlib
import sys
import warnings

import numpy as np
import pytest
import sympy as sp

BENCHMARKS = pathlib.Path(__file__).resolve().parents[2] / "benchmarks"
G = 9.81


@pytest.fixture(scope="module")
def bench():
    sys.path.insert(0, str(BENCHMARKS))
    import blind2_systems
    import generic_systems

    return blind2_systems, generic_systems


def _inertial(name, q, t):
    """The system ``name``'s Lagrangian from its bodies' inertial positions (functions of
    ``t`` through the coordinates ``q``, themselves functions of ``t``)."""

    def kinetic(mass, *position):
        return sp.Rational(1, 2) * mass * sum(sp.diff(p, t) ** 2 for p in position)

    if name == "offset_spring_pendulum":
        bob = (0.5 * sp.sin(q[0]), -0.5 * sp.cos(q[0]))
        stretch = sp.sqrt((bob[0] - 0.4) ** 2 + (bob[1] + 0.8) ** 2) - 0.3
        return kinetic(0.5, *bob) - 0.5 * G * bob[1] - 3.0 * stretch ** 2
    if name == "bead_rotating_parabola":
        turn = 2.5 * t
        bead = (q[0] * sp.cos(turn), q[0] * sp.sin(turn), 0.8 * q[0] ** 2)
        return kinetic(1.0, *bead) - G * bead[2]
    if name == "cart_stiffening_pendulum":
        bob = (q[0] + 0.6 * sp.sin(q[1]), -0.6 * sp.cos(q[1]))
        return (kinetic(0.8, q[0]) + kinetic(0.4, *bob) - 0.4 * G * bob[1] - 3.0 * q[0] ** 2
                - 5.0 * q[0] ** 4)
    if name == "ball_rotating_dish":
        turn = 1.5 * t
        ball = (q[0] * sp.cos(turn) - q[1] * sp.sin(turn),
                q[0] * sp.sin(turn) + q[1] * sp.cos(turn), 0.5 * (q[0] ** 2 + q[1] ** 2))
        return kinetic(1.0, *ball) - G * ball[2]
    if name == "three_link_arm":
        lagrangian, joint = 0, (0, 0)
        angle = 0
        for mass, length, relative in zip((1.0, 0.7, 0.4), (0.5, 0.4, 0.3), q, strict=True):
            angle = angle + relative
            tip = (joint[0] + length * sp.sin(angle), joint[1] - length * sp.cos(angle))
            centre = ((joint[0] + tip[0]) / 2, (joint[1] + tip[1]) / 2)
            lagrangian += (kinetic(mass, *centre)
                           + kinetic(mass * length ** 2 / 12, angle) - mass * G * centre[1])
            joint = tip
        return lagrangian
    if name == "half_car":
        front = q[0] + 0.6 * sp.sin(q[1])
        rear = q[0] - 0.5 * sp.sin(q[1])
        return (kinetic(1.0, q[0]) + kinetic(0.4, q[1]) + kinetic(0.15, q[2])
                + kinetic(0.15, q[3]) - 6.0 * (front - q[2]) ** 2 - 5.0 * (rear - q[3]) ** 2
                - 30.0 * (q[2] ** 2 + q[3] ** 2))
    raise KeyError(name)


def test_every_system_has_an_independent_derivation(bench):
    blind2, _ = bench
    table = blind2.systems()
    assert len(table) == 6
    assert sorted(s["coords"].n for s in table.values()) == [1, 1, 2, 2, 3, 4]
    assert sum(s["unforced"] for s in table.values()) >= 3
    kinds = {k for s in table.values() for k in s["kinds"]}
    assert kinds == {"linear", "angle"}


@pytest.mark.parametrize("name", ["offset_spring_pendulum", "bead_rotating_parabola",
                                  "cart_stiffening_pendulum", "ball_rotating_dish",
                                  "three_link_arm", "half_car"])
def test_lagrangian_matches_the_inertial_derivation(bench, name):
    blind2, _ = bench
    system = blind2.systems()[name]
    coords = system["coords"]
    t = sp.Symbol("t")
    paths = [sp.Function(f"path_{k}")(t) for k in range(coords.n)]
    independent = _inertial(name, paths, t)
    # the time derivatives become the velocities, the paths the coordinates; in a rotating
    # frame the time must drop out
    independent = independent.subs({sp.Derivative(p, t): v
                                    for p, v in zip(paths, coords.qd, strict=True)})
    independent = independent.subs(dict(zip(paths, coords.q, strict=True)))
    args = (*coords.q, *coords.qd, t)
    ours = sp.lambdify(args, system["L"] + 0 * t, "numpy")
    theirs = sp.lambdify(args, independent, "numpy")
    rng = np.random.default_rng(3)
    states = rng.uniform(-1.2, 1.2, (2 * coords.n, 50))
    for time in (0.0, 0.7, 3.1):
        np.testing.assert_allclose(ours(*states, time), theirs(*states, time), rtol=1e-12,
                                   atol=1e-12)


@pytest.mark.parametrize("name", ["offset_spring_pendulum", "bead_rotating_parabola",
                                  "cart_stiffening_pendulum", "ball_rotating_dish",
                                  pytest.param("three_link_arm", marks=pytest.mark.slow),
                                  "half_car"])
def test_truth_conserves_energy_without_damping_or_force(bench, name):
    blind2, gs = bench
    system = dict(blind2.systems()[name])
    system["damping"] = np.zeros_like(system["damping"])
    coords = system["coords"]
    truth = gs.Truth(system)
    lagrangian = system["L"]
    energy = sp.lambdify((*coords.q, *coords.qd),
                         sum(v * sp.diff(lagrangian, v) for v in coords.qd) - lagrangian,
                         "numpy")
    rng = np.random.default_rng(1)
    x0 = np.r_[system["center"] + system["q0"] * rng.uniform(-1, 1, coords.n),
               rng.uniform(-0.5, 0.5, coords.n)]
    t = np.linspace(0.0, 1.5, 301)
    y = truth.simulate(x0, t, lambda time: np.zeros(coords.n))
    values = energy(*y.T)
    scale = np.abs(values).max() + np.abs(y[:, coords.n:]).max() ** 2
    assert np.ptp(y[:, 0]) > 1e-3  # it moves
    assert np.max(np.abs(values - values[0])) < 1e-8 * scale
    # the truth's accelerations put back into its forces give no force
    q, qd = y[:, :coords.n], y[:, coords.n:]
    qdd = truth.accelerations(q, qd, np.zeros_like(q))
    np.testing.assert_allclose(truth.forces(q, qd, qdd), 0.0, atol=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["offset_spring_pendulum", "bead_rotating_parabola",
                                  "cart_stiffening_pendulum", "ball_rotating_dish",
                                  "three_link_arm", "half_car"])
def test_hand_built_catalog_is_right_free_of_noise(bench, name):
    import pysindy_xl as px
    from pysindy_xl.catalog.growth_data import END_PERCENTILE

    blind2, gs = bench
    system = blind2.systems()[name]
    truth = gs.Truth(system)
    runs, test, xs, ts, us = gs.case_data(system, truth, 0.0, 0, True)
    low, high = np.percentile(np.vstack(xs), [END_PERCENTILE, 100 - END_PERCENTILE], axis=0)
    catalog = px.AutomaticCatalog(list(system["coords"].names), kinds=system["kinds"],
                                  bounds=[(float(a), float(b)) for a, b in zip(low, high,
                                                                                strict=True)],
                                  **system["hand"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = px.XLSINDy(catalog).fit(xs, ts, u=us)
    scores = gs.score(*gs._xlsindy_functions(model), system, truth, test, runs, True)
    assert scores["right"], scores
