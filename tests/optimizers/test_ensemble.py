"""Ensemble fits: inclusion probabilities and coefficient intervals from noisy positions,
against the true coefficients (sympy.physics.mechanics ground truth), and next to PySINDy's
own EnsembleOptimizer."""

import warnings

import numpy as np
import pysindy as ps
import pytest
import scipy.stats
from support.paper import noisy_run, paper_catalog, true_coefficients

import pysindy_xl as px
from pysindy_xl.optimizers import CatalogOptimizer, CatalogProblem


def _noisy(system, seed, level=0.01, duration=30.0, active=None):
    t, noisy, data, _ = noisy_run(system, seed, level, duration=duration, active=active)
    return t, noisy, data


def _ensemble_outcome(system, angles, seed, **options):
    library = paper_catalog(system.coords, angles)
    true = true_coefficients(system, library.fit())
    t, noisy, data = _noisy(system, seed)
    model = px.XLSINDy(library, optimizer=px.EnsembleOptimizer(**{"n_models": 12, **options})
                       ).fit(noisy, t, u=data["tau"])
    support = true != 0
    low, high = model.coef_interval_
    return {
        "exact": np.array_equal(model.coefficients() != 0, support),
        "true_inclusion": model.inclusion_probability_[support].min(),
        "false_inclusion": model.inclusion_probability_[~support].max(),
        "covered": bool(np.all((low[support] <= true[support]) & (true[support] <= high[support]))),
        "model": model,
    }


def test_cart_pole_ensemble_from_noisy_positions(cart_pole_system, capsys):
    outcome = _ensemble_outcome(cart_pole_system, [1], seed=0)
    assert outcome["exact"]
    assert outcome["true_inclusion"] >= 0.9
    # measured over 10 seeds (20 fits): false terms <= 0.2 in 7; this seed's worst false
    # term enters fewer than half of the subsample fits, so the ensemble's model is exact
    assert outcome["false_inclusion"] < 0.5
    assert outcome["covered"]
    outcome["model"].print(uncertainty=True)
    assert "P=1.00" in capsys.readouterr().out


@pytest.mark.slow
def test_double_pendulum_ensemble_over_seeds(double_pendulum_system):
    """Issue 13 acceptance cell (measured: see the closing note); honest floors asserted."""
    outcomes = [_ensemble_outcome(double_pendulum_system, [0, 1], seed) for seed in range(5)]
    assert sum(o["exact"] for o in outcomes) >= 4
    assert all(o["true_inclusion"] >= 0.9 for o in outcomes)
    assert sum(o["false_inclusion"] <= 0.2 for o in outcomes) >= 2
    # measured on seeds 0-9 (20 fits, benchmarks/results/noise_sweep.md): false terms <= 0.2
    # in 7 (below the 9/10 target), intervals covering every true coefficient in 10
    assert sum(o["covered"] for o in outcomes) >= 4


@pytest.mark.slow
def test_complementary_pairs_meet_the_acceptance_cell(double_pendulum_system):
    """Issue 13 acceptance: forced double pendulum, 1 % position noise, 10 seeds: every true
    term included with probability >= 0.9, every false term <= 0.2, every true coefficient
    inside its 95 % interval, each in at least 9 seeds (measured: 10, 10 and 9)."""
    outcomes = [_ensemble_outcome(double_pendulum_system, [0, 1], seed, n_models=20,
                                  sampling="complementary_pairs") for seed in range(10)]
    assert sum(o["exact"] for o in outcomes) >= 9
    assert sum(o["true_inclusion"] >= 0.9 for o in outcomes) >= 9
    assert sum(o["false_inclusion"] <= 0.2 for o in outcomes) >= 9
    assert sum(o["covered"] for o in outcomes) >= 9


