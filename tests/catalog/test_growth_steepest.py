"""The steepest climb of grow_catalog (``steepest=True``) keeps the two rules of the default
climb: a move that the data-sized ceiling refuses is tried with constant kinetic
coefficients, and the second climb stops once it holds the first climb's end. Against three
masses on springs derived with sympy.physics.mechanics and integrated by scipy at 1e-10, and
against the stated rules on a climber whose catalogs are scored by a table."""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from sympy.physics import mechanics as me

from pysindy_xl.catalog import climb_ends as climb_ends_module
from pysindy_xl.catalog import grow_catalog
from pysindy_xl.catalog import growth as growth_module
from pysindy_xl.catalog.ascents import climb, steepest_climb
from pysindy_xl.catalog.automatic import AutomaticCatalog
from pysindy_xl.catalog.candidates import parameters_key
from pysindy_xl.catalog.climbs import Climber
from pysindy_xl.catalog.moves import REPEATED, START, holds, moved

STIFFNESS, HARDENING, COUPLING, DAMPING = 3.0, 2.0, 2.0, 0.1


def _three_masses():
    """Unit masses on a line: the first tied to the wall by a hardening spring
    ``1.5 x1^2 + 0.5 x1^4``, each next one to the one before by ``(x_{i+1} - x_i)^2``; viscous
    damping and a force on each. Returns ``accelerations(y (6,), u (3,))``."""
    x = me.dynamicsymbols("x1:4")
    v = me.dynamicsymbols("x1:4", 1)
    u = sp.symbols("u1:4")
    frame = me.ReferenceFrame("N")
    wall = me.Point("O")
    wall.set_vel(frame, 0)
    masses = []
    for k in range(3):
        point = wall.locatenew(f"P{k}", x[k] * frame.x)
        point.set_vel(frame, v[k] * frame.x)
        masses.append(me.Particle(f"m{k}", point, 1.0))
    masses[0].potential_energy = (STIFFNESS / 2 * x[0] ** 2 + HARDENING / 4 * x[0] ** 4
                                  + COUPLING / 2 * (x[1] - x[0]) ** 2
                                  + COUPLING / 2 * (x[2] - x[1]) ** 2)
    method = me.LagrangesMethod(me.Lagrangian(frame, *masses), list(x))
    method.form_lagranges_equations()
    forcing = method.forcing + sp.Matrix([u[k] - DAMPING * v[k] for k in range(3)])
    mass = sp.lambdify(x, method.mass_matrix)
    rhs = sp.lambdify([*x, *v, *u], forcing)

    def accelerations(y, force):
        return np.linalg.solve(np.asarray(mass(*y[:3]), float),
                               np.asarray(rhs(*y, *force), float)[:, 0])

    return accelerations


@pytest.fixture(scope="module")
def three_masses():
    accelerations = _three_masses()
    t = np.arange(0.0, 5.0, 2e-3)
    xs, us = [], []
    rng = np.random.default_rng(0)
    for _ in range(2):
        frequencies = rng.uniform(0.1, 1.0, (5, 3))
        phases = rng.uniform(0, 2 * np.pi, (5, 3))

        def force(time, frequencies=frequencies, phases=phases):
            return 0.8 * np.sin(2 * np.pi * frequencies * time + phases).sum(axis=0)

        y0 = np.r_[0.3 * rng.uniform(-1, 1, 3), rng.uniform(-0.5, 0.5, 3)]
        solution = solve_ivp(lambda time, y: np.r_[y[3:], accelerations(y, force(time))],
                             (t[0], t[-1]), y0, t_eval=t, method="DOP853", rtol=1e-10,
                             atol=1e-10)
        xs.append(solution.y[:3].T)
        us.append(np.array([force(time) for time in t]))
    return accelerations, t, xs, us


def _without_degree_pairs(monkeypatch):
    """Leave out the joint first moves with a degree (``"interaction+degree"``): on this rig
    that pair states the law from the first catalog at once, and the mechanism under test
    is reached only on the path through the single moves."""
    joint = growth_module.joint_moves

    def single_pairs(*args):
        return [m for m in joint(*args) if not set(m.split("+")) & set(REPEATED)]

    monkeypatch.setattr(growth_module, "joint_moves", single_pairs)


