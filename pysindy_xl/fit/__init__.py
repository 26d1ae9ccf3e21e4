"""The fit stage: trajectories in, a catalog problem out, solved.

One fit of :class:`~pysindy_xl.XLSINDy` goes one way through here::

    check_fit   ->  build_problem  ->  choose_noise_model  ->  solve      ->  wrap
    arrays          CatalogProblem     problem, weighting      optimizer      attributes

(:mod:`~pysindy_xl.fit.trajectories`, :mod:`~pysindy_xl.fit.build` with
:mod:`~pysindy_xl.fit.still`, :mod:`~pysindy_xl.fit.noise_model`,
:mod:`~pysindy_xl.fit.solve`, :mod:`~pysindy_xl.fit.wrap` with
:mod:`~pysindy_xl.fit.diagnostics`). :meth:`XLSINDy.regression
<pysindy_xl.XLSINDy.regression>` and the fit-quality report (:mod:`pysindy_xl.quality`)
build their rows with the same :func:`build_problem`.
"""

from .build import UNFORCED_WIDTH_MULTIPLES, CatalogMap, build_problem, probe_points
from .noise_model import RememberedSmoother, choose_noise_model, fit_smoother
from .solve import resolve_optimizer, solve
from .trajectories import (
    FORMULATIONS,
    check_fit,
    differentiation_function,
    estimator_trajectories,
    resolve_formulation,
    trajectory_data,
)
from .wrap import catalog_dynamics

__all__ = ["CatalogMap", "build_problem", "probe_points", "resolve_optimizer", "choose_noise_model",
           "fit_smoother", "RememberedSmoother", "solve", "catalog_dynamics",
           "check_fit", "estimator_trajectories", "trajectory_data", "differentiation_function",
           "resolve_formulation", "FORMULATIONS", "UNFORCED_WIDTH_MULTIPLES"]
