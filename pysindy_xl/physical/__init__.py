"""Physical consistency of identified rigid-body parameters.

:mod:`.structure` says what a catalog's coefficients stand for physically (base parameters as
images of the bodies' inertial parameters, friction coefficients, with the dry friction laws of
:mod:`.friction`); :mod:`.sdp` states rigid bodies' constraints on them as linear matrix
inequalities and solves the programs that realize base parameters or fit under the constraints
(cvxpy); :mod:`.rigid_body` evaluates the equations of motion of any parameters on the
kinematic tree (mass matrix, bias forces). Used by
:class:`~pysindy_xl.optimizers.PhysicalOptimizer` and the MJCF export.
"""

from .friction import dry_friction_law, regularized_dry_friction
from .rigid_body import KinematicTree, physical_parameters_from_base, rigid_body_dynamics
from .sdp import body_constraints, consistent_least_squares, realize
from .structure import (
    INERTIAL_PARAMETERS,
    PhysicalStructure,
    catalog_structure,
    friction_columns,
    friction_kind,
    pseudo_inertia_matrix,
)

__all__ = [
    "INERTIAL_PARAMETERS",
    "PhysicalStructure",
    "catalog_structure",
    "friction_columns",
    "friction_kind",
    "pseudo_inertia_matrix",
    "dry_friction_law",
    "regularized_dry_friction",
    "body_constraints",
    "consistent_least_squares",
    "realize",
    "KinematicTree",
    "physical_parameters_from_base",
    "rigid_body_dynamics",
]
