"""The growth stops climbing once the held-out criterion is at its noise floor: what the
noise of the positions alone leaves to a right law (:mod:`pysindy_xl.catalog.floor`).

Ground truth: two carts on springs coupled by a third (``sympy.physics.mechanics``,
integrated by scipy at 1e-10), unforced, positions with 2 % noise.
"""

import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from support.growth import coupled_carts

from pysindy_xl.catalog import grow_catalog
from pysindy_xl.catalog.floor import floor_reached


def _free_runs(accelerations, starts, noise, duration=10.0, rate=200.0, seed=0):
    """Unforced runs from the states ``starts`` (scipy DOP853, 1e-10): times, noisy
    positions (N, 2) of each."""
    t = np.arange(0.0, duration, 1.0 / rate)
    rng = np.random.default_rng(seed)
    xs = []
    for start in starts:
        y = solve_ivp(lambda _, s: np.r_[s[2:], accelerations(s[None, :2], s[None, 2:])[0]],
                      (t[0], t[-1]), start, t_eval=t, method="DOP853", rtol=1e-10,
                      atol=1e-10).y
        x = y[:2].T
        xs.append(x + noise * x.std(axis=0) * rng.normal(size=x.shape))
    return [t] * len(xs), xs


@pytest.fixture(scope="module")
def grown():
    accelerations = coupled_carts()
    ts, xs = _free_runs(accelerations, [(0.5, -0.3, 0.0, 0.8), (-0.4, 0.6, 0.9, 0.0)], 0.02)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = grow_catalog(xs, ts, coordinates=["x1", "x2"], kinds="linear")
        plain = grow_catalog(xs, ts, coordinates=["x1", "x2"], kinds="linear",
                             noise_floor=False)
    return accelerations, xs, found, plain


@pytest.mark.slow
def test_the_climb_stops_at_the_noise_floor_with_the_law(grown):
    accelerations, xs, found, plain = grown
    # the law's criterion is at its floor (unforced, far above EXACT: only the floor stops)
    result = [step for step in found.steps if step.chosen][-1]
    assert result.criterion > 1e-4
    assert floor_reached(result.criterion, result.noise_floor, 0.05), found.table()
    assert "noise floor" in found.table().splitlines()[0]
    # fewer catalogs tried than without the stop, and the same catalog kept
    assert len(found.steps) < len(plain.steps), (found.table(), plain.table())
    assert found.catalog.describe() == plain.catalog.describe()
    # the law: accelerations against sympy's over the recorded box
    rng = np.random.default_rng(1)
    span = np.abs(np.vstack(xs)).max(axis=0)
    q = rng.uniform(-span, span, (200, 2))
    qd = rng.uniform(-1.0, 1.0, (200, 2))
    true = accelerations(q, qd)
    error = np.linalg.norm(found.model.predict(q, qd) - true) / np.linalg.norm(true)
    assert error < 0.03, error


def test_the_floor_is_off_without_noise():
    accelerations = coupled_carts()
    ts, xs = _free_runs(accelerations, [(0.5, -0.3, 0.0, 0.8)], 0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = grow_catalog(xs, ts, coordinates=["x1", "x2"], kinds="linear",
                             moves=("interaction",))
    # free of noise, the floor is round-off: far below what stops a climb
    assert all(not step.noise_floor > 1e-6 for step in found.steps), found.table()
