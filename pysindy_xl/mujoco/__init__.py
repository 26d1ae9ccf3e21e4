"""MuJoCo systems, data generation, reference catalogs and validation of identified models.

Subpackages by concern: :mod:`.systems`, :mod:`.simulation`, :mod:`.catalogs` and
:mod:`.evaluation`. Public names load on first use (PEP 562): importing this package imports
neither MuJoCo, SymPy, PySINDy nor matplotlib.

>>> import pysindy_xl.mujoco as pxm
>>> pxm.get_system("cart-pole").coordinate_names
('x', 'theta')
"""

from __future__ import annotations

from .._optional import import_optional, lazy_attributes

# public name -> submodule that defines it (imported on first attribute access)
_LAZY = {
    **dict.fromkeys(("ActuatorLaw", "actuator_law", "start_on_reference"), "systems.actuation"),
    **dict.fromkeys(("SYSTEMS", "CartDoublePendulum", "CartPole", "DoublePendulum",
                     "MJCFSystem", "MuJoCoSystem", "TriplePendulum", "coordinate_system",
                     "default_xml_path", "equations_of_motion", "get_system",
                     "system_from_metadata"), "systems.registry"),
    **dict.fromkeys(("ConstraintWarning", "generate_dataset", "simulate_trajectory"),
                    "simulation.generate"),
    **dict.fromkeys(("Integration", "UnstableSimulationError", "choose_integration"),
                    "simulation.integration"),
    **dict.fromkeys(("FORCING_MODES", "SumOfSinusoids"), "simulation.forcing"),
    "FourierTrajectory": "simulation.fourier",
    "excitation_trajectory": "simulation.excitation",
    **dict.fromkeys(("CATALOG_KINDS", "classical_terms", "lagrange_terms", "reference_catalog",
                     "true_coefficients"), "catalogs.reference"),
    **dict.fromkeys(("KinematicCatalog", "PolynomialLagrangeLibrary", "kinematic_catalog"),
                    "catalogs.kinematic"),
    **dict.fromkeys(("Payload", "identify_payload"), "catalogs.payload"),
    **dict.fromkeys(("DEFAULT_DIVERGENCE_BOUND", "ValidationResult", "compare_trajectories",
                     "validate_model", "validation_trajectory"), "evaluation.validation"),
    "compare_physics": "evaluation.physics",
    **dict.fromkeys(("plot_validation", "plot_coefficients"), "evaluation.plots"),
    # the data of a generated run (kept here by the public API; defined in pysindy_xl.data)
    **dict.fromkeys(("Dataset", "Trajectory", "load_dataset"), "..data.dataset"),
}

__all__ = ["import_mujoco", *_LAZY]

def import_mujoco():
    """The ``mujoco`` module, imported on first use: the one way this package imports MuJoCo.

    Returns
    -------
    module
        The ``mujoco`` package.

    Raises
    ------
    ImportError
        ``pysindy_xl._optional.MissingExtraError``, naming the ``pysindy-xl[mujoco]`` extra,
        when MuJoCo is not installed.

    Examples
    --------
    >>> from pysindy_xl.mujoco import import_mujoco
    >>> hasattr(import_mujoco(), "MjModel")
    True
    """
    return import_optional("mujoco", purpose="MuJoCo simulation (pysindy_xl.mujoco)")


__getattr__, __dir__ = lazy_attributes(__name__, _LAZY)
