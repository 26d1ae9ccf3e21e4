"""The growth's held-out folds, and the fold of the extreme states against a stand-in.

A pendulum on a torsion spring (``sympy.physics.mechanics``, integrated by scipy) has the
potential ``-W cos(theta) + k theta^2 / 2``. On the range of a recording, sines and cosines of
``theta`` and ``2 theta`` imitate ``theta^2``: a time block held out inside that range cannot
tell the stand-in from the law, while a fold fitted inside a threshold of the states and judged
beyond it can.
"""

import warnings

import numpy as np
import pytest
import sympy as sp
from support.growth import forced_runs, torsion_pendulum, wide_force_error

from pysindy_xl.catalog import grow_catalog
from pysindy_xl.catalog.folds import extreme_masks, held_out_splits


def _arrays(ts, xs, us=None):
    return {"x": xs, "t": ts, "u": us, "x_dot": None, "x_ddot": None}


def test_extreme_masks_hold_out_stretches_beyond_every_training_state():
    t = np.linspace(0.0, 10.0, 2001)
    xs = [np.c_[np.sin(3 * t) * (1 + 0.1 * t), np.cos(2 * t)],
          np.c_[0.5 * np.sin(2 * t), np.cos(5 * t) * np.exp(-0.1 * t)]]
    eligible = [t < 8, np.ones_like(t, dtype=bool)]
    margin = 0.3
    held = extreme_masks([t, t], xs, eligible, margin=margin, fraction=0.2)
    # a subset of the eligible samples, at most the share asked for, and some of it
    assert not held[0][t >= 8].any()
    share = sum(int(h.sum()) for h in held) / sum(int(e.sum()) for e in eligible)
    assert 0.1 < share <= 0.2
    # each held-out stretch away from the ends holds a test function of half-width margin
    pieces = 0
    for mask, ok in zip(held, eligible, strict=True):
        edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(int), 0]))
        for a, b in zip(edges[::2], edges[1::2], strict=True):
            if a > 0 and ok[b - 1] and b < len(t) and ok[b]:
                pieces += 1
                assert t[b - 1] - t[a] >= 2 * margin - 1e-9
    assert pieces >= 2
    # every training sample lies closer to the median than the farthest held-out one, in
    # every coordinate-scaled sense the fold uses (the largest scaled distance)
    pool = np.vstack([x[e] for x, e in zip(xs, eligible, strict=True)])
    scale = np.subtract(*np.percentile(pool, [75, 25], axis=0))
    center = np.median(pool, axis=0)
    reach = [np.abs((x - center) / scale).max(axis=1) for x in xs]
    inside = max(r[e & ~h].max() for r, e, h in zip(reach, eligible, held, strict=True))
    beyond = [r[h] for r, h in zip(reach, held, strict=True) if h.any()]
    assert all(inside < b.max() for b in beyond)
    assert inside < np.concatenate(beyond).max() * 0.97


def test_held_out_splits_of_the_extremes_train_inside_and_judge_beyond():
    t = np.linspace(0.0, 10.0, 2001)
    x = (np.sin(3 * t) * (1 + 0.5 * np.sin(0.4 * t)))[:, None]
    arrays = _arrays([t], [x])
    (train, blocks), = held_out_splits(arrays, 5, region="extremes", margin=0.2)[0]
    assert len(blocks) == 2  # the time block and the extreme stretches
    # every training piece holds a test function of half-width margin (no empty gaps)
    assert min(piece[-1] - piece[0] for piece in train["t"]) >= 2 * 0.2 - 1e-9
    assert np.all(blocks[0]["t"][0] >= 8.0 - 1e-9)
    trained = np.abs(np.vstack(train["x"])).max()
    assert trained < np.abs(np.vstack(blocks[1]["x"])).max()
    # nothing is both fitted and judged
    fitted = np.concatenate(train["t"])
    judged = np.concatenate([piece for block in blocks for piece in block["t"]])
    assert not np.intersect1d(fitted, judged).size
    # both: the region block as well; cross-validated: one more split, on the extremes
    assert len(held_out_splits(arrays, 5, region="both", margin=0.2)[0][0][1]) == 3
    splits, reported = held_out_splits(arrays, 5, cross_validate=True, region="extremes",
                                       margin=0.2)
    assert len(splits) == 6 and reported == (4, 5)
    assert np.abs(np.vstack(splits[-1][0]["x"])).max() == pytest.approx(trained)
    with pytest.raises(ValueError, match="region"):
        held_out_splits(arrays, 5, region="corners", margin=0.2)
    with pytest.raises(ValueError, match="margin"):
        held_out_splits(arrays, 5, region="extremes")


@pytest.mark.slow
def test_the_extreme_states_fold_refuses_the_stand_in_that_the_time_blocks_keep():
    accelerations, forces = torsion_pendulum()
    ts, xs, us = forced_runs(accelerations, seed=1, noise=0.05)
    assert np.abs(np.vstack(xs)).max() < 1.6  # the check below reaches 2.5
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        blocks = grow_catalog(xs, ts, us, coordinates=["theta"], kinds="angle", region="block")
        extremes = grow_catalog(xs, ts, us, coordinates=["theta"], kinds="angle",
                                region="extremes")
    # the region block keeps sines and cosines of 2 theta for the spring: wrong beyond the data
    assert blocks.catalog.angle_degree == 0 and blocks.catalog.trig_degree == 2
    assert wide_force_error(blocks, forces) > 0.05
    # the extreme states keep the law: cos(theta) and theta^2, right beyond the data
    assert extremes.catalog.angle_degree == 2 and extremes.catalog.trig_degree == 1
    assert wide_force_error(extremes, forces) < 0.01
    lagrangian = extremes.model.lagrangian()
    theta = {str(s): s for s in lagrangian.free_symbols}["theta"]
    assert abs(float(lagrangian.coeff(theta ** 2)) + 1.5) < 0.05 * 1.5, lagrangian
    assert abs(float(lagrangian.coeff(sp.cos(theta))) - 3.924) < 0.05 * 3.924, lagrangian