def test_complementary_pairs_count_a_term_only_when_both_halves_keep_it():
    """A true term among 60 null columns: 70 % subsamples share their noise, and a null
    column that fits it enters many of them (up to 0.95 here); disjoint halves must both
    keep it. Two seeds where a null column enters most subsample fits (0.95 and 0.60) and
    at most 0.30 of the pairs (seeds 1 and 3, once also run: 0.00 and 0.25 against 0.00)."""
    null_inclusion = {"pairs": [], "subsamples": []}
    for seed in (0, 2):
        rng = np.random.default_rng(seed)
        signal, *nulls = rng.normal(size=(61, 600))
        theta = np.column_stack([0.3 * signal + rng.normal(size=600), signal, *nulls])
        pairs = px.EnsembleOptimizer(n_models=20, n_chunks=10,
                                     sampling="complementary_pairs").fit_catalog(theta, 1, [0])
        kept = pairs.coef_samples_ != 0
        np.testing.assert_array_equal(pairs.inclusion_probability_,
                                      np.mean(kept[0::2] & kept[1::2], axis=0))
        assert pairs.inclusion_probability_[1] >= 0.5 and pairs.coef_[1] != 0
        # the halves are disjoint and cover the data, each spreads as much around the whole
        # data's estimate as that estimate around the truth: no widening (sqrt(f/(1-f)) = 1)
        quantile = scipy.stats.t.ppf(0.975, df=19)
        center = np.where(pairs.inclusion_probability_ >= 0.5, pairs.coef_,
                          np.median(pairs.coef_samples_, axis=0))
        np.testing.assert_allclose(
            pairs.coef_interval_ - center,
            np.outer([-1, 1], quantile * pairs.coef_samples_.std(axis=0, ddof=1)))
        subsamples = px.EnsembleOptimizer(n_models=20, n_chunks=10).fit_catalog(theta, 1, [0])
        null_inclusion["pairs"].append(pairs.inclusion_probability_[2:])
        null_inclusion["subsamples"].append(subsamples.inclusion_probability_[2:])
    assert np.max(null_inclusion["pairs"]) <= 0.5 < np.max(null_inclusion["subsamples"])
    assert np.mean(null_inclusion["pairs"]) < 0.5 * np.mean(null_inclusion["subsamples"])


class _LeastSquares(CatalogOptimizer):
    """A catalog optimizer that cannot refit a given support: least squares on every column."""

    def _solve(self, problem):
        theta, force_columns = problem.theta, problem.force_columns
        rest = np.setdiff1d(np.arange(theta.shape[1]), force_columns)
        self.coef_ = np.full(theta.shape[1], -1.0)
        self.coef_[rest] = np.linalg.lstsq(theta[:, rest], theta[:, force_columns].sum(1),
                                           rcond=None)[0]
        return self


def test_refit_is_the_least_squares_of_the_included_terms_on_all_rows():
    rng = np.random.default_rng(3)
    a, b, c, d = rng.normal(size=(4, 800))
    theta = np.column_stack([2 * a - 0.5 * c + 0.3 * rng.normal(size=800), a, b, c, d])
    refit = px.EnsembleOptimizer(n_models=10).fit_catalog(theta, 1, [0])
    median = px.EnsembleOptimizer(n_models=10, aggregate="median").fit_catalog(theta, 1, [0])
    assert (refit.aggregate_, median.aggregate_) == ("refit", "median")
    np.testing.assert_array_equal(refit.coef_ != 0, [True, True, False, True, False])
    np.testing.assert_array_equal(refit.coef_samples_, median.coef_samples_)
    expected = np.linalg.lstsq(theta[:, [1, 3]], theta[:, 0], rcond=None)[0]
    np.testing.assert_allclose(refit.coef_[[1, 3]], expected, rtol=1e-12)
    assert not np.allclose(median.coef_[[1, 3]], expected, rtol=1e-6, atol=0)
    np.testing.assert_allclose(refit.coef_interval_.mean(axis=0)[[1, 3]], expected)
    with pytest.raises(ValueError, match="aggregate: 'refit' needs an optimizer that refits"):
        px.EnsembleOptimizer(_LeastSquares(), aggregate="refit").fit_catalog(theta, 1, [0])
    assert px.EnsembleOptimizer(_LeastSquares(), n_models=4).fit_catalog(
        theta, 1, [0]).aggregate_ == "median"
    with pytest.raises(ValueError, match="aggregate"):
        px.EnsembleOptimizer(aggregate="mean").fit_catalog(theta, 1, [0])
    with pytest.raises(ValueError, match=r"support: expected a boolean array of shape \(5,\)"):
        px.ExplicitOptimizer().fit_problem(
            CatalogProblem.from_arrays(theta, 1, [0]), [1, 1, 0, 1, 0])


