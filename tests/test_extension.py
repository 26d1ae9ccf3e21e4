"""A new catalog library and a new optimizer, written outside the package, used through XLSINDy.

Nothing here edits the package: the library (a Rayleigh dissipation function) and the
optimizer (least squares with the forces fixed, pruned by a relative threshold) register
themselves when defined, and fit, print, save, load and pickle like the built-in ones. The
optimizer declares its capabilities once (its ``catalog_tags``) and works, unchanged, inside
the ensemble and the physically consistent wrappers, which forward those tags.
Ground truth: a damped, forced Duffing oscillator integrated by scipy at tight tolerance.
"""

import dataclasses
import json
import pickle

import numpy as np
import pytest
import scipy.integrate
import sympy as sp

import pysindy_xl as px
from pysindy_xl.feature_library import LIBRARY_TYPES, SymbolicLibrary
from pysindy_xl.optimizers import OPTIMIZER_TYPES, CatalogOptimizer, CatalogTags, catalog_tags

MASS, DAMPING, STIFFNESS, HARDENING = 0.7, 0.15, 2.0, 0.5


class RayleighDissipation(SymbolicLibrary):
    """Candidate terms ``D_k(qd)`` of a Rayleigh dissipation function: each feature is the
    column ``dD_k/dqd_i`` of every coordinate's equation."""

    category = "rayleigh"

    def __init__(self, coords, terms):
        self.coords = coords
        self.terms = terms

    def _build_symbolic(self):
        terms = [sp.sympify(term) for term in self.terms]
        self.terms_ = terms
        matrix = sp.Matrix(self.coords.n, len(terms),
                           lambda i, k: sp.diff(terms[k], self.coords.qd[i]))
        return [f"D[{term}]" for term in terms], matrix

    def _feature_terms(self):
        return self.terms_

    def to_spec(self):
        from pysindy_xl.expressions import format_expression

        return {"type": self.spec_type, "terms": [format_expression(sp.sympify(term))
                                                  for term in self.terms]}

    @classmethod
    def from_spec(cls, spec, reader):
        return cls(reader.coords, reader.terms(spec))


class ThresholdedLeastSquares(CatalogOptimizer):
    """Least squares with the forces fixed to -1, dropping terms whose contribution is below
    ``threshold`` times the largest, refitted until the support settles; refits a given
    support (``_solve_support``)."""

    def catalog_tags(self):  # its capabilities, declared once: explicit regression
        return dataclasses.replace(super().catalog_tags(), requires_forces=True)

    def __init__(self, threshold=1e-3):
        self.threshold = threshold

    def _check_params(self):
        if not 0 <= self.threshold < 1:
            raise ValueError(f"threshold: expected a number in [0, 1), got {self.threshold}")

    def _solve(self, problem, support=None):
        theta, forces = problem.theta, problem.force_columns
        terms = np.setdiff1d(np.arange(problem.n_features), forces)
        if support is not None:
            terms = terms[support[terms]]
        rhs = theta[:, forces].sum(axis=1)
        while True:
            coef = np.linalg.lstsq(theta[:, terms], rhs, rcond=None)[0]
            size = np.abs(coef) * np.linalg.norm(theta[:, terms], axis=0)
            keep = size >= self.threshold * size.max()
            if keep.all() or support is not None:
                break
            terms = terms[keep]
        self.coef_ = np.zeros(problem.n_features)
        self.coef_[terms] = coef
        self.coef_[forces] = -1.0
        return self

    def _solve_support(self, problem, support):
        return self._solve(problem, support)


def _duffing(seed=0):
    """Positions, exact velocities and accelerations and forces of
    ``m x'' + c x' + k x + h x^3 = u`` (scipy, rtol 1e-11)."""
    rng = np.random.default_rng(seed)
    amplitudes, frequencies = rng.uniform(0.5, 1.5, 3), rng.uniform(0.3, 2.0, 3)

    def force(t):
        return np.sum(amplitudes[:, None] * np.sin(np.outer(frequencies, np.atleast_1d(t))),
                      axis=0)

    def rhs(t, state):
        x, v = state
        return [v, (force(t)[0] - DAMPING * v - STIFFNESS * x - HARDENING * x**3) / MASS]

    t = np.linspace(0, 20, 4001)
    solution = scipy.integrate.solve_ivp(rhs, (0, 20), [0.3, 0.0], t_eval=t, rtol=1e-11,
                                         atol=1e-12)
    x, v = solution.y
    u = force(t)
    a = (u - DAMPING * v - STIFFNESS * x - HARDENING * x**3) / MASS
    return t, x[:, None], v[:, None], a[:, None], u[:, None]


def _catalog():
    coords = px.Coordinates(["x"])
    q, qd = coords.q[0], coords.qd[0]
    return px.CatalogRepartition([
        px.LagrangeLibrary(coords, [qd**2, q**2, q**4, q**3]),
        RayleighDissipation(coords, [qd**2, qd**4]),
    ])


#: The true coefficients of the catalog: L = m/2 x'^2 - k/2 x^2 - h/4 x^4, D = c/2 x'^2; the
#: Euler-Lagrange operator gives m x'' + k x + h x^3 + c x' = u
EXPECTED = {"F[tau]": -1.0, "L[x_dot**2]": MASS / 2, "L[x**2]": -STIFFNESS / 2,
            "L[x**4]": -HARDENING / 4, "L[x**3]": 0.0, "D[x_dot**2]": DAMPING / 2,
            "D[x_dot**4]": 0.0}


@pytest.fixture(scope="module")
def fitted():
    t, x, v, a, u = _duffing()
    model = px.XLSINDy(_catalog(), ThresholdedLeastSquares()).fit(x, t, x_dot=v, x_ddot=a,
                                                                   u=u)
    return model, (t, x, v, a, u)


