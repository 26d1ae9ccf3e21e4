"""Springs on a difference of two coordinates (a joint's deflection ``l - m``).

Two mechanisms: the backward phase exchanges a degree family grown several steps from its
lowest degree too (a trigonometric stand-in grown to ``sin/cos degree 3`` for ``(a - b)^2``
is left at once, not one degree at a time), and the family ``differences`` states such a
spring in one column ``(l - m)^2`` (the default move ``"differences"``), where the products
of powers need three (``m^2, l m, l^2``) that the sparse selection must keep together and
``cos(l - m) = cos(l) cos(m) + sin(l) sin(m)`` stands in with two.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import pysindy_xl as px
from pysindy_xl.catalog.backward import _stepped_down, backward_phase, removed
from pysindy_xl.catalog.candidates import parameters_key
from pysindy_xl.catalog.keep_rules import single_keeps
from pysindy_xl.catalog.moves import MOVES, START, holds, moved
from pysindy_xl.catalog.path import GrowthStep

KINDS = ["angle", "angle"]


class _Climber:
    """The part of :class:`~pysindy_xl.catalog.climbs.Climber` that the backward phase uses,
    with made-up criteria: the law exact, a stand-in 1e-3 growing as it loses degrees, a
    catalog without the coupling's families 1."""

    def __init__(self, law):
        self.law, self.kinds, self.tolerance, self.physical = law, KINDS, 0.05, False
        self.tried = []

    def size(self, parameters):
        return px.AutomaticCatalog(["a", "b"], kinds=KINDS, **parameters).n_terms

    def moved(self, state, move, skip=0):
        return moved(state, move, self.kinds, 2, skip)

    def attempt(self, parameters, move, ahead=()):
        self.tried.append(move)
        exact = parameters_key(parameters) == parameters_key(self.law)
        coupled = parameters["interaction"] == 2 and parameters["kinetic"] == "configuration"
        criterion = (1e-10 if exact else 1e-3 * (4 - parameters["trig_degree"]) if coupled
                     else 1.0)
        return GrowthStep(move, "", self.size(parameters), 8, criterion, criterion, criterion,
                          False)

    def keeps(self, step, best):
        return single_keeps(step, best, self.tolerance)

    def compared(self, step, best):
        return step.criterion, best.criterion

    def settled(self, step, floor=True):
        return step.criterion < 1e-8

    def refused(self, step):
        return False


def test_backward_exchange_leaves_a_family_grown_several_degrees_at_once():
    # the climb's end: sines and cosines to degree 3 standing in for (a - b)^2; the law is
    # the catalog with degree 1 and the angles' powers (a^2, a b, b^2)
    end = dict(START, trig_degree=3, interaction=2, kinetic="configuration")
    law = dict(START, trig_degree=1, angle_degree=2, interaction=2, kinetic="configuration")
    climber = _Climber(law)
    best = GrowthStep("trig_degree", "", climber.size(end), 8, 1e-3, 1e-3, 1e-3, True)
    state, best, path = backward_phase(climber, end, best, [], MOVES)
    assert parameters_key(state) == parameters_key(law), (state, climber.tried)
    assert best.criterion == 1e-10
    # the one-step exchange (degree 2 beside the powers) was tried first, and refused
    assert "-trig_degree+angle_degree" in climber.tried
    assert path[-1].move == "-trig_degree*2+angle_degree"
    # the angles' powers are exchanged one step at a time only (all of them out for sines and
    # cosines one degree up is the stand-in that the blocks cannot tell from a spring at noise)
    assert len(_stepped_down(dict(START, angle_degree=3), "angle_degree", KINDS)) == 1


