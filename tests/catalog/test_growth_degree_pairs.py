"""grow_catalog's joint first move of a degree with the interaction order, against a
Henon-Heiles oscillator whose equations are written out by hand and integrated by scipy at
1e-10: its coupling ``x^2 y`` needs a product of two coordinates' powers above the first
catalog's degree, which neither the degree move nor the interaction move adds alone."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import pysindy_xl as px
from pysindy_xl.catalog import grow_catalog
from pysindy_xl.catalog.moves import MOVES, START, joint_moves


def _accelerations(y, u, c=0.1):
    """L = (xd^2 + yd^2) / 2 - (x^2 + y^2) - (x^2 y - y^3 / 3), viscous damping ``c``."""
    x, z, xd, zd = y
    return np.array([-2 * x - 2 * x * z - c * xd + u[0],
                     -2 * z - x ** 2 + z ** 2 - c * zd + u[1]])


def _runs(seeds=(0, 1), duration=8.0, rate=200.0):
    t = np.arange(0.0, duration, 1.0 / rate)
    xs, us = [], []
    for seed in seeds:
        rng = np.random.default_rng(seed)
        frequencies, phases = rng.uniform(0.1, 1.0, (2, 4)), rng.uniform(0, 2 * np.pi, (2, 4))

        def force(time, frequencies=frequencies, phases=phases):
            return 0.5 * np.sin(2 * np.pi * frequencies * time + phases).sum(axis=1)

        solution = solve_ivp(lambda time, y: np.r_[y[2:], _accelerations(y, force(time))],
                             (t[0], t[-1]), np.r_[rng.uniform(-0.4, 0.4, 2), 0.0, 0.0],
                             t_eval=t, method="DOP853", rtol=1e-10, atol=1e-10)
        xs.append(solution.y[:2].T)
        us.append(np.array([force(time) for time in t]))
    return t, xs, us


def test_a_degree_with_the_interaction_order_is_a_joint_move():
    """From the first catalog, one degree step with the interaction order adds ``x^2 y`` and
    ``x y^2``, which neither adds alone; two degree moves together never qualify."""
    def size(parameters):
        return px.AutomaticCatalog(["x", "y"], **parameters).n_terms

    joint = joint_moves(MOVES, ["linear", "linear"], 2, size)
    assert "interaction+degree" in joint
    assert not any(set(name.split("+")) <= {"degree", "trig_degree", "angle_degree"}
                   for name in joint)
    assert size(START) == 9  # (the pair's catalog: x..x^3, y..y^3, x y, x^2 y, x y^2)
    assert px.AutomaticCatalog(["x", "y"], degree=3, interaction=2).n_terms > size(START) + 3


@pytest.fixture(scope="module")
def henon_heiles():
    return _runs()


def test_the_cubic_coupling_is_found(henon_heiles):
    """The growth keeps the pair (degree 3, interaction 2) and the model's accelerations
    match the hand-written equations on fresh states."""
    t, xs, us = henon_heiles
    found = grow_catalog(xs, [t, t], us, coordinates=["x", "y"], kinds="linear",
                         moves=("kinetic", "interaction", "degree"))
    assert found.catalog.degree == 3 and found.catalog.interaction == 2
    rng = np.random.default_rng(5)
    states = np.c_[rng.uniform(-0.5, 0.5, (40, 2)), rng.uniform(-1, 1, (40, 2))]
    forces = rng.uniform(-1, 1, (40, 2))
    truth = np.array([_accelerations(y, u) for y, u in zip(states, forces, strict=True)])
    predicted = found.model.predict(states[:, :2], states[:, 2:], forces)
    assert np.linalg.norm(predicted - truth) / np.linalg.norm(truth) < 0.01
