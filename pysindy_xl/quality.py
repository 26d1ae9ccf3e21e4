"""The fit-quality report, at its former path: :mod:`pysindy_xl.evaluation.quality`."""

from .evaluation.quality import (  # noqa: F401
    __all__,
    fit_quality,
    force_prediction,
    plot_identification,
    quality_lines,
)
