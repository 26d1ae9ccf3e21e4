"""The choose step of the fit stage: where the noise of measured-force data sits.

A weak problem of positions and measured forces is built for position noise (test functions
as wide as the motion's spectrum allows, rows weighted by the noise the positions propagate
into them). :func:`choose_noise_model` also builds it for force noise (narrow test
functions, unweighted rows) and keeps whichever predicts held-out time blocks of the data
best, by the rule and the derivative-free score of :mod:`pysindy_xl.weak.selection`.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib

import numpy as np
from sklearn.base import clone

from ..optimizers import EnsembleOptimizer, catalog_tags
from ..weak import BumpTestFunctions, WhittakerSmoother, selection
from .build import build_problem, with_mass_matrices
from .solve import solve

__all__ = ["RememberedSmoother", "choose_noise_model", "fit_smoother"]


class RememberedSmoother:
    """A smoother that smooths each distinct input once.

    The default, candidates' and scoring rows of :func:`choose_noise_model` smooth the same
    pieces and the same (seeded) noisy draws. Results are kept by the content of ``(t, x)``
    (and weights); ``deepcopy`` is the object itself, and a shallow copy keeps its last weights,
    as the weak regression's propagation needs.

    Parameters
    ----------
    smoother : WhittakerSmoother, optional
        The smoother remembered; default None: ``WhittakerSmoother()``.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 101)
    >>> remembered = RememberedSmoother()
    >>> first = remembered.smooth(t, np.sin(t)[:, None])
    >>> remembered.smooth(t, np.sin(t)[:, None]) is first
    True
    """

    def __init__(self, smoother=None):
        self.smoother = smoother or WhittakerSmoother()
        self._results = {}

    def __deepcopy__(self, memo):
        return self

    @staticmethod
    def _key(*arrays):
        digest = hashlib.sha1()
        for array in arrays:
            digest.update(np.ascontiguousarray(array, dtype=float).reshape(-1).view(np.uint8))
        return digest.hexdigest()

    def smooth(self, t, x):
        """``smoother.smooth(t, x)``, computed once per distinct ``(t, x)``.

        Parameters
        ----------
        t : array, shape (N,)
            Times.
        x : array, shape (N, n)
            Positions.

        Returns
        -------
        q, qd, qdd : ndarray, shape (N, n)
            Smoothed positions and their derivatives (the remembered result).
        """
        key = ("smooth", self._key(t, x))
        if key not in self._results:
            fitted = copy.deepcopy(self.smoother)
            self._results[key] = (fitted, fitted.smooth(t, x))
        self._fitted, result = self._results[key]
        for name in ("lam_", "noise_"):
            if hasattr(self._fitted, name):
                setattr(self, name, getattr(self._fitted, name))
        return result

    def resmooth(self, t, x):
        """The last :meth:`smooth`'s ``resmooth(t, x)``, computed once per distinct input.

        Parameters
        ----------
        t : array, shape (N,)
            Times.
        x : array, shape (N, n)
            Positions (a noisy draw), smoothed with the weights the last :meth:`smooth` chose.

        Returns
        -------
        q, qd, qdd : ndarray, shape (N, n)
            Smoothed positions and their derivatives.
        """
        weights = getattr(self._fitted, "lam_", ())
        key = ("resmooth", self._key(t, x, weights))
        if key not in self._results:
            self._results[key] = self._fitted.resmooth(t, x)
        return self._results[key]


def fit_smoother(smoother=None):
    """The smoother of one fit.

    ``smoother`` remembered (:class:`RememberedSmoother`) where it propagates the noise of the
    positions, the case in which :func:`choose_noise_model` builds the rows again.

    Parameters
    ----------
    smoother : WhittakerSmoother or other smoother, optional
        The estimator's smoother; default None: ``WhittakerSmoother()``.

    Returns
    -------
    smoother
        A :class:`RememberedSmoother` around it, or ``smoother`` itself when it has no
        ``resmooth`` (does not propagate noise) or is a :class:`RememberedSmoother` already
        (shared by several fits of the same data, as :func:`~pysindy_xl.grow_catalog` does).
    """
    smoother = smoother or WhittakerSmoother()
    if isinstance(smoother, RememberedSmoother):  # shared by several fits: remembers already
        return smoother
    return (RememberedSmoother(smoother) if callable(getattr(smoother, "resmooth", None))
            else smoother)


def _unbagged(optimizer):
    """``optimizer`` (unfitted) with any :class:`~pysindy_xl.EnsembleOptimizer` inside it
    replaced by its base optimizer: the fits on time blocks compare noise models, for which
    one fit stands for the bag's point estimate at a twentieth of the cost."""
    if isinstance(optimizer, EnsembleOptimizer):  # its pilot: one fit of its base
        return _unbagged(optimizer.pilot())
    params = optimizer.get_params(deep=False) if hasattr(optimizer, "get_params") else {}
    inner = params.get("optimizer")
    if inner is not None and hasattr(inner, "get_params"):
        return clone(optimizer).set_params(optimizer=_unbagged(inner))
    return clone(optimizer)


