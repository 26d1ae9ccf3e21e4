"""The share rule of the unforced law search (``laws.explained_coordinates``): a law whose
equation for a coordinate is a negligible touch does not explain that coordinate.

A quarter car (body on a suspension spring over a light wheel on a stiff tyre), unforced, 3 %
noise on the positions: the law couples the two masses through the suspension spring. A law
that couples them through inertia (``x1_dot x2_dot``, which the system does not have) in
place of the spring holds about as well on the data, and is one term smaller when it also
leaves out the wheel's damping; its wheel equation carries about 5e-4 of the body's share in
the units of the catalog's balance, and the rule refuses it. Balanced over the law's own
columns instead (a "mend" tried for the half-car of the second blind set, not kept), that
law's wheel share rises to about 1e-2 and it is chosen on seeds 1, 2 and 4, with
accelerations 2.4 % off.

Ground truth: the equations of motion integrated by scipy (DOP853, tolerances 1e-10).
"""

import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import pysindy_xl as px

BODY, WHEEL, SUSPENSION, TYRE, BODY_DAMPING, WHEEL_DAMPING = 1.0, 0.15, 12.0, 60.0, 0.3, 0.2


def _accelerations(q, qd):
    """Body ``x1`` and wheel ``x2`` accelerations, any leading shape."""
    spring = SUSPENSION * (q[..., 1] - q[..., 0])
    return np.stack([(spring - BODY_DAMPING * qd[..., 0]) / BODY,
                     (-spring - TYRE * q[..., 1] - WHEEL_DAMPING * qd[..., 1]) / WHEEL], -1)


def _runs(seed, noise=0.03):
    """Two free runs of 10 s at 200 Hz, noise on the positions (``noise`` of their spread)."""
    t = np.arange(0.0, 10.0, 1 / 200)
    rng = np.random.default_rng(seed)
    xs = []
    for start in ([0.5, 0.5, 0.0, 0.4], [-0.3, -0.6, 0.5, -1.0]):
        q = solve_ivp(lambda _, y: np.r_[y[2:], _accelerations(y[:2], y[2:])], (0, t[-1]),
                      start, t_eval=t, method="DOP853", rtol=1e-10, atol=1e-10).y[:2].T
        xs.append(q + noise * q.std(axis=0) * rng.normal(size=q.shape))
    return xs, [t, t]


@pytest.mark.parametrize("seed", range(6))
def test_quarter_car_law_couples_by_the_spring(seed):
    xs, ts = _runs(seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = px.XLSINDy(px.AutomaticCatalog(["x1", "x2"], kinds="linear", degree=2,
                                               interaction=2, kinetic="constant")).fit(xs, ts)
    terms = {name for name, value in zip(model.get_feature_names(), model.coefficients(),
                                         strict=True) if value != 0}
    assert "L[x1*x2]" in terms  # the spring couples the masses (an inertial term may join it)
    assert {"L[x1_dot**2]", "L[x2_dot**2]", "L[x1**2]", "L[x2**2]"} <= terms
    # accelerations over the recorded positions at random velocities, against the truth
    q = np.vstack(xs)[::40]
    qd = np.random.default_rng(1).normal(scale=0.5, size=q.shape)
    true = _accelerations(q, qd)
    assert np.linalg.norm(model.predict(q, qd) - true) / np.linalg.norm(true) < 0.02
