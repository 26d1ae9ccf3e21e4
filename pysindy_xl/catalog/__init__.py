"""Catalogs that build themselves: candidate Lagrangian terms from the coordinates' names and
kinds (:class:`AutomaticCatalog`), grown on data while a held-out criterion improves
(:func:`grow_catalog`)."""

from .automatic import DISSIPATION, AutomaticCatalog
from .bases import (
    KINDS,
    anchored_spring,
    bspline,
    exponential_pair,
    natural_splines,
    quadratic_end_splines,
    truncated_power_splines,
)
from .growth import MORE_MOVES, MOVES, GrowthResult, GrowthStep, grow_catalog
from .kinds import coordinate_kinds

__all__ = ["AutomaticCatalog", "grow_catalog", "GrowthResult", "GrowthStep", "MOVES", "MORE_MOVES",
           "coordinate_kinds", "DISSIPATION", "KINDS", "bspline", "natural_splines",
           "quadratic_end_splines", "truncated_power_splines", "exponential_pair",
           "anchored_spring"]