@pytest.mark.slow
def test_refit_coefficients_are_closer_to_the_truth_than_the_median(cart_pole_system):
    """The ensemble picks the terms, all the rows size them: at 3 % position noise the
    full-data refit of the included terms is more accurate than the median of the fits.
    (On the rows as they are: whitened by the residual's covariance, the default, both are
    closer, 0.24 % against 0.28 %.)"""
    library = paper_catalog(cart_pole_system.coords, [1])
    true = true_coefficients(cart_pole_system, library.fit())
    support = true != 0
    errors = {"refit": [], "median": []}
    for seed in range(5):
        t, noisy, data = _noisy(cart_pole_system, seed, level=0.03)
        for aggregate in errors:
            model = px.XLSINDy(library, optimizer=px.EnsembleOptimizer(aggregate=aggregate),
                               residual_covariance=False).fit(noisy, t, u=data["tau"])
            assert np.array_equal(model.coefficients() != 0, support)
            errors[aggregate].append(np.abs(model.coefficients()[support] / true[support] - 1))
    # measured: 0.24 % against 0.39 %
    assert np.median(errors["refit"]) < 0.7 * np.median(errors["median"])


def test_same_support_as_pysindys_ensemble_in_physical_units(cart_pole_system):
    system = cart_pole_system
    library = paper_catalog(system.coords, [1])
    true = true_coefficients(system, library.fit())
    t, noisy, data = _noisy(system, 1, level=0.001, duration=20.0)
    # the rows as they are: at 0.1 % noise the residual-covariance weighting (the default)
    # moves the coefficients by up to 7e-5 relative, a bias of the smoother and quadrature
    # that it weighs more, outside intervals that describe the sampling spread only
    ours = px.XLSINDy(library, optimizer=px.EnsembleOptimizer(n_models=10),
                      residual_covariance=False).fit(noisy, t, u=data["tau"])
    theirs = px.XLSINDy(library, optimizer=px.ExplicitOptimizer(
        method=ps.EnsembleOptimizer(ps.STLSQ(threshold=0.02), bagging=True, n_models=10)),
        residual_covariance=False).fit(noisy, t, u=data["tau"])
    support = true != 0
    np.testing.assert_array_equal(ours.coefficients() != 0, support)
    np.testing.assert_array_equal(theirs.coefficients() != 0, support)
    np.testing.assert_allclose(ours.coefficients()[support], theirs.coefficients()[support],
                               rtol=0.02)
    # ours reports the spread in the coefficients' own units, around the true values; at
    # 0.1 % noise the intervals are ~1e-4 wide and the quadrature and smoothing bias
    # (~1e-5 relative, not a sampling spread) can sit just outside them
    low, high = ours.coef_interval_
    slack = 2e-5 * np.abs(true[support])
    assert np.all(low[support] - slack <= true[support])
    assert np.all(true[support] <= high[support] + slack)
    assert np.all(high[support] - low[support] < 0.01 * np.abs(true[support]))


def test_bad_ensemble_options():
    with pytest.raises(ValueError, match="fraction"):
        px.EnsembleOptimizer(fraction=1.5).fit_catalog(np.ones((10, 2)), 1, [0])
    with pytest.raises(TypeError, match="optimizer"):
        px.EnsembleOptimizer(optimizer=object()).fit_catalog(np.ones((10, 2)), 1, [0])
    with pytest.raises(ValueError, match="sampling"):
        px.EnsembleOptimizer(sampling="bootstrap").fit_catalog(np.ones((10, 2)), 1, [0])
    with pytest.raises(ValueError, match="n_models: complementary pairs need an even"):
        px.EnsembleOptimizer(n_models=5, sampling="complementary_pairs").fit_catalog(
            np.ones((10, 2)), 1, [0])
    with pytest.raises(ValueError, match="uncertainty"):
        c = px.Coordinates(["x"])
        t = np.linspace(0, 10, 500)
        x = np.sin(t)
        px.XLSINDy(px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])).fit(
            x, t, x_dot=np.cos(t), x_ddot=-x, u=-0.5 * x).print(
            uncertainty=True)


