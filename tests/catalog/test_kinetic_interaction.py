"""The kinetic coefficients' own interaction order (``AutomaticCatalog(kinetic_interaction=)``)
and the growth's retry with it under the ceiling.

Ground truth: a cart on a spring carrying a pendulum, coupled by a spring to a second cart
(``sympy.physics.mechanics``, integrated by scipy at 1e-10): its Lagrangian holds
``cos(a) a_dot x1_dot`` (an inertia of one coordinate's function) and ``x1 x2`` (a potential
product of two coordinates).
"""

import warnings

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from sklearn.base import clone
from support.catalog_setups import ceiling_climber

import pysindy_xl as px
from pysindy_xl.catalog import AutomaticCatalog
from pysindy_xl.catalog.backward import removed
from pysindy_xl.catalog.candidates import parameters_key
from pysindy_xl.catalog.moves import START, holds, kinetic_order, moved
from pysindy_xl.catalog.retries import attempt_within_limits

NAMES, KINDS = ["x1", "x2", "a"], ["linear", "linear", "angle"]
CART, SECOND, BOB, LENGTH, GRAVITY = 1.0, 0.8, 0.3, 0.5, 9.81
SPRINGS, COUPLING, DAMPING = (1.5, 1.0), 1.0, 0.05


def _cart_pendulum_and_cart():
    """The system by ``LagrangesMethod``: ``accelerations(q, qd, u)`` of arrays (N, 3)."""
    from sympy.physics import mechanics as me
    q = me.dynamicsymbols("x1 x2 a")
    qd = [me.dynamicsymbols(name, 1) for name in ("x1", "x2", "a")]
    forces = sp.symbols("u0:3")
    frame = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(frame, 0)
    first = origin.locatenew("P1", q[0] * frame.x)
    first.set_vel(frame, qd[0] * frame.x)
    second = origin.locatenew("P2", q[1] * frame.x)
    second.set_vel(frame, qd[1] * frame.x)
    bob = first.locatenew("B", LENGTH * (sp.sin(q[2]) * frame.x - sp.cos(q[2]) * frame.y))
    bob.v2pt_theory(first, frame, frame.orientnew("R", "Axis", (q[2], frame.z)))
    bodies = [me.Particle("cart", first, CART), me.Particle("second", second, SECOND),
              me.Particle("bob", bob, BOB)]
    bodies[0].potential_energy = SPRINGS[0] * q[0] ** 2 / 2 + COUPLING * (q[0] - q[1]) ** 2 / 2
    bodies[1].potential_energy = SPRINGS[1] * q[1] ** 2 / 2
    bodies[2].potential_energy = BOB * GRAVITY * bob.pos_from(origin).dot(frame.y)
    # the pendulum's torque and damping act on its angle (a couple on the cart and the bob)
    rod = frame.orientnew("R2", "Axis", (q[2], frame.z))
    method = me.LagrangesMethod(me.Lagrangian(frame, *bodies), q, forcelist=[
        (first, (forces[0] - DAMPING * qd[0]) * frame.x),
        (second, (forces[1] - DAMPING * qd[1]) * frame.x),
        (rod, (forces[2] - DAMPING * qd[2]) * frame.z)], frame=frame)
    method.form_lagranges_equations()
    states = [*q, *qd, *forces]
    mass = sp.lambdify(states, method.mass_matrix)
    forcing = sp.lambdify(states, method.forcing)

    def accelerations(qv, qdv, uv):
        return np.array([np.linalg.solve(np.asarray(mass(*a, *b, *c), float),
                                         np.asarray(forcing(*a, *b, *c), float).ravel())
                         for a, b, c in zip(np.atleast_2d(qv), np.atleast_2d(qdv),
                                            np.atleast_2d(uv), strict=True)])

    return accelerations


def _forced_run(accelerations, seed, duration=12.0, rate=100.0):
    rng = np.random.default_rng(seed)
    f, phase = rng.uniform(0.2, 1.5, (3, 4)), rng.uniform(0, 2 * np.pi, (3, 4))
    scale = np.array([1.5, 1.5, 0.3])

    def force(time):
        return scale * np.sin(2 * np.pi * f * time + phase).sum(axis=1) / 2

    t = np.arange(0.0, duration, 1.0 / rate)
    solution = solve_ivp(lambda time, y: np.concatenate(
        [y[3:], accelerations(y[:3], y[3:], force(time))[0]]), (t[0], t[-1]),
        [0.2, -0.1, 0.3, 0.0, 0.0, 0.0], t_eval=t, method="DOP853", rtol=1e-10, atol=1e-10)
    x, xd = solution.y[:3].T, solution.y[3:].T
    u = np.array([force(time) for time in t])
    return t, x, xd, accelerations(x, xd, u), u


def _kinetic_terms(catalog):
    return [t for t in catalog.lagrange_terms() if any(str(s).endswith("_dot")
                                                       for s in t.free_symbols)]


