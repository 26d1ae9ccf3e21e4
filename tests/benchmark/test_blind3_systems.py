"""The third blind set of ``benchmarks/blind3_systems.py``: its Lagrangians against an
independent derivation from the bodies' positions in an inertial frame (time derivatives by
sympy; the half-disk's centre of mass and inertia and the Furuta rod's kinetic energy by
integration over the body; the ball's spin from the rolling condition), its truth's equations
against energy conservation (undamped, unforced, scipy at tight tolerance), and each hand-built
catalog right on noise-free data (the reference that makes the benchmark's "right"
reachable)."""

import pathlib
import sys
import warnings

import numpy as np
import pytest
import sympy as sp

BENCHMARKS = pathlib.Path(__file__).resolve().parents[2] / "benchmarks"
G = 9.81
NAMES = ["magnetic_spring", "rocking_half_disk", "furuta_pendulum", "flexible_joint_arm",
         "ball_on_beam", "elastic_crane"]


@pytest.fixture(scope="module")
def bench():
    sys.path.insert(0, str(BENCHMARKS))
    import blind3_systems
    import generic_systems

    return blind3_systems, generic_systems


def _speed2(t, *position):
    return sum(sp.diff(p, t) ** 2 for p in position)


def _inertial(name, q, t):
    """The system ``name``'s Lagrangian from its bodies' inertial positions (functions of
    ``t`` through the coordinates ``q``, themselves functions of ``t``)."""
    half = sp.Rational(1, 2)
    if name == "magnetic_spring":
        # repulsion force c / distance^2 from magnets at -2 and +2: potential c / distance
        x = q[0]
        return half * 0.5 * _speed2(t, x) - 3.5 / (x + 2) - 3.5 / (2 - x)
    if name == "rocking_half_disk":
        # the half-disk's centroid and inertia about the rim's centre, integrated over it
        rho, phi, radius, mass = sp.symbols("rho phi radius mass", positive=True)
        area = sp.pi * radius ** 2 / 2
        offset = sp.integrate(rho * sp.sin(phi) * rho, (rho, 0, radius), (phi, 0, sp.pi)) / area
        about_centre = mass / area * sp.integrate(rho ** 3, (rho, 0, radius), (phi, 0, sp.pi))
        values = {radius: sp.Float(0.3), mass: 1}
        offset, about_centre = offset.subs(values), about_centre.subs(values)
        # rolling: turned by theta (counter-clockwise), the rim's centre has moved by -r theta
        centre = (-0.3 * q[0], 0.3)
        com = (centre[0] + offset * sp.sin(q[0]), centre[1] - offset * sp.cos(q[0]))
        spin = about_centre - offset ** 2  # about the centre of mass
        return (half * _speed2(t, *com) + half * spin * sp.diff(q[0], t) ** 2
                - G * com[1])
    if name == "furuta_pendulum":
        # arm (inertia 0.1 about the vertical, length 0.2, spring 1); uniform rod (mass 1,
        # length 0.3) from the arm's tip, its points p(s) integrated over s
        a, b = q
        s = sp.Symbol("s", positive=True)
        point = (0.2 * sp.cos(a) - s * sp.sin(b) * sp.sin(a),
                 0.2 * sp.sin(a) + s * sp.sin(b) * sp.cos(a), -s * sp.cos(b))
        density = 1 / sp.Float(0.3)
        rod = sp.integrate(sp.expand(half * density * _speed2(t, *point)
                                     - density * G * point[2]), (s, 0, 0.3))
        return half * 0.1 * sp.diff(a, t) ** 2 - half * 1.0 * a ** 2 + rod
    if name == "flexible_joint_arm":
        # motor rotor 0.05; link of mass 0.5, centre of mass 0.3 from the joint, 0.055 about it
        motor, link = q
        com = (0.3 * sp.sin(link), -0.3 * sp.cos(link))
        return (half * 0.05 * sp.diff(motor, t) ** 2 + half * 0.5 * _speed2(t, *com)
                + half * 0.055 * sp.diff(link, t) ** 2 - 0.5 * G * com[1]
                - half * 5.0 * (link - motor) ** 2)
    if name == "ball_on_beam":
        r, b = q
        mass, radius = 0.2, 0.02
        normal = (-sp.sin(b), sp.cos(b))
        along = (sp.cos(b), sp.sin(b))
        centre = [r * along[i] + radius * normal[i] for i in range(2)]
        # the ball's spin from the rolling condition: its contact point moves with the beam's
        # point under it
        omega = sp.Symbol("omega")
        contact = [sp.diff(centre[i], t) + omega * radius * along[i] for i in range(2)]
        beam_point = [sp.diff(r * along[i], t).subs(sp.Derivative(r, t), 0) for i in range(2)]
        slip = sp.trigsimp(sp.expand((contact[0] - beam_point[0]) * along[0]
                                     + (contact[1] - beam_point[1]) * along[1]))
        spin = sp.solve(slip, omega)[0]
        return (half * 0.1 * sp.diff(b, t) ** 2 + half * mass * _speed2(t, *centre)
                + half * 0.4 * mass * radius ** 2 * spin ** 2 - mass * G * centre[1]
                - half * 4.0 * b ** 2 - half * 4.0 * r ** 2)
    if name == "elastic_crane":
        x, r, theta = q
        payload = (x + r * sp.sin(theta), -r * sp.cos(theta))
        return (half * 1.0 * sp.diff(x, t) ** 2 + half * 0.5 * _speed2(t, *payload)
                - 0.5 * G * payload[1] - half * 4.0 * x ** 2 - half * 50.0 * (r - 0.8) ** 2)
    raise KeyError(name)


