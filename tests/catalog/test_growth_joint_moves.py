"""grow_catalog's joint first move and its physical keep rule, against a double pendulum
derived independently with sympy.physics.mechanics and integrated by scipy at 1e-10."""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from sympy.physics import mechanics as me

from pysindy_xl.catalog import grow_catalog

G = 9.81


def _double_pendulum(m1=1.0, m2=0.6, l1=0.7, l2=0.5, c=0.05):
    """Two point masses on rods, angles from the vertical, viscous damping ``c`` and a torque
    on each angle; returns ``accelerations(y (4,), tau (2,))`` and the mass matrix ``M(q)``."""
    a, b = me.dynamicsymbols("a b")
    ad, bd = me.dynamicsymbols("a b", 1)
    ta, tb = sp.symbols("tau_a tau_b")
    frame = me.ReferenceFrame("N")
    pivot = me.Point("O")
    pivot.set_vel(frame, 0)
    first = pivot.locatenew("P1", l1 * (sp.sin(a) * frame.x - sp.cos(a) * frame.y))
    second = first.locatenew("P2", l2 * (sp.sin(b) * frame.x - sp.cos(b) * frame.y))
    first.set_vel(frame, first.pos_from(pivot).dt(frame))
    second.set_vel(frame, second.pos_from(pivot).dt(frame))
    bodies = [me.Particle("p1", first, m1), me.Particle("p2", second, m2)]
    bodies[0].potential_energy = m1 * G * first.pos_from(pivot).dot(frame.y)
    bodies[1].potential_energy = m2 * G * second.pos_from(pivot).dot(frame.y)
    lagrangian = me.Lagrangian(frame, *bodies)
    method = me.LagrangesMethod(lagrangian, [a, b])
    method.form_lagranges_equations()
    forcing = method.forcing + sp.Matrix([ta - c * ad, tb - c * bd])
    symbols = [a, b, ad, bd, ta, tb]
    mass = sp.lambdify(symbols[:2], method.mass_matrix)
    rhs = sp.lambdify(symbols, forcing)

    def accelerations(y, tau):
        return np.linalg.solve(np.asarray(mass(*y[:2]), float),
                               np.asarray(rhs(*y, *tau), float)[:, 0])

    return accelerations, mass


def _runs(accelerations, seeds=(0, 1), duration=6.0, rate=200.0):
    t = np.arange(0.0, duration, 1.0 / rate)
    xs, us = [], []
    for seed in seeds:
        rng = np.random.default_rng(seed)
        frequencies, phases = rng.uniform(0.2, 1.2, (2, 3)), rng.uniform(0, 2 * np.pi, (2, 3))

        def torque(time, frequencies=frequencies, phases=phases):
            return 1.5 * np.sin(2 * np.pi * frequencies * time + phases).sum(axis=1)

        solution = solve_ivp(lambda time, y: np.r_[y[2:], accelerations(y, torque(time))],
                             (t[0], t[-1]), np.r_[rng.uniform(-1, 1, 2), 0.0, 0.0], t_eval=t,
                             method="DOP853", rtol=1e-10, atol=1e-10)
        xs.append(solution.y[:2].T)
        us.append(np.array([torque(time) for time in t]))
    return t, xs, us


@pytest.fixture(scope="module")
def pendulum():
    accelerations, mass = _double_pendulum()
    t, xs, us = _runs(accelerations)
    return accelerations, mass, t, xs, us


def _fresh_error(model, accelerations, seed: int) -> float:
    """Relative error of ``model``'s accelerations against the sympy truth on 40 random
    states and torques."""
    rng = np.random.default_rng(seed)
    states = np.c_[rng.uniform(-1, 1, (40, 2)), rng.uniform(-2, 2, (40, 2))]
    tau = rng.uniform(-1.5, 1.5, (40, 2))
    truth = np.array([accelerations(y, u) for y, u in zip(states, tau, strict=True)])
    predicted = model.predict(states[:, :2], states[:, 2:], tau)
    return float(np.linalg.norm(predicted - truth) / np.linalg.norm(truth))


def test_the_coupling_is_a_first_move_of_its_own(pendulum):
    """``cos(a - b) a_dot b_dot`` needs configuration-dependent kinetic coefficients over
    products of both angles' functions: the pair of moves is tried from the first catalog,
    beside each move alone, and the growth keeps it; the model's accelerations match the
    sympy truth on fresh states."""
    accelerations, _, t, xs, us = pendulum
    found = grow_catalog(xs, [t, t], us, coordinates=["a", "b"], kinds="angle",
                         moves=("kinetic", "interaction"), tolerance=0.05)
    moves = [step.move for step in found.steps]
    assert moves[:4] == ["start", "kinetic", "interaction", "kinetic+interaction"]
    assert found.steps[3].chosen
    assert found.catalog.interaction == 2 and found.catalog.kinetic == "configuration"
    # the joint catalog spans the coupling: cos(a - b) = cos(a) cos(b) + sin(a) sin(b)
    terms = set(found.catalog.lagrange_terms())
    (a, b), (ad, bd) = found.model.feature_library_.coords.q, found.model.feature_library_.coords.qd
    assert {sp.cos(a) * sp.cos(b) * ad * bd, sp.sin(a) * sp.sin(b) * ad * bd} <= terms
    assert _fresh_error(found.model, accelerations, seed=3) < 0.01


def test_the_physical_steepest_climb_keeps_only_positive_definite_fits(pendulum):
    """With ``physical``, once a kept catalog's fits have a positive definite mass matrix on
    all their training states, every catalog kept after it has too, and so has the chosen
    model on the data, as the sympy mass matrix is; a catalog whose fits have not is
    reported. The steepest climb (the best move from each kept catalog) keeps the coupling,
    and the model's accelerations match the sympy truth."""
    accelerations, mass, t, xs, us = pendulum
    noisy = [x + 0.01 * x.std(axis=0) * np.random.default_rng(k).normal(size=x.shape)
             for k, x in enumerate(xs)]
    found = grow_catalog(noisy, [t, t], us, coordinates=["a", "b"], kinds="angle",
                         moves=("kinetic", "interaction", "trig_degree"), physical=True,
                         steepest=True)
    table = found.table()
    kept = [step.definite for step in found.steps if step.chosen]
    assert kept[-1] == 1.0 and all(later == 1.0 for k, value in enumerate(kept)
                                   for later in kept[k:] if value == 1.0), table
    # the first catalog (constant kinetic coefficients, no product of the angles) is fitted
    # without an inertia of its own: reported
    assert found.steps[0].definite == 0.0 and "not positive definite" in found.steps[0].note
    assert all(0.0 <= step.definite <= 1.0 for step in found.steps)
    assert found.model.mass_matrix_check_["positive_definite_fraction"] == 1.0
    true_mass = np.array([np.asarray(mass(*q), float) for q in xs[0][::50]])
    assert np.all(np.linalg.eigvalsh(true_mass) > 0)
    assert (found.catalog.interaction, found.catalog.kinetic) == (2, "configuration")
    assert _fresh_error(found.model, accelerations, seed=4) < 0.02
    with pytest.raises(TypeError, match="steepest"):
        grow_catalog(noisy, [t, t], us, coordinates=["a", "b"], kinds="angle",
                     moves=("kinetic",), steepest=1)
    with pytest.raises(TypeError, match="physical"):
        grow_catalog(noisy, [t, t], us, coordinates=["a", "b"], kinds="angle",
                     moves=("kinetic",), physical="yes")
