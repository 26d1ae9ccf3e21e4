"""The paper-style catalog of the acceptance systems (``tests/ground_truth.py``), its true
coefficients, noisy runs and the validation of a model by simulation."""

import numpy as np
import sympy as sp
from ground_truth import random_force, random_initial_state

import pysindy_xl as px


def paper_catalog(coords: px.Coordinates, angles) -> px.CatalogRepartition:
    """Velocity monomials (degree 2) x trigonometric monomials of the angles (degree 2),
    plus viscous friction on every coordinate."""
    trig = [f(coords.q[i]) for i in angles for f in (sp.sin, sp.cos)]
    terms = px.products([1, *px.monomials(trig, 2)], [1, *px.monomials(coords.qd, 2)])
    terms = [t for t in terms if t.free_symbols]
    friction = px.ClassicalLibrary(coords, coords.qd, mask=np.eye(coords.n, dtype=bool))
    return px.CatalogRepartition([px.LagrangeLibrary(coords, terms), friction])


def true_coefficients(system, library):
    """The system's Lagrangian and viscous friction expanded in the fitted ``library``."""
    friction = {(system.coords.qd[i], i): c for i, c in enumerate(system.friction)}
    return library.ideal_coefficients(lagrangian=system.lagrangian, classical=friction)


_CLEAN_RUNS = {}


def noisy_run(system, seed, level, duration=30.0, dt=0.01, active=None):
    """``(t, noisy q, clean run, force)``: a forced run with Gaussian position noise of
    ``level`` times each coordinate's standard deviation."""
    t = np.arange(0.0, duration, dt)
    force = random_force(system, seed, active=active)
    key = (system.name, str(system.lagrangian), system.friction.tobytes(),
           system.force_amplitude.tobytes(), seed, duration, dt,
           None if active is None else tuple(active))
    if key not in _CLEAN_RUNS:  # the noise levels of a sweep share their seeds' runs
        _CLEAN_RUNS[key] = system.simulate(random_initial_state(system, seed), t, force)
    data = {name: value.copy() for name, value in _CLEAN_RUNS[key].items()}
    rng = np.random.default_rng(10_000 + seed)
    noisy = data["q"] + level * data["q"].std(axis=0) * rng.normal(size=data["q"].shape)
    return t, noisy, data, force


def validates(model, system, seed):
    """Whether ``model`` simulates a fresh 5 s forced run within 10 % of each coordinate's
    range (RMSE); a failed simulation does not validate."""
    t = np.arange(0.0, 5.0, 0.01)
    force = random_force(system, seed)
    x0 = random_initial_state(system, seed)
    truth = system.simulate(x0, t, force)
    try:
        sim = model.simulate(x0, t, u=lambda s: force(s))
    except px.SimulationError:
        return False
    rmse = np.sqrt(np.mean((sim[:, : system.n] - truth["q"]) ** 2, axis=0))
    return bool(np.all(rmse < 0.1 * np.ptp(truth["q"], axis=0)))
