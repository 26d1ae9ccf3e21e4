"""The fit-quality R^2 of unforced fits judges each equation over its kinetic part, against a
mass hanging on a spring under gravity integrated by scipy at 1e-10: ``m xdd = m g - k x - c
xd``. Around the rest length ``m g / k`` the gravity and spring terms are large and nearly
cancel, while the inertia that states the accelerations is small: a figure over the largest
term called laws exact that explain nothing."""

import warnings

import numpy as np
import pytest
from support.files import write_csv
from support.springs import hanging_spring as hanging_spring_runs

import pysindy_xl as px
from pysindy_xl.cli import main
from pysindy_xl.cli.automatic import POOR_R2, honest_exit
from pysindy_xl.cli.steps import CLIError
from pysindy_xl.fit.kinetic_scale import inertial_columns
from pysindy_xl.fit.wrap import catalog_dynamics
from pysindy_xl.quality import fit_quality, quality_lines


@pytest.fixture(scope="module")
def hanging_spring():
    """Two free 10 s runs at 200 Hz: times, positions, velocities, accelerations."""
    return hanging_spring_runs()


def _arguments(data, formulation):
    t, x, xd, xdd = data
    if formulation == "strong":  # exact derivatives
        return {"x": x, "t": [t, t], "x_dot": xd, "x_ddot": xdd}
    return {"x": x, "t": [t, t]}  # positions only: weak form


def _fit(library, arguments):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return px.XLSINDy(library).fit(**arguments)


def _acceleration_error(model, data):
    _, x, xd, xdd = data
    predicted = model.predict(np.vstack(x), np.vstack(xd))
    return float(np.linalg.norm(predicted - np.vstack(xdd)) / np.linalg.norm(np.vstack(xdd)))


def _library(terms):
    c = px.Coordinates(["x"])
    (x,), (xd,) = c.q, c.qd
    lagrangian = [xd**2, x] + [term(x, xd) for term in terms]
    return px.LagrangeLibrary(c, lagrangian) + px.ClassicalLibrary(c, [xd])


@pytest.mark.parametrize("formulation", ["strong", "weak"])
def test_the_law_scores_one_and_a_catalog_without_the_spring_explains_nothing(
        hanging_spring, formulation):
    """With the spring (``x^2``) the fit is the law and R^2 is 1; without it, the fit keeps
    a law of kinetic terms alone (free motion in a position-dependent metric, no force at
    all: accelerations off by a factor of about 50), whose residual is its whole kinetic
    part: R^2 = 0 and the honest exit fails it. Over the largest term (``x x_dot^2``) its
    residual looked like nothing (R^2 = 1)."""
    arguments = _arguments(hanging_spring, formulation)
    law = _fit(_library([lambda x, xd: x**2]), arguments)
    assert _acceleration_error(law, hanging_spring) < 1e-6
    quality = fit_quality(law, arguments)
    assert quality["r2"] > 1 - 1e-9 and quality["r2_per_coordinate"]["x"] == quality["r2"]
    honest_exit(quality["r2"])
    free = _fit(_library([lambda x, xd: x * xd**2, lambda x, xd: x**2 * xd**2]), arguments)
    assert _acceleration_error(free, hanging_spring) > 10
    free_quality = fit_quality(free, arguments)
    assert free_quality["r2"] < POOR_R2
    with pytest.raises(CLIError, match="explains nothing"):
        honest_exit(free_quality["r2"])
    assert quality["target"] == free_quality["target"] == "kinetic"
    assert quality["formulation"] == formulation


def test_r2_is_set_by_the_kinetic_part_not_by_the_largest_term(hanging_spring):
    """The law with its kinetic part divided by 4 (accelerations four times the law's): the
    residual is 3/4 of the law's kinetic part and the kinetic part 1/4, so R^2 = 1 - 3^2 =
    -8, whatever the size of the nearly cancelling spring and gravity terms (about 9 times
    the kinetic part here: over them, R^2 was 0.99)."""
    arguments = _arguments(hanging_spring, "strong")
    model = _fit(_library([lambda x, xd: x**2]), arguments)
    problem = model.regression(**arguments)
    kinetic = problem.catalog_map.columns[inertial_columns(model, problem)]
    assert [model.get_feature_names()[j] for j in kinetic] == ["L[x_dot**2]"]
    model.coef_[kinetic] /= 4
    model.dynamics_ = catalog_dynamics(model.feature_library_, model.coef_, np.zeros(1, bool))
    assert _acceleration_error(model, hanging_spring) == pytest.approx(3, rel=1e-3)
    quality = fit_quality(model, arguments)
    assert quality["r2"] == pytest.approx(-8, rel=1e-6)
    with pytest.raises(CLIError, match="explains nothing"):
        honest_exit(quality["r2"])
    lines = quality_lines(quality)
    assert lines[0] == "fit quality: R^2 = -8.0000 (x -8.0000)"
    assert "|kinetic part|^2, averaged over the equations" in lines[1]


def test_identify_on_unforced_positions_exits_zero_for_the_law(hanging_spring, tmp_path,
                                                                capsys):
    """``pysindy-xl identify`` on free runs (positions only, no forces): the grown catalog
    holds the law and the honest exit passes it."""
    t, x, _, _ = hanging_spring
    path = write_csv(tmp_path / "free.csv", ["t", "x", "trajectory"],
                     [np.r_[t, t], np.vstack(x)[:, 0], np.repeat([0.0, 1.0], len(t))])
    assert main(["identify", str(path), "--coordinates", "x", "--quiet"]) == 0
    out = capsys.readouterr().out
    r2 = float(out.split("fit quality: R^2 = ")[1].split()[0])
    assert r2 > 0.999
    assert "|kinetic part|^2" in out and "implicit solver" in out