def test_the_steepest_climb_retries_a_refused_move_narrowed_and_drops_the_stand_in_after(
        three_masses, monkeypatch):
    """From the first catalog the steepest climb keeps the joint move (configuration-dependent
    kinetic coefficients over products of two coordinates, 72 terms): a stand-in. The
    quartic spring then needs degree 4, 147 terms there, over a ceiling of 100. The retry
    keeps the kinetic family the climb kept, over single coordinates' functions (75 terms,
    holding the law), before it would drop it (constant coefficients, 39 terms); the climb
    keeps it, and the backward phase drops the stand-in family (``"-kinetic"``): the law,
    39 terms. The model's accelerations match the sympy truth on fresh states."""
    accelerations, t, xs, us = three_masses
    monkeypatch.setattr(growth_module, "MAX_TERMS", 100)
    _without_degree_pairs(monkeypatch)
    found = grow_catalog(xs, [t, t], us, coordinates=["x1", "x2", "x3"], kinds="linear",
                         moves=("kinetic", "interaction", "degree"), steepest=True)
    assert found.max_terms == 100
    table = found.table()
    kept = [(step.move, step.terms) for step in found.steps if step.chosen]
    assert kept == [("start", 15), ("kinetic+interaction", 72), ("degree@k1", 75),
                    ("-kinetic", 39)], table
    refused = [step for step in found.steps if step.note.startswith("ceiling")]
    assert [(step.move, step.terms) for step in refused] == [("degree", 117), ("degree", 147)]
    # each refused move is followed by its retry: degree 3, then 4, kinetic coefficients
    # of single coordinates' functions (within the ceiling: no constant retry)
    first = next(k for k, step in enumerate(found.steps) if step is refused[0])
    assert [(step.move, step.terms) for step in found.steps[first:first + 4]] == [
        ("degree", 117), ("degree@k1", 63), ("degree", 147), ("degree@k1", 75)]
    assert not any(step.move == "degree-kinetic" for step in found.steps)
    assert (found.catalog.kinetic, found.catalog.degree, found.catalog.interaction) == (
        "constant", 4, 2)
    assert found.held_out_error < 1e-6
    coef = dict(zip(found.model.get_feature_names(), found.model.coefficients(), strict=True))
    scale = 2 * coef["L[x1_dot**2]"]  # the unit mass of x1
    np.testing.assert_allclose(scale, 1.0, rtol=1e-4)
    np.testing.assert_allclose(-4 * coef["L[x1**4]"] / scale, HARDENING, rtol=1e-4)
    rng = np.random.default_rng(7)
    states = np.c_[rng.uniform(-0.3, 0.3, (40, 3)), rng.uniform(-0.5, 0.5, (40, 3))]
    forces = rng.uniform(-1.0, 1.0, (40, 3))
    truth = np.array([accelerations(y, f) for y, f in zip(states, forces, strict=True)])
    predicted = found.model.predict(states[:, :3], states[:, 3:], forces)
    assert np.linalg.norm(predicted - truth) / np.linalg.norm(truth) < 1e-4


@pytest.mark.slow
def test_the_second_steepest_climb_is_given_the_first_ones_end(three_masses, monkeypatch):
    """With ``good_enough=0`` (and no noise floor) the growth climbs twice: the second
    steepest climb, from the second-best first move (the interaction), is given the first
    climb's end (the law beside stand-in kinetic coefficients of single coordinates'
    functions) and ends on the law itself."""
    _, t, xs, us = three_masses
    monkeypatch.setattr(growth_module, "MAX_TERMS", 100)
    _without_degree_pairs(monkeypatch)
    calls = []

    def recorded(climber, order, forced=None, end=None):
        out = steepest_climb(climber, order, forced, end)
        calls.append((forced, end, out[0]))
        return out

    monkeypatch.setattr(climb_ends_module, "steepest_climb", recorded)
    found = grow_catalog(xs, [t, t], us, coordinates=["x1", "x2", "x3"], kinds="linear",
                         moves=("kinetic", "interaction", "degree"), steepest=True,
                         good_enough=0.0, noise_floor=False)
    law = dict(START, interaction=2, degree=4)
    # the first climb ends on the law with the stand-in kinetic coefficients kept over single
    # coordinates' functions (the refused degree move's retry keeps them); the backward
    # phase drops them
    end = dict(law, kinetic="configuration", kinetic_interaction=1)
    assert [(forced, end) for forced, end, _ in calls] == [(None, None), ("interaction", end)]
    assert calls[0][2] == end and calls[1][2] == law  # (the second climb reaches the law)
    assert (found.catalog.kinetic, found.catalog.degree, found.catalog.interaction) == (
        "constant", 4, 2)


# -- the climbs' rules on catalogs scored by a table -------------------------------------------
FIXED = {"coordinates": ["x", "y"], "kinds": ["linear", "linear"]}


class _ScoredFits:
    """Catalogs scored by ``criterion(parameters)``, those over ``max_terms`` refused as the
    ceiling; the catalogs asked for are recorded."""

    def __init__(self, criterion, max_terms):
        self.criterion, self.max_terms, self.asked = criterion, max_terms, []

    @staticmethod
    def fit_key(parameters):
        return parameters_key(parameters)

    def get(self, parameters, ahead=()):
        self.asked.append(dict(parameters))
        size = AutomaticCatalog(**FIXED, **parameters).n_terms
        if size > self.max_terms:
            return {"description": "", "terms": size, "active": 0, "time_error": np.inf,
                    "region_error": np.inf, "criterion": np.inf, "definite": 0.0,
                    "note": f"ceiling: {size} > max_terms {self.max_terms}"}
        value = float(self.criterion(parameters))
        return {"description": "", "terms": size, "active": size, "time_error": value,
                "region_error": value, "criterion": value}