def test_parallel_fits_give_the_same_ensemble():
    rng = np.random.default_rng(0)
    a, b, c = rng.normal(size=(3, 600))
    theta = np.column_stack([2 * a - 0.5 * c + 0.05 * rng.normal(size=600), a, b, c])
    serial = px.EnsembleOptimizer(n_models=6).fit_catalog(theta, 1, [0])
    parallel = px.EnsembleOptimizer(n_models=6, n_jobs=2).fit_catalog(theta, 1, [0])
    np.testing.assert_array_equal(serial.coef_samples_, parallel.coef_samples_)
    np.testing.assert_array_equal(serial.coef_interval_, parallel.coef_interval_)
    with pytest.raises(TypeError, match="n_jobs"):
        px.EnsembleOptimizer(n_jobs="all").fit_catalog(theta, 1, [0])


def test_progress_shows_every_fit_and_changes_nothing(capsys):
    rng = np.random.default_rng(1)
    a, b, c = rng.normal(size=(3, 600))
    theta = np.column_stack([2 * a - 0.5 * c + 0.05 * rng.normal(size=600), a, b, c])
    quiet = px.EnsembleOptimizer(n_models=6).fit_catalog(theta, 1, [0])
    assert capsys.readouterr().err == ""
    shown = px.EnsembleOptimizer(n_models=6, progress=True).fit_catalog(theta, 1, [0])
    bar = capsys.readouterr().err
    assert "ExplicitOptimizer fits" in bar and "6/6" in bar
    np.testing.assert_array_equal(quiet.coef_samples_, shown.coef_samples_)
    np.testing.assert_array_equal(quiet.coef_, shown.coef_)
    with pytest.raises(TypeError, match="progress"):
        px.EnsembleOptimizer(progress="yes").fit_catalog(theta, 1, [0])


class _RecordingImplicit(px.ImplicitOptimizer):
    """An ImplicitOptimizer that records the mass matrices each of its fits receives."""

    received = []

    def fit_problem(self, problem, support=None):
        _RecordingImplicit.received.append(problem.mass_matrices)
        return super().fit_problem(problem, support)


def test_every_fit_gets_the_mass_matrices_its_optimizer_takes():
    rng = np.random.default_rng(0)
    a, b, c = rng.normal(size=(3, 400))
    theta = np.column_stack([a - 2 * b + 0.01 * rng.normal(size=400), a, b, c])
    moments = 0.01**2 * 400 * np.eye(4)[None]
    masses = rng.normal(size=(5, 4, 1, 1))
    _RecordingImplicit.received.clear()
    implicit = px.EnsembleOptimizer(_RecordingImplicit(), n_models=4).fit_catalog(
        theta, 1, [], noise_moments=moments, mass_matrices=masses)
    assert len(_RecordingImplicit.received) == 5  # four subsample fits and the refit
    for received in _RecordingImplicit.received:
        np.testing.assert_array_equal(received, masses)
    assert implicit.aggregate_ == "refit"
    np.testing.assert_array_equal(implicit.coef_ != 0, [True, True, True, False])
    # an explicit optimizer takes none: accepted and unused
    px.EnsembleOptimizer(n_models=4).fit_catalog(theta, 1, [0], mass_matrices=masses)
    with pytest.raises(ValueError, match="mass_matrices"):
        px.EnsembleOptimizer(n_models=4).fit_catalog(theta, 1, [0],
                                                     mass_matrices=masses[:, :2])