def test_the_kinetic_order_is_its_own_and_the_potential_keeps_its_products():
    shared = AutomaticCatalog(NAMES, kinds=KINDS, interaction=2)
    narrow = AutomaticCatalog(NAMES, kinds=KINDS, interaction=2, kinetic_interaction=1)
    terms = narrow.lagrange_terms()
    names = set(map(str, terms))
    assert "x1*x2" in names and "a_dot*x1_dot*cos(a)" in names
    assert "a_dot*x1*x1_dot*cos(a)" not in names
    assert "a_dot*x1*x1_dot*cos(a)" in set(map(str, shared.lagrange_terms()))
    # no kinetic coefficient of two coordinates' functions, and the same potential
    for term in _kinetic_terms(narrow):
        assert len({s for s in term.free_symbols if not str(s).endswith("_dot")}) <= 1, term
    assert set(shared.lagrange_terms()) - set(_kinetic_terms(shared)) == \
        set(terms) - set(_kinetic_terms(narrow))
    # 6 velocity products times 1 + 2 + 2 + 2 coefficients of at most one coordinate (1; x1,
    # x1^2; x2, x2^2; sin a, cos a), where the shared order adds their 9 products of two
    # within degree 2 (x1 x2; x1 or x1^2 by sin a or cos a; the same of x2)
    velocity_products = 6
    assert len(_kinetic_terms(narrow)) == velocity_products * 7
    assert len(_kinetic_terms(shared)) == velocity_products * (7 + 9)
    assert narrow.n_terms == shared.n_terms - velocity_products * 9
    # None is the shared order, term for term; the order is read for the kinetic part only
    for order in (1, 2):
        same = AutomaticCatalog(NAMES, kinds=KINDS, interaction=order, kinetic_interaction=order)
        default = AutomaticCatalog(NAMES, kinds=KINDS, interaction=order)
        assert same.content_key() == default.content_key()
        assert same.describe() == default.describe()
    assert narrow.content_key() != shared.content_key()
    assert "kinetic configuration (interaction 1)" in narrow.describe()
    assert clone(narrow).get_params()["kinetic_interaction"] == 1
    assert "kinetic_interaction=1" in repr(narrow)
    constant = AutomaticCatalog(NAMES, kinds=KINDS, interaction=2, kinetic="constant")
    assert constant.content_key() == clone(constant).set_params(
        kinetic_interaction=1).content_key()


@pytest.mark.parametrize("bad, error", [(0, ValueError), (1.5, ValueError), ("1", TypeError)])
def test_a_bad_kinetic_order_is_refused_by_name(bad, error):
    with pytest.raises(error, match="kinetic_interaction"):
        AutomaticCatalog(NAMES, kinds=KINDS, kinetic_interaction=bad).lagrange_terms()


def test_the_narrow_catalog_fits_the_law_and_saves(tmp_path):
    accelerations = _cart_pendulum_and_cart()
    t, x, xd, xdd, u = _forced_run(accelerations, seed=0)
    catalog = AutomaticCatalog(NAMES, kinds=KINDS, interaction=2, kinetic_interaction=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = px.XLSINDy(catalog).fit(x, t, x_dot=xd, x_ddot=xdd, u=u)
    kept = {name: c for name, c in zip(model.get_feature_names(), model.coefficients(),
                                       strict=True) if c != 0}
    # the Lagrangian up to the scale the forces fix: the cross inertia m l cos(a) a_dot x1_dot
    # and the coupling spring's product  kc x1 x2
    assert kept["L[a_dot*x1_dot*cos(a)]"] == pytest.approx(BOB * LENGTH, rel=1e-3)
    assert kept["L[x1*x2]"] == pytest.approx(COUPLING, rel=1e-3)
    # the accelerations on other states (another forced run) against sympy's
    _, x2, xd2, xdd2, u2 = _forced_run(accelerations, seed=1, duration=4.0)
    error = np.linalg.norm(model.predict(x2, xd2, u2) - xdd2) / np.linalg.norm(xdd2)
    assert error < 1e-3
    path = tmp_path / "model.json"
    model.save(path)
    loaded = px.XLSINDy.load(path)
    assert loaded.get_feature_names() == model.get_feature_names()
    assert np.allclose(loaded.predict(x2, xd2, u2), model.predict(x2, xd2, u2))


def test_a_kinetic_move_over_the_ceiling_is_retried_with_single_coordinate_inertias():
    state = moved(dict(START), "interaction", KINDS, 3)  # the potential's products are in
    target = moved(state, "kinetic", KINDS, 3)
    sizes = [AutomaticCatalog(NAMES, kinds=KINDS, max_terms=10 ** 6, **p).n_terms
             for p in (target, dict(target, kinetic_interaction=1))]
    climber = ceiling_climber((sizes[0] + sizes[1]) // 2, NAMES, KINDS)
    tried = {parameters_key(state)}
    parameters, step = attempt_within_limits(climber, target, "kinetic", tried)
    # the constant-kinetic retry is the state itself (tried): the kinetic order gives way
    assert [move for move, _ in climber.attempts] == ["kinetic", "kinetic@k1"]
    assert parameters == dict(target, kinetic_interaction=1) and step.terms == sizes[1]
    assert not step.note and kinetic_order(parameters) == 1
    assert holds(parameters, state) and not holds(parameters, target)
    # under the ceiling the move is fitted as it is; below the order 2, nothing is retried
    assert attempt_within_limits(ceiling_climber(sizes[0], NAMES, KINDS), target, "kinetic",
                                 set())[0] == target
    low = ceiling_climber(10, NAMES, KINDS)
    attempt_within_limits(low, moved(dict(START), "kinetic", KINDS, 3), "kinetic", set())
    assert [move for move, _ in low.attempts] == ["kinetic", "kinetic-kinetic"]
    # the backward phase drops the family with its order, and the potential's order alone
    assert "kinetic_interaction" not in removed(parameters, "kinetic", KINDS, START)
    fewer = removed(parameters, "interaction", KINDS, START)
    assert fewer["interaction"] == 1 and "kinetic_interaction" not in fewer


def test_the_narrow_suffix_of_a_move():
    joint = moved(dict(START), "kinetic+interaction@k1", KINDS, 3)
    assert joint == dict(START, kinetic="configuration", interaction=2, kinetic_interaction=1)
    assert moved(dict(START), "kinetic@k1", KINDS, 3) is None  # already single coordinates
    assert moved(dict(START), "interaction@k1", KINDS, 3) is None  # constant coefficients
    # a later interaction move grows the potential's products alone
    assert kinetic_order(moved(joint, "interaction", KINDS, 3)) == 1
