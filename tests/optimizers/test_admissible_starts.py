"""Admissible starts of the unforced law search (issue 34, product catalogs).

The admissible lasso (:func:`~pysindy_xl.optimizers.admissible.admissible_supports`) gives
sparse laws whose mean mass matrix is positive definite; the noise-ratio selection refines
them like its other candidates. On the cart double pendulum at 3 % noise the greedy paths over
the paper catalog end in a momentum balance of rank-one inertia and no admissible candidate.
"""

import sys

import numpy as np
import pytest

from pysindy_xl.optimizers.admissible import admissible_supports, reference_mass_matrices


def _rank_one_imitation(seed=0):
    """Columns 0, 1 carry the two coordinates' inertia, column 2 is a potential: the law
    ``c0 + c1 + c2 = 0``. Column 3 (inertia of rank one) imitates ``c0 + c1``."""
    rng = np.random.default_rng(seed)
    a, b, c = rng.normal(size=(3, 400))
    theta = np.column_stack([a, b, -(a + b), a + b + 1e-3 * c])
    mass = np.zeros((2, 4, 2, 2))
    mass[:, 0, 0, 0] = mass[:, 1, 1, 1] = 1.0
    mass[:, 3] = [[1.0, 1.0], [1.0, 1.0]]
    return theta, mass


def test_admissible_lasso_leaves_out_the_law_of_rank_one_inertia():
    theta, mass = _rank_one_imitation()
    supports = admissible_supports(theta, mass)
    assert supports
    assert all(set(s.tolist()) == {0, 1, 2} for s in supports)
    # the law of the imitation holds better: only the inequality keeps it out
    residual = np.linalg.norm(theta[:, 2] + theta[:, 3]) / np.linalg.norm(theta[:, 2])
    true_residual = np.linalg.norm(theta[:, :3].sum(axis=1))
    assert residual < 1e-2 and true_residual < 1e-9


def test_reference_inertia_is_unit_free():
    _, mass = _rank_one_imitation()
    reference = reference_mass_matrices(mass)
    assert reference.shape == (4, 2, 2)
    # scaling one coordinate's unit (its rows and columns) leaves the reference unchanged
    unit = np.diag([10.0, 1.0])
    rescaled = unit @ mass @ unit
    np.testing.assert_allclose(reference_mass_matrices(rescaled), reference)


def test_admissible_starts_without_cvxpy_name_it(monkeypatch):
    """cvxpy is a dependency: a broken install says what is missing, never fits otherwise."""
    theta, mass = _rank_one_imitation()
    monkeypatch.setitem(sys.modules, "cvxpy", None)  # import cvxpy raises ImportError
    with pytest.raises(ImportError, match="cvxpy"):
        admissible_supports(theta, mass)


def test_no_admissible_starts_without_any_definite_combination():
    theta, mass = _rank_one_imitation()
    assert admissible_supports(theta, mass[:, :, :1, :1] * 0) == []


@pytest.mark.slow
def test_cart_double_pendulum_unforced_at_3_percent_paper_catalog():
    """The noise sweep's cell (three 10 s unforced runs, 3 % position noise, seed 2): before
    the admissible starts, a 6-term law of constant inertia (rank one on the data) with a
    held-out ratio of 4.4; now the true 12-term law (held-out ratio about 1.3)."""
    from support.unforced_cells import fit_unforced_cell

    model, true = fit_unforced_cell("cart_double_pendulum", 0.03, seed=2)
    coef = model.coefficients()
    np.testing.assert_array_equal(coef != 0, true != 0)
    scale = (coef @ true) / (coef @ coef)
    np.testing.assert_allclose(coef[true != 0] * scale, true[true != 0], rtol=0.05)
    assert model.selection_.admissible
    assert model.selection_.cv_ratio[model.selection_.size - 1] < 2