def test_the_new_types_registered_themselves():
    assert LIBRARY_TYPES[RayleighDissipation.spec_type] is RayleighDissipation
    assert OPTIMIZER_TYPES[ThresholdedLeastSquares.spec_type] is ThresholdedLeastSquares
    assert RayleighDissipation.spec_type.endswith("test_extension.RayleighDissipation")


def test_a_new_library_and_optimizer_identify_the_true_law(fitted, capsys):
    model, _ = fitted
    coef = dict(zip(model.get_feature_names(), model.coefficients(), strict=True))
    for name, value in EXPECTED.items():
        assert coef[name] == pytest.approx(value, rel=1e-6, abs=1e-9), name
    assert model.optimizer_.__class__ is ThresholdedLeastSquares
    model.print()
    printed = capsys.readouterr().out
    assert "0.7*x_ddot" in printed and "0.15*x_dot" in printed


def test_save_load_and_pickle_keep_the_model(fitted, tmp_path):
    model, (t, x, v, a, u) = fitted
    path = tmp_path / "duffing.json"
    model.save(path)
    document = json.loads(path.read_text())
    kinds = [spec["type"] for spec in document["feature_library"]["libraries"]]
    assert RayleighDissipation.spec_type in kinds
    assert document["optimizer"] == {"type": ThresholdedLeastSquares.spec_type,
                                     "params": {"threshold": 1e-3}}
    loaded = px.XLSINDy.load(path)
    np.testing.assert_array_equal(loaded.coefficients(), model.coefficients())
    assert isinstance(loaded.optimizer_, ThresholdedLeastSquares)
    np.testing.assert_array_equal(loaded.predict(x, v, u), model.predict(x, v, u))
    np.testing.assert_allclose(model.predict(x, v, u), a, rtol=1e-6, atol=1e-8)
    copy = pickle.loads(pickle.dumps(model))
    np.testing.assert_array_equal(copy.predict(x, v, u), model.predict(x, v, u))


def test_a_file_naming_an_unregistered_type_is_refused(fitted, tmp_path):
    model, _ = fitted
    path = tmp_path / "duffing.json"
    model.save(path)
    document = json.loads(path.read_text())
    document["feature_library"]["libraries"][-1]["type"] = "somewhere.Else"
    path.write_text(json.dumps(document))
    with pytest.raises(ValueError, match="unknown library type 'somewhere.Else'"):
        px.XLSINDy.load(path)
    document = json.loads(path.read_text())
    document["feature_library"]["libraries"][-1]["type"] = RayleighDissipation.spec_type
    document["optimizer"]["params"]["threshold"] = 2.0
    path.write_text(json.dumps(document))
    with pytest.raises(ValueError, match="optimizer: threshold: expected a number in"):
        px.XLSINDy.load(path)


def test_a_name_taken_by_another_class_is_refused():
    with pytest.raises(TypeError, match="spec_type: 'LagrangeLibrary' is already the name"):
        type("Impostor", (SymbolicLibrary,), {"spec_type": "LagrangeLibrary"})


def test_the_wrappers_forward_the_tags_declared_once():
    own = ThresholdedLeastSquares().catalog_tags()
    assert own == CatalogTags(requires_forces=True, can_refit=True)
    assert ThresholdedLeastSquares().requires_forces  # the tags answer as attributes too
    ensemble = catalog_tags(px.EnsembleOptimizer(ThresholdedLeastSquares()))
    assert ensemble == dataclasses.replace(own, can_refit=False, balances_rows=False)
    physical = catalog_tags(px.PhysicalOptimizer(ThresholdedLeastSquares()))
    assert physical == dataclasses.replace(own, balances_rows=False)


@pytest.mark.parametrize("wrapper", [
    lambda base: px.EnsembleOptimizer(base, n_models=6, fraction=0.6),
    lambda base: px.PhysicalOptimizer(base),
], ids=["ensemble", "physical"])
def test_the_new_optimizer_works_inside_the_wrappers_unchanged(wrapper):
    t, x, v, a, u = _duffing()
    model = px.XLSINDy(_catalog(), wrapper(ThresholdedLeastSquares())).fit(
        x, t, x_dot=v, x_ddot=a, u=u)
    coef = dict(zip(model.get_feature_names(), model.coefficients(), strict=True))
    for name, value in EXPECTED.items():
        assert coef[name] == pytest.approx(value, rel=1e-6, abs=1e-9), name
    if isinstance(model.optimizer_, px.EnsembleOptimizer):  # it refits: the tag said so
        assert model.optimizer_.aggregate_ == "refit"
        np.testing.assert_array_equal(model.inclusion_probability_ > 0.5,
                                      np.array(list(EXPECTED.values())) != 0)
    else:  # the selecting fit inside is the new optimizer's
        assert isinstance(model.optimizer_.optimizer_, ThresholdedLeastSquares)
    # its requires_forces reaches the estimator through the wrapper: unforced data refused
    with pytest.raises(ValueError, match="u: explicit regression needs the generalized"):
        px.XLSINDy(_catalog(), wrapper(ThresholdedLeastSquares())).fit(x, t, x_dot=v,
                                                                      x_ddot=a)


class _LegacyDeclared(CatalogOptimizer):
    """Capabilities as class attributes (before CatalogTags): they still declare the tags."""

    requires_forces = True
    derivative_estimate = "unbiased"

    def _solve(self, problem):  # pragma: no cover - never fitted here
        raise NotImplementedError


def test_tags_declared_as_class_attributes_still_count():
    tags = _LegacyDeclared().catalog_tags()
    assert tags.requires_forces and tags.derivative_estimate == "unbiased"
    assert catalog_tags(px.EnsembleOptimizer(_LegacyDeclared())).requires_forces
