"""Errors-in-variables total least squares on every column of a complete catalog
(:class:`TotalLeastSquaresOptimizer`)."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np

from .._validation import Interval, Options, validate_params
from ._base import CatalogOptimizer, warn_unexplained
from ._sparse import column_norms, null_vector, triangular_factor
from .laws import UndeterminedLawWarning, normalize_law
from .noise_ratio import noise_pencil

__all__ = ["TotalLeastSquaresOptimizer"]

_NORMALIZATIONS = ("dominant", "inertia")


class TotalLeastSquaresOptimizer(CatalogOptimizer):
    r"""Unforced law of a complete catalog by errors-in-variables total least squares.

    Where no column is spurious (a kinematic catalog), the unforced law needs no selection: it
    is the direction the noisy columns (moments ``S = E[E^T E]``) contradict least,

    .. math:: \hat\xi = \arg\min_{\xi \ne 0} \frac{\lVert \Theta \xi \rVert^2}{\xi^T S \xi},

    the smallest generalized eigenvector of ``(Theta^T Theta, S)`` (Fuller, 1987, section
    4.1); without noise moments, the smallest right singular vector of the unit-norm columns.
    Further directions whose ratio ``rho_k <= undetermined_ratio * max(rho_1, 1)`` hold as
    well: the law is then undetermined (``undetermined_``, with a warning).

    Parameters
    ----------
    undetermined_ratio : float, default 3.0
        Further directions with a noise ratio within this factor of ``max(rho_1, 1)`` are
        reported as undetermined.
    normalization : {"dominant", "inertia"}, default "dominant"
        :func:`~pysindy_xl.optimizers.laws.normalize_law`, or a mean mass-matrix trace of ``n``
        over the sample states; given mass matrices, the kinetic energy is made positive.

    Attributes
    ----------
    coef_ : ndarray, shape (F,)
        The law, normalized (``normalization``).
    noise_ratio_ : float
        The law's noise ratio (about 1 when it holds); nan without noise moments.
    pencil_ratios_ : ndarray
        Noise ratios of the principal directions, ascending.
    undetermined_ : ndarray, shape (k, F)
        Further laws the data hold as well (normalized as ``coef_``).
    column_norms_ : ndarray, shape (F,)
        Norms of the columns.
    selection_method_ : str
        ``"total least squares"``.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> a, b = rng.normal(size=(2, 2000))
    >>> clean = np.column_stack([a, b, a - 2 * b])
    >>> theta = clean + 0.05 * rng.normal(size=clean.shape)
    >>> opt = TotalLeastSquaresOptimizer().fit_catalog(theta, 1, [],
    ...                                                noise_moments=5.0 * np.eye(3)[None])
    >>> (opt.coef_ / opt.coef_[0]).round(1) + 0.0, len(opt.undetermined_)
    (array([ 1., -2., -1.]), 0)
    """

    spec_type = "TotalLeastSquaresOptimizer"

    def catalog_tags(self):
        """What this optimizer can do and needs.

        It uses the mass matrices and wants unbiased derivatives.

        Returns
        -------
        CatalogTags
            The tags (:class:`~pysindy_xl.optimizers.tags.CatalogTags`): ``requires_forces``,
            ``can_refit``, ``balances_rows``, ``derivative_estimate``, ...
        """
        return dataclasses.replace(super().catalog_tags(), uses_mass_matrices=True,
                                   derivative_estimate="unbiased")

    _parameter_constraints = {
        "undetermined_ratio": [Interval("real", 1)],
        "normalization": [Options(_NORMALIZATIONS)],
    }

    def __init__(self, undetermined_ratio=3.0, normalization="dominant"):
        self.undetermined_ratio = undetermined_ratio
        self.normalization = normalization

    def _check_params(self):
        validate_params(self)

    def _solve(self, problem):
        return self._solve_support(problem, np.ones(problem.n_features, dtype=bool))

    def _solve_support(self, problem, support):
        """The law on the columns of ``support`` (all of them by :meth:`_solve`)."""
        theta, n = problem.theta, problem.n_coordinates
        norms, nonzero = column_norms(theta)
        columns = np.flatnonzero(np.asarray(support, dtype=bool) & nonzero)
        if columns.size < 2:
            raise ValueError(f"theta: {columns.size} non-zero column(s) in the support; a law "
                             "needs at least two")
        scaled = theta[:, columns] / norms[columns]
        factor = triangular_factor(scaled)
        moments = problem.pooled_moments()
        if moments is None:
            singular = np.linalg.svd(factor, compute_uv=False)
            singular = np.concatenate([singular, np.zeros(columns.size - singular.size)])
            ratios = (singular[::-1] / max(singular[0], 1e-300)) ** 2
            directions = null_vector(scaled)[0][:, None]
            self.noise_ratio_ = np.nan
            undetermined = np.zeros(0, dtype=int)
        else:
            local = moments[np.ix_(columns, columns)] / np.outer(norms[columns], norms[columns])
            ratios, directions = noise_pencil(factor, local)
            self.noise_ratio_ = float(ratios[0])
            limit = self.undetermined_ratio * max(float(ratios[0]), 1.0)
            undetermined = np.flatnonzero(ratios[1:] <= limit) + 1
        laws = np.zeros((1 + undetermined.size, theta.shape[1]))
        laws[:, columns] = directions[:, np.concatenate([[0], undetermined])].T / norms[columns]
        laws = np.array([self._normalize(law, norms, problem) for law in laws])
        self.column_norms_ = norms
        self.pencil_ratios_ = np.asarray(ratios)
        self.coef_ = laws[0]
        self.undetermined_ = laws[1:]
        self.selection_method_ = "total least squares"
        if len(self.undetermined_):
            warnings.warn(
                f"TotalLeastSquaresOptimizer: the data hold {len(self.undetermined_)} further "
                "independent law(s) to the noise (noise ratios "
                f"{np.round(ratios[undetermined], 2).tolist()} against {ratios[0]:.3g}): the "
                "combination is undetermined, see undetermined_. Record trajectories at "
                "several energy levels, or force a coordinate.",
                UndeterminedLawWarning, stacklevel=4)
        warn_unexplained("TotalLeastSquaresOptimizer", theta, n, self.coef_, problem.force_columns)
        return self

    def _normalize(self, law, norms, problem):
        """Scale of ``normalization``; sign of a positive kinetic energy."""
        law = normalize_law(law, norms, problem.force_columns, problem.reference_columns)
        if problem.mass_matrices is None:
            return law
        trace = float(np.mean(np.einsum("sfii,f->s", problem.mass_matrices, law)))
        forced = np.any(law[problem.force_columns] != 0) if len(problem.force_columns) else False
        if self.normalization == "inertia" and trace != 0 and not forced:
            return law * (problem.n_coordinates / trace)
        return -law if trace < 0 and not forced else law
