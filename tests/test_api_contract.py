"""The public API contract (shared/API.md): every name it lists at the package root and in the
modules it names stays importable, whatever the layout."""

import importlib

import pytest

import pysindy_xl as px

ROOT = ["Coordinates", "monomials", "products", "LagrangeLibrary", "ClassicalLibrary",
        "ExternalForces", "CatalogRepartition", "ExplicitOptimizer", "ImplicitOptimizer",
        "MixedOptimizer", "XLSINDy", "BumpTestFunctions", "WhittakerSmoother",
        "EnsembleOptimizer", "kinematic_catalog", "MassMatrixDynamics", "SimulationError",
        "SingularMassMatrixError", "JointFrictionLibrary", "FRICTION_MODELS"]
MODULES = {
    "pysindy_xl.expressions": ["parse_expression"],
    "pysindy_xl.quality": ["force_prediction"],
    "pysindy_xl.mujoco": ["get_system", "MJCFSystem", "generate_dataset", "load_dataset",
                          "Dataset", "Trajectory", "simulate_trajectory",
                          "validation_trajectory", "validate_model", "reference_catalog",
                          "actuator_law", "start_on_reference", "kinematic_catalog"],
}
METHODS = ["fit", "coefficients", "get_feature_names", "equations", "print", "lagrangian",
           "predict", "simulate", "to_jax", "to_gymnasium", "save", "load",
           "physical_parameters", "to_mjcf", "predict_forces"]


@pytest.mark.parametrize("name", ROOT)
def test_root_names(name):
    assert name in px.__all__
    assert getattr(px, name) is not None


@pytest.mark.parametrize("module", sorted(MODULES))
def test_module_names(module):
    loaded = importlib.import_module(module)
    missing = [name for name in MODULES[module] if getattr(loaded, name, None) is None]
    assert missing == []


def test_model_methods_and_alternate_constructor():
    missing = [name for name in METHODS if not callable(getattr(px.XLSINDy, name, None))]
    assert missing == []
    assert callable(px.ExternalForces.from_signed_indices)
    assert px.FRICTION_MODELS == ("viscous", "coulomb", "asymmetric", "stribeck", "offset")
