"""The honest exit of ``pysindy-xl identify`` reads the fit's own mass-matrix check, against a
mass hanging on a spring under gravity integrated by scipy at 1e-10 (``m xdd = m g - k x - c
xd``, free runs, positions only).

A catalog whose kinetic coefficient may change sign (``x_dot^2``, ``x x_dot^2``, the gravity
``x``, viscous friction, no spring) fits the weak form with a law ``(x - x0) x_dot^2 + ...``
whose inertia vanishes at ``x0`` inside the recorded motion: R^2 about 0.9, above the bar of
"explains nothing", while its accelerations are off by orders of magnitude. The fit warns
that its mass matrix is not positive definite; the exit reads that same check and fails it.
The catalog with the spring (``x^2``) gives the law and exits 0."""

import warnings

import numpy as np
import pytest
from support.files import write_csv
from support.springs import hanging_spring

import pysindy_xl as px
import pysindy_xl.mujoco.catalogs.reference as reference
from pysindy_xl.cli import main
from pysindy_xl.cli.automatic import POOR_R2, honest_exit
from pysindy_xl.cli.steps import CLIError
from pysindy_xl.fit.diagnostics import mass_matrix_failure
from pysindy_xl.quality import fit_quality


def _sign_changing(x, xd):
    """Kinetic coefficient ``a + b x``, which the fit may let change sign; no spring."""
    return [xd**2, x * xd**2, x]


def _with_the_spring(x, xd):
    return [xd**2, x, x**2]


def _catalog(terms):
    c = px.Coordinates(["x"])
    (x,), (xd,) = c.q, c.qd
    return px.LagrangeLibrary(c, terms(x, xd)) + px.ClassicalLibrary(c, [xd])


@pytest.fixture(scope="module")
def runs():
    """Two free 10 s runs at 200 Hz."""
    return hanging_spring()


def _relative_acceleration_error(model, runs):
    _, x, xd, xdd = runs
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        predicted = model.predict(np.vstack(x), np.vstack(xd))
    return float(np.linalg.norm(predicted - np.vstack(xdd)) / np.linalg.norm(np.vstack(xdd)))


def test_a_law_whose_inertia_vanishes_on_its_data_fails_the_exit_despite_its_r2(runs):
    t, x, _, _ = runs
    arguments = {"x": x, "t": [t, t]}  # positions only: the weak form
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = px.XLSINDy(_catalog(_sign_changing)).fit(**arguments)
    assert any(issubclass(w.category, px.IdentificationWarning)
               and "not positive definite" in str(w.message) for w in caught)
    found = dict(zip(model.get_feature_names(), model.coefficients(), strict=True))
    # the inertia a + b x vanishes inside the recorded positions
    rest = -found["L[x_dot**2]"] / found["L[x*x_dot**2]"]
    assert np.vstack(x).min() < rest < np.vstack(x).max()
    assert _relative_acceleration_error(model, runs) > 10  # against scipy's truth
    quality = fit_quality(model, arguments)
    assert quality["r2"] >= POOR_R2  # the R^2 alone passes it
    honest_exit(quality["r2"])
    check = model.mass_matrix_check_
    assert 0 < check["positive_definite_fraction"] < 1
    with pytest.raises(CLIError, match=r"is not physical \(the identified mass matrix is not "
                                       r"positive definite on \d+% of the training states") as e:
        honest_exit(quality["r2"], mass_matrix_check=check)
    assert "explains nothing" not in str(e.value)  # the R^2's advice is not given
    assert "kinetic coefficients that cannot change sign" in str(e.value)
    assert mass_matrix_failure(check) in str(e.value)  # the fit-time warning's own words


@pytest.mark.parametrize("terms, status", [(_sign_changing, 1), (_with_the_spring, 0)])
def test_identify_exits_by_the_mass_matrix_of_the_fitted_catalog(runs, tmp_path, capsys,
                                                                  monkeypatch, terms, status):
    """Through ``pysindy-xl identify`` on a CSV of the free runs, the reference catalog
    replaced by the one of the case (the CLI's catalogs cannot state it): the real fit path
    (implicit solver, weak form), fit quality and exit."""
    t, x, _, _ = runs
    path = write_csv(tmp_path / "free.csv", ["t", "x", "trajectory"],
                     [np.r_[t, t], np.vstack(x)[:, 0], np.repeat([0.0, 1.0], len(t))])
    monkeypatch.setattr(reference, "reference_catalog", lambda *a, **k: _catalog(terms))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = main(["identify", str(path), "--coordinates", "x", "--catalog", "lagrange",
                     "--quiet"])
    captured = capsys.readouterr()
    assert code == status, captured.err
    r2 = float(captured.out.split("fit quality: R^2 = ")[1].split()[0])
    assert "implicit solver, weak formulation" in captured.out
    if status:
        assert r2 >= POOR_R2  # failed by the mass matrix, not by the R^2
        assert "is not physical" in captured.err and "not positive definite" in captured.err
        assert "explains nothing" not in captured.err
    else:
        assert r2 > 0.999 and captured.err.count("error") == 0


def test_a_physical_check_passes_and_a_missing_one_is_not_judged():
    healthy = {"positive_definite_fraction": 1.0, "median_condition": 2.3}
    assert honest_exit(0.999, 0.01, mass_matrix_check=healthy) is None
    assert honest_exit(0.999, mass_matrix_check=None) is None
    with pytest.raises(CLIError, match=r"explains nothing \(R\^2 = 0.2 below 0.5\) and is not "
                                       r"physical \(.* on 0.05% of"):
        honest_exit(0.2, mass_matrix_check={"positive_definite_fraction": 0.9995,
                                            "median_condition": 3.0})
