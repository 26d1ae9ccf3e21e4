"""The linear coordinates' powers beyond ``x^4`` where no family states the potential.

A magnet between two fixed magnets that repel it (``V = c (1/(d - x) + 1/(d + x))``) has a
potential that no polynomial, trigonometric, exponential or spline family states; on the
recorded range its expansion needs ``x^6``. With the degree move stopped at 4 the growth answers
``x..x^4`` (force error up to 9.6 % over the recorded positions on these seeds); with the limit
at 6 (:data:`~pysindy_xl.catalog.moves.LIMITS`) it goes on where the held-out criterion asks.
"""

import numpy as np
import pytest
from support.growth import forced_runs

from pysindy_xl.catalog import grow_catalog

MASS, STRENGTH, GAP, DAMPING = 0.5, 3.5, 2.0, 0.1


def _magnet_force(x):
    """``-dV/dx`` of ``V = STRENGTH (1/(GAP - x) + 1/(GAP + x))``."""
    return -STRENGTH * (1 / (GAP - x) ** 2 - 1 / (GAP + x) ** 2)


def _accelerations(x, x_dot, tau):
    return (_magnet_force(x) - DAMPING * x_dot + tau) / MASS


@pytest.mark.slow
def test_a_magnet_between_repelling_magnets_is_expanded_beyond_the_fourth_power():
    errors = []
    for seed in (0, 1, 2):
        ts, xs, us = forced_runs(_accelerations, seed=seed, noise=0.01, amplitude=1.0)
        found = grow_catalog(xs, ts, us, coordinates=["x"])
        low, high = np.quantile(np.concatenate(xs), [0.02, 0.98])
        q = np.linspace(low, high, 101)[:, None]
        q_dot, q_ddot = np.full_like(q, 0.3), np.full_like(q, 0.5)
        true = MASS * q_ddot - _magnet_force(q) + DAMPING * q_dot
        predicted = found.model.predict_forces(q, q_dot, q_ddot)
        errors.append(np.linalg.norm(predicted - true) / np.linalg.norm(true))
    # x..x^4 on these seeds: 0.9 %, 9.6 %, 1.8 %; with x^6 reachable: 1.1 %, 1.9 %, 0.2 %
    assert max(errors) < 0.03, errors
