"""Ensembles of catalog fits: inclusion probabilities and coefficient intervals
(:class:`EnsembleOptimizer`)."""

from __future__ import annotations

import collections
import dataclasses
import warnings

import joblib
import numpy as np
import scipy.stats
from sklearn.base import clone

from .._validation import Boolean, HasMethods, InstanceOf, Interval, Options, validate_params
from ._base import CatalogOptimizer, solve_problem, warn_unexplained
from ._wrapping import WrappingOptimizer
from .tags import catalog_tags

__all__ = ["EnsembleOptimizer"]

#: Ways of drawing the fits' rows (see ``sampling``).
SAMPLINGS = ("subsamples", "complementary_pairs")
#: Ways of computing the coefficients of the included terms (see ``aggregate``).
AGGREGATES = ("auto", "refit", "median")


class EnsembleOptimizer(WrappingOptimizer, CatalogOptimizer):
    r"""Subsample-and-refit ensemble around any catalog optimizer.

    The optimizer is refit on ``n_models`` subsamples of the rows, contiguous chunks of time
    drawn without replacement, the same in every coordinate's block (neighbouring rows share
    noise). Per term it reports the inclusion probability ``P(xi_j != 0)`` and an interval;
    the model keeps the terms included in at least ``inclusion`` of the fits and, where the
    optimizer can, refits them on all the rows (the median of fits made with different
    companion terms can split equal terms unevenly). With complementary pairs (Shah and
    Samworth, 2013) a pair of disjoint halves includes a term only when both keep it,

    .. math:: \hat\Pi_j = \frac{1}{B} \sum_{b=1}^{B}
              \mathbb{1}[\xi^{(A_b)}_j \ne 0] \, \mathbb{1}[\xi^{(A_b^c)}_j \ne 0],

    so a chance term must fit two independent noise draws (small true terms drop more often).

    Parameters
    ----------
    optimizer : catalog optimizer, optional
        Refit on every subsample (cloned); default ``ExplicitOptimizer()``.
    n_models : int, default 20
        Number of fits.
    fraction : float, default 0.7
        Fraction of the chunks in each subsample (``sampling="subsamples"``).
    n_chunks : int, default 20
        Contiguous chunks of each coordinate's rows.
    inclusion : float, default 0.5
        Inclusion probability from which a term enters the model.
    aggregate : {"auto", "refit", "median"}, default "auto"
        Coefficients of the included terms: the optimizer's refit of them on all the rows
        (``fit_problem(problem, support)``), the median over the fits keeping them, or
        (``"auto"``) the refit where the tag ``can_refit`` allows.
    sampling : {"subsamples", "complementary_pairs"}, default "subsamples"
        Random ``fraction`` of the chunks per fit, or ``n_models / 2`` pairs of disjoint halves
        (``n_models`` even).
    confidence : float, default 0.95
        Coverage of the coefficient intervals.
    random_state : int or None, default 0
        Seed of the subsamples.
    n_jobs : int or None, default None
        joblib workers (``None``: as ``joblib.parallel_config`` says; the result does not
        depend on it).
    progress : bool, default False
        Show a tqdm bar over the fits.

    Attributes
    ----------
    coef_ : ndarray, shape (F,)
        Coefficients of the included terms, zero elsewhere.
    aggregate_ : str
        ``"refit"`` or ``"median"``.
    coef_samples_ : ndarray, shape (n_models, F)
        Coefficients of every successful fit.
    inclusion_probability_ : ndarray, shape (F,)
        Fraction of the successful fits (pairs) that keep each term.
    coef_interval_ : ndarray, shape (2, F)
        ``confidence`` interval: ``coef_`` (included terms) or the fits' median, plus or minus
        Student's quantile times the fits' standard deviation widened by ``sqrt(f / (1 - f))``
        (delete-d jackknife, subsample fraction ``f``). Smoothing bias is not covered.
    n_failed_ : int
        Fits that raised.

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

    spec_type = "EnsembleOptimizer"

    def catalog_tags(self):
        """What this optimizer can do and needs.

        The base optimizer's tags; every fit balances its own subsample.

        Returns
        -------
        CatalogTags
            The tags (:class:`~pysindy_xl.optimizers.tags.CatalogTags`): ``requires_forces``,
            ``can_refit``, ``balances_rows``, ``derivative_estimate``, ...
        """
        return dataclasses.replace(catalog_tags(self._base()), balances_rows=False, can_refit=False)

    _parameter_constraints = {
        "optimizer": [None, HasMethods("a catalog optimizer", "fit_catalog")],
        "n_models": [Interval("int", 2)],
        "fraction": [Interval("real", 0, 1, low_open=True)],
        "n_chunks": [Interval("int", 2)],
        "inclusion": [Interval("real", 0, 1, low_open=True)],
        "confidence": [Interval("real", 0, 1, low_open=True)],
        "random_state": [None, Interval("int", 0),
                         InstanceOf((np.random.Generator, np.random.BitGenerator,
                                     np.random.SeedSequence, list, tuple, np.ndarray),
                                    "a numpy Generator or seed")],
        "n_jobs": [None, Interval("int")],
        "sampling": [Options(SAMPLINGS)],
        "aggregate": [Options(AGGREGATES)],
        "progress": [Boolean()],
    }

    def __init__(self, optimizer=None, n_models=20, fraction=0.7, n_chunks=20, inclusion=0.5,
                 confidence=0.95, random_state=0, n_jobs=None, sampling="subsamples",
                 aggregate="auto", progress=False):
        self.optimizer = optimizer
        self.n_models = n_models
        self.fraction = fraction
        self.n_chunks = n_chunks
        self.inclusion = inclusion
        self.aggregate = aggregate
        self.sampling = sampling
        self.confidence = confidence
        self.random_state = random_state
        self.n_jobs = n_jobs
        self.progress = progress

    def _check_params(self):
        validate_params(self)
        if isinstance(self.optimizer, EnsembleOptimizer):
            raise ValueError("optimizer: an EnsembleOptimizer cannot bag another "
                             "EnsembleOptimizer (n_models squared fits); bag its base "
                             "optimizer")
        base = self._base()
        if self.aggregate == "refit" and not catalog_tags(base).can_refit:
            raise ValueError("aggregate: 'refit' needs an optimizer that refits a support (tag "
                             f"can_refit), {type(base).__name__} does not (use 'median' or 'auto')")
        if self.sampling == "complementary_pairs" and self.n_models % 2:
            raise ValueError(f"n_models: complementary pairs need an even number of fits, got "
                             f"{self.n_models}")

    def _solve(self, problem):
        """Fit the base optimizer on subsamples of the rows (with their noise moments), then
        aggregate.
        """
        theta = problem.theta
        n_rows = problem.n_samples
        n_chunks = min(int(self.n_chunks), n_rows)
        edges = np.linspace(0, n_rows, n_chunks + 1).astype(int)
        rng = np.random.default_rng(self.random_state)
        if self.sampling == "complementary_pairs":
            subsamples = _complementary_halves(rng, n_chunks, int(self.n_models) // 2)
        else:
            n_keep = max(2, int(round(self.fraction * n_chunks)))
            subsamples = [np.sort(rng.choice(n_chunks, size=n_keep, replace=False))
                          for _ in range(int(self.n_models))]
        base = self._base()
        problems = [problem.subsample(np.concatenate([np.arange(edges[k], edges[k + 1])
                                                      for k in chunks]))
                    for chunks in subsamples]
        fits = joblib.Parallel(n_jobs=self.n_jobs, return_as="generator")(
            joblib.delayed(_fit_subsample)(base, part) for part in problems)
        if self.progress:
            from tqdm.auto import tqdm

            fits = tqdm(fits, total=len(problems), desc=f"{type(base).__name__} fits", unit="fit")
        outcomes = list(fits)
        fits = [coef for coef, _, _ in outcomes]
        failed = np.array([coef is None for coef in fits])
        if failed.all():
            raise RuntimeError(f"EnsembleOptimizer: every fit of the ensemble failed (first: "
                               f"{outcomes[0][2]})")
        _report_subsample_fits(outcomes)
        samples = np.array([coef for coef in fits if coef is not None])
        self.coef_samples_ = samples
        self.n_failed_ = int(failed.sum())
        if self.sampling == "complementary_pairs":
            kept = np.zeros((len(fits), theta.shape[1]), dtype=bool)
            kept[~failed] = samples != 0
            whole = ~(failed[0::2] | failed[1::2])
            if not whole.any():
                raise RuntimeError("EnsembleOptimizer: no complementary pair has two "
                                   "successful fits")
            self.inclusion_probability_ = np.mean((kept[0::2] & kept[1::2])[whole], axis=0)
        else:
            self.inclusion_probability_ = np.mean(samples != 0, axis=0)
        included = self.inclusion_probability_ >= self.inclusion
        self.aggregate_ = ("refit" if self.aggregate == "refit" or (
            self.aggregate == "auto" and catalog_tags(base).can_refit) else "median")
        if self.aggregate_ == "refit":
            refit = (f"EnsembleOptimizer: the refit on the {int(included.sum())} term(s) kept "
                     f"by at least {self.inclusion} of the fits")
            try:
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always")
                    coef = clone(base).fit_problem(problem, included).coef_
            except (ValueError, RuntimeError) as error:  # e.g. no law on the agreed terms
                raise type(error)(
                    f"{refit} failed ({error}); the fits disagree, try aggregate='median', a "
                    "lower inclusion or more data") from error
            for w in caught:  # the final model's own warnings, said of the ensemble
                warnings.warn(f"{refit}: {w.message}", w.category, stacklevel=2)
        else:
            coef = np.zeros(theta.shape[1])
            for j in np.flatnonzero(included):
                coef[j] = np.median(samples[samples[:, j] != 0, j])
            warn_unexplained("EnsembleOptimizer", theta, problem.n_coordinates, coef,
                             problem.force_columns)
        self.coef_ = coef
        share = np.mean([len(chunks) for chunks in subsamples]) / n_chunks
        # delete-d jackknife: a subsample of fraction f spreads sqrt((1 - f) / f) times the
        # full-data estimate's own spread; Student's quantile, not the fits' percentiles
        center = np.where(included, self.coef_, np.median(samples, axis=0))
        half_width = np.zeros_like(center)
        if len(samples) > 1:
            quantile = scipy.stats.t.ppf(0.5 + self.confidence / 2, df=len(samples) - 1)
            half_width = (quantile * np.sqrt(share / max(1 - share, 1 / n_chunks))
                          * samples.std(axis=0, ddof=1))
        self.coef_interval_ = np.array([center - half_width, center + half_width])
        return self

    def plot(self, feature_names=None, axes=None):
        """Inclusion probabilities and coefficient distributions of the ensemble.

        Parameters
        ----------
        feature_names : list of str, optional
            Names of the features; default None: their indices.
        axes : pair of matplotlib Axes, optional
            Where to draw; default None: a new figure.

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


