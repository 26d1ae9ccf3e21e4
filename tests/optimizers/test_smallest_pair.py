"""The smallest pencil pair alone (``smallest_pair``) against the generalized eigenproblem."""

import numpy as np
import pytest
import scipy.linalg

from pysindy_xl.optimizers.noise_ratio import SMALLEST_ALONE, noise_pencil, smallest_pair


def _pencil(rng, n_rows, k, noise):
    """Noisy columns holding one law, and their noise moments."""
    clean = rng.normal(size=(n_rows, k))
    clean[:, 0] = clean[:, 1:4] @ [1.0, -2.0, 0.5]
    theta = clean + noise * rng.normal(size=(n_rows, k))
    return theta, noise**2 * n_rows * np.eye(k)


@pytest.mark.parametrize("k", [SMALLEST_ALONE, 90])
def test_matches_the_generalized_eigenproblem(k):
    rng = np.random.default_rng(0)
    theta, moments = _pencil(rng, 6 * k, k, 0.05)
    value, vector = smallest_pair(theta, moments)
    # independent: LAPACK's symmetric-definite solver on the Gram matrix (well conditioned here)
    values, vectors = scipy.linalg.eigh(theta.T @ theta, moments)
    assert value == pytest.approx(values[0], rel=1e-9)
    assert abs(vector @ moments @ vectors[:, 0]) == pytest.approx(1.0, abs=1e-9)
    # the law found is the planted one
    law = vector / vector[0]
    assert law[1:4] == pytest.approx([-1.0, 2.0, -0.5], abs=0.05)
    assert np.abs(law[4:]).max() < 0.05


def test_triangular_tall_and_stacked_agree_with_the_full_decomposition():
    rng = np.random.default_rng(1)
    theta, moments = _pencil(rng, 200, 50, 0.01)
    r_factor = np.linalg.qr(theta, mode="r")
    values, vectors = noise_pencil(theta, moments)
    for factor in (theta, r_factor):  # tall, and square upper triangular
        value, vector = smallest_pair(factor, moments)
        assert value == pytest.approx(values[0], rel=1e-10)
        # the vectors' alignment is second order in their error; 1e-10 flips with the BLAS kernel
        assert abs(vector @ moments @ vectors[:, 0]) == pytest.approx(1.0, abs=1e-8)
    stacked = smallest_pair(np.stack([theta, 2 * theta]), np.stack([moments, moments]))
    assert stacked[0].shape == (2,) and stacked[1].shape == (2, 50)
    assert stacked[0] == pytest.approx([values[0], 4 * values[0]], rel=1e-10)


def test_small_pencils_are_the_full_decompositions_first_pair():
    rng = np.random.default_rng(2)
    theta, moments = _pencil(rng, 100, 8, 0.05)
    values, vectors = noise_pencil(theta, moments)
    value, vector = smallest_pair(theta, moments)
    assert value == values[0] and np.array_equal(vector, vectors[:, 0])


def test_an_exact_law_without_noise_is_found():
    rng = np.random.default_rng(3)
    theta, _ = _pencil(rng, 300, 60, 0.0)  # column 0 an exact combination: W singular
    value, vector = smallest_pair(theta, np.eye(60))
    assert value == pytest.approx(0.0, abs=1e-20)
    law = vector / vector[0]
    assert law[1:4] == pytest.approx([-1.0, 2.0, -0.5], abs=1e-8)
