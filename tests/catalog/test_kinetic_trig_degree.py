"""Kinetic coefficients of the second trigonometric degree (``kinetic_trig_degree``): the
``sin(theta)^2 phi_dot^2`` of a spherical pendulum, against a truth derived independently with
sympy.physics.mechanics."""

import numpy as np
import pytest
import sympy as sp
from ground_truth import TrueSystem
from sympy.physics import mechanics as me

import pysindy_xl as px
from pysindy_xl.catalog import grow_catalog
from pysindy_xl.catalog.backward import removed
from pysindy_xl.catalog.moves import START, holds, kinetic_trig_degree, moved

G = 9.81


def _spherical_pendulum(mass=1.0, length=1.0, friction=(0.05, 0.05)) -> TrueSystem:
    """A point mass on a rod, on a two-axis gimbal whose outer axis ``N.x`` is horizontal
    (gravity along ``+N.y``): ``phi`` turns the gimbal about ``N.x``, ``theta`` the rod about
    the gimbal's ``z`` axis from ``N.x``; hanging at ``theta = pi/2``, ``phi = 0``. Derived by
    LagrangesMethod (no Lagrangian written by hand), with viscous friction and a torque on each
    axis."""
    theta, phi = me.dynamicsymbols("theta phi")
    theta_d, phi_d = me.dynamicsymbols("theta phi", 1)
    coords = px.Coordinates(["theta", "phi"])
    frame = me.ReferenceFrame("N")
    gimbal = frame.orientnew("A", "Axis", (phi, frame.x))
    rod = gimbal.orientnew("B", "Axis", (theta, gimbal.z))
    origin = me.Point("O")
    origin.set_vel(frame, 0)
    bob = origin.locatenew("P", length * rod.x)
    bob.v2pt_theory(origin, frame, rod)
    particle = me.Particle("bob", bob, mass)
    particle.potential_energy = -mass * G * bob.pos_from(origin).dot(frame.y)
    c = tuple(sp.Symbol(f"c_{name}", real=True) for name in coords.names)
    loads = [(rod, (coords.tau[0] - c[0] * theta_d) * gimbal.z),
             (gimbal, (coords.tau[1] - c[1] * phi_d) * frame.x)]
    lagrangian = me.Lagrangian(frame, particle)
    method = me.LagrangesMethod(lagrangian, [theta, phi], forcelist=loads, frame=frame)
    method.form_lagranges_equations()
    plain = {theta_d: coords.qd[0], phi_d: coords.qd[1], theta: coords.q[0], phi: coords.q[1]}
    energy = particle.kinetic_energy(frame) + particle.potential_energy
    return TrueSystem(name="spherical_pendulum", coords=coords,
                      lagrangian=sp.expand(lagrangian.xreplace(plain)),
                      friction=np.asarray(friction, float),
                      mass_matrix_expr=sp.simplify(method.mass_matrix.xreplace(plain)),
                      forcing_symbolic=method.forcing.xreplace(plain), friction_symbols=c,
                      energy_expr=sp.expand(energy.xreplace(plain)),
                      force_amplitude=np.array([1.0, 0.8]))


def _recorded(system, seeds, noise, duration=8.0, rate=500.0):
    """Noisy positions, times and torques of forced runs about the hanging state."""
    t = np.arange(0.0, duration, 1.0 / rate)
    xs, us, clean = [], [], []
    for seed in seeds:
        rng = np.random.default_rng(seed)
        frequencies, phases = rng.uniform(0.1, 1.0, (5, 2)), rng.uniform(0, 2 * np.pi, (5, 2))

        def torque(time, frequencies=frequencies, phases=phases):
            return system.force_amplitude * np.sin(
                2 * np.pi * frequencies * np.asarray(time)[..., None, None] + phases).sum(-2) / 2.5

        x0 = np.r_[np.pi / 2 + rng.uniform(-0.4, 0.4), rng.uniform(-0.5, 0.5),
                   rng.uniform(-0.5, 0.5, 2)]
        run = system.simulate(x0, t, torque)
        clean.append(run)
        xs.append(run["q"] + noise * run["q"].std(axis=0) * rng.normal(size=run["q"].shape))
        us.append(run["tau"])
    return t, xs, us, clean


def _fresh_states(clean, count=400, seed=11):
    """States off the trajectories (in the recorded box, velocities and accelerations drawn)."""
    q = np.vstack([run["q"] for run in clean])
    qd = np.vstack([run["qd"] for run in clean])
    qdd = np.vstack([run["qdd"] for run in clean])
    rng = np.random.default_rng(seed)

    def draw(values):
        return rng.uniform(values.min(axis=0), values.max(axis=0), (count, values.shape[1]))

    return draw(q), draw(qd), draw(qdd)


def _force_error(model, system, states):
    """Relative error of the model's generalized forces ``M(q) qdd - f(q, qd, 0)`` (friction
    in both) against the truth's."""
    q, qd, qdd = states
    unforced = system.accelerations(q, qd, np.zeros_like(q))
    truth = np.einsum("nij,nj->ni", system.mass_matrix(q), qdd - unforced)
    predicted = model.predict_forces(q, qd, qdd)
    return np.linalg.norm(predicted - truth) / np.linalg.norm(truth)


