"""The trimmed criterion of a cross-validated growth (``combine="trimmed"``): one failing fit
out of five held-out blocks does not refuse the right catalog. Against a hardening spring
integrated by scipy at 1e-10, whose nonlinearity shows only in a burst of large swings."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pysindy_xl.catalog import grow_catalog
from pysindy_xl.catalog.candidates import combine_errors

# m xdd + c xd + k x + h x^3 = tau: strongly damped, so the swings of the burst die out
MASS, DAMPING, STIFFNESS, HARDENING = 1.5, 3.0, 2.0, 1.0


def _burst(seed: int, noise: float = 0.005, duration: float = 10.0, rate: float = 200.0):
    """A forced run whose force is large only around its middle (a Gaussian envelope of
    0.3 s over a floor of 3 %): the swings beyond the linear range (``|x|`` above 0.5)
    fall in one or two of five time blocks. Positions with Gaussian noise of ``noise`` times
    their standard deviation."""
    t = np.arange(0.0, duration, 1.0 / rate)
    rng = np.random.default_rng(seed)
    frequencies, phases = rng.uniform(0.3, 1.2, 4), rng.uniform(0, 2 * np.pi, 4)

    def force(time):
        envelope = 0.03 + 0.97 * np.exp(-0.5 * ((time / duration - 0.5) / 0.03) ** 2)
        return 6.0 * envelope * np.sin(2 * np.pi * np.multiply.outer(time, frequencies)
                                       + phases).sum(axis=-1)

    def rhs(time, y):
        return [y[1], (force(time) - DAMPING * y[1] - STIFFNESS * y[0]
                       - HARDENING * y[0] ** 3) / MASS]

    x = solve_ivp(rhs, (0, t[-1]), [0.0, 0.0], t_eval=t, method="DOP853", rtol=1e-10,
                  atol=1e-10).y[0]
    noisy = x + noise * x.std() * np.random.default_rng(seed + 1).normal(size=len(t))
    return noisy[:, None], t, force(t)[:, None], x


@pytest.mark.parametrize("seed", [0, 4])
def test_one_failing_block_does_not_refuse_the_law(seed):
    """Fitted without the block of the largest swings, the hardening spring's catalog
    (``x..x^4``) fails on that block (above 20 %, four times the next block's error at
    least): the RMS over the five blocks then keeps a stand-in (an asymmetric
    ``x^2`` force), the trimmed criterion keeps the law, whose coefficients match the
    integrated ones."""
    x, t, u, truth = _burst(seed)
    reach = [float(np.abs(block).max()) for block in np.array_split(truth, 5)]
    assert sum(r > 0.5 for r in reach) <= 2 and min(reach) < 0.05  # the burst
    options = {"coordinates": ["x"], "moves": ("degree",), "cross_validate": True}
    trimmed = grow_catalog(x, t, u, combine="trimmed", **options)
    plain = grow_catalog(x, t, u, **options)
    assert trimmed.catalog.degree == 4, trimmed.table()
    coef = dict(zip(map(str, trimmed.model.feature_library_.feature_terms_),
                    trimmed.model.coef_, strict=False))
    truth_coef = {"x**4": -HARDENING / 4, "x**2": -STIFFNESS / 2, "x_dot**2": MASS / 2}
    for name, value in truth_coef.items():
        assert coef[name] == pytest.approx(value, rel=0.05), (name, coef)
    # the law's step: one block's fit fails, the others hold; the plain RMS is dominated by it
    law = next(step for step in trimmed.steps if step.terms == 6)
    errors = np.sort(law.block_errors)
    assert errors[-1] > 0.2 and errors[-1] > 4 * errors[-2], law.block_errors
    assert law.criterion == pytest.approx(np.sqrt(np.mean(errors[:-1] ** 2)))
    assert plain.catalog.degree != 4, plain.table()
    plain_law = next(step for step in plain.steps if step.terms == 6)
    assert plain_law.block_errors == law.block_errors  # the same fits, another criterion
    assert plain_law.criterion > 2.5 * law.criterion


def test_the_default_criterion_is_the_rms_of_every_block():
    """``combine`` defaults to the RMS; a failed fit (inf) refuses a catalog under the RMS and
    is left out by the trimmed criterion."""
    errors = [0.01, np.inf, 0.02, 0.01, 0.03]
    assert combine_errors(errors) == np.inf
    assert combine_errors(errors, "trimmed") == pytest.approx(np.sqrt((1 + 4 + 1 + 9) / 4) / 100)
    assert combine_errors([0.3, 0.4]) == pytest.approx(np.sqrt(0.125))


def test_bad_combine_is_refused():
    x, t, u, _ = _burst(0)
    with pytest.raises(ValueError, match="combine: expected one of"):
        grow_catalog(x, t, u, coordinates=["x"], cross_validate=True, combine="median")
    with pytest.raises(ValueError, match="combine: 'trimmed' needs cross_validate"):
        grow_catalog(x, t, u, coordinates=["x"], combine="trimmed")
    with pytest.raises(ValueError, match="n_blocks >= 4"):
        grow_catalog(x, t, u, coordinates=["x"], cross_validate=True, n_blocks=3,
                     combine="trimmed")
    with pytest.raises(ValueError, match="at least 4 held-out blocks"):
        combine_errors([0.1, 0.2, 0.3], "trimmed")
    with pytest.raises(ValueError, match="combine: expected one of"):
        combine_errors([0.1, 0.2, 0.3, 0.4], "mean")
