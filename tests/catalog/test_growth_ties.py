"""The near ties of the growth's criterion judged again by cross-validation
(``grow_catalog(tie_break=True)``, :mod:`pysindy_xl.catalog.ties`).

Ground truth: a pendulum on a torsion spring (``sympy.physics.mechanics``, integrated by scipy
at 1e-10), whose ``theta^2`` a polynomial stand-in (``theta^2`` and ``theta^4`` without the
cosine) imitates on the recorded range; beyond it the stand-in's force is wrong.
"""

import warnings

import numpy as np
import pytest
import sympy as sp
from support.growth import TORSION, WEIGHT, forced_runs, torsion_pendulum, wide_force_error

from pysindy_xl.catalog import grow_catalog
from pysindy_xl.catalog.path import GrowthStep
from pysindy_xl.catalog.ties import SAME_LAW, TIE_CANDIDATES, TIE_REACH, break_ties, near_ties


def _grow(*args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return grow_catalog(*args, **kwargs)


def test_the_near_ties_judged_on_every_block_give_the_law_not_the_stand_in():
    accelerations, forces = torsion_pendulum()
    ts, xs, us = forced_runs(accelerations, seed=3, noise=0.05)
    assert np.abs(np.vstack(xs)).max() < 1.8  # the check below reaches 2.5
    plain = _grow(xs, ts, us, coordinates=["theta"], kinds="angle", tie_break=False)
    found = _grow(xs, ts, us, coordinates=["theta"], kinds="angle")
    # two held-out blocks per run prefer theta^2 and theta^4 without the cosine: wrong beyond
    # the recorded angles
    assert plain.catalog.trig_degree == 0 and plain.catalog.angle_degree == 4
    assert wide_force_error(plain, forces) > 0.03
    assert all(np.isnan(step.tie_error) for step in plain.steps)
    # judged on all the blocks, the law (cos(theta) and theta^2) is lower
    ties = [step for step in found.steps if np.isfinite(step.tie_error)]
    assert len(ties) >= 2
    chosen = min(ties, key=lambda step: step.tie_error)
    assert chosen.chosen and chosen.criterion > min(step.criterion for step in ties)
    assert found.catalog.trig_degree == 1 and found.catalog.angle_degree == 2
    assert wide_force_error(found, forces) < 0.01
    lagrangian = found.model.lagrangian()
    theta = {str(s): s for s in lagrangian.free_symbols}["theta"]
    assert abs(float(lagrangian.coeff(theta ** 2)) + TORSION / 2) < 0.05 * TORSION / 2
    assert abs(float(lagrangian.coeff(sp.cos(theta))) - WEIGHT) < 0.05 * WEIGHT
    assert "all blocks" in found.table() and "all blocks" not in plain.table()


def test_no_second_judgment_where_the_criterion_is_cross_validated():
    accelerations, _ = torsion_pendulum()
    ts, xs, us = forced_runs(accelerations, seed=3, noise=0.05, n_runs=1, duration=5.0)
    plain = _grow(xs, ts, us, coordinates=["theta"], kinds="angle")
    cross = _grow(xs, ts, us, coordinates=["theta"], kinds="angle", cross_validate=True)
    assert any(np.isfinite(step.tie_error) for step in plain.steps)
    assert all(np.isnan(step.tie_error) for step in cross.steps)


def _step(move, criterion, active=3, definite=1.0, note=""):
    return GrowthStep(move, "", 5, active, criterion, criterion, criterion, False, note=note,
                      definite=definite)


def test_near_ties_keep_one_step_per_law_within_reach():
    best = _step("degree", 0.010)
    same_law = _step("coulomb", 0.010 * (1 + SAME_LAW / 2), active=4)  # a family left out
    other = _step("trig", 0.011, active=4)
    twin = _step("gyroscopic", 0.011 * (1 - SAME_LAW / 2))  # the same law as ``other``
    far = _step("kinetic", 0.010 * (1 + TIE_REACH) * 1.01)
    failed = _step("splines", 0.0105, note="fit failed: ValueError")
    indefinite = _step("interaction", 0.0102, definite=0.5)
    steps = [far, other, same_law, best, failed, indefinite, twin]
    assert near_ties(steps, best) == [best, indefinite, twin]
    assert near_ties(steps, best, physical=True) == [best, twin]
    many = [best] + [_step(f"m{k}", 0.010 + 2e-4 * k, active=k + 4) for k in range(1, 9)]
    assert len(near_ties(many, best)) == TIE_CANDIDATES
    assert near_ties([best, far], best) == [best]


class _TableJudge:
    """Cross-validated criteria from a table, by the catalogs' parameters."""

    def __init__(self, table):
        self.table, self.asked = table, []

    def get(self, parameters, ahead=()):
        self.asked.append(parameters["name"])
        return {"criterion": self.table[parameters["name"]]}


def test_break_ties_applies_the_keep_rule_on_the_cross_validated_criterion():
    ties = [_step("a", 0.010), _step("b", 0.011), _step("c", 0.012)]
    names = {id(step): {"name": step.move} for step in ties}
    judge = _TableJudge({"a": 0.02, "b": 0.015, "c": 0.03})
    assert break_ties(ties, lambda step: names[id(step)], judge).move == "b"
    assert judge.asked == ["a", "b", "c"]
    assert [step.tie_error for step in ties] == [0.02, 0.015, 0.03]
    # within the tolerance, the catalog whose fit keeps fewer terms; otherwise the choice
    level = _TableJudge({"a": 0.02, "b": 0.02 * 0.97, "c": np.inf})
    assert break_ties(ties, lambda step: names[id(step)], level).move == "a"
    ties[2].active = 2
    fewer = _TableJudge({"a": 0.02, "b": 0.02 * 0.97, "c": 0.02 * 1.04})
    assert break_ties(ties, lambda step: names[id(step)], fewer).move == "c"


@pytest.mark.parametrize("value", ["yes", 1, None])
def test_tie_break_must_be_a_bool(value):
    accelerations, _ = torsion_pendulum()
    ts, xs, us = forced_runs(accelerations, seed=0, noise=0.01, n_runs=1, duration=4.0)
    with pytest.raises((TypeError, ValueError), match="tie_break"):
        grow_catalog(xs, ts, us, coordinates=["theta"], kinds="angle", tie_break=value)
