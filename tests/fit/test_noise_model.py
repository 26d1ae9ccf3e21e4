"""The noise model of a weak fit of measured forces, chosen by held-out force error.

Ground truth: a driven pendulum ``q'' + 9.81 sin q = tau`` integrated by scipy at tight
tolerance. Real arms have nearly exact (quantized) encoders and noisy torques; simulations
usually noisy positions and exact torques. The fit must tell the two apart from the data."""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import pysindy_xl as px
from pysindy_xl.weak import WeakNoise
from pysindy_xl.weak.selection import (
    MARGIN,
    NoiseModel,
    bandwidth_half_width,
    choose_noise_model,
    time_folds,
)

GRAVITY = 9.81


def _torque(t):
    return 3.0 * np.sin(1.1 * t) + 2.0 * np.sin(2.3 * t + 1.0) + 1.5 * np.sin(4.1 * t + 2.0)


def _pendulum(duration=20.0, rate=500.0):
    t = np.arange(0.0, duration, 1.0 / rate)
    solution = solve_ivp(lambda s, y: [y[1], _torque(s) - GRAVITY * np.sin(y[0])], (0, t[-1]),
                         [0.3, 0.0], t_eval=t, rtol=1e-11, atol=1e-12, method="DOP853")
    return t, solution.y[0][:, None], _torque(t)[:, None]


def _library():
    c = px.Coordinates(["q"])
    return px.LagrangeLibrary(c, [c.qd[0] ** 2, sp.cos(c.q[0]), c.q[0] ** 2])


def _gravity_error(model):
    """Relative error of the identified ``9.81`` (gravity over inertia): the coefficient of
    ``cos q`` against that of ``q_dot^2 / 2``."""
    names = model.feature_library_.get_feature_names()
    coef = dict(zip(names, model.coef_, strict=True))
    inertia = 2 * coef["L[q_dot**2]"]
    return abs(coef["L[cos(q)]"] / inertia - GRAVITY) / GRAVITY


@pytest.mark.parametrize("seed", [0, 1])
def test_torque_sensor_offset_and_exact_encoders_choose_the_force_noise_model(seed):
    """Encoders quantized at 1e-5 rad, torques with 10 % white noise and a constant sensor
    offset the catalog has no column for (a real torque sensor's): the narrow unweighted
    rows predict held-out blocks better, are chosen, and identify gravity better than
    the position-noise model forced by ``residual_covariance=True``."""
    t, q, tau = _pendulum()
    rng = np.random.default_rng(seed)
    q = np.round(q / 1e-5) * 1e-5
    tau = tau + 0.5 + 0.1 * np.std(tau) * rng.normal(size=tau.shape)
    model = px.XLSINDy(_library()).fit(q, t, u=tau)
    choice = model.weak_info_["noise_model"]
    assert choice["chosen"] == "forces"
    errors = [c["held_out_error"] for c in choice["candidates"]]
    assert min(errors[1:]) < 0.8 * errors[0]
    forced = px.XLSINDy(_library(), residual_covariance=True).fit(q, t, u=tau)
    assert "noise_model" not in forced.weak_info_
    assert _gravity_error(model) < 0.01
    assert _gravity_error(model) < 0.6 * _gravity_error(forced)


def test_noisy_positions_and_exact_torques_keep_the_position_noise_model():
    """Positions with 1 % noise, exact torques: the held-out blocks cannot prefer the narrow
    rows by a margin, and the fit is the position-noise model's (the same coefficients as
    ``residual_covariance=True``)."""
    t, q, tau = _pendulum()
    q = q + 0.01 * np.std(q) * np.random.default_rng(0).normal(size=q.shape)
    model = px.XLSINDy(_library()).fit(q, t, u=tau)
    assert model.weak_info_["noise_model"]["chosen"] == "positions"
    forced = px.XLSINDy(_library(), residual_covariance=True).fit(q, t, u=tau)
    np.testing.assert_allclose(model.coef_, forced.coef_, rtol=1e-12, atol=1e-14)
    assert _gravity_error(model) < 0.01


