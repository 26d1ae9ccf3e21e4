"""grow_catalog's backward phase on a quartic torsion rotor from sympy.physics.mechanics.

On a small range ``cos(phi) = 1 - phi^2/2 + phi^4/24 - ...``, so ``{phi^2, phi^4, cos(phi)}`` are
nearly dependent and the starting catalog's cosine stands in for the quartic spring
(``-7.4 phi^2 - 12.8 cos(phi)`` instead of ``-phi^2 - 0.5 phi^4``): the climb alone keeps the
stand-in, which fails beyond the recorded range. The backward phase gives the sines and cosines
up (exchanged for the angle's powers) and finds the law.
"""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from support.growth import K2, K4, quartic_rotor
from support.growth import ROTOR_INERTIA as INERTIA

from pysindy_xl.catalog import grow_catalog
from pysindy_xl.catalog.backward import REMOVALS, removed


def _noisy_runs(accelerations, noise=0.03, duration=8.0, rate=200.0, amplitude=1.2):
    """Two forced runs (sums of sines), positions with Gaussian noise of ``noise`` x their
    standard deviation."""
    t = np.arange(0.0, duration, 1.0 / rate)
    noise_rng = np.random.default_rng(0)
    xs, us = [], []
    for seed in (0, 1):
        rng = np.random.default_rng(seed)
        frequencies, phases = rng.uniform(0.2, 1.5, 4), rng.uniform(0, 2 * np.pi, 4)

        def torque(time, frequencies=frequencies, phases=phases):
            return amplitude * np.sin(2 * np.pi * frequencies * time + phases).sum() / 2

        solution = solve_ivp(lambda time, y: [y[1], accelerations(y[0], y[1], torque(time))],
                             (t[0], t[-1]), [rng.uniform(-0.5, 0.5), 0.0], t_eval=t,
                             method="DOP853", rtol=1e-10, atol=1e-10)
        x = solution.y[0][:, None]
        xs.append(x + noise * x.std() * noise_rng.normal(size=x.shape))
        us.append(np.array([[torque(time)] for time in t]))
    return [t, t], xs, us


@pytest.mark.slow
def test_backward_phase_gives_up_the_cosine_that_stands_in_for_a_quartic_spring():
    accelerations, forces = quartic_rotor()
    ts, xs, us = _noisy_runs(accelerations)
    found = grow_catalog(xs, ts, us, coordinates=["phi"], kinds="angle")
    # the law, not a stand-in: no trigonometric term, the coefficients of the truth
    lagrangian = found.model.lagrangian()
    symbols = {str(symbol): symbol for symbol in lagrangian.free_symbols}
    phi, phi_dot = symbols["phi"], symbols["phi_dot"]
    assert not lagrangian.has(sp.sin, sp.cos), lagrangian
    truth = {phi_dot ** 2: INERTIA / 2, phi ** 2: -K2 / 2, phi ** 4: -K4 / 4}
    coefficients = sp.Poly(lagrangian, phi, phi_dot).as_dict()
    for term, value in truth.items():
        powers = sp.Poly(term, phi, phi_dot).monoms()[0]
        assert abs(float(coefficients.get(powers, 0.0)) - value) < 0.03 * abs(value), lagrangian
    # it holds beyond the recorded range (|phi| <= 1.2), where a cosine turns away
    assert np.abs(np.vstack(xs)).max() < 1.25
    q = np.linspace(-2.0, 2.0, 41)[:, None]
    qd = np.full_like(q, 0.7)
    qdd = np.full_like(q, -1.5)
    true = forces(q, qd, qdd)
    predicted = found.model.predict_forces(q, qd, qdd)
    assert np.linalg.norm(predicted - true) < 0.03 * np.linalg.norm(true)
    # the path reports the backward steps like the others, and one of them was kept
    kept = [step.move for step in found.steps if step.chosen]
    assert any(move.startswith("-") for move in kept), found.table()
    assert "-trig" in found.table()


def test_removals_keep_each_angle_a_function_and_refuse_unknown_moves():
    start = {"degree": 2, "trig_degree": 1, "angle_degree": 0, "interaction": 1,
             "kinetic": "constant", "gyroscopic": False, "dissipation": ("viscous",),
             "splines": None}
    # the starting catalog has nothing to drop
    assert all(removed(start, move, ["angle", "linear"], start) is None for move in REMOVALS)
    grown = dict(start, trig_degree=2, angle_degree=2, interaction=2, kinetic="configuration",
                 dissipation=("viscous", "coulomb"), splines=8)
    assert removed(grown, "trig", ["angle"], start)["trig_degree"] == 0
    assert removed(grown, "trig_degree", ["angle"], start)["trig_degree"] == 1
    assert removed(grown, "angle_degree", ["angle"], start)["angle_degree"] == 0
    assert removed(dict(grown, trig_degree=0), "angle_degree", ["angle"], start) is None
    assert removed(grown, "trig", ["linear"], start) is None
    assert removed(grown, "splines", ["linear"], start)["splines"] is None
    assert removed(grown, "interaction", ["linear"], start)["interaction"] == 1
    assert removed(grown, "kinetic", ["linear"], start)["kinetic"] == "constant"
    assert removed(grown, "coulomb", ["linear"], start)["dissipation"] == ("viscous",)
    with pytest.raises(ValueError, match="move"):
        removed(grown, "sines", ["angle"], start)
