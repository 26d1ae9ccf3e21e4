"""What the growth of an automatic catalog computes once and shares between its fits: the
smoothing of the data (one RememberedSmoother) and the catalogs' terms. Shared or not, the fits
are the same to the bit; the ground truth is a Duffing oscillator integrated by scipy."""

import pickle

import numpy as np
import pytest
from sklearn.base import clone
from support.growth import HARDENING, MASS, STIFFNESS, noisy_duffing

import pysindy_xl as px
from pysindy_xl.fit import RememberedSmoother, fit_smoother


def _catalog(degree):
    return px.AutomaticCatalog(["x"], kinds="linear", bounds=[(-2.0, 2.0)], degree=degree,
                               kinetic="constant")


def test_fits_sharing_a_remembered_smoother_are_bit_identical():
    x, t, u = noisy_duffing()
    shared = RememberedSmoother()
    assert fit_smoother(shared) is shared  # kept, not wrapped again
    template = px.XLSINDy(formulation="weak", smoother=shared)
    for degree in (2, 4, 4):
        plain = px.XLSINDy(_catalog(degree), formulation="weak").fit(x, t, u=u)
        reused = clone(template).set_params(feature_library=_catalog(degree)).fit(x, t, u=u)
        np.testing.assert_array_equal(reused.coefficients(), plain.coefficients())
    # the Duffing law (forces: m xdd + c xd + k x + h x^3), up to the noise
    names = reused.get_feature_names()
    coef = dict(zip(names, reused.coefficients(), strict=True))
    np.testing.assert_allclose(2 * coef["L[x_dot**2]"], MASS, rtol=0.05)
    np.testing.assert_allclose(-2 * coef["L[x**2]"], STIFFNESS, rtol=0.05)
    np.testing.assert_allclose(-4 * coef["L[x**4]"], HARDENING, rtol=0.1)
    assert len(shared._results) >= 2  # pieces and noise draws, each smoothed once


def test_catalog_terms_are_shared_by_clones_and_follow_the_parameters():
    catalog = _catalog(3)
    terms = [lib.terms for lib in catalog.libraries if hasattr(lib, "terms")]
    copy = clone(catalog)
    assert [lib.terms for lib in copy.libraries if hasattr(lib, "terms")] == terms
    assert copy.libraries[0] is not catalog.libraries[0]  # libraries of its own to fit
    catalog.set_params(degree=4)
    assert catalog.n_terms == copy.n_terms + 1
    grown = [lib.terms for lib in catalog.libraries if hasattr(lib, "terms")]
    assert sum(map(len, grown)) == sum(map(len, terms)) + 1
    assert px.AutomaticCatalog(**catalog.get_params()).lagrange_terms() == \
        catalog.lagrange_terms()
    pickle.loads(pickle.dumps(copy.fit()))


def test_held_out_rows_without_noise_propagation_are_the_same_rows():
    x, t, u = noisy_duffing()
    model = px.XLSINDy(_catalog(4), formulation="weak").fit(x[:3000], t[:3000], u=u[:3000])
    full = model.regression(x[3000:], t[3000:], u=u[3000:], formulation="weak")
    light = model.regression(x[3000:], t[3000:], u=u[3000:], formulation="weak",
                             propagate_noise=False)
    np.testing.assert_array_equal(light.theta, full.theta)
    assert full.row_noise is not None and light.row_noise is None
    # the held-out rows obey the fitted law: residual small against the forces' part
    coef = model.coef_[light.catalog_map.columns]
    forces = light.theta[:, light.force_columns] @ coef[light.force_columns]
    assert np.linalg.norm(light.theta @ coef) < 0.05 * np.linalg.norm(forces)
    with pytest.raises(TypeError, match="propagate_noise"):
        model.regression(x[3000:], t[3000:], u=u[3000:], propagate_noise="no")
