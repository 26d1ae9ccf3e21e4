"""The mass-matrix check of a fit: one rule (:func:`mass_matrix_failure`) for the fit-time
warning and for the command line's exit, on mass matrices whose definiteness is known."""

import numpy as np
import pytest

import pysindy_xl as px
from pysindy_xl.fit.diagnostics import mass_matrix_failure, mass_matrix_report


def _report(mass):
    return mass_matrix_report(mass, np.linalg.eigvalsh(mass), ["x", "theta"])


def test_a_kinetic_coefficient_changing_sign_is_reported_on_the_states_where_it_is_negative():
    """``M = diag(a + b x, 1)`` on 2,000 evenly spaced ``x``: not positive definite exactly
    where ``a + b x <= 0``; the warning opens with the failure the exit reports."""
    x = np.linspace(2.0, 2.9, 2000)
    inertia = x - 2.45  # vanishes at rest, as a fit of the hanging spring's sign-changing law
    mass = np.zeros((len(x), 2, 2))
    mass[:, 0, 0], mass[:, 1, 1] = inertia, 1.0
    with pytest.warns(px.IdentificationWarning) as records:
        report = _report(mass)
    assert report["positive_definite_fraction"] == np.mean(inertia > 1e-9 * np.abs(inertia).max())
    failure = mass_matrix_failure(report)
    assert failure == "the identified mass matrix is not positive definite on 50% of the " \
                      "training states"
    message = str(records[0].message)
    assert message.startswith(failure) and "no positive inertia on ['x']" in message


def test_one_bad_state_in_two_thousand_fails_and_is_not_rounded_to_zero():
    mass = np.tile(np.diag([2.0, 1.0]), (2000, 1, 1))
    mass[7] = [[2.0, 1.5], [1.5, 1.0]]  # determinant -0.25: indefinite
    with pytest.warns(px.IdentificationWarning, match=r"on 0\.05% of the training states"):
        report = _report(mass)
    assert report["positive_definite_fraction"] == 1999 / 2000
    assert mass_matrix_failure(report).endswith("on 0.05% of the training states")


def test_a_positive_definite_matrix_passes_without_a_warning(recwarn):
    angle = np.linspace(-3, 3, 500)
    mass = np.empty((len(angle), 2, 2))  # a cart-pole's, positive definite everywhere
    mass[:, 0, 0], mass[:, 1, 1] = 1.5, 0.32
    mass[:, 0, 1] = mass[:, 1, 0] = 0.4 * np.cos(angle)
    report = _report(mass)
    assert report["positive_definite_fraction"] == 1.0 and not recwarn.list
    assert mass_matrix_failure(report) is None and mass_matrix_failure(None) is None
    assert mass_matrix_failure({"positive_definite_fraction": float("nan"),
                                "median_condition": float("nan")}) is None