def _climber(criterion, max_terms=1000, retry_kinetic=True):
    fits = _ScoredFits(criterion, max_terms)
    climber = Climber(fits, None, FIXED, FIXED["kinds"], tolerance=0.05, good_enough=1e-6,
                      physical=False, retry_kinetic=retry_kinetic, criterion="forces")
    assert climber.start().criterion == 1.0
    return climber, fits


def _families(parameters) -> float:
    """Each of three families lowers the criterion by its factor (a law found family by
    family)."""
    factors = {"interaction": 0.5, "degree": 0.7, "coulomb": 0.8}
    return float(np.prod([factor for family, factor in factors.items()
                          if holds(parameters, moved(START, family, FIXED["kinds"], 2))]))


@pytest.mark.parametrize("steepest", [False, True])
def test_a_second_climb_stops_once_it_holds_the_first_climbs_end(steepest):
    """Every family lowers the criterion: a climb without an end takes them all; one given
    the first climb's end stops at the first kept catalog that holds it (every family of the
    end at least as far grown), whichever way it climbs, and tries nothing beyond it."""
    order = ["interaction", "degree", "coulomb", "kinetic"]
    climber, _ = _climber(_families)
    full, best, _ = steepest_climb(climber, order) if steepest else climb(climber, order)
    assert (full["interaction"], full["degree"], full["dissipation"]) == (
        2, 3, ("viscous", "coulomb"))
    assert best.criterion == pytest.approx(0.5 * 0.7 * 0.8)
    end = moved(START, "interaction", FIXED["kinds"], 2)
    climber, fits = _climber(_families)
    state, best, path = (steepest_climb(climber, order, "coulomb", end) if steepest
                         else climb(climber, ["coulomb", *order], end))
    assert holds(state, end) and not holds(state, full)
    assert state == dict(end, dissipation=("viscous", "coulomb"))
    assert best.criterion == pytest.approx(0.5 * 0.8) and path[-1] is best
    assert [step.move for step in path] == ["coulomb", "interaction"]
    # no catalog beyond it was tried: the climb stopped there
    assert not [p for p in fits.asked if holds(p, state) and p != state]


def _stand_in(parameters) -> float:
    """The law needs the interaction and degree 4 with constant kinetic coefficients;
    configuration-dependent ones with the interaction are a stand-in that beats every other
    catalog of one move from the first."""
    interaction = parameters["interaction"] == 2
    if parameters["kinetic"] == "configuration":
        return 0.3 if interaction else 1.0
    if interaction:
        return {2: 0.5, 3: 0.4}.get(parameters["degree"], 0.01)  # degree 4 and above: the law
    return 1.0 if parameters["degree"] == 2 else 0.9


@pytest.mark.parametrize("steepest", [False, True])
def test_a_move_the_ceiling_refuses_is_tried_with_constant_kinetic_coefficients(steepest):
    """The climb keeps the stand-in, whose degree moves are then over the ceiling (its
    size, 25 terms); with constant kinetic coefficients they are within it and degree 4
    states the law: both climbs try ``"degree-kinetic"`` after each refused degree move and
    keep the law. A climb that may not retry (an explicit ``max_terms``) keeps the
    stand-in."""
    order = ["kinetic+interaction", "interaction", "degree", "kinetic"]
    stand_in = moved(START, "kinetic+interaction", FIXED["kinds"], 2)
    ceiling = AutomaticCatalog(**FIXED, **stand_in).n_terms
    assert ceiling == 25
    climber, _ = _climber(_stand_in, ceiling)
    state, best, path = steepest_climb(climber, order) if steepest else climb(climber, order)
    assert [step.move for step in path] == ["kinetic+interaction", "degree-kinetic"]
    assert state == dict(START, interaction=2, degree=4) and best.criterion == 0.01
    # (a move whose constant-kinetic retry is the catalog itself is retried with kinetic
    # coefficients of single coordinates, "kinetic@k1": over this ceiling too)
    narrow = [step for step in climber.steps if step.move.endswith("@k1")]
    assert all(step.note.startswith("ceiling") for step in narrow)
    steps = [(step.move, step.terms) for step in climber.steps if step not in narrow]
    refused = steps.index(("degree", 35))
    assert steps[refused:refused + 4] == [
        ("degree", 35), ("degree-kinetic", 14), ("degree", 43), ("degree-kinetic", 19)]
    # from the law (degree 4) the climb looks further: degree 5 (no better), 6 (over the ceiling)
    assert steps[refused + 4:] == [("degree", 25), ("degree", 32)]
    assert all(step.note.startswith("ceiling") == (step.terms > ceiling)
               for step in climber.steps)
    climber, _ = _climber(_stand_in, ceiling, retry_kinetic=False)
    state, best, path = steepest_climb(climber, order) if steepest else climb(climber, order)
    assert [step.move for step in path] == ["kinetic+interaction"] and state == stand_in
    assert not [step for step in climber.steps if step.move.endswith("-kinetic")]
