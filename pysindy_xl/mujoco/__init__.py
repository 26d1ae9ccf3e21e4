"""MuJoCo systems and their catalogs; the names of data generation and validation handed on.

Subpackages by concern: :mod:`.systems` and :mod:`.catalogs` (no simulation); the names of
:mod:`pysindy_xl.simulation` and :mod:`pysindy_xl.evaluation` are handed on here. Public names
load on first use (PEP 562): importing this package imports neither MuJoCo, SymPy, PySINDy nor
matplotlib.

>>> import pysindy_xl.mujoco as pxm
>>> pxm.get_system("cart-pole").coordinate_names
('x', 'theta')
"""

from __future__ import annotations

from .._optional import import_mujoco, lazy_attributes

# public name -> submodule that defines it (imported on first attribute access)
_LAZY = {
    **dict.fromkeys(("ActuatorLaw", "actuator_law", "start_on_reference"), "systems.actuation"),
    **dict.fromkeys(("SYSTEMS", "CartDoublePendulum", "CartPole", "DoublePendulum",
                     "MJCFSystem", "MuJoCoSystem", "TriplePendulum", "coordinate_system",
                     "default_xml_path", "equations_of_motion", "get_system",
                     "system_from_metadata"), "systems.registry"),
    **dict.fromkeys(("ConstraintWarning", "generate_dataset", "simulate_trajectory"),
                    "..simulation.generate"),
    **dict.fromkeys(("Integration", "UnstableSimulationError", "choose_integration"),
                    "..simulation.integration"),
    **dict.fromkeys(("FORCING_MODES", "SumOfSinusoids"), "..simulation.forcing"),
    "FourierTrajectory": "..simulation.fourier",
    "excitation_trajectory": "..simulation.excitation",
    **dict.fromkeys(("CATALOG_KINDS", "classical_terms", "lagrange_terms", "reference_catalog",
                     "true_coefficients"), "catalogs.reference"),
    **dict.fromkeys(("KinematicCatalog", "PolynomialLagrangeLibrary", "kinematic_catalog"),
                    "catalogs.kinematic"),
    **dict.fromkeys(("Payload", "identify_payload"), "catalogs.payload"),
    **dict.fromkeys(("DEFAULT_DIVERGENCE_BOUND", "ValidationResult", "compare_trajectories",
                     "validate_model", "validation_trajectory"), "..evaluation.validation"),
    "compare_physics": "..evaluation.physics",
    **dict.fromkeys(("plot_validation", "plot_coefficients"), "..evaluation.plots"),
    # the data of a generated run (kept here by the public API; defined in pysindy_xl.data)
    **dict.fromkeys(("Dataset", "Trajectory", "load_dataset"), "..data.dataset"),
}

__all__ = ["import_mujoco", *_LAZY]

__getattr__, __dir__ = lazy_attributes(__name__, _LAZY)
