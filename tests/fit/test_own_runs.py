"""An identified model simulated along its own runs (``fit.own_runs``): a law that holds the
rows but drives the states away from them is found, where and when it leaves.

Ground truth: a unit-mass spring ``2 x'' + 3 x = u`` (forced runs from a chosen motion, the
force by the law) and its free run from ``x = 1`` at rest, in closed form; the law with the
spring's sign turned, ``2 x'' - 3 x = u``, leaves that run when ``cosh(sqrt(1.5) t)`` reaches
ten times the recorded range.
"""

import functools

import numpy as np
import pytest

import pysindy_xl as px
from pysindy_xl.catalog.final_fit import final_answer
from pysindy_xl.catalog.path import GrowthStep
from pysindy_xl.fit.own_runs import own_runs_divergence

T = np.linspace(0.0, 20.0, 2001)
MOTION = np.c_[np.sin(T) + 0.5 * np.sin(2.7 * T)]
MOTION_DDOT = (-np.sin(T) - 3.645 * np.sin(2.7 * T))[:, None]
FREE = np.c_[np.cos(np.sqrt(1.5) * T)]  # the spring's free run from x = 1 at rest


@functools.cache  # (read only: simulated, never refitted)
def _law(stiffness):
    """``2 x'' + stiffness x = u`` identified from the forced motion (exact data)."""
    catalog = px.AutomaticCatalog(["x"], kinetic="constant")
    return px.XLSINDy(catalog).fit(MOTION, T, u=2 * MOTION_DDOT + stiffness * MOTION)


def test_the_law_stays_in_its_free_run_and_a_turned_spring_leaves_it_on_time():
    assert own_runs_divergence(_law(3.0), FREE, T) is None
    verdict = own_runs_divergence(_law(-3.0), FREE, T)
    # the recorded range of x is [-1, 1] (middle 0, half 1): the turned law's x = cosh(...)
    # passes 10 at arccosh(10) / sqrt(1.5)
    leaves = np.arccosh(10.0) / np.sqrt(1.5)
    assert verdict is not None and verdict.startswith("run 0 leaves its recorded range (x)")
    assert abs(float(verdict.rsplit("t = ", 1)[1].split()[0]) - leaves) < 0.1


def test_every_run_is_simulated_and_the_first_that_leaves_is_named():
    other = np.c_[0.5 * np.cos(np.sqrt(1.5) * T)]
    verdict = own_runs_divergence(_law(-3.0), [other, FREE], [T, T])
    assert verdict.startswith("run 0 ")
    assert own_runs_divergence(_law(3.0), [other, FREE], [T, T]) is None


def test_an_angle_may_turn_past_its_range_but_not_its_velocity():
    # the turned spring read as an angle: its position is not checked, its velocity is
    verdict = own_runs_divergence(_law(-3.0), FREE, T, kinds=["angle"])
    assert verdict is not None and "(x_dot)" in verdict


def test_a_simulation_stopped_by_its_evaluation_count_gives_no_verdict():
    assert own_runs_divergence(_law(-3.0), FREE, T, max_evaluations=30) is None


def test_bad_arguments_are_named():
    with pytest.raises(ValueError, match="model"):
        own_runs_divergence(px.XLSINDy(), FREE, T)
    with pytest.raises(ValueError, match="widen"):
        own_runs_divergence(_law(3.0), FREE, T, widen=1.0)
    with pytest.raises(ValueError, match="t"):
        own_runs_divergence(_law(3.0), [FREE, FREE], T)  # one time array for two runs
    with pytest.raises(ValueError, match=r"t\[0\]"):
        own_runs_divergence(_law(3.0), [FREE], [T[:-1]])
    with pytest.raises(ValueError, match="x"):
        own_runs_divergence(_law(3.0), np.c_[FREE, FREE], T)  # two columns, one coordinate
    with pytest.raises(ValueError, match="kinds"):
        own_runs_divergence(_law(3.0), FREE, T, kinds=["angle", "angle"])
    with pytest.raises(ValueError, match="kinds"):
        own_runs_divergence(_law(3.0), FREE, T, kinds=["angular"])


def test_the_growth_answers_with_an_alternative_that_stays_in_its_free_runs():
    # the chosen catalog's final fit is the turned spring; the second catalog's is the law
    steps = [GrowthStep("chosen", "", 4, 3, 0.1, 0.1, 0.1, True, support=(("turned",),)),
             GrowthStep("other", "", 4, 3, 0.2, 0.2, 0.2, False, support=(("law",),))]
    models = {"turned": _law(-3.0), "law": _law(3.0)}

    def check(model):
        return own_runs_divergence(model, FREE, T)

    step, _, model, failed = final_answer(
        steps[0], {"kinetic": "constant"}, steps, lambda step: {"kinetic": "constant"},
        {"coordinates": ["x"]}, fit=lambda catalog, judged: models[judged[0][0]], check=check)
    assert step is steps[1] and failed is None
    assert model.coefficients() == pytest.approx(models["law"].coefficients())
    # where no alternative stays in the runs, the choice is kept, with the reason
    step, _, model, failed = final_answer(
        steps[0], {"kinetic": "constant"}, steps[:1], None, {"coordinates": ["x"]},
        fit=lambda catalog, judged: models["turned"], check=check)
    assert step is steps[0] and failed.startswith("run 0 leaves")