def test_time_folds_hold_out_inside_and_fit_outside():
    """Test functions whose support crosses a block edge are neither fitted nor scored in
    that fold; every test function inside a block is scored exactly once."""
    rng = np.random.default_rng(0)
    start = np.sort(rng.uniform(0, 9, 200))
    supports = np.column_stack([np.zeros(200), start, start + 1.0])
    fit, held = time_folds(supports, np.array([[0.0, 10.0]]), 5)
    edges = np.linspace(0, 10, 6)
    for k in range(5):
        inside = (supports[:, 1] >= edges[k]) & (supports[:, 2] <= edges[k + 1])
        apart = (supports[:, 2] < edges[k]) | (supports[:, 1] > edges[k + 1])
        np.testing.assert_array_equal(held[k], inside)
        np.testing.assert_array_equal(fit[k], apart)
    assert held.sum(axis=0).max() == 1


def test_rows_of_the_noise_keep_their_runs():
    """Leaving out rows cuts the runs of consecutive test functions, coordinate by
    coordinate, and keeps the draws of the rows left."""
    draws = np.arange(2 * 12 * 1, dtype=float).reshape(2, 12, 1)
    noise = WeakNoise(draws, 2, np.array([[0, 6, 0, 2], [6, 12, 1, 2]]))
    keep = np.tile([True, False, True, True, False, True], 2)
    part = noise.rows(keep)
    np.testing.assert_array_equal(part.draws, draws[:, keep])
    assert part.runs.tolist() == [[0, 1, 0, 2], [1, 3, 0, 2], [3, 4, 0, 2],
                                  [4, 5, 1, 2], [5, 7, 1, 2], [7, 8, 1, 2]]


def test_too_short_data_keep_the_default():
    """Blocks too short to hold a scoring test function: no choice is made (None)."""
    supports = np.array([[0, 0.0, 6.0], [0, 4.0, 10.0]])
    rows = np.ones((2, 3))
    best, errors = choose_noise_model([(None, rows, supports, None)], (rows, supports, None),
                                      np.array([[0.0, 10.0]]), [0], None)
    assert best is None and errors == []


def test_a_candidate_too_wide_for_the_blocks_yields_to_one_that_fits():
    """Short data: the first candidate's wide test functions leave too few rows outside any
    block, the second's narrow ones plenty. The second is scored and chosen (its law
    ``f = 2 x`` recovered); the first counts as unfitted (``inf``) instead of blocking the
    choice."""
    rng = np.random.default_rng(0)
    spans = np.array([[0.0, 10.0]])

    def rows_of(supports):
        x = rng.normal(size=len(supports))
        return np.column_stack([2.0 * x + 0.01 * rng.normal(size=len(x)), -x])

    wide = np.array([[0, 0.0, 6.0], [0, 2.0, 8.0], [0, 4.0, 10.0]])
    start = np.linspace(0.0, 9.8, 200)
    narrow = np.column_stack([np.zeros(200), start, start + 0.2])
    rows = rows_of(narrow)

    def solve(theta, noise, weigh):  # the force column's coefficient fixed at 1
        slope = np.linalg.lstsq(theta[:, 1:], -theta[:, 0], rcond=None)[0]
        return np.concatenate([[1.0], slope])

    best, errors = choose_noise_model(
        [(NoiseModel("positions", 3.0, True), rows_of(wide), wide, None),
         (NoiseModel("forces", 0.1, False), rows, narrow, None)],
        (rows, narrow, None), spans, [0], solve)
    assert best == 1
    assert errors[0] == np.inf and errors[1] < 0.01


