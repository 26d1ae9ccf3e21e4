"""Each row of the "coming from PySINDy" table, called as a PySINDy user would."""

import numpy as np
import pysindy as ps
import pytest

import pysindy_xl as px

T = np.linspace(0, 20, 2001)
DT = T[1] - T[0]


@pytest.fixture(scope="module")
def oscillator():
    """x'' + 0.2 x' + 4 x = u for a known u: exact closed-form data."""
    coords = px.Coordinates(["x"])
    library = px.LagrangeLibrary(coords, [coords.qd[0] ** 2, coords.q[0] ** 2]) + \
        px.ClassicalLibrary(coords, [coords.qd[0]])
    x = np.sin(1.3 * T) + 0.5 * np.cos(0.7 * T)
    xd = 1.3 * np.cos(1.3 * T) - 0.35 * np.sin(0.7 * T)
    xdd = -1.69 * np.sin(1.3 * T) - 0.245 * np.cos(0.7 * T)
    u = xdd + 0.2 * xd + 4 * x
    return library, x, xd, xdd, u


def _check(model):
    # L = 0.5 x_dot^2 - 2 x^2, friction 0.2, force -1
    np.testing.assert_allclose(model.coefficients(), [-1.0, 0.5, -2.0, 0.2], rtol=1e-4)


def test_one_coordinate_as_1d_arrays(oscillator):
    library, x, xd, xdd, u = oscillator
    model = px.XLSINDy(library).fit(x, T, x_dot=xd, x_ddot=xdd, u=u)  # 1-D everywhere
    _check(model)
    assert model.predict(x, xd, u).shape == (len(T), 1)
    sim = model.simulate([x[0], xd[0]], T[:200], u=u[:200])          # 1-D u, as fit took it
    np.testing.assert_allclose(sim[:, 0], x[:200], atol=1e-4)


def test_default_time_step(oscillator):
    library, x, xd, xdd, u = oscillator
    model = px.XLSINDy(library, t_default=DT).fit(x, x_dot=xd, x_ddot=xdd, u=u)
    _check(model)
    assert model.score(x, x_dot=xd, x_ddot=xdd, u=u) > 0.999999


def test_pysindy_optimizer_passed_directly(oscillator):
    library, x, xd, xdd, u = oscillator
    model = px.XLSINDy(library, optimizer=ps.STLSQ(threshold=1e-3)).fit(
        x, T, x_dot=xd, x_ddot=xdd, u=u)
    _check(model)
    assert isinstance(model.optimizer_, px.ExplicitOptimizer)
    with pytest.raises(TypeError, match="expected an instance"):
        px.XLSINDy(library, optimizer=ps.STLSQ).fit(x, T, x_dot=xd, x_ddot=xdd, u=u)


def test_complexity_and_differentiate(oscillator):
    library, x, xd, xdd, u = oscillator
    model = px.XLSINDy(library).fit(x, T, u=u)  # positions only: weak form
    assert model.complexity == 4
    velocity = model.differentiate(x, T)
    assert velocity.shape == (len(T), 1)
    assert np.abs(velocity[:, 0] - xd).max() < 1e-4
    with_method = px.XLSINDy(library, differentiation_method=ps.FiniteDifference(order=4))
    assert np.abs(with_method.differentiate(x, T)[:, 0] - xd).max() < 1e-4


def test_several_trajectories_as_lists(oscillator):
    library, x, xd, xdd, u = oscillator
    halves = [slice(0, 1000), slice(1000, None)]
    model = px.XLSINDy(library).fit([x[h] for h in halves], [T[h] for h in halves],
                                    u=[u[h] for h in halves])
    _check(model)
