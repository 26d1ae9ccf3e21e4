"""RestrictedOptimizer: another optimizer's fit on some of the catalog's columns.

Ground truth: a linear regression with known coefficients, and the forced Duffing oscillator
(scipy at 1e-10) whose law the restricted fit must recover from noisy positions.
"""

import json
import pickle
import warnings

import numpy as np
import pytest
from support.growth import DAMPING, HARDENING, MASS, STIFFNESS, noisy_duffing

import pysindy_xl as px
from pysindy_xl.optimizers import RestrictedOptimizer


def _regression(seed=0):
    """400 rows: column 0 the force, the law ``1, 0.5, 0.2`` on columns 1-3, column 4 noise."""
    rng = np.random.default_rng(seed)
    theta = rng.normal(size=(400, 5))
    theta[:, 0] = theta[:, 1:4] @ [1.0, 0.5, 0.2] + 1e-3 * rng.normal(size=400)
    return theta


def test_the_fit_leaves_out_the_columns_not_allowed_and_solves_the_others():
    theta = _regression()
    full = px.ExplicitOptimizer().fit_catalog(theta, 1, [0]).coef_
    restricted = RestrictedOptimizer(px.ExplicitOptimizer(), columns=[1, 2]).fit_catalog(
        theta, 1, [0])
    # the force column is always allowed; column 3 is left out, so the others absorb nothing
    # of it (they are independent): least squares on 1 and 2 gives the law's values
    assert (full != 0).tolist() == [True, True, True, True, False]
    assert (restricted.coef_ != 0).tolist() == [True, True, True, False, False]
    np.testing.assert_allclose(restricted.coef_[:3], [-1.0, 1.0, 0.5], atol=0.03)
    lstsq = np.linalg.lstsq(theta[:, 1:3], theta[:, 0], rcond=None)[0]
    np.testing.assert_allclose(restricted.coef_[1:3], lstsq, rtol=1e-8)
    # no columns: the wrapped optimizer alone
    np.testing.assert_array_equal(RestrictedOptimizer(px.ExplicitOptimizer()).fit_catalog(
        theta, 1, [0]).coef_, full)


def test_a_restricted_catalog_fit_finds_duffing_and_saves(tmp_path):
    x, t, u = noisy_duffing(noise=0.01)
    catalog = px.AutomaticCatalog(["x"], degree=4, kinetic="constant")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        free = px.XLSINDy(catalog).fit(x, t, u=u)
        names = free.get_feature_names()
        law = ["L[x_dot**2]", "L[x**2]", "L[x**4]", "C_x[x_dot]"]
        allowed = [names.index(name) for name in law]
        model = px.XLSINDy(catalog, optimizer=RestrictedOptimizer(
            px.EnsembleOptimizer(px.ExplicitOptimizer(), n_models=8), columns=allowed)
        ).fit(x, t, u=u)
    coef = dict(zip(names, model.coefficients(), strict=True))
    assert {name for name, value in coef.items() if value != 0} <= {*law, "F[tau]"}
    # m x_dd + c x_d + k x + h x^3 = u, from L = m/2 x_d^2 - k/2 x^2 - h/4 x^4 and c x_d
    scale = 2 * coef["L[x_dot**2]"] / MASS
    np.testing.assert_allclose(np.array([coef["L[x**2]"], coef["L[x**4]"], coef["C_x[x_dot]"]])
                               / scale, [-STIFFNESS / 2, -HARDENING / 4, DAMPING], rtol=0.05)
    # an ensemble's per-column figures are spread over the catalog's columns
    assert model.inclusion_probability_.shape == (len(names),)
    assert np.all(model.inclusion_probability_[[j for j, name in enumerate(names)
                                                if name not in (*law, "F[tau]")]] == 0)
    # it pickles, and saves to JSON and loads with its coefficients
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(model)).coefficients(),
                                  model.coefficients())
    path = tmp_path / "restricted.json"
    model.save(path)
    loaded = px.XLSINDy.load(path)
    assert type(loaded.optimizer).__name__ == "RestrictedOptimizer"
    np.testing.assert_array_equal(loaded.coefficients(), model.coefficients())
    # the allowed columns are in the file: a refit of the loaded model is restricted too
    assert loaded.optimizer.columns == allowed
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        np.testing.assert_array_equal(loaded.fit(x, t, u=u).coefficients(),
                                      model.coefficients())


