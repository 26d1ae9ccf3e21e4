"""The fit stage: trajectories in, a catalog problem out, solved.

One fit of :class:`~pysindy_xl.XLSINDy` goes one way through here::

    check_fit   ->  build_problem  ->  choose_noise_model  ->  solve      ->  wrap
    arrays          CatalogProblem     problem, weighting      optimizer      attributes

(:mod:`~pysindy_xl.fit.trajectories`, :mod:`~pysindy_xl.fit.build` with
:mod:`~pysindy_xl.fit.still`, :mod:`~pysindy_xl.fit.noise_model`,
:mod:`~pysindy_xl.fit.solve`, :mod:`~pysindy_xl.fit.wrap` with
:mod:`~pysindy_xl.fit.diagnostics`). :meth:`XLSINDy.regression
<pysindy_xl.XLSINDy.regression>` and the fit-quality report (:mod:`pysindy_xl.quality`)
build their rows with the same :func:`build_problem`; the fit-quality report and the catalog
growth's held-out criterion judge an unforced law's equations over their kinetic part
(:mod:`~pysindy_xl.fit.kinetic_scale`).
"""

from .build import UNFORCED_WIDTH_MULTIPLES, CatalogMap, build_problem
from .build import probe_points as probe_points
from .noise_model import RememberedSmoother as RememberedSmoother
from .noise_model import choose_noise_model as choose_noise_model
from .noise_model import fit_smoother as fit_smoother
from .solve import resolve_optimizer as resolve_optimizer
from .solve import solve
from .trajectories import FORMULATIONS as FORMULATIONS
from .trajectories import check_fit, resolve_formulation
from .trajectories import differentiation_function as differentiation_function
from .trajectories import estimator_trajectories as estimator_trajectories
from .trajectories import trajectory_data as trajectory_data
from .wrap import catalog_dynamics as catalog_dynamics

# the other stages of XLSINDy.fit above are importable from here, not public (not in __all__)
__all__ = ["build_problem", "solve", "check_fit", "resolve_formulation", "CatalogMap",
           "UNFORCED_WIDTH_MULTIPLES"]
