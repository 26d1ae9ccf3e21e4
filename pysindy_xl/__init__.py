"""pysindy-xl: sparse identification of mechanical systems from data."""

from .symbols import Coordinates, monomials, products

__all__ = ["Coordinates", "monomials", "products"]
__version__ = "0.1.0"