@pytest.mark.parametrize("columns", [[-1], [0.5], ["a"], [[1, 2]], [True]])
def test_bad_columns_are_named(columns):
    with pytest.raises(ValueError, match="columns"):
        RestrictedOptimizer(px.ExplicitOptimizer(), columns=columns).fit_catalog(
            _regression(), 1, [0])


def test_lists_of_columns_round_trip_through_a_spec_and_bad_ones_are_named():
    from pysindy_xl.optimizers import GroupedOptimizer
    from pysindy_xl.optimizers._base import optimizer_from_spec

    restricted = RestrictedOptimizer(px.ExplicitOptimizer(), columns=np.array([3, 1, 4]))
    grouped = GroupedOptimizer(restricted, groups=[[1, 2], (5, np.int64(6))])
    spec = grouped.to_spec()
    assert spec["params"]["groups"] == [[1, 2], [5, 6]]
    assert spec["params"]["optimizer"]["params"]["columns"] == [3, 1, 4]
    loaded = optimizer_from_spec(json.loads(json.dumps(spec)))
    assert loaded.groups == [[1, 2], [5, 6]] and loaded.optimizer.columns == [3, 1, 4]
    for columns, message in (([[[1]]], "list"), ([-1], "columns"), ([1.5], "columns"),
                             ({"a": 1}, "optimizer")):
        with pytest.raises(ValueError, match=message):
            optimizer_from_spec({"type": "RestrictedOptimizer", "params": {"columns": columns}})
    with pytest.raises(ValueError, match="groups"):
        optimizer_from_spec({"type": "GroupedOptimizer", "params": {"groups": [[-1]]}})


def test_without_selection_every_allowed_column_is_refitted_on_every_row():
    # the selection's threshold drops column 3 (0.2) among 1-3; without selection the allowed
    # columns are least squares on every row, whatever the threshold
    theta = _regression()
    strict = px.ExplicitOptimizer(threshold=0.3)
    selected = RestrictedOptimizer(strict, columns=[1, 2, 3]).fit_catalog(theta, 1, [0])
    assert (selected.coef_ != 0).tolist() == [True, True, True, False, False]
    given = RestrictedOptimizer(strict, columns=[1, 2, 3], select=False).fit_catalog(
        theta, 1, [0])
    assert (given.coef_ != 0).tolist() == [True, True, True, True, False]
    lstsq = np.linalg.lstsq(theta[:, 1:4], theta[:, 0], rcond=None)[0]
    np.testing.assert_allclose(given.coef_[1:4], lstsq, rtol=1e-8)
    np.testing.assert_allclose(given.coef_[:4], [-1.0, 1.0, 0.5, 0.2], atol=0.01)
    # an ensemble refits with the single fit it bags
    bagged = RestrictedOptimizer(px.EnsembleOptimizer(strict), columns=[1, 2, 3],
                                 select=False).fit_catalog(theta, 1, [0])
    np.testing.assert_allclose(bagged.coef_, given.coef_, rtol=1e-10)


def test_without_selection_an_optimizer_that_cannot_refit_is_named():
    class NoRefit(px.ExplicitOptimizer):
        def catalog_tags(self):
            import dataclasses
            return dataclasses.replace(super().catalog_tags(), can_refit=False)

        def pilot(self):
            return self

    with pytest.raises(TypeError, match="optimizer: NoRefit cannot refit a given support"):
        RestrictedOptimizer(NoRefit(), columns=[1], select=False).fit_catalog(
            _regression(), 1, [0])
    with pytest.raises((TypeError, ValueError), match="select"):
        RestrictedOptimizer(px.ExplicitOptimizer(), select="no").fit_catalog(
            _regression(), 1, [0])
