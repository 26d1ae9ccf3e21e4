"""Physical consistency of identified rigid-body parameters: what a catalog's coefficients stand
for (:mod:`.structure`, :mod:`.friction`), the rigid bodies' constraints and programs
(:mod:`.sdp`, cvxpy), and the equations of motion of any parameters (:mod:`.rigid_body`).
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

__all__ = ["INERTIAL_PARAMETERS", "PhysicalStructure", "catalog_structure", "friction_columns",
           "friction_kind", "pseudo_inertia_matrix", "dry_friction_law", "regularized_dry_friction",
           "body_constraints", "consistent_least_squares", "realize", "KinematicTree",
           "physical_parameters_from_base", "rigid_body_dynamics"]
