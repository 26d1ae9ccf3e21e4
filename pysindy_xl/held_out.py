"""Held-out validation of an identified model, at its former path:
:mod:`pysindy_xl.evaluation.held_out`."""

from .evaluation.held_out import (  # noqa: F401
    SCORING_DERIVATIVES,
    ForceScore,
    __all__,
    blocked_cross_validation,
    score_forces,
    scoring_derivatives,
)
