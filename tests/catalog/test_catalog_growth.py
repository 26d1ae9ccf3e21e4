"""grow_catalog against systems derived independently with sympy.physics.mechanics."""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from support.growth import scalar_laws
from sympy.physics import mechanics as me

import pysindy_xl as px
from pysindy_xl.catalog import grow_catalog

G = 9.81


def _torsion_pendulum(m=0.5, length=0.8, k=3.0, c=0.05):
    """Point mass on a rod with a torsion spring ``k q^2 / 2`` at the pivot, viscous damping and
    a torque, by LagrangesMethod; returns (accelerations(q, qd, tau), true forces(q, qd, qdd))."""
    q = me.dynamicsymbols("q")
    qd = me.dynamicsymbols("q", 1)
    tau = sp.Symbol("tau")
    frame = me.ReferenceFrame("N")
    rod = frame.orientnew("A", "Axis", (q, frame.z))
    pivot = me.Point("O")
    pivot.set_vel(frame, 0)
    bob = pivot.locatenew("P", length * rod.y * -1)
    bob.v2pt_theory(pivot, frame, rod)
    particle = me.Particle("p", bob, m)
    particle.potential_energy = -m * G * length * sp.cos(q) + k * q ** 2 / 2
    lagrangian = me.Lagrangian(frame, particle)
    method = me.LagrangesMethod(lagrangian, [q], forcelist=[(rod, (tau - c * qd) * frame.z)],
                                frame=frame)
    method.form_lagranges_equations()
    return scalar_laws(method, q, qd, tau)


def _runs(accelerations, seeds, duration=8.0, rate=200.0, amplitude=2.5, forced=True):
    t = np.arange(0.0, duration, 1.0 / rate)
    xs, us = [], []
    for seed in seeds:
        rng = np.random.default_rng(seed)
        frequencies, phases = rng.uniform(0.2, 1.5, 4), rng.uniform(0, 2 * np.pi, 4)

        def torque(time, frequencies=frequencies, phases=phases):
            return amplitude * np.sin(2 * np.pi * frequencies * time + phases).sum() / 2 \
                if forced else 0.0

        solution = solve_ivp(lambda time, y: [y[1], accelerations(y[0], y[1], torque(time))],
                             (t[0], t[-1]), [rng.uniform(-1, 1), rng.uniform(-2, 2)],
                             t_eval=t, method="DOP853", rtol=1e-10, atol=1e-10)
        xs.append(solution.y[0][:, None])
        us.append(np.array([[torque(time)] for time in t]))
    return t, xs, us


def test_growth_finds_a_torsion_spring_that_sines_only_imitate():
    accelerations, forces = _torsion_pendulum()
    t, xs, us = _runs(accelerations, seeds=(0, 1))
    noisy = [x + 0.01 * x.std() * np.random.default_rng(7).normal(size=x.shape) for x in xs]
    found = grow_catalog(noisy, [t, t], us, coordinates=["theta"], kinds="angle",
                         moves=("trig_degree", "angle_degree"))
    kept = [step.move for step in found.steps if step.chosen]
    assert "angle_degree" in kept
    # the right structure: the forces off the trajectories, in a box twice as wide
    span = np.abs(np.vstack(xs)).max()
    rng = np.random.default_rng(3)
    q = rng.uniform(-2 * span, 2 * span, 400)
    qd, qdd = rng.uniform(-4, 4, 400), rng.uniform(-10, 10, 400)
    truth = forces(q, qd, qdd)
    predicted = found.model.predict_forces(q[:, None], qd[:, None], qdd[:, None])[:, 0]
    assert np.linalg.norm(predicted - truth) / np.linalg.norm(truth) < 0.05
    assert found.held_out_error < 0.05
    table = found.table()
    assert "angle_degree" in table and "criterion" in table.splitlines()[0]


def test_unforced_growth_predicts_accelerations():
    accelerations, _ = _torsion_pendulum()
    t, xs, _ = _runs(accelerations, seeds=(4, 5, 6), duration=10.0, forced=False)
    found = grow_catalog(xs, [t, t, t], None, coordinates=["theta"], kinds="angle",
                         moves=("angle_degree",))
    assert found.criterion == "accelerations"
    q = np.linspace(-1.5, 1.5, 50)
    qd = np.linspace(-2, 2, 50)
    predicted = found.model.predict(q[:, None], qd[:, None])[:, 0]
    truth = accelerations(q, qd, 0.0)
    assert np.linalg.norm(predicted - truth) / np.linalg.norm(truth) < 0.05


