"""Ensembles of catalog fits: inclusion probabilities and coefficient intervals.

Any catalog optimizer is refit on ``n_models`` subsamples of the rows of the regression
matrix (strong or weak). Rows are subsampled by contiguous chunks of time, the same chunks in
every coordinate's block (the rows of one instant belong together, and neighbouring rows are
correlated through smoothing and overlapping test functions), without replacement, so that
cross-validated selection inside each fit never sees a row twice:

.. math:: \\xi^{(b)} = \\text{optimizer}(\\Theta_{R_b}), \\quad b = 1..B,

with ``R_b`` a random ``fraction`` of the chunks. The ensemble reports, per catalog term, the
inclusion probability ``P(xi_j != 0)`` and intervals of ``xi_j`` (from the fits' spread), in the
coefficients' own (physical) units, and its model keeps the terms included in at least
``inclusion`` of the fits with their median coefficient.
"""

from __future__ import annotations

import joblib
import numpy as np
import scipy.stats
from sklearn.base import clone

from .._validation import check_instance, check_option
from ._base import (
    CatalogOptimizer,
    accepts_noise_moments,
    check_catalog_problem,
    check_noise_moments,
)
from .explicit import ExplicitOptimizer

__all__ = ["EnsembleOptimizer"]


class EnsembleOptimizer(CatalogOptimizer):
    """Subsample-and-refit ensemble around any catalog optimizer (see the module docs).

    Parameters
    ----------
    optimizer : catalog optimizer, optional
        Refit on every subsample (cloned); default ``ExplicitOptimizer()``.
    n_models : int, default 20
        Number of fits.
    fraction : float, default 0.7
        Fraction of the time chunks in each subsample.
    n_chunks : int, default 20
        Contiguous chunks of each coordinate's rows.
    inclusion : float, default 0.5
        Inclusion probability from which a term enters the ensemble's model.
    confidence : float, default 0.95
        Coverage of the coefficient intervals.
    random_state : int or None, default 0
    n_jobs : int or None, default None
        Fits run in parallel by joblib (``None``: one at a time, or as a surrounding
        ``joblib.parallel_config`` says, e.g. a Dask or Ray backend; ``-1``: every core). The
        subsamples are drawn first, so the result does not depend on it.

    Attributes
    ----------
    coef_ : ndarray, shape (F,)
        Median coefficient of each term included in at least ``inclusion`` of the fits.
    coef_samples_ : ndarray, shape (n_models, F)
        Coefficients of every fit (failed fits are left out).
    inclusion_probability_ : ndarray, shape (F,)
    coef_interval_ : ndarray, shape (2, F)
        ``confidence`` interval of each coefficient: the median over the fits (zeros included)
        plus or minus Student's quantile times their standard deviation, widened by
        ``sqrt(f / (1 - f))`` for the subsample fraction ``f`` (delete-d jackknife), since a
        subsample estimate spreads less around the full-data one than the full-data estimate
        spreads around the truth. Smoothing bias is not covered.
    n_failed_ : int
        Fits that raised (e.g. no law found on a subsample).

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> rng = np.random.default_rng(0)
    >>> a, b, c = rng.normal(size=(3, 400))
    >>> force = 2 * a - 0.5 * c + 0.05 * rng.normal(size=400)
    >>> theta = np.column_stack([force, a, b, c])          # one coordinate, force column 0
    >>> opt = px.EnsembleOptimizer(n_models=10).fit_catalog(theta, 1, [0])
    >>> opt.inclusion_probability_.round(1).tolist()
    [1.0, 1.0, 0.0, 1.0]
    >>> bool(opt.coef_interval_[0, 1] < 2 < opt.coef_interval_[1, 1])
    True
    """

    def __init__(self, optimizer=None, n_models=20, fraction=0.7, n_chunks=20, inclusion=0.5,
                 confidence=0.95, random_state=0, n_jobs=None):
        self.optimizer = optimizer
        self.n_models = n_models
        self.fraction = fraction
        self.n_chunks = n_chunks
        self.inclusion = inclusion
        self.confidence = confidence
        self.random_state = random_state
        self.n_jobs = n_jobs

    def _check_params(self):
        for name in ("n_models", "n_chunks"):
            check_option(name, getattr(self, name), "int", low=2)
        for name in ("fraction", "inclusion", "confidence"):
            check_option(name, getattr(self, name), "real", low=0, low_open=True, high=1)
        if self.optimizer is not None:
            check_instance("optimizer", self.optimizer, "a catalog optimizer", "fit_catalog")
        if self.n_jobs is not None:
            check_option("n_jobs", self.n_jobs, "int")

    def fit_catalog(self, theta, n_coordinates, force_columns, noise_moments=None):
        """Fit the ensemble on a stacked catalog matrix.

        Parameters
        ----------
        theta : array, shape (n_coordinates * N, F)
        n_coordinates : int
        force_columns : sequence of int
        noise_moments : array, shape (n_coordinates, F, F), optional
            Errors-in-variables moments of all rows; each fit gets its subsample's share
            (the errors are stationary along the rows) when its optimizer takes them.

        Returns
        -------
        self
        """
        self._check_params()
        # the inner optimizers balance the coordinates of their own subsamples
        theta, force_columns = check_catalog_problem(theta, n_coordinates, force_columns,
                                                     balance=False)
        if noise_moments is not None:
            noise_moments = check_noise_moments(noise_moments, int(n_coordinates),
                                                theta.shape[1])
        n_rows = theta.shape[0] // n_coordinates
        n_chunks = min(int(self.n_chunks), n_rows)
        edges = np.linspace(0, n_rows, n_chunks + 1).astype(int)
        n_keep = max(2, int(round(self.fraction * n_chunks)))
        rng = np.random.default_rng(self.random_state)
        base = ExplicitOptimizer() if self.optimizer is None else self.optimizer
        extra = {}
        if noise_moments is not None and accepts_noise_moments(base):
            extra["noise_moments"] = noise_moments * (n_keep / n_chunks)
        subsamples = []
        for _ in range(int(self.n_models)):
            chunks = np.sort(rng.choice(n_chunks, size=n_keep, replace=False))
            rows = np.concatenate([np.arange(edges[k], edges[k + 1]) for k in chunks])
            subsamples.append((np.arange(n_coordinates)[:, None] * n_rows
                               + rows[None, :]).ravel())
        fits = joblib.Parallel(n_jobs=self.n_jobs)(
            joblib.delayed(_fit_subsample)(base, theta[rows], n_coordinates, force_columns,
                                           extra) for rows in subsamples)
        samples = [coef for coef in fits if coef is not None]
        failed = len(fits) - len(samples)
        if not samples:
            raise RuntimeError("EnsembleOptimizer: every fit of the ensemble failed")
        samples = np.array(samples)
        self.coef_samples_ = samples
        self.n_failed_ = failed
        self.inclusion_probability_ = np.mean(samples != 0, axis=0)
        included = self.inclusion_probability_ >= self.inclusion
        coef = np.zeros(theta.shape[1])
        for j in np.flatnonzero(included):
            coef[j] = np.median(samples[samples[:, j] != 0, j])
        self.coef_ = coef
        # A subsample of a fraction f of the data spreads around the full-data estimate by
        # sqrt((1 - f) / f) times that estimate's own sampling spread (delete-d jackknife),
        # so the fits' standard deviation is scaled back up by sqrt(f / (1 - f)). Student's
        # quantile of that spread (it is estimated from the fits), not the fits' own
        # percentiles: the 2.5 and 97.5 percentiles of 20 fits are those of the two most
        # extreme ones, far noisier than a spread measured with all of them (and too narrow
        # on average).
        center = np.median(samples, axis=0)
        half_width = np.zeros_like(center)
        if len(samples) > 1:
            quantile = scipy.stats.t.ppf(0.5 + self.confidence / 2, df=len(samples) - 1)
            half_width = (quantile * np.sqrt(n_keep / max(n_chunks - n_keep, 1))
                          * samples.std(axis=0, ddof=1))
        self.coef_interval_ = np.array([center - half_width, center + half_width])
        return self

    def plot(self, feature_names=None, axes=None):
        """Inclusion probabilities and coefficient distributions of the ensemble.

        Parameters
        ----------
        feature_names : list of str, optional
        axes : pair of matplotlib Axes, optional

        Returns
        -------
        pair of matplotlib Axes
        """
        import matplotlib.pyplot as plt

        shown = np.flatnonzero(self.inclusion_probability_ > 0)
        names = (np.asarray(feature_names) if feature_names is not None
                 else np.array([f"f{j}" for j in range(len(self.coef_))]))
        if axes is None:
            _, axes = plt.subplots(1, 2, figsize=(10, 0.3 * len(shown) + 1.5), sharey=True)
        y = np.arange(len(shown))
        axes[0].barh(y, self.inclusion_probability_[shown])
        axes[0].axvline(self.inclusion, color="k", lw=0.8, ls="--")
        axes[0].set_yticks(y, names[shown])
        axes[0].set_xlabel("inclusion probability")
        axes[1].boxplot([self.coef_samples_[:, j] for j in shown], vert=False, positions=y)
        axes[1].set_xscale("symlog", linthresh=1e-3)
        axes[1].set_xlabel("coefficient over the ensemble")
        return axes


def _fit_subsample(base, theta, n_coordinates, force_columns, extra):
    """Coefficients of one subsample fit, or None when it fails (no law, too few rows)."""
    try:
        fitted = clone(base).fit_catalog(theta, n_coordinates, force_columns, **extra)
    except (ValueError, RuntimeError, np.linalg.LinAlgError):
        return None
    return np.asarray(fitted.coef_, dtype=float)