# -- the catalog ---------------------------------------------------------------------------------
def test_catalog_holds_sin_squared_kinetic_terms_when_asked():
    names = ["a", "b"]
    (_, b), (a_dot, b_dot) = px.Coordinates(names).q, px.Coordinates(names).qd
    default = px.AutomaticCatalog(names, kinds="angle")
    second = px.AutomaticCatalog(names, kinds="angle", kinetic_trig_degree=2)
    terms = {str(t) for t in second.lagrange_terms()}
    assert str(sp.sin(b) ** 2 * a_dot ** 2) in terms
    assert str(sp.sin(b) * sp.cos(b) * a_dot ** 2) in terms
    assert not any("cos(b)**2" in t for t in terms)  # (1 - sin^2: a dependency)
    assert not any("sin(b)**2" in t for t in map(str, default.lagrange_terms()))
    # independent of the potential's trigonometric degree, either way
    potential_only = px.AutomaticCatalog(names, kinds="angle", trig_degree=2)
    assert str(sp.sin(b) ** 2 * a_dot ** 2) not in map(str, potential_only.lagrange_terms())
    assert "sin(b)**2" not in str([t for t in second.lagrange_terms()
                                   if not t.has(a_dot) and not t.has(b_dot)])
    # per angle 4 functions against 2: 3 velocity products x (1 + 8) against (1 + 4)
    assert second.n_terms - default.n_terms == 3 * 4
    assert "kinetic configuration (sin/cos degree 2)" in second.describe()
    assert "kinetic_trig_degree=2" in repr(second)
    assert second.content_key() != default.content_key()
    assert px.AutomaticCatalog(names, kinds="angle", kinetic_trig_degree=1).content_key() \
        == default.content_key()
    constant = px.AutomaticCatalog(names, kinds="angle", kinetic="constant")
    assert px.AutomaticCatalog(names, kinds="angle", kinetic="constant",
                               kinetic_trig_degree=2).content_key() == constant.content_key()


@pytest.mark.parametrize("value", [-1, 1.5, "2"])
def test_bad_kinetic_trig_degree_is_named(value):
    with pytest.raises((ValueError, TypeError), match="kinetic_trig_degree"):
        _ = px.AutomaticCatalog(["a"], kinds="angle", kinetic_trig_degree=value).n_terms


def test_the_move_sets_the_degree_and_the_backward_phase_undoes_it():
    kinds = ["linear", "angle"]
    state = moved(dict(START), "kinetic_trig_degree", kinds, 2)
    assert state["kinetic"] == "configuration" and kinetic_trig_degree(state) == 2
    assert moved(state, "kinetic_trig_degree", kinds, 2) is None
    assert moved(dict(START), "kinetic_trig_degree", ["linear"], 1) is None  # no angle
    assert moved(dict(START), "kinetic_trig_degree", ["angle"], 1) is None  # one coordinate
    kinetic = moved(dict(START), "kinetic", kinds, 2)
    assert holds(state, kinetic) and not holds(kinetic, state)
    assert removed(state, "kinetic_trig_degree", kinds, START) == kinetic
    assert removed(state, "kinetic", kinds, START) == dict(START)


# -- fits of the spherical pendulum --------------------------------------------------------------
@pytest.fixture(scope="module")
def spherical():
    system = _spherical_pendulum()
    t, xs, us, clean = _recorded(system, seeds=(0, 1), noise=0.01)
    test = _recorded(system, seeds=(5,), noise=0.0)[3]
    return system, t, xs, us, _fresh_states(clean + test)


def test_truth_is_the_spherical_pendulum(spherical):
    system = spherical[0]
    theta, phi = system.coords.q
    theta_dot, phi_dot = system.coords.qd
    expected = (theta_dot ** 2 + sp.sin(theta) ** 2 * phi_dot ** 2) / 2 \
        + G * sp.sin(theta) * sp.cos(phi)
    assert sp.simplify(system.lagrangian - expected) == 0


@pytest.mark.slow
def test_fixed_catalog_fits_the_spherical_pendulum_from_noisy_positions(spherical):
    system, t, xs, us, states = spherical
    catalog = px.AutomaticCatalog(["theta", "phi"], kinds="angle", interaction=2,
                                  kinetic_trig_degree=2)
    model = px.XLSINDy(catalog).fit(xs, [t, t], u=us)
    assert _force_error(model, system, states) < 0.02
    # without the second degree no catalog states the inertia: the same fit is far off
    narrow = px.XLSINDy(px.AutomaticCatalog(["theta", "phi"], kinds="angle",
                                            interaction=2)).fit(xs, [t, t], u=us)
    assert _force_error(narrow, system, states) > 3 * _force_error(model, system, states)


@pytest.mark.slow
def test_growth_finds_the_spherical_pendulum(spherical):
    system, t, xs, us, states = spherical
    found = grow_catalog(xs, [t, t], us, coordinates=["theta", "phi"], kinds="angle")
    (theta, _), (_, phi_dot) = system.coords.q, system.coords.qd
    assert str(sp.sin(theta) ** 2 * phi_dot ** 2) in map(str, found.catalog.lagrange_terms())
    assert _force_error(found.model, system, states) < 0.03
