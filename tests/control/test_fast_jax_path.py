"""``to_jax()`` of a kinematic-catalog model: the written-out polynomials with unrolled
elimination give what the rigid-body kernel with LU gives, and what the model's own NumPy code
gives (the ground truth of the fit)."""

import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import pysindy_xl as px
from pysindy_xl.export.jax_dynamics import dynamics_function
from pysindy_xl.mujoco import generate_dataset, get_system, reference_catalog


@pytest.fixture(scope="module", params=["cart-pole", "cart-double-pendulum"])
def kinematic_model(request):
    system = get_system(request.param)
    data = generate_dataset(system, n_trajectories=1, duration=2.0, seed=0, progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = px.XLSINDy(reference_catalog(system, "kinematic"))
        model.fit(**data.fit_arguments(forces="tau"))
    assert model.dynamics_.rigid_parts  # the kernel path exists for this model
    return model


@pytest.mark.slow
def test_to_jax_takes_the_expression_path_and_agrees_with_the_kernel(kinematic_model):
    dynamics = kinematic_model.dynamics_
    n = dynamics.coords.n
    rng = np.random.default_rng(1)
    states = np.c_[rng.uniform(-np.pi, np.pi, (200, n)), rng.uniform(-3, 3, (200, n))]
    forces = rng.uniform(-5, 5, (200, n))
    with jax.enable_x64(True):
        fast = kinematic_model.to_jax()
        kernel = dynamics_function(dynamics, solver="lu")
        assert fast.solver == "gauss" and kernel.solver == "lu"
        got = np.asarray(fast(jnp.asarray(states), jnp.asarray(forces)))
        expected = np.asarray(kernel(jnp.asarray(states), jnp.asarray(forces)))
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-10 * np.abs(expected).max())
    numpy_accelerations = dynamics.accelerations(states[:, :n], states[:, n:], forces)
    np.testing.assert_allclose(got[:, n:], numpy_accelerations, rtol=1e-9, atol=1e-9)


@pytest.mark.slow
def test_to_jax_of_an_arm_solves_by_elimination_and_agrees_with_lu():
    """Five joints (past the written-out path): the rigid-body kernel with unrolled elimination
    gives what LU gives, and what the model's NumPy code gives."""
    from kinematic_models import robot_arm

    from pysindy_xl.mujoco import MJCFSystem
    system = MJCFSystem(robot_arm(5))
    data = generate_dataset(system, n_trajectories=1, duration=1.0, seed=0, progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = px.XLSINDy(reference_catalog(system, "kinematic"))
        model.fit(**data.fit_arguments(forces="tau"))
    dynamics = model.dynamics_
    assert dynamics.rigid_parts
    rng = np.random.default_rng(2)
    states = np.c_[rng.uniform(-np.pi, np.pi, (100, 5)), rng.uniform(-2, 2, (100, 5))]
    forces = rng.uniform(-5, 5, (100, 5))
    with jax.enable_x64(True):
        fast = model.to_jax()
        lu = dynamics_function(dynamics, solver="lu")
        assert fast.solver == "gauss"
        got = np.asarray(fast(jnp.asarray(states), jnp.asarray(forces)))
        expected = np.asarray(lu(jnp.asarray(states), jnp.asarray(forces)))
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-10 * np.abs(expected).max())
    numpy_accelerations = dynamics.accelerations(states[:, :5], states[:, 5:], forces)
    np.testing.assert_allclose(got[:, 5:], numpy_accelerations, rtol=1e-8, atol=1e-8)