@pytest.mark.parametrize("shrink", [0.45, 0.0])
def test_an_unscored_first_candidate_stays_against_one_that_predicts_nothing(shrink):
    """Short data again, but the narrow candidate's law is shrunk (as errors in its variables
    shrink a narrow fit of noisy positions: here by 45 %, or its law is the zero one) and
    its rows hold what it cannot explain. Its held-out force error is then no better than the
    zero law's (1): the first, which could not be scored, is judged as the zero law and
    stays."""
    rng = np.random.default_rng(1)
    spans = np.array([[0.0, 10.0]])
    wide = np.array([[0, 0.0, 6.0], [0, 2.0, 8.0], [0, 4.0, 10.0]])
    start = np.linspace(0.0, 9.8, 200)
    narrow = np.column_stack([np.zeros(200), start, start + 0.2])
    x = rng.normal(size=200)
    rows = np.column_stack([2.0 * x, -x + 2.0 * rng.normal(size=200)])

    def solve(theta, noise, weigh):  # the force column's coefficient fixed at 1
        return np.array([1.0, 2.0 * (1.0 - shrink)])

    best, errors = choose_noise_model(
        [(NoiseModel("positions", 3.0, True), rows[:3], wide, None),
         (NoiseModel("forces", 0.1, False), rows, narrow, None)],
        (rows, narrow, None), spans, [0], solve)
    assert errors[0] == np.inf and errors[1] > 1.0 - MARGIN
    assert best == 0


@pytest.mark.parametrize(("position_noise", "chosen"), [(0.1, 0), (0.01, 1)])
def test_noisy_positions_in_the_scoring_rows_keep_the_first_candidate(position_noise, chosen):
    """The second candidate's law is exact, the first's 25 % off. Where the positions' noise
    (draws of the scoring rows' errors) makes up more than a tenth of the first's held-out
    residual, the comparison is not trusted and the first stays; where it is small, the
    better law is chosen."""
    rng = np.random.default_rng(0)
    start = np.linspace(0.0, 9.8, 200)
    supports = np.column_stack([np.zeros(200), start, start + 0.2])
    x = rng.normal(size=200)
    rows = np.column_stack([2.0 * x, -x])
    draws = position_noise * rng.normal(size=(50, 200, 2))
    noise = WeakNoise(draws, 1, np.array([[0, 200, 0, 2]]))

    def solve(theta, noise, weigh):
        return np.array([1.0, 2.5 if weigh else 2.0])

    best, errors = choose_noise_model(
        [(NoiseModel("positions", 0.2, True), rows, supports, None),
         (NoiseModel("forces", 0.2, False), rows, supports, None)],
        (rows, supports, noise), np.array([[0.0, 10.0]]), [0], solve)
    assert best == chosen
    assert errors[1] < 0.5 * errors[0]


def test_bandwidth_half_width_matches_the_bump_response():
    """At the half-width for 10 Hz, the bump's frequency response (by quadrature) is
    1/sqrt(2) at 10 Hz, to 2 %."""
    h = bandwidth_half_width(10.0, power=6)
    s = np.linspace(-1, 1, 20001)
    bump = (1 - s**2) ** 6
    response = np.trapezoid(bump * np.cos(2 * np.pi * 10.0 * h * s), s) / np.trapezoid(bump, s)
    assert response == pytest.approx(2**-0.5, rel=0.02)


def test_the_candidates_rows_smooth_each_piece_once_and_change_nothing(monkeypatch):
    """The noise-model choice builds its rows again from the same pieces and draws: with
    the fit's remembering smoother each is smoothed once, and the fit is the same, to the
    bit, as with a smoother that smooths again every time."""
    from pysindy_xl import model as model_module

    t, q, tau = _pendulum(duration=12.0)
    q = q + 1e-3 * np.random.default_rng(0).normal(size=q.shape)
    calls = {"smooth": 0, "resmooth": 0}

    class Counting(px.WhittakerSmoother):
        def smooth(self, t, x):
            calls["smooth"] += 1
            return super().smooth(t, x)

        def resmooth(self, t, x):
            calls["resmooth"] += 1
            return super().resmooth(t, x)

    remembered = px.XLSINDy(_library(), smoother=Counting()).fit(q, t, u=tau)
    assert "noise_model" in remembered.weak_info_  # the choice was made: rows built twice
    assert calls == {"smooth": 1, "resmooth": 1}
    monkeypatch.setattr(model_module, "fit_smoother", lambda smoother: smoother)
    again = px.XLSINDy(_library(), smoother=Counting()).fit(q, t, u=tau)
    assert calls == {"smooth": 3, "resmooth": 3}  # the default rows, then the scoring rows
    np.testing.assert_array_equal(again.coef_, remembered.coef_)
