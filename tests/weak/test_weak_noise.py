"""The propagated noise of the weak rows and the generalized least squares it enables.

Ground truth: a moving-average process of known covariance, and the residual of the true law
(coefficients from sympy.physics.mechanics) on positions with noise of known level."""

import numpy as np
import pytest
from support.paper import noisy_run, paper_catalog, true_coefficients, validates

import pysindy_xl as px
from pysindy_xl.optimizers import CatalogOptimizer
from pysindy_xl.weak import WeakNoise, weak_regression


def _autocorrelation(rows, lags):
    """Autocorrelation at ``lags`` of the rows (R,) or of each column of (R, D), pooled."""
    rows = rows.reshape(rows.shape[0], -1)
    variance = np.mean(rows**2)
    return np.array([np.mean(rows[: len(rows) - lag] * rows[lag:]) / variance
                     for lag in lags])


def test_whitener_decorrelates_a_moving_average():
    """Rows ``e_k = a_k - 0.5 a_{k-1}`` (lag-one correlation -0.4, as the weak rows' half a
    support apart): whitened fresh draws are uncorrelated with unit variance (up to the
    taper's bias, -0.05 at lag one); the two runs are whitened independently."""
    rng = np.random.default_rng(0)

    def moving_average(n_draws, n_rows):
        innovations = rng.normal(size=(n_draws, n_rows + 1))
        return 3.0 * (innovations[:, 1:] - 0.5 * innovations[:, :-1])

    runs = np.array([[0, 300, 0, 8], [300, 600, 0, 8]])  # one masked gap between them
    draws = np.concatenate([moving_average(40, 300), moving_average(40, 300)], axis=1)
    noise = WeakNoise(draws[:, :, None], 1, runs)
    whiten = noise.whitener(np.array([1.0]))
    fresh = np.concatenate([moving_average(200, 300), moving_average(200, 300)], axis=1).T
    assert _autocorrelation(fresh, [1])[0] == pytest.approx(-0.5 / 1.25, abs=0.02)
    white = whiten(fresh)
    assert np.mean(white**2) == pytest.approx(1.0, abs=0.05)
    assert np.all(np.abs(_autocorrelation(white, range(1, 6))) < 0.07)
    # block diagonal: a change in the second run leaves the first run's rows as they were
    changed = fresh.copy()
    changed[300:] += 1.0
    np.testing.assert_array_equal(whiten(changed)[:300], white[:300])
    assert noise.whitener(np.array([0.0])) is None  # a law without noise: nothing to weigh


