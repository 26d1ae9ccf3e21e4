"""MuJoCo systems, data generation, reference catalogs and validation of identified models.

The pipeline of the paper as a library: MJCF models of the cart-pole, the double pendulum and
the double pendulum on a cart (:mod:`.systems`), randomly forced trajectories with noise
(:mod:`.generate`), datasets as NPZ + JSON (:mod:`.dataset`), the reference catalogs of the
paper's comparison (:mod:`.catalogs`), catalogs derived from the kinematic tree of any MJCF
model (:mod:`.kinematic`) and the validation of an identified model against a fresh MuJoCo
trajectory (:mod:`.validation`, :mod:`.plots`), open loop or closed loop through the MJCF's
actuator law (:mod:`.actuation`). Every generated run is integrated stably and faithfully to
the continuous equations, and checked (:mod:`.integration`).
"""

from ..data.constraints import contiguous_segments, unconstrained_samples, unconstrained_windows
from ..data.dataset import Dataset, DatasetError, Trajectory, load_dataset
from .actuation import ActuatorLaw, actuator_law, start_on_reference
from .catalogs import (
    CATALOG_KINDS,
    classical_terms,
    lagrange_terms,
    reference_catalog,
    true_coefficients,
)
from .excitation import excitation_trajectory
from .forcing import FORCING_MODES, SumOfSinusoids
from .fourier import FourierTrajectory
from .generate import (
    NOISE_MODELS,
    ConstraintWarning,
    add_noise,
    generate_dataset,
    noise_levels,
    simulate_trajectory,
)
from .integration import Integration, UnstableSimulationError, choose_integration
from .kinematic import KinematicCatalog, PolynomialLagrangeLibrary, kinematic_catalog
from .payload import Payload, identify_payload
from .systems import (
    SYSTEMS,
    CartDoublePendulum,
    CartPole,
    DoublePendulum,
    MJCFSystem,
    MuJoCoSystem,
    TriplePendulum,
    coordinate_system,
    default_xml_path,
    equations_of_motion,
    get_system,
    system_from_metadata,
)
from .validation import (
    DEFAULT_DIVERGENCE_BOUND,
    ValidationResult,
    compare_physics,
    compare_trajectories,
    validate_model,
    validation_trajectory,
)

__all__ = [
    "Integration",
    "UnstableSimulationError",
    "choose_integration",
    "SYSTEMS",
    "CartDoublePendulum",
    "CartPole",
    "DoublePendulum",
    "MJCFSystem",
    "MuJoCoSystem",
    "TriplePendulum",
    "default_xml_path",
    "equations_of_motion",
    "get_system",
    "system_from_metadata",
    "coordinate_system",
    "unconstrained_samples",
    "unconstrained_windows",
    "contiguous_segments",
    "NOISE_MODELS",
    "ConstraintWarning",
    "noise_levels",
    "FORCING_MODES",
    "SumOfSinusoids",
    "FourierTrajectory",
    "excitation_trajectory",
    "Payload",
    "identify_payload",
    "add_noise",
    "generate_dataset",
    "simulate_trajectory",
    "Dataset",
    "DatasetError",
    "Trajectory",
    "load_dataset",
    "CATALOG_KINDS",
    "classical_terms",
    "lagrange_terms",
    "reference_catalog",
    "true_coefficients",
    "KinematicCatalog",
    "PolynomialLagrangeLibrary",
    "kinematic_catalog",
    "DEFAULT_DIVERGENCE_BOUND",
    "ValidationResult",
    "compare_trajectories",
    "start_on_reference",
    "compare_physics",
    "validate_model",
    "ActuatorLaw",
    "actuator_law",
    "validation_trajectory",
    "plot_validation",
    "plot_coefficients",
]


def __getattr__(name):
    # plots import matplotlib: load them on first use only
    if name in ("plot_validation", "plot_coefficients"):
        from . import plots

        return getattr(plots, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