def test_difference_family_terms_sizes_and_refusals():
    catalog = px.AutomaticCatalog(["m", "l"], kinds="angle", kinetic="constant", differences=2)
    assert str(catalog.lagrange_terms()[-1]) == "(l - m)**2"
    assert catalog.n_terms == px.AutomaticCatalog(["m", "l"], kinds="angle",
                                                  kinetic="constant").n_terms + 1
    assert "differences ..^2" in catalog.describe()
    # pairs of one kind only: a cart and a pendulum have no difference
    mixed = px.AutomaticCatalog(["x1", "x2", "th"], kinds=["linear", "linear", "angle"],
                                kinetic="constant", differences=4)
    assert [str(t) for t in mixed.lagrange_terms() if "x1 + x2" in str(t)] == [
        f"(-x1 + x2)**{k}" for k in (2, 3, 4)]
    with pytest.raises(ValueError, match="differences"):
        px.AutomaticCatalog(["m", "l"], kinds="angle", differences=1).lagrange_terms()
    with pytest.raises(ValueError, match="differences"):
        px.AutomaticCatalog(["m", "l"], kinds="angle", differences=-1).lagrange_terms()
    # the move grows it by degree steps and the backward phase takes them back
    assert moved(START, "differences", KINDS, 2)["differences"] == 2
    assert moved(START, "differences", KINDS, 2, skip=1)["differences"] == 3
    assert moved(dict(START, differences=4), "differences", KINDS, 2) is None
    assert moved(START, "differences", ["linear", "angle"], 2) is None
    assert removed(dict(START, differences=2), "differences", KINDS, START)["differences"] == 0
    assert removed(dict(START, differences=3), "differences", KINDS, START)["differences"] == 2
    assert holds(dict(START, differences=2), START) and not holds(START, dict(START,
                                                                           differences=2))


def _joint_arm_runs(noise, motor=0.05, link=0.1, weight=1.4715, stiffness=5.0):
    """Forced runs of a flexible-joint arm (motor angle m, link angle l, joint spring
    ``stiffness (l - m)^2 / 2``, gravity on the link, viscous friction 0.05), positions with
    Gaussian noise of ``noise`` times their standard deviation; and its forces."""
    damping = 0.05

    def forces(q, qd, qdd):
        spring = stiffness * (q[:, 1] - q[:, 0])
        return np.c_[motor * qdd[:, 0] - spring + damping * qd[:, 0],
                     link * qdd[:, 1] + spring + weight * np.sin(q[:, 1]) + damping * qd[:, 1]]

    t = np.arange(0.0, 10.0, 1e-3)
    xs, us = [], []
    for seed in (0, 1):
        rng = np.random.default_rng(seed)
        f, p = rng.uniform(0.1, 1.0, 4), rng.uniform(0, 2 * np.pi, 4)

        def torque(time, f=f, p=p):
            return 0.4 * np.sin(2 * np.pi * f * time + p).sum() / 2

        def rhs(time, y):
            m_, l_, md, ld = y
            spring = stiffness * (l_ - m_)
            return [md, ld, (torque(time) + spring - damping * md) / motor,
                    (-spring - weight * np.sin(l_) - damping * ld) / link]

        y = solve_ivp(rhs, (0, t[-1]), [0.0, 0.0, 0.0, 0.0], t_eval=t, method="DOP853",
                      rtol=1e-10, atol=1e-10).y
        x = y[:2].T
        xs.append(x + noise * x.std(axis=0) * rng.normal(size=x.shape))
        us.append(np.c_[[torque(time) for time in t], np.zeros_like(t)])
    return [t, t], xs, us, forces


@pytest.mark.slow
def test_growth_with_differences_states_the_joint_spring_and_holds_off_the_trajectories():
    ts, xs, us, forces = _joint_arm_runs(0.01)
    found = px.grow_catalog(xs, ts, us, coordinates=["m", "l"], kinds="angle")
    lagrangian = found.model.lagrangian()
    assert "(l - m)**2" in str(lagrangian), lagrangian
    # off the recorded deflections (within +-0.6 rad): deflections to 1.5 rad
    rng = np.random.default_rng(3)
    q = rng.uniform(-1.2, 1.2, size=(400, 2))
    qd, qdd = rng.uniform(-2, 2, size=(400, 2)), rng.uniform(-10, 10, size=(400, 2))
    assert np.abs(np.diff(np.vstack(xs), axis=1)).max() < 0.7
    true = forces(q, qd, qdd)
    predicted = found.model.predict_forces(q, qd, qdd)
    assert np.linalg.norm(predicted - true) < 0.05 * np.linalg.norm(true)
