"""The fit stage: trajectories in, a catalog problem out, solved.

One fit of :class:`~pysindy_xl.XLSINDy` goes one way through here::

    check_fit   ->  build_problem  ->  choose_noise_model  ->  solve      ->  fitted_state
    arrays          CatalogProblem     problem, weighting      optimizer      attributes

* :mod:`~pysindy_xl.fit.trajectories`: the catalog, the checked arrays of ``fit``, the
  formulation (:func:`resolve_formulation`), missing derivatives for the strong form;
* :mod:`~pysindy_xl.fit.build`: the :class:`~pysindy_xl.optimizers.CatalogProblem` of the
  catalog on the data, strong or weak, with its row noise and its :class:`CatalogMap` back
  to the catalog (still coordinates, :mod:`~pysindy_xl.fit.still`, and dependent columns
  left out);
* :mod:`~pysindy_xl.fit.noise_model`: for measured forces, position noise or force noise,
  whichever predicts held-out time blocks best (:mod:`pysindy_xl.weak.selection`);
* :mod:`~pysindy_xl.fit.solve`: the optimizer for the problem and the reweighting solver;
* :mod:`~pysindy_xl.fit.wrap`: the solution back in the catalog's terms, the identified
  dynamics in mass-matrix form, the orientation of free laws;
* :mod:`~pysindy_xl.fit.diagnostics`: the identified mass matrix on the training states.

:meth:`XLSINDy.regression <pysindy_xl.XLSINDy.regression>` and the fit-quality report
(:mod:`pysindy_xl.quality`) build their rows with the same :func:`build_problem`.
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
from .wrap import catalog_dynamics, fitted_state

__all__ = [
    "CatalogMap",
    "build_problem",
    "probe_points",
    "resolve_optimizer",
    "choose_noise_model",
    "fit_smoother",
    "RememberedSmoother",
    "solve",
    "fitted_state",
    "catalog_dynamics",
    "check_fit",
    "estimator_trajectories",
    "trajectory_data",
    "differentiation_function",
    "resolve_formulation",
    "FORMULATIONS",
    "UNFORCED_WIDTH_MULTIPLES",
]
