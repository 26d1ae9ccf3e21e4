"""The growth's final fit on all the data is the regression its criterion judged: the chosen
catalog is fitted with the search's weak-form test functions.

Ground truth: a unit mass in a log-cosh well (``sympy.physics.mechanics``, integrated by scipy
at 1e-10), unforced and free of noise, whose potential only the flexible basis (natural
splines) states.
"""

import warnings

import numpy as np
from scipy.integrate import solve_ivp
from support.growth import log_cosh_well

from pysindy_xl.catalog import grow_catalog
from pysindy_xl.weak import BumpTestFunctions


def _free_runs(accelerations, starts, duration=10.0, rate=250.0):
    """Unforced runs of a one-coordinate law from the states ``starts`` (scipy DOP853, 1e-10
    tolerances): times and positions (N, 1) of each."""
    t = np.arange(0.0, duration, 1.0 / rate)
    xs = [solve_ivp(lambda time, y: [y[1], accelerations(y[0], y[1], 0.0)], (t[0], t[-1]),
                    list(start), t_eval=t, method="DOP853", rtol=1e-10, atol=1e-10).y[0][:, None]
          for start in starts]
    return [t] * len(xs), xs


def test_the_final_fit_is_the_judged_regression_and_gives_the_law():
    accelerations, _ = log_cosh_well()
    ts, xs = _free_runs(accelerations, [(0.948, -0.995), (0.512, 0.294)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = grow_catalog(xs, ts, coordinates=["x"], moves=("splines",), tie_break=False)
    assert found.catalog.spline_columns()  # the flexible basis was kept
    # the accelerations of the fitted law against sympy's over the recorded range (with the
    # default test functions the final fit kept a combination of splines that nearly
    # vanishes on the data: accelerations off by a factor of about 900 here)
    low, high = np.percentile(np.vstack(xs), [5, 95])
    q = np.linspace(low, high, 41)[:, None]
    for speed in (-1.0, 0.0, 1.0):
        qd = np.full_like(q, speed)
        true = accelerations(q, qd, 0.0)
        error = np.linalg.norm(found.model.predict(q, qd) - true) / np.linalg.norm(true)
        assert error < 0.02, (speed, error)
    # the search's test functions: one half-width, a third of a fifth of a 10 s run
    tests = found.model.test_functions
    assert isinstance(tests, BumpTestFunctions)
    assert np.isclose(tests.width, (ts[0][len(ts[0]) // 5 - 1] - ts[0][0]) / 3)