def test_unforced_growth_prefers_the_torsion_spring_to_a_stand_in():
    """Unforced, a cos(theta) in the inertia imitates the torsion spring along the recorded
    path as well as theta^2 states it; tried first, it would stay in the catalog. The moves go
    in the order of what each achieves alone, and theta^2 wins on the farthest block."""
    accelerations, _ = _torsion_pendulum()
    t, xs, _ = _runs(accelerations, seeds=(4, 5), duration=10.0, forced=False)
    noisy = [x + 0.01 * x.std() * np.random.default_rng(7).normal(size=x.shape) for x in xs]
    found = grow_catalog(noisy, [t, t], None, coordinates=["theta"], kinds="angle",
                         moves=("kinetic", "trig_degree", "angle_degree"))
    assert found.catalog.kinetic == "constant" and found.catalog.angle_degree >= 2
    first = [step.move for step in found.steps[1:4]]
    assert first == ["kinetic", "trig_degree", "angle_degree"]  # each tried alone first
    span = np.abs(np.vstack(xs)).max()
    q = np.linspace(-1.5 * span, 1.5 * span, 60)
    qd = np.zeros_like(q)
    predicted = found.model.predict(q[:, None], qd[:, None])[:, 0]
    truth = accelerations(q, qd, 0.0)
    assert np.linalg.norm(predicted - truth) / np.linalg.norm(truth) < 0.01


def test_growth_refuses_bad_data():
    t = np.linspace(0, 10, 1001)
    x = np.c_[np.sin(t), np.full_like(t, 0.3)]
    with pytest.raises(ValueError, match="x: coordinate 'y' is constant"):
        grow_catalog(x, t, np.c_[np.cos(t), np.cos(t)], coordinates=["x", "y"])
    short = np.sin(t[:12])[:, None]
    with pytest.raises(ValueError, match="x: 12 samples of 1 coordinates are too short"):
        grow_catalog(short, t[:12], np.cos(t[:12])[:, None], coordinates=["x"])
    with pytest.raises(ValueError, match="max_terms: the smallest catalog has"):
        grow_catalog(np.sin(t)[:, None], t, np.cos(t)[:, None], coordinates=["x"], max_terms=2)
    with pytest.raises(ValueError, match="kinds: coordinate 'x' has the unknown kind 'rotary'"):
        grow_catalog(np.sin(t)[:, None], t, np.cos(t)[:, None], coordinates=["x"],
                     kinds="rotary")
    with pytest.raises(ValueError, match="moves: unknown"):
        grow_catalog(np.sin(t)[:, None], t, np.cos(t)[:, None], coordinates=["x"],
                     moves=("everything",))
    with pytest.raises(ValueError, match="coordinates: expected 1 names"):
        grow_catalog(np.sin(t)[:, None], t, np.cos(t)[:, None], coordinates=["x", "y"])


_T = np.linspace(0, 10, 1001)
_X, _U = np.sin(_T)[:, None], np.cos(_T)[:, None]


@pytest.mark.parametrize("x, t, u, options, error, message", [
    (np.where(_T[:, None] > 5, np.nan, _X), _T, _U, {}, ValueError, "x: contains NaN or inf"),
    (_X + 1j * _X, _T, _U, {}, TypeError, "x: expected real numbers, got complex values"),
    (_X.astype(str), _T, _U, {}, TypeError, "x: expected real numbers, got an array of str"),
    (_X, _T, _U > 0, {}, TypeError, "u: expected real numbers, got booleans"),
    (_X, _T, _U[1:], {}, ValueError, r"u: expected shape \(1001, 1\), got \(1000, 1\)"),
    (_X, _T[::-1], _U, {}, ValueError, "t: times must be strictly increasing"),
    (_X, _T, _U, {"progress": 3}, TypeError, "progress: expected a callable"),
])
def test_growth_refuses_what_the_model_refuses(x, t, u, options, error, message):
    """The data are checked as XLSINDy.fit checks them: nothing is cast or dropped silently,
    and NaN is named, not taken for a constant coordinate."""
    with pytest.raises(error, match=message):
        grow_catalog(x, t, u, coordinates=["x"], **options)