def test_the_draws_describe_the_noise_of_the_recorded_rows(cart_pole_system):
    """The residual of the true law on noisy positions (5 %) is correlated across rows half
    a test-function support apart, and whitened by the covariance the propagated draws give,
    it has the variance of the whitened draws: the draws describe the noise of the recorded
    rows. (The tapered stationary covariance whitens only partly: both variances are about
    0.6, and lag correlations of 0.3-0.5 remain; see the module's notes.)"""
    system = cart_pole_system
    library = paper_catalog(system.coords, [1]).fit()
    true = true_coefficients(system, library)
    raw, ratios = [], []
    for seed in range(3):
        t, noisy, data, _ = noisy_run(system, seed, 0.05)
        trajectory = {"t": t, "x": noisy, "x_dot": None, "u": data["tau"],
                      "mask": np.ones(len(t), bool)}
        theta, _, noise, _ = weak_regression(library, [trajectory], px.BumpTestFunctions(),
                                             px.WhittakerSmoother(), noise="draws")
        overlap = int(noise.runs[0, 3])
        whiten = noise.whitener(true)
        residual = (theta @ true).reshape(system.n, -1)
        whitened = whiten(theta @ true).reshape(system.n, -1)
        draws = np.stack([whiten(draw @ true) for draw in noise.draws], axis=1)
        draws = draws.reshape(system.n, -1, len(noise.draws))
        raw += [_autocorrelation(r, [overlap // 2])[0] for r in residual]
        ratios += [np.mean(w**2) / np.mean(d**2) for w, d in zip(whitened, draws, strict=True)]
    assert np.max(np.abs(raw)) > 0.3, raw
    assert np.all((np.array(ratios) > 0.5) & (np.array(ratios) < 2.0)), ratios


def test_moments_are_those_of_the_draws(cart_pole_system):
    """``noise="moments"`` (the default) returns what the draws give, unchanged."""
    system = cart_pole_system
    library = paper_catalog(system.coords, [1]).fit()
    t, noisy, data, _ = noisy_run(system, 0, 0.02, duration=12.0)
    trajectory = {"t": t, "x": noisy, "x_dot": None, "u": data["tau"],
                  "mask": np.ones(len(t), bool)}
    parts = [weak_regression(library, [trajectory], px.BumpTestFunctions(),
                             px.WhittakerSmoother(), noise=kind) for kind in ("moments", "draws")]
    np.testing.assert_allclose(parts[0][2], parts[1][2].moments(), rtol=1e-12)
    with pytest.raises(ValueError, match="noise: expected 'moments', 'draws' or 'none'"):
        weak_regression(library, [trajectory], px.BumpTestFunctions(), px.WhittakerSmoother(),
                        noise="both")


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 4])
def test_double_pendulum_on_a_cart_at_five_percent(cart_double_pendulum_system, seed):
    """Seeds of the noise sweep where the rows fitted as they are lose a true term (seed 0:
    the cart's friction) or split one between substitutes (seed 4): with the residual's
    covariance, the defaults find the exact law. (On seed 4 the single-fit pilot splits the
    term too; the fit weighted by its law does not, and reweighting by that law settles.)"""
    system = cart_double_pendulum_system
    library = paper_catalog(system.coords, [1, 2])
    t, noisy, data, _ = noisy_run(system, seed, 0.05)
    model = px.XLSINDy(library).fit(noisy, t, u=data["tau"])
    true = true_coefficients(system, library.fit())
    coef, support = model.coefficients(), true != 0
    assert np.array_equal(coef != 0, support), model.equations()
    assert np.median(np.abs(coef[support] - true[support]) / np.abs(true[support])) < 0.03


class _NoLaw(CatalogOptimizer):
    def _solve(self, problem):
        raise ValueError("no law on these rows")


class _FailingPilot(px.ExplicitOptimizer):
    """An explicit fit whose pilot cannot find a law."""

    def pilot(self):
        return _NoLaw()


def test_pilots_of_the_optimizers():
    """An ensemble's pilot is one unfitted fit of its base optimizer (its parameters kept);
    a mixed fit's pilot has the pilots of its parts; others are their own clone."""
    base = px.ExplicitOptimizer(threshold=0.05)
    pilot = px.EnsembleOptimizer(base, n_models=7).pilot()
    assert type(pilot) is px.ExplicitOptimizer and pilot.get_params() == base.get_params()
    assert not hasattr(pilot, "coef_") and pilot is not base
    mixed = px.MixedOptimizer(px.EnsembleOptimizer(base), px.ImplicitOptimizer(alpha=0.1))
    pilot = mixed.pilot()
    assert type(pilot.explicit_optimizer) is px.ExplicitOptimizer
    assert pilot.implicit_optimizer.get_params() == mixed.implicit_optimizer.get_params()
    assert type(mixed.explicit_optimizer) is px.EnsembleOptimizer  # the original unchanged


def test_a_failing_pilot_leaves_the_rows_unweighted(cart_pole_system):
    """The weighting needs a first law: when the pilot finds none, the model says so and
    fits the rows as they are (the same law as ``residual_covariance=False``)."""
    system = cart_pole_system
    library = paper_catalog(system.coords, [1])
    t, noisy, data, _ = noisy_run(system, 1, 0.01)
    with pytest.warns(UserWarning, match=r"residual_covariance: the pilot fit failed "
                      r"\(no law on these rows\); the rows are fitted unweighted"):
        model = px.XLSINDy(library, _FailingPilot(), residual_covariance=True).fit(
            noisy, t, u=data["tau"])
    plain = px.XLSINDy(library, _FailingPilot(), residual_covariance=False).fit(
        noisy, t, u=data["tau"])
    np.testing.assert_array_equal(model.coefficients(), plain.coefficients())
    true = true_coefficients(system, library.fit())
    assert np.array_equal(model.coefficients() != 0, true != 0)


def test_partly_forced_cart_pole_weighs_the_free_pendulums_rows(cart_pole_system):
    """Cart-pole driven on the cart only, 3 %, the noise sweep's seed 9. The law is one
    explicit problem (every term reaches the cart's force), and only the undriven pendulum's
    rows tell ``4.9 cos(theta)`` and ``0.25 theta_dot**2`` from their small-angle substitutes
    ``-2.5 sin(theta)**2`` and ``0.25 theta_dot**2 cos(theta)``. Whitened, those rows are in
    units of their own noise, as the cart's are; rebalanced by their scales afterwards they
    weighed (0.68 / 1.48)^2 of the cart's, and the fit took the substitutes."""
    system = cart_pole_system
    library = paper_catalog(system.coords, [1])
    t, noisy, data, _ = noisy_run(system, 9, 0.03, active=[0])
    model = px.XLSINDy(library).fit(noisy, t, u=data["tau"])
    assert model.optimizer_.mode_ == "explicit"
    true = true_coefficients(system, library.fit())
    coef, support = model.coefficients(), true != 0
    assert np.array_equal(coef != 0, support), model.equations()
    assert np.max(np.abs(coef[support] - true[support]) / np.abs(true[support])) < 0.03
    assert validates(model, system, 509)


class _DelegatingSmoother:
    """A user's smoother (not a WhittakerSmoother) that smooths like one."""

    def __init__(self, resmooth):
        self.inner = px.WhittakerSmoother()
        if resmooth:  # the protocol of noise propagation: noise_ and resmooth
            self.resmooth = lambda t, x: self.inner.resmooth(t, x)

    def smooth(self, t, x):
        out = self.inner.smooth(t, x)
        self.noise_ = self.inner.noise_
        return out


def test_a_custom_smoother_propagates_noise_through_the_protocol():
    """A smoother of its own class with ``noise_`` and ``resmooth`` gets the noise propagated
    exactly as the WhittakerSmoother it wraps; one without ``resmooth`` is told so (it used to
    be dropped silently)."""
    coords = px.Coordinates(["x"])
    library = px.CatalogRepartition([
        px.ExternalForces(coords),
        px.LagrangeLibrary(coords, [coords.qd[0] ** 2, coords.q[0] ** 2])]).fit()
    t = np.linspace(0, 20, 2001)
    x = np.sin(t)[:, None] + 0.01 * np.random.default_rng(0).normal(size=(2001, 1))
    runs = [{"t": t, "x": x, "x_dot": None, "u": np.zeros((2001, 1)),
             "mask": np.ones(2001, bool)}] * 2
    bumps = px.BumpTestFunctions(width=2.0)
    theta, _, moments, _ = weak_regression(library, runs, bumps, px.WhittakerSmoother())
    assert moments is not None and np.all(np.diag(moments[0])[1:] > 0)  # forces: exact
    theta_c, _, moments_c, _ = weak_regression(library, runs, bumps, _DelegatingSmoother(True))
    np.testing.assert_array_equal(theta_c, theta)
    np.testing.assert_allclose(moments_c, moments, rtol=1e-12)
    with pytest.warns(UserWarning, match=r"smoother: _DelegatingSmoother has no resmooth "
                                         r"method .* not propagated") as record:
        theta_w, _, moments_w, _ = weak_regression(library, runs, bumps,
                                                   _DelegatingSmoother(False))
    assert len([w for w in record if "resmooth" in str(w.message)]) == 1  # once, not per run
    np.testing.assert_array_equal(theta_w, theta)
    assert moments_w is None
