"""Logged time stamps: jittered, gapped and repeated, against independent truth.

A 1 kHz log (steps jittering about their median, gaps of several steps where samples were
lost) must give what the same motion sampled uniformly gives: test functions that integrate
known functions exactly, a smoother as accurate, propagated noise whose covariance is the one
a Monte Carlo of fresh noise gives, and the same identified law (ground truth: sympy mechanics
integrated by scipy at the recorded times).
"""

import numpy as np
import pytest
from ground_truth import random_force, random_initial_state
from scipy.integrate import quad
from support.paper import paper_catalog, true_coefficients

import pysindy_xl as px
from pysindy_xl.weak import (
    BumpTestFunctions,
    WhittakerSmoother,
    quadrature_weights,
    split_at_gaps,
)
from pysindy_xl.weak.regression import propagated_draws
from pysindy_xl.weak.smoothing import whittaker_smooth


def _log_stamps(duration, step, rng, jitter=0.08, gap_rate=0.003, longest=9):
    """Stamps of a log: steps of ``step`` jittered by ``jitter`` of it, and at a rate of
    ``gap_rate`` gaps of 2 to ``longest`` steps."""
    n = int(duration / step)
    steps = step * np.clip(1 + jitter * rng.standard_normal(n), 0.3, None)
    gaps = rng.random(n) < gap_rate
    steps[gaps] = step * rng.integers(2, longest + 1, gaps.sum())
    t = np.concatenate([[0.0], np.cumsum(steps)])
    return t[t <= duration]


def test_test_functions_integrate_known_functions_on_a_jittered_grid():
    rng = np.random.default_rng(0)
    t = _log_stamps(6.0, 1e-3, rng)
    t = np.sort(np.concatenate([t, t[1000:1010] + 1e-7]))  # bunched stamps as well
    h = 0.5
    phi, dphi, _ = BumpTestFunctions(width=h, n_functions=7).matrices(t)
    centers = np.linspace(t[0] + h, t[-1] - h, 7)

    def f(s):
        return np.sin(3 * s) + 0.2 * s**2

    for k, c in enumerate(centers):
        exact = quad(lambda s, c=c: (1 - ((s - c) / h) ** 2) ** 6 * f(s), c - h, c + h,
                     epsabs=1e-13)[0]
        assert phi[k] @ f(t) == pytest.approx(exact, rel=1e-7)
    # the noise of the samples is not amplified by the bunched ones (the cubic rule's weights
    # there were large and of both signs: 10 times the noise in an integral)
    weights = quadrature_weights(t)
    assert np.sqrt(np.sum(weights**2)) < 1.2 * np.sqrt((t[-1] - t[0]) * 1e-3)
    # integration by parts: int phi q' = -int phi' q
    np.testing.assert_allclose(phi @ (3 * np.cos(3 * t)), -(dphi @ np.sin(3 * t)), atol=1e-6)


