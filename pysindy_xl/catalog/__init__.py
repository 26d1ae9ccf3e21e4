"""Catalogs that build themselves: candidate Lagrangian terms from the coordinates' names and
kinds (:class:`AutomaticCatalog`), grown on data while a held-out criterion improves
(:func:`grow_catalog`)."""

from .automatic import DISSIPATION, AutomaticCatalog, coordinate_kinds
from .bases import (
    KINDS,
    bspline,
    exponential_pair,
    natural_splines,
    quadratic_end_splines,
    truncated_power_splines,
)
from .growth import MORE_MOVES, MOVES, GrowthResult, GrowthStep, grow_catalog

__all__ = ["AutomaticCatalog", "grow_catalog", "GrowthResult", "GrowthStep", "MOVES", "MORE_MOVES",
           "coordinate_kinds", "DISSIPATION", "KINDS", "bspline", "natural_splines",
           "quadratic_end_splines", "truncated_power_splines", "exponential_pair"]