def test_partly_forced_noisy_positions_bag_the_explicit_part(double_pendulum_system, capsys):
    # only the first link is driven; the free link couples to it, so the whole problem is
    # explicit. On this seed one cross-validated fit keeps a noise term (the benchmark's
    # single-fit mixed cell: 10 terms for 9); the bagged explicit part, as for fully forced
    # data, keeps only the true ones.
    system = double_pendulum_system
    library = paper_catalog(system.coords, [0, 1])
    true = true_coefficients(system, library.fit())
    t, noisy, data = _noisy(system, 1, level=0.05, active=[0])
    model = px.XLSINDy(library).fit(noisy, t, u=data["tau"])
    assert isinstance(model.optimizer_, px.MixedOptimizer)
    assert isinstance(model.optimizer_.explicit_optimizer_, px.EnsembleOptimizer)
    assert model.optimizer_.mode_ == "explicit"
    support = true != 0
    np.testing.assert_array_equal(model.coefficients() != 0, support)
    np.testing.assert_allclose(model.coefficients()[support], true[support], rtol=0.05)
    # the ensemble is the whole model: its uncertainty is the model's
    assert np.all(model.inclusion_probability_[support] >= 0.5)
    assert np.all(model.inclusion_probability_[~support] < 0.5)
    low, high = model.coef_interval_
    assert np.all((low <= model.coefficients()) & (model.coefficients() <= high))
    model.print(uncertainty=True)
    assert "P=1.00" in capsys.readouterr().out


class _NoisyExplicit(px.ExplicitOptimizer):
    """An ExplicitOptimizer whose selecting fits warn once each, and fail on rows whose first
    force value is the marker 99 (the subsamples holding the first chunk); its refits of a
    given support pass."""

    def fit_problem(self, problem, support=None):
        if support is None:
            warnings.warn("a note from one fit", RuntimeWarning, stacklevel=2)
            if problem.theta[0, 0] == 99.0:
                raise ValueError("marked rows")
        return super().fit_problem(problem, support)


@pytest.mark.parametrize("n_jobs", [None, pytest.param(2, marks=pytest.mark.slow)])
def test_subsample_warnings_and_failures_are_reported_once_with_counts(n_jobs):
    rng = np.random.default_rng(2)
    a, b, c = rng.normal(size=(3, 600))
    theta = np.column_stack([2 * a - 0.5 * c + 0.05 * rng.normal(size=600), a, b, c])
    theta[0] = [99.0, 49.5, 0.0, 0.0]  # the marker row still satisfies force = 2 a - c / 2
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        opt = px.EnsembleOptimizer(_NoisyExplicit(), n_models=10, n_jobs=n_jobs).fit_catalog(
            theta, 1, [0])
    messages = [str(w.message) for w in caught]
    notes = [m for m in messages if "a note from one fit" in m]
    n_fitted = 10 - opt.n_failed_
    assert 0 < opt.n_failed_ < 10
    # every fit warned, the successful and the failed ones: one line says so (processes too)
    assert notes == ["EnsembleOptimizer: 10 of 10 subsample fits warned: a note from one fit"]
    assert [w.category for w in caught if "a note" in str(w.message)] == [RuntimeWarning]
    failed = [m for m in messages if "failed" in m]
    assert failed == [f"EnsembleOptimizer: {opt.n_failed_} of 10 subsample fits failed and are "
                      "left out (first: ValueError: marked rows)"]
    assert len(opt.coef_samples_) == n_fitted
    np.testing.assert_array_equal(opt.coef_ != 0, [True, True, False, True])


def test_a_coordinate_the_agreed_terms_leave_unexplained_is_named():
    """Coordinate 1 is unforced and only b enters it: the refit gives b a coefficient of
    round-off size, and the ensemble says the model cannot predict coordinate 1."""
    rng = np.random.default_rng(4)
    a, b = rng.normal(size=(2, 300))
    zero = np.zeros(300)
    theta = np.column_stack([np.r_[2 * a + 0.01 * rng.normal(size=300), zero],
                             np.r_[a, zero], np.r_[zero, b]])
    for aggregate in ("refit", "median"):
        with pytest.warns(px.IdentificationWarning, match=r"coordinate\(s\) \[1\]; the model "
                          "cannot predict them") as caught:
            px.EnsembleOptimizer(n_models=6, aggregate=aggregate).fit_catalog(theta, 2, [0])
        final = [str(w.message) for w in caught if "subsample" not in str(w.message)]
        assert len(final) == 1
        assert final[0].startswith("EnsembleOptimizer: " + (
            "the refit on the 2 term(s) kept by at least 0.5 of the fits: ExplicitOptimizer: "
            if aggregate == "refit" else "no identified term"))