def _applies(problem, residual_covariance, test_functions) -> bool:
    origin = problem.catalog_map
    return (residual_covariance == "auto" and test_functions is None
            and problem.row_noise is not None and origin is not None
            and origin.formulation == "weak"
            and bool(origin.forced[origin.coordinates].all()))


def choose_noise_model(problem, library, data, optimizer, smoother=None,
                       residual_covariance="auto", test_functions=None):
    """The problem and weighting to solve: position noise (``problem`` as built, weighted)
    or force noise (narrow test functions, unweighted), by held-out force error.

    Chosen only for the weak form on positions and forces of every moving coordinate, with
    the default test functions and ``residual_covariance="auto"``; otherwise ``problem`` and
    ``residual_covariance`` come back as they are. The choice and every candidate's error
    are recorded in the problem's ``catalog_map.weak_info["noise_model"]``.

    Parameters
    ----------
    problem : CatalogProblem
        From :func:`~pysindy_xl.fit.build_problem` (weak form, with its row noise).
    library : fitted CatalogRepartition
        The catalog.
    data : list of dict
        The trajectories the problem was built from.
    optimizer : catalog optimizer
        Cloned for each fit on time blocks, without bagging (an ensemble's base optimizer).
    smoother : smoother, optional
        The fit's smoother (:func:`fit_smoother`); default None.
    residual_covariance : bool or "auto", default "auto"
        The estimator's setting; only ``"auto"`` lets the noise model be chosen.
    test_functions : BumpTestFunctions, optional
        The estimator's setting; default None (the default test functions, which the choice
        needs).

    Returns
    -------
    problem : CatalogProblem
        The problem to solve.
    weigh : bool or "auto"
        For :func:`~pysindy_xl.fit.solve`.
    """
    if not _applies(problem, residual_covariance, test_functions):
        return problem, residual_covariance
    origin = problem.catalog_map
    info = origin.weak_info
    tests = BumpTestFunctions()
    remembered = (smoother if isinstance(smoother, RememberedSmoother)
                  else RememberedSmoother(smoother))
    steps = np.concatenate([np.diff(d["t"]) for d in data])
    scoring = max(selection.bandwidth_half_width(selection.SCORING_BANDWIDTH, tests.power),
                  tests.min_samples * float(np.quantile(steps, 0.999)))
    width = min(scoring, info["half_width"])

    def built(half_width, propagate=False):
        other = build_problem(library, data, "weak", test_functions=tests,
                              smoother=remembered,
                              half_width=half_width, still=~origin.coordinates,
                              propagate=propagate)
        columns = np.searchsorted(other.catalog_map.columns, origin.columns)
        noise = None if other.row_noise is None else other.row_noise.columns(columns)
        return dataclasses.replace(
            problem, theta=other.theta[:, columns], row_noise=noise,
            noise_moments=None if noise is None else noise.moments(),
            noise_draws=None if noise is None else noise.draws,
            catalog_map=dataclasses.replace(origin, weak_info=other.catalog_map.weak_info))

    scored = built(scoring, propagate=True)
    forces = dataclasses.replace(scored, row_noise=None, noise_moments=None,
                                 noise_draws=None) if width == scoring else built(width)
    candidates = [(selection.NoiseModel("positions", info["half_width"], True), problem),
                  (selection.NoiseModel("forces", width, False), forces)]

    if catalog_tags(optimizer).uses_mass_matrices:  # once, for every fit on blocks
        problem = with_mass_matrices(problem, library)

    def fit(rows, noise, weigh):
        part = dataclasses.replace(
            problem, theta=rows, row_noise=noise,
            noise_moments=None if noise is None else noise.moments(),
            noise_draws=None if noise is None else noise.draws)
        return solve(_unbagged(optimizer), part, weigh=weigh).coef_

    spans = np.array([[d["t"][0], d["t"][-1]] for d in data])
    best, errors = selection.choose_noise_model(
        [(model, p.theta, p.catalog_map.weak_info["supports"], p.row_noise)
         for model, p in candidates],
        (scored.theta, scored.catalog_map.weak_info["supports"], scored.row_noise),
        spans, problem.force_columns, fit)
    model, chosen = candidates[0 if best is None else best]
    record = {"chosen": model.name, "half_width": model.half_width,
              "scoring_half_width": scoring,
              "candidates": [{"noise": m.name, "half_width": m.half_width,
                              "held_out_error": e}
                             for (m, _), e in zip(candidates, errors, strict=False)]}
    chosen_info = {**chosen.catalog_map.weak_info, "noise_model": record}
    return (dataclasses.replace(chosen, catalog_map=dataclasses.replace(
        chosen.catalog_map, weak_info=chosen_info)), model.weigh)