def test_smoother_on_jittered_stamps_chooses_a_near_best_weight():
    # Quantized encoders (1e-5 rad) at 1 kHz on a log's stamps: the weight chosen from the
    # data gives velocities within 3 times the error of the best weight in hindsight (against
    # the analytic velocity). It was chosen 100 times too small (the risk of the velocity
    # counted the ends, where the error grows with the weight and the test functions vanish):
    # 8 to 14 times the best error.
    t = _log_stamps(5.0, 1e-3, np.random.default_rng(1))
    truth = np.column_stack([np.sin(2 * t) + 0.3 * np.sin(5.1 * t), 0.5 * np.cos(1.3 * t)])
    velocity = np.column_stack([2 * np.cos(2 * t) + 1.53 * np.cos(5.1 * t),
                                -0.65 * np.sin(1.3 * t)])
    rng = np.random.default_rng(2)
    encoder = np.round((truth + 2e-6 * rng.standard_normal(truth.shape)) / 1e-5) * 1e-5
    inside = slice(len(t) // 10, -len(t) // 10)  # where the test functions weigh the samples

    def error(qd):
        return np.sqrt(np.mean((qd - velocity)[inside] ** 2, axis=0))

    best = np.min([error(whittaker_smooth(t, encoder, [lam, lam])[1])
                   for lam in 10.0 ** np.arange(2, 12.1, 0.5)], axis=0)
    chosen = error(WhittakerSmoother().smooth(t, encoder)[1])
    assert np.all(chosen < 3 * best), chosen / best


def test_propagated_noise_covariance_matches_monte_carlo_on_a_jittered_grid():
    # The rows' errors drawn by re-noising the recorded positions (what the fit does) against
    # those of fresh noise on the true positions: same variance per row, same correlation of
    # neighbouring rows, on a jittered grid with gaps.
    coords = px.Coordinates(["x"])
    library = px.LagrangeLibrary(coords, [coords.qd[0] ** 2, coords.q[0] ** 2,
                                          coords.q[0] ** 4]).fit()
    rng = np.random.default_rng(3)
    t = _log_stamps(8.0, 0.005, rng, gap_rate=0.01)
    truth = (np.sin(1.3 * t) + 0.4 * np.sin(3.1 * t + 1))[:, None]
    sigma, lam, n_draws = 0.01, np.array([1e4]), 300
    noisy = truth + sigma * rng.standard_normal(truth.shape)
    phi, dphi, _ = BumpTestFunctions(width=0.6).matrices(t)

    def rows(x):
        return library.weak_transform(px.stack_variables(*whittaker_smooth(t, x, lam), t=t),
                                      phi, dphi)

    block = rows(noisy)
    draws = propagated_draws(library, {"t": t, "x": noisy, "u": None}, (lam, sigma, 3), phi,
                             dphi, block, n_draws, np.random.default_rng(4))
    fresh = np.array([rows(truth + sigma * rng.standard_normal(truth.shape))
                      for _ in range(n_draws)])
    fresh -= fresh.mean(axis=0)
    coef = np.array([0.5, -1.0, 0.1])
    for sample in (draws @ coef, fresh @ coef):
        assert sample.shape == (n_draws, phi.shape[0])
    drawn, monte_carlo = draws @ coef, fresh @ coef
    # per row within the sampling error of 300 draws (a variance to about 8 %), on average
    # within a few per cent
    np.testing.assert_allclose(drawn.var(axis=0), monte_carlo.var(axis=0), rtol=0.5)
    assert np.mean(drawn.var(axis=0)) == pytest.approx(np.mean(monte_carlo.var(axis=0)),
                                                       rel=0.08)

    def lag_correlation(sample, lag):
        return np.mean(sample[:, :-lag] * sample[:, lag:]) / np.mean(sample**2)

    for lag in (1, 2, 4):
        assert lag_correlation(drawn, lag) == pytest.approx(lag_correlation(monte_carlo, lag),
                                                            abs=0.05)


@pytest.mark.slow
def test_jittered_and_gapped_stamps_identify_as_well_as_uniform(double_pendulum_system):
    # The same motion recorded on uniform stamps and on a log's stamps (jitter, gaps of up to
    # 9 steps, and one gap long enough to cut the record): the same law, as accurately.
    system = double_pendulum_system
    library = paper_catalog(system.coords, [0, 1])
    true = true_coefficients(system, library)
    support = true != 0
    log = _log_stamps(24.0, 0.004, np.random.default_rng(5), gap_rate=0.01)
    log = np.concatenate([log[log < 12.0], log[log >= 12.5]])  # 0.5 s lost
    uniform = np.arange(0.0, 24.0, 0.004)
    x0, force = random_initial_state(system, 3), random_force(system, 3)
    errors, infos = {}, {}
    for name, t in (("uniform", uniform), ("log", log)):
        data = system.simulate(x0, t, force)
        noise = np.random.default_rng(8).normal(size=data["q"].shape)
        positions = data["q"] + 0.01 * data["q"].std(axis=0) * noise
        model = px.XLSINDy(library).fit(positions, t, u=data["tau"])
        coef = model.coefficients()
        assert np.array_equal(coef != 0, support), name
        errors[name] = np.median(np.abs(coef[support] - true[support]) / np.abs(true[support]))
        infos[name] = model.weak_info_
    assert errors["log"] < max(1.5 * errors["uniform"], 2e-3), errors
    assert infos["uniform"]["gaps"] == [] and infos["uniform"]["time_grid"]["uniform"]
    gaps = infos["log"]["gaps"]  # only the 0.5 s gap is longer than h / min_samples
    assert len(gaps) == 1 and gaps[0]["length"] == pytest.approx(0.5, abs=0.02)
    assert infos["log"]["segments"] == [0, 0]
    assert not infos["log"]["time_grid"]["uniform"]
    assert infos["log"]["time_grid"]["stamp_noise_ratio"] < 1.0  # the stamps are sampling times


def test_gaps_cut_trajectories_and_short_pieces_are_named(cart_pole_system):
    system = cart_pole_system
    library = paper_catalog(system.coords, [1])
    t = np.arange(0.0, 20.0, 0.01)
    data = system.simulate(random_initial_state(system, 1), t, random_force(system, 1))
    keep = (t < 18.0) | (t > 19.5)  # 1.5 s lost, 0.5 s left after it
    with pytest.warns(UserWarning, match=r"pieces \(between 1 gaps longer than .* of "
                                         r"trajectories \[0\] are shorter than one test"):
        model = px.XLSINDy(library).fit(data["q"][keep], t[keep], u=data["tau"][keep])
    assert model.weak_info_["segments"] == [0]
    assert model.weak_info_["gaps"][0]["time"] == pytest.approx(17.99)
    segments, source, gaps = split_at_gaps([{"t": t[keep], "x": data["q"][keep],
                                             "u": None, "mask": np.ones(keep.sum(), bool)}],
                                           0.1)
    assert [len(s["t"]) for s in segments] == [np.sum(t < 18.0), np.sum(t > 19.5)]
    assert source.tolist() == [0, 0] and len(gaps) == 1
    assert all(len(s["mask"]) == len(s["t"]) for s in segments)


def test_repeated_stamps_are_refused_by_name():
    coords = px.Coordinates(["x"])
    library = px.LagrangeLibrary(coords, [coords.qd[0] ** 2, coords.q[0] ** 2])
    t = np.linspace(0, 10, 1001)
    t[500] = t[499]
    with pytest.raises(ValueError, match=r"t: times must be strictly increasing; 1 step\(s\) "
                                         r"are not, the first repeated at samples 499 and 500"):
        px.XLSINDy(library).fit(np.sin(t), t, u=np.sin(t))


def test_strong_form_derivatives_on_jittered_stamps_are_as_accurate_as_on_uniform_ones():
    # The default smoothed differences (Savitzky-Golay, then central differences) smoothed in
    # sample order: on a log's stamps the accelerations were 10 times their own size in error.
    from pysindy_xl.fit import differentiation_function

    log = _log_stamps(5.0, 1e-3, np.random.default_rng(1))
    derivative = differentiation_function()
    errors = {}
    for name, t in (("log", log), ("uniform", np.linspace(0.0, log[-1], len(log)))):
        x = (np.sin(2 * t) + 0.3 * np.sin(5.1 * t))[:, None]
        acceleration = -4 * np.sin(2 * t) - 7.803 * np.sin(5.1 * t)
        encoder = np.round(x / 1e-5) * 1e-5
        estimate = derivative(derivative(encoder, t), t)[:, 0]
        errors[name] = np.sqrt(np.mean((estimate - acceleration)[100:-100] ** 2))
    assert errors["log"] < 1.2 * errors["uniform"], errors


def test_arrival_stamps_are_reported(cart_pole_system):
    # Samples taken every 10 ms and stamped when they arrive (late by up to 2 ms, and queued
    # behind a late one): the positions look far noisier at their stamps than in sample order.
    system = cart_pole_system
    library = paper_catalog(system.coords, [1])
    taken = np.arange(0.0, 20.0, 0.01)
    data = system.simulate(random_initial_state(system, 2), taken, random_force(system, 2))
    rng = np.random.default_rng(0)
    stamps = np.maximum.accumulate(taken + 0.002 * rng.random(len(taken)))
    stamps += 1e-6 * np.arange(len(taken))
    with pytest.warns(UserWarning, match="may be arrival times"):
        model = px.XLSINDy(library).fit(data["q"], stamps, u=data["tau"])
    assert model.weak_info_["time_grid"]["stamp_noise_ratio"] > 10