def _complementary_halves(rng, n_chunks, n_pairs):
    """``2 n_pairs`` sorted chunk sets: a random half of the chunks, then its complement."""
    halves = []
    for _ in range(n_pairs):
        order = rng.permutation(n_chunks)
        halves += [np.sort(order[: n_chunks // 2]), np.sort(order[n_chunks // 2:])]
    return halves


def _fit_subsample(base, problem):
    """One subsample fit: ``(coef or None, its warnings as (category, message), error or None)``;
    the warnings are recorded so that the ensemble reports them together.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            fitted = solve_problem(clone(base), problem)
            coef, error = np.asarray(fitted.coef_, dtype=float), None
        except (ValueError, RuntimeError, np.linalg.LinAlgError) as failure:
            coef, error = None, f"{type(failure).__name__}: {failure}"
    return coef, [(w.category, str(w.message)) for w in caught], error


def _report_subsample_fits(outcomes):
    """One warning per distinct message of the fits (with its count), one for the failed fits."""
    n_fits = len(outcomes)
    counts = collections.Counter(message for _, caught, _ in outcomes for message in
                                 dict.fromkeys(caught))  # each fit counts a message once
    for (category, message), count in counts.items():
        warnings.warn(f"EnsembleOptimizer: {count} of {n_fits} subsample fits warned: "
                      f"{message}", category, stacklevel=3)
    errors = [error for _, _, error in outcomes if error is not None]
    if errors:
        warnings.warn(f"EnsembleOptimizer: {len(errors)} of {n_fits} subsample fits failed "
                      f"and are left out (first: {errors[0]})", UserWarning, stacklevel=3)
