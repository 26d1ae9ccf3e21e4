"""Issue 12 acceptance: the kinematic catalog identified from noisy positions only.

A 3-link planar arm (off-axis centres of mass, full inertia tensors, joint damping), every joint
forced, positions recorded with 1 % Gaussian noise (std = 0.01 x each coordinate's std), no
velocity or acceleration given: ``XLSINDy`` on the kinematic catalog takes its default weak
pipeline (Whittaker smoothing, test functions, sparsity selection). The identified mass matrix
and gravity torque are compared with MuJoCo's ``mj_fullM`` and ``qfrc_bias`` (zero velocity)
at 20 random states, and the model is validated against a fresh 5 s MuJoCo trajectory.

Measured (4 trajectories of 5 s at 2 ms, seeds 0-9): relative error of M(q) 1.7, 0.16, 0.68,
0.41, 0.41, 0.56, 3.6, 1.2, 0.36, 0.06 %; of the gravity torque 1.5, 0.17, 0.66, 0.40, 0.37,
0.62, 3.2, 1.2, 0.39, 0.06 %: all within the 5 % target. Validation: 9 of 10 valid; seed 0
(M within 1.7 %) diverges at 2.96 s of the chaotic 5 s validation trajectory. With 2
trajectories of 2 s (sample every 5 ms) the errors reach 20 % (seed 7): that much data is not
enough, so the tests use the longer record.
"""

import warnings

import mujoco
import numpy as np
import pytest
from kinematic_models import PLANAR_ARM

import pysindy_xl as px
from pysindy_xl.evaluation.validation import validate_model
from pysindy_xl.mujoco import MJCFSystem, generate_dataset
from pysindy_xl.mujoco.catalogs.kinematic import kinematic_catalog


def _mujoco_mass_and_gravity(system, qpos):
    model = system.mj_model()
    data = mujoco.MjData(model)
    masses, gravity = [], []
    for position in qpos:
        data.qpos[:], data.qvel[:] = position, 0.0
        mujoco.mj_forward(model, data)
        matrix = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, matrix)
        masses.append(matrix)
        gravity.append(data.qfrc_bias.copy())  # zero velocity: gravity only
    return np.array(masses), np.array(gravity)


def _relative_error(a, b):
    return float(np.abs(a - b).max() / np.abs(b).max())


def identify_from_noisy_positions(seed):
    """Errors of M(q) and gravity against MuJoCo, and the validation, for one seed."""
    system = MJCFSystem(PLANAR_ARM, force_amplitude=4.0)
    catalog = kinematic_catalog(system, coulomb=False)
    data = generate_dataset(system, n_trajectories=4, duration=5.0, seed=seed, sample_every=2,
                            noise=0.01, noise_model="positions", progress=False)
    arguments = data.fit_arguments(forces="tau")
    assert arguments["x_dot"] is None and arguments["x_ddot"] is None  # positions only
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # trajectory pieces shorter than a test function
        model = px.XLSINDy(catalog.library()).fit(**arguments)
    assert model.formulation_ == "weak"  # the default pipeline for positions only
    identified = catalog.lagrange_coefficients(model)
    q = np.random.default_rng(5).uniform(-np.pi, np.pi, (20, system.n))
    masses, gravity = _mujoco_mass_and_gravity(system, q)
    assert _relative_error(catalog.mass_matrix(q), masses) < 1e-9  # the catalog's truth
    result = validate_model(model, system, duration=5.0, seed=seed + 100)
    return {"mass": _relative_error(catalog.mass_matrix(q, identified), masses),
            "gravity": _relative_error(catalog.gravity_torque(q, identified), gravity),
            "valid": result.valid, "model": model}


@pytest.fixture(scope="module")
def outcomes():
    """The identification of seeds 0-5, computed once for the module's tests."""
    return [identify_from_noisy_positions(seed) for seed in range(6)]


@pytest.mark.slow
def test_planar_arm_from_one_percent_position_noise(outcomes):
    outcome = outcomes[1]
    assert outcome["mass"] < 0.05 and outcome["gravity"] < 0.05
    assert outcome["valid"]
    coefficients = dict(zip(outcome["model"].get_feature_names(),
                            outcome["model"].coefficients(), strict=True))
    # joint damping from noisy positions (measured: 0.198, 0.101, 0.050 for this seed)
    assert coefficients["C_shoulder[shoulder_dot]"] == pytest.approx(0.2, rel=0.05)
    assert coefficients["C_elbow[elbow_dot]"] == pytest.approx(0.1, rel=0.05)


@pytest.mark.slow
def test_planar_arm_from_one_percent_position_noise_over_seeds(outcomes):
    mass = [o["mass"] for o in outcomes]
    gravity = [o["gravity"] for o in outcomes]
    assert max(mass) < 0.05 and max(gravity) < 0.05, (mass, gravity)
    # the honest floor: seed 0 diverges at 2.96 s of the chaotic validation trajectory
    assert sum(o["valid"] for o in outcomes) >= 5, [o["valid"] for o in outcomes]