@pytest.mark.parametrize("options, error, message", [
    ({"search_optimizer": "fast"}, ValueError, "search_optimizer: expected 'auto', one of"),
    ({"search_optimizer": 3}, TypeError, "search_optimizer: expected a catalog optimizer"),
    ({"search_samples": 0}, ValueError, "search_samples: expected an integer >= 1 or None"),
    ({"search_samples": "all"}, TypeError, "search_samples: expected an integer >= 1"),
    ({"coordinates": None}, ValueError, "coordinates: expected a non-empty list of names"),
    ({"coordinates": ["x", 3]}, TypeError, "coordinates: expected names"),
    ({"coordinates": "x, y, x"}, ValueError, r"coordinates: the names \['x'\] are given more"),
])
def test_growth_options_are_refused_by_name(options, error, message):
    """A search optimizer that no fit accepts is refused before the search (its fits would
    all fail, and the growth end on the final fit alone)."""
    x = np.c_[_X, np.cos(1.3 * _T), np.sin(0.7 * _T)]
    with pytest.raises(error, match=message):
        grow_catalog(x, _T, np.c_[_U, _U, _U], **{"coordinates": ["x", "y", "z"], **options})


def test_ceiling_is_reported_in_the_path():
    t = np.linspace(0, 20, 2001)
    x = (np.sin(t) + 0.5 * np.sin(2.7 * t))[:, None]
    xdd = (-np.sin(t) - 3.645 * np.sin(2.7 * t))[:, None]
    found = grow_catalog(x, t, 2 * xdd + 3 * x + x ** 3, coordinates=["x"], max_terms=5,
                         moves=("degree",))
    assert any(step.note.startswith("ceiling") for step in found.steps)
    assert found.catalog.n_terms <= 5
    assert isinstance(found.catalog, px.AutomaticCatalog)


def test_mixed_forcing_grows_coupled_oscillators():
    """Force on x1 only: 0.5 x1'' + ... = tau, x2 free; the coupling spring needs x1 x2."""
    c = px.Coordinates(["x1", "x2"])
    (x1, x2), (v1, v2) = c.q, c.qd
    lagrangian = (v1 ** 2 / 2 + 0.75 * v2 ** 2 - x1 ** 2 - 1.5 * x2 ** 2
                  - 0.8 * (x1 - x2) ** 2)
    method = me.LagrangesMethod(lagrangian.subs({x1: me.dynamicsymbols("a"),
                                                 x2: me.dynamicsymbols("b"),
                                                 v1: me.dynamicsymbols("a", 1),
                                                 v2: me.dynamicsymbols("b", 1)}),
                                [me.dynamicsymbols("a"), me.dynamicsymbols("b")])
    method.form_lagranges_equations()
    mass = np.array(method.mass_matrix, dtype=float)
    a, b = me.dynamicsymbols("a"), me.dynamicsymbols("b")
    stiffness = -np.array(method.forcing.jacobian([a, b]), dtype=float)
    t = np.arange(0.0, 10.0, 0.005)
    xs, us = [], []
    for seed in (0, 1):
        rng = np.random.default_rng(seed)
        frequencies, phases = rng.uniform(0.1, 0.8, 4), rng.uniform(0, 2 * np.pi, 4)

        def force(time, frequencies=frequencies, phases=phases):
            return np.array([np.sin(2 * np.pi * frequencies * time + phases).sum(), 0.0])

        solution = solve_ivp(
            lambda time, y: np.r_[y[2:], np.linalg.solve(mass, force(time) - stiffness @ y[:2])],
            (t[0], t[-1]), np.r_[rng.uniform(-0.5, 0.5, 2), 0, 0], t_eval=t, method="DOP853",
            rtol=1e-10, atol=1e-10)
        xs.append(solution.y[:2].T)
        us.append(np.array([force(time) for time in t]))
    found = grow_catalog(xs, [t, t], us, coordinates=["x1", "x2"], moves=("interaction",))
    assert found.criterion == "forces"
    q = np.random.default_rng(5).uniform(-1, 1, (50, 2))
    qd = np.random.default_rng(6).uniform(-1, 1, (50, 2))
    u = np.c_[np.random.default_rng(7).uniform(-1, 1, 50), np.zeros(50)]
    truth = np.linalg.solve(mass, (u - q @ stiffness.T).T).T
    predicted = found.model.predict(q, qd, u)
    assert np.linalg.norm(predicted - truth) / np.linalg.norm(truth) < 0.02