def test_the_set(bench):
    blind3, _ = bench
    table = blind3.systems()
    assert sorted(table) == sorted(NAMES)
    assert sorted(s["coords"].n for s in table.values()) == [1, 1, 2, 2, 2, 3]
    assert sum(s["unforced"] for s in table.values()) >= 3
    assert {k for s in table.values() for k in s["kinds"]} == {"linear", "angle"}


@pytest.mark.parametrize("name", NAMES)
def test_lagrangian_matches_the_inertial_derivation(bench, name):
    blind3, _ = bench
    system = blind3.systems()[name]
    coords = system["coords"]
    t = sp.Symbol("t")
    paths = [sp.Function(f"path_{k}")(t) for k in range(coords.n)]
    independent = _inertial(name, paths, t)
    independent = independent.subs({sp.Derivative(p, t): v
                                    for p, v in zip(paths, coords.qd, strict=True)})
    independent = independent.subs(dict(zip(paths, coords.q, strict=True)))
    args = (*coords.q, *coords.qd)
    ours = sp.lambdify(args, system["L"], "numpy")
    theirs = sp.lambdify(args, independent, "numpy")
    rng = np.random.default_rng(3)
    states = rng.uniform(-1.2, 1.2, (2 * coords.n, 50))
    states[:coords.n] += system["center"][:, None]
    difference = ours(*states) - theirs(*states)
    # a potential matters up to a constant
    np.testing.assert_allclose(difference - difference[0], 0.0, atol=1e-10)


@pytest.mark.parametrize("name", NAMES)
def test_truth_conserves_energy_without_damping_or_force(bench, name):
    blind3, gs = bench
    system = dict(blind3.systems()[name])
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
    q, qd = y[:, :coords.n], y[:, coords.n:]
    qdd = truth.accelerations(q, qd, np.zeros_like(q))
    np.testing.assert_allclose(truth.forces(q, qd, qdd), 0.0, atol=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("name", NAMES)
def test_hand_built_catalog_is_right_free_of_noise(bench, name):
    import pysindy_xl as px
    from pysindy_xl.catalog.growth_data import END_PERCENTILE

    blind3, gs = bench
    system = blind3.systems()[name]
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
