"""The consensus of two folds (``grow_catalog(region="consensus")``): the time and region
blocks and the extreme states judge each change together.

Ground truth: a pendulum on a torsion spring (``sympy.physics.mechanics``, integrated by scipy),
where sines and cosines of ``theta`` and ``2 theta`` imitate ``theta^2`` on the recorded range
and the time blocks keep them; and a forced Duffing oscillator, whose hardening shows only in
the extreme states, so that a fold fitted inside them alone cannot see it.
"""


import numpy as np
import pytest
import sympy as sp
from support.growth import (
    HARDENING,
    MASS,
    STIFFNESS,
    TORSION,
    WEIGHT,
    forced_runs,
    noisy_duffing,
    quiet_growth,
    torsion_pendulum,
    wide_force_error,
)

from pysindy_xl.catalog import grow_catalog
from pysindy_xl.catalog.growth import GROWTH_REGIONS
from pysindy_xl.catalog.keep_rules import consensus_criteria, consensus_keeps
from pysindy_xl.catalog.path import GrowthStep


@pytest.mark.slow
def test_the_consensus_refuses_the_stand_in_that_the_time_blocks_keep():
    accelerations, forces = torsion_pendulum()
    ts, xs, us = forced_runs(accelerations, seed=1, noise=0.05)
    assert np.abs(np.vstack(xs)).max() < 1.6  # the check below reaches 2.5
    blocks = quiet_growth(xs, ts, us, coordinates=["theta"], kinds="angle")
    both = quiet_growth(xs, ts, us, coordinates=["theta"], kinds="angle", region="consensus")
    # the default keeps sines and cosines of 2 theta for the spring: wrong beyond the data
    assert blocks.catalog.angle_degree == 0 and blocks.catalog.trig_degree == 2
    assert wide_force_error(blocks, forces) > 0.05
    # the stand-in is better on the time blocks, the law on the extreme states
    stand_in = next(s for s in both.steps if s.move == "trig_degree" and s.terms == 6)
    law = next(s for s in both.steps if s.move == "angle_degree" and s.terms == 6)
    assert stand_in.criterion < law.criterion and law.second_error < stand_in.second_error
    # the consensus keeps the law: cos(theta) and theta^2, right beyond the data
    assert both.catalog.angle_degree == 2 and both.catalog.trig_degree == 1
    assert wide_force_error(both, forces) < 0.01
    lagrangian = both.model.lagrangian()
    theta = {str(s): s for s in lagrangian.free_symbols}["theta"]
    assert abs(float(lagrangian.coeff(theta ** 2)) + TORSION / 2) < 0.05 * TORSION / 2
    assert abs(float(lagrangian.coeff(sp.cos(theta))) - WEIGHT) < 0.05 * WEIGHT
    # every kept catalog was judged by both folds; the second fold was asked only about
    # candidates within reach of the kept one on the first
    assert all(np.isfinite(s.second_error) and s.second_cpu_seconds > 0
               for s in both.steps if s.chosen)
    assert any(np.isnan(s.second_error) for s in both.steps)


def test_the_consensus_keeps_a_hardening_that_only_the_extreme_states_show():
    x, t, u = noisy_duffing()
    extremes = quiet_growth(x, t, u, coordinates=["x"], kinds="linear", region="extremes")
    both = quiet_growth(x, t, u, coordinates=["x"], kinds="linear", region="consensus")
    # fitted inside the threshold, x^4 extrapolates worse than the start: the extremes fold
    # stops at the start
    assert extremes.catalog.degree == 2
    # both catalogs fail the extreme states (a residual above the forces'): that fold cannot
    # tell them apart, and the time blocks decide
    hardening = next(s for s in both.steps if s.chosen and s.move == "degree")
    assert min(hardening.second_error, both.steps[0].second_error) >= 1
    assert both.catalog.degree == 4
    coef = dict(zip(both.model.get_feature_names(), both.model.coefficients(), strict=True))
    np.testing.assert_allclose(2 * coef["L[x_dot**2]"], MASS, rtol=0.05)
    np.testing.assert_allclose(-2 * coef["L[x**2]"], STIFFNESS, rtol=0.05)
    np.testing.assert_allclose(-4 * coef["L[x**4]"], HARDENING, rtol=0.1)


def _step(criterion, active=3):
    return GrowthStep("degree", "", 5, active, criterion, criterion, criterion, False)


def test_the_combined_criterion_is_the_geometric_mean_where_the_second_fold_judges():
    assert consensus_criteria(_step(0.04), _step(0.01), _step(0.25), _step(0.64)) == (
        pytest.approx(0.1), pytest.approx(0.08))
    # both fail the second fold: the first decides alone
    assert consensus_criteria(_step(0.04), _step(0.01), _step(1.5), _step(6.0)) == (0.04, 0.01)
    # a candidate within the tolerance with fewer fitted terms is kept, as on one fold
    assert consensus_keeps(_step(0.1, 2), _step(0.1, 3), _step(0.1), _step(0.1), 0.05)
    assert not consensus_keeps(_step(0.1, 3), _step(0.1, 3), _step(0.1), _step(0.1), 0.05)
    assert not consensus_keeps(_step(0.01), _step(0.1), _step(np.inf), _step(0.1), 0.05)


@pytest.mark.parametrize("region", ["Consensus", "consensus ", None, 1])
def test_an_unknown_region_is_refused(region):
    x, t, u = noisy_duffing()
    with pytest.raises(ValueError, match="region"):
        grow_catalog(x, t, u, coordinates=["x"], kinds="linear", region=region)
    assert "consensus" in GROWTH_REGIONS