@pytest.mark.slow
def test_unforced_growth_finds_a_coupling_that_takes_two_moves():
    """Unforced spring pendulum: the coupling needs r^2 theta_dot^2 (kinetic move) and
    r cos(theta) (interaction move), each coordinate's equation judged on its own scale."""
    r, th = me.dynamicsymbols("r theta")
    rd, thd = me.dynamicsymbols("r theta", 1)
    lagrangian = (rd ** 2 + r ** 2 * thd ** 2) / 2 + G * r * sp.cos(th) - 10 * (r - 1) ** 2
    method = me.LagrangesMethod(lagrangian, [r, th])
    method.form_lagranges_equations()
    symbols = [r, th, rd, thd]
    mass = sp.lambdify(symbols, method.mass_matrix)
    forcing = sp.lambdify(symbols, method.forcing)

    def accelerations(y):
        return np.linalg.solve(np.asarray(mass(*y), float), np.asarray(forcing(*y), float)[:, 0])

    t = np.arange(0.0, 10.0, 0.001)
    xs = []
    for seed in (2, 3):
        rng = np.random.default_rng(seed)
        y0 = np.r_[1.5 + 0.45 * rng.uniform(-1, 1), 0.75 * rng.uniform(-1, 1),
                   rng.uniform(-1, 1, 2)]
        solution = solve_ivp(lambda time, y: np.r_[y[2:], accelerations(y)], (t[0], t[-1]), y0,
                             t_eval=t, method="DOP853", rtol=1e-10, atol=1e-10)
        xs.append(solution.y[:2].T)
    found = grow_catalog(xs, [t, t], None, coordinates=["r", "theta"], kinds={"theta": "angle"},
                         moves=("kinetic", "interaction", "angle_degree"))
    assert found.catalog.interaction == 2 and found.catalog.kinetic == "configuration"
    rng = np.random.default_rng(9)
    states = np.c_[rng.uniform(1.2, 1.8, 40), rng.uniform(-0.8, 0.8, 40),
                   rng.uniform(-1, 1, (40, 2))]
    truth = np.array([accelerations(y) for y in states])
    predicted = found.model.predict(states[:, :2], states[:, 2:])
    assert np.linalg.norm(predicted - truth) / np.linalg.norm(truth) < 0.01


@pytest.mark.slow
def test_growth_looks_two_moves_ahead_when_no_single_move_helps():
    """The forced double pendulum of ``benchmarks/generic_systems.py`` at 1 % noise, seed 2:
    its coupling ``cos(a - b) a_dot b_dot`` needs products of the two angles' functions and
    configuration-dependent kinetic coefficients at once; each move alone scores worse than the
    start (42 % held-out, 46 % and 59 %), so a one-move climb stops at the start catalog. The
    look-ahead over pairs of moves finds the law; accelerations checked against the sympy truth
    integrated at 1e-10 on fresh states."""
    import pathlib
    import sys
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "benchmarks"))
    import generic_systems as bench

    system = bench.systems()["double_pendulum"]
    truth = bench.Truth(system)
    runs = bench.make_runs(system, truth, 2, True)
    xs = bench._noisy(runs, 0.01, 2)
    found = grow_catalog(xs, [r["t"] for r in runs], [r["u"] for r in runs],
                         coordinates=list(system["coords"].names), kinds=system["kinds"])
    assert any("+" in step.move and step.chosen for step in found.steps)
    assert found.catalog.interaction == 2 and found.catalog.kinetic == "configuration"
    test = bench.make_runs(system, truth, 502, True, n_runs=1, duration=2.0)[0]
    predicted = found.model.predict(test["q"], test["qd"], test["u"])
    error = np.linalg.norm(predicted - test["qdd"]) / np.linalg.norm(test["qdd"])
    assert error < 0.02


def test_cross_validated_growth_holds_out_every_block():
    """``cross_validate``: one fit per held-out block; the hardening spring's law is found
    as with the two blocks at once, and a non-boolean is refused."""
    t = np.linspace(0, 20, 2001)
    x = np.c_[np.sin(t) + 0.5 * np.sin(2.7 * t)]
    xdd = -np.sin(t) - 3.645 * np.sin(2.7 * t)
    u = 2 * xdd[:, None] + 3 * x + x ** 3
    found = grow_catalog(x, t, u, coordinates=["x"], moves=("degree",), cross_validate=True)
    assert [(step.move, step.terms, step.chosen) for step in found.steps] == \
        [("start", 4, True), ("degree", 5, False), ("degree", 6, True)]
    coef = dict(zip(map(str, found.model.feature_library_.feature_terms_),
                    found.model.coef_, strict=False))
    assert coef["x**4"] == pytest.approx(-0.25, rel=1e-3)
    assert found.held_out_error < 1e-3
    with pytest.raises(TypeError, match="cross_validate"):
        grow_catalog(x, t, u, coordinates=["x"], cross_validate="yes")
