"""Feature libraries: symbolic columns against sympy.physics.mechanics, numeric layout, catalogs.

The Euler-Lagrange columns are checked against :class:`sympy.physics.mechanics.LagrangesMethod`
applied to each candidate term on its own (an implementation that shares nothing with
:func:`pysindy_xl.feature_library.euler_lagrange`), and ``transform`` against a per-entry
``sympy.lambdify`` of ``symbolic_matrix()``.
"""

import copy

import numpy as np
import pysindy as ps
import pytest
import sympy as sp
from sklearn.base import clone
from sklearn.exceptions import NotFittedError
from sympy.physics import mechanics as me

import pysindy_xl as px
from pysindy_xl.feature_library import stack_variables

# --------------------------------------------------------------------------------------------
# independent Euler-Lagrange operator
# --------------------------------------------------------------------------------------------


def lagranges_method_columns(term, coords):
    """Euler-Lagrange expressions of ``term`` by sympy.physics.mechanics.LagrangesMethod.

    The term is rewritten in dynamic symbols q(t), LagrangesMethod forms the equations
    ``d/dt dL/dqd - dL/dq`` and the result is mapped back to the plain coordinate symbols.
    """
    time = me.dynamicsymbols._t
    q = me.dynamicsymbols(" ".join(f"lm_{name}" for name in coords.names), seq=True)
    qd = [qi.diff(time) for qi in q]
    qdd = [qi.diff(time, 2) for qi in q]
    forward = {**dict(zip(coords.q, q, strict=True)), **dict(zip(coords.qd, qd, strict=True)),
               coords.t: time}
    lagrangian = sp.sympify(term).xreplace(forward)
    method = me.LagrangesMethod(lagrangian, q)
    eom = method.form_lagranges_equations()
    # derivative nodes are matched before the q(t) they contain
    back = {**dict(zip(qdd, coords.qdd, strict=True)), **dict(zip(qd, coords.qd, strict=True)),
            **dict(zip(q, coords.q, strict=True))}
    return [sp.expand(e.xreplace(back).xreplace({time: coords.t})) for e in eom]


def assert_columns_match_lagranges_method(library, coords):
    matrix = library.fit().symbolic_matrix()
    assert matrix.shape == (coords.n, len(library.terms))
    for j, term in enumerate(library.terms):
        expected = lagranges_method_columns(term, coords)
        for i in range(coords.n):
            assert sp.expand(matrix[i, j] - expected[i]) == 0, (
                f"term {term}, equation {coords.names[i]}: {matrix[i, j]} != {expected[i]}"
            )


def test_euler_lagrange_columns_of_simple_pendulum():
    coords = px.Coordinates(["theta"])
    (th,), (thd,) = coords.q, coords.qd
    terms = [
        thd**2, sp.cos(th), thd**2 * sp.cos(th), sp.sin(th) ** 2 * thd**2, th * thd**3,
        sp.exp(th) * thd**2, sp.sqrt(1 + thd**2), thd**2 * coords.t, sp.tan(th) * thd**2,
        2**thd, sp.cos(2 * th) * thd**4, th**3 * sp.sin(th), thd * sp.sin(th),
    ]
    library = px.LagrangeLibrary(coords, terms)
    assert_columns_match_lagranges_method(library, coords)
    # spot check against the textbook pendulum: L = thd^2/2 + cos(th) -> th_ddot + sin(th)
    names = library.get_feature_names()
    assert names[:2] == ["L[theta_dot**2]", "L[cos(theta)]"]
    assert library.symbolic_matrix()[0, 0] == 2 * coords.qdd[0]
    assert library.symbolic_matrix()[0, 1] == sp.sin(th)


def test_euler_lagrange_columns_of_two_dof_catalog():
    coords = px.Coordinates(["a", "b"])
    (a, b), (ad, bd) = coords.q, coords.qd
    # a representative part of a product catalog (the whole one costs LagrangesMethod ~10 s)
    trig = [sp.sin(a), sp.cos(b), sp.cos(a) * sp.cos(b), sp.sin(a) * sp.sin(b), sp.sin(b) ** 2]
    terms = px.products([1, *trig], [1, ad, bd**2, ad * bd])[1:]
    terms += [sp.cos(a - b) * ad * bd, a * bd**2, sp.exp(-b) * ad**2 * bd]
    library = px.LagrangeLibrary(coords, terms)
    assert_columns_match_lagranges_method(library, coords)


def test_lagrangian_of_double_pendulum_gives_ground_truth_equations(double_pendulum_system):
    """E @ xi with the true Lagrangian expanded in a catalog equals M qdd - f (LagrangesMethod
    with particles and gravity, in ground_truth.py), here without friction."""
    system = double_pendulum_system
    coords = system.coords
    trig = [f(q) for q in coords.q for f in (sp.sin, sp.cos)]
    terms = px.products([1, *px.monomials(trig, 2)], [1, *px.monomials(coords.qd, 2)])[1:]
    library = px.CatalogRepartition([px.LagrangeLibrary(coords, terms)])
    xi = library.ideal_coefficients(lagrangian=system.lagrangian)
    rng = np.random.default_rng(0)
    q, qd = rng.uniform(-2, 2, (50, 2)), rng.uniform(-2, 2, (50, 2))
    qdd, tau = rng.normal(size=(50, 2)), rng.normal(size=(50, 2))
    theta = library.transform(stack_variables(q, qd, qdd, tau))
    residual = (theta @ xi).reshape(2, 50).T  # EL(L) - tau, per coordinate
    frictionless = system.with_friction([0.0, 0.0])
    mass = frictionless.mass_matrix(q)
    forcing = np.einsum("kij,kj->ki", mass, frictionless.accelerations(q, qd, tau))
    expected = np.einsum("kij,kj->ki", mass, qdd) - forcing
    np.testing.assert_allclose(residual, expected, rtol=1e-9, atol=1e-9)


def test_zero_columns_are_reported():
    coords = px.Coordinates(["x", "theta"])
    (x, th), (xd, thd) = coords.q, coords.qd
    terms = [
        sp.Integer(1),             # constant
        thd * sp.cos(th),          # total derivative of sin(theta)
        xd * x,                    # d/dt x^2/2
        xd * th + thd * x,         # d/dt (x theta)
        coords.t,                  # function of time only
        xd * sp.cos(th),           # NOT a total derivative
        thd**2,
        xd * th,                   # NOT a total derivative alone
    ]
    library = px.LagrangeLibrary(coords, terms).fit()
    assert library.zero_terms_ == [0, 1, 2, 3, 4]
    rng = np.random.default_rng(1)
    z = rng.normal(size=(30, 4 * 2 + 1))
    theta = library.transform(z)
    assert np.all(theta[:, :5] == 0)
    assert np.all(np.linalg.norm(theta[:, 5:], axis=0) > 0)


@pytest.mark.filterwarnings("ignore::numpy.exceptions.ComplexWarning")
@pytest.mark.parametrize("kind", ["lagrange", "classical"])
def test_complex_terms_refused(kind):
    coords = px.Coordinates(["x"])
    term = sp.I * coords.qd[0] ** 2
    with pytest.raises(ValueError, match="terms"):
        if kind == "lagrange":
            px.LagrangeLibrary(coords, [term]).fit().transform(np.ones((2, 5)))
        else:
            px.ClassicalLibrary(coords, [term]).fit().transform(np.ones((2, 5)))


def test_lagrange_terms_must_be_state_functions():
    coords = px.Coordinates(["x"])
    with pytest.raises(ValueError, match="terms.*x_ddot"):
        px.LagrangeLibrary(coords, [coords.qdd[0] * coords.q[0]]).fit()
    with pytest.raises(ValueError, match="terms.*tau_x"):
        px.LagrangeLibrary(coords, [coords.tau[0]]).fit()
    with pytest.raises(ValueError, match="terms.*y"):
        px.LagrangeLibrary(coords, [sp.Symbol("y")]).fit()
    with pytest.raises(ValueError, match="terms"):
        px.LagrangeLibrary(coords, []).fit()
    with pytest.raises(TypeError, match="terms"):
        px.LagrangeLibrary(coords, ["x_dot**2"]).fit()
    with pytest.raises(TypeError, match="coords"):
        px.LagrangeLibrary(["x"], [coords.qd[0] ** 2]).fit()


# --------------------------------------------------------------------------------------------
# numeric transform
# --------------------------------------------------------------------------------------------


def _mixed_catalog(coords):
    (x, th), (xd, thd), xdd = coords.q, coords.qd, coords.qdd[0]
    forces = px.ExternalForces(coords, interlink=[[1.0, -0.5], [0.0, 2.0]])
    lagrange = px.LagrangeLibrary(coords, [xd**2, thd**2, sp.cos(th), xd * thd * sp.cos(th),
                                           thd * sp.cos(th)])
    classical = px.ClassicalLibrary(
        coords,
        [xd, thd * sp.Abs(thd), sp.Integer(1), xdd * sp.sin(th), coords.t * x, coords.tau[1]],
        mask=[[1, 0], [0, 1], [1, 1], [0, 1], [1, 0], [1, 1]],
    )
    return px.CatalogRepartition([forces, lagrange, classical])


def test_transform_equals_lambdify_of_symbolic_matrix():
    coords = px.Coordinates(["x", "theta"])
    library = _mixed_catalog(coords).fit()
    rng = np.random.default_rng(2)
    n_samples = 40
    z = rng.uniform(-2, 2, size=(n_samples, 4 * coords.n + 1))
    theta = library.transform(z)
    matrix = library.symbolic_matrix()
    assert theta.shape == (coords.n * n_samples, library.n_output_features_)
    assert matrix.shape == (coords.n, library.n_output_features_)
    for c in range(coords.n):
        for j in range(matrix.shape[1]):
            f = sp.lambdify(coords.variables, matrix[c, j], "numpy")
            expected = np.broadcast_to(f(*z.T), (n_samples,))
            np.testing.assert_allclose(
                theta[c * n_samples:(c + 1) * n_samples, j], expected, rtol=1e-12, atol=1e-12,
                err_msg=f"entry ({c}, {j}) = {matrix[c, j]}",
            )


def test_layout_is_coordinate_major():
    coords = px.Coordinates(["x", "theta"])
    x, th = coords.q
    # x enters only the equation of theta, theta_dot only the equation of x
    library = px.ClassicalLibrary(coords, [x, coords.qd[1]], mask=[[0, 1], [1, 0]]).fit()
    assert library.get_feature_names() == ["C_theta[x]", "C_x[theta_dot]"]
    q = np.array([[1.0, 10.0], [2.0, 20.0], [3.0, 30.0]])
    qd = np.array([[0.1, 0.01], [0.2, 0.02], [0.3, 0.03]])
    theta = library.transform(stack_variables(q, qd))
    expected = np.array([
        [0.0, 0.01], [0.0, 0.02], [0.0, 0.03],  # equation of x, samples 0..2
        [1.0, 0.0], [2.0, 0.0], [3.0, 0.0],     # equation of theta, samples 0..2
    ])
    np.testing.assert_array_equal(theta, expected)


def test_stack_variables_order_and_checks():
    q, qd = np.arange(6.0).reshape(3, 2), 10 + np.arange(6.0).reshape(3, 2)
    qdd, tau, t = 20 + np.arange(6.0).reshape(3, 2), 30 + np.arange(6.0).reshape(3, 2), [0, 1, 2]
    z = stack_variables(q, qd, qdd, tau, t)
    np.testing.assert_array_equal(z, np.column_stack([q, qd, qdd, tau, t]))
    np.testing.assert_array_equal(stack_variables(q, qd),
                                  np.column_stack([q, qd, np.zeros((3, 5))]))
    with pytest.raises(ValueError, match="qd"):
        stack_variables(q, qd[:2])
    with pytest.raises(ValueError, match="tau"):
        stack_variables(q, qd, tau=np.zeros((3, 3)))
    with pytest.raises(ValueError, match="t"):
        stack_variables(q, qd, t=[0, 1])
    with pytest.raises(ValueError, match="q"):
        stack_variables(np.zeros(3), np.zeros(3))


def test_transform_input_checks():
    coords = px.Coordinates(["x"])
    library = px.LagrangeLibrary(coords, [coords.qd[0] ** 2])
    with pytest.raises(NotFittedError):
        library.transform(np.zeros((3, 5)))
    library.fit()
    with pytest.raises(ValueError, match=r"x: expected .*\(n_samples, 5\)"):
        library.transform(np.zeros((3, 4)))
    with pytest.raises(ValueError, match="x: expected"):
        library.transform(np.zeros(5))
    z = np.zeros((3, 5))
    z[1, 2] = np.nan
    with pytest.raises(ValueError, match="x: contains NaN"):
        library.transform(z)
    z[1, 2] = np.inf
    with pytest.raises(ValueError, match="x: contains NaN"):
        library.transform(z)
    with pytest.raises(ValueError, match="x: expected"):
        library.fit(np.zeros((3, 7)))


# --------------------------------------------------------------------------------------------
# ClassicalLibrary
# --------------------------------------------------------------------------------------------


def test_classical_library_mask_and_names():
    coords = px.Coordinates(["x", "theta"])
    x, th = coords.q
    library = px.ClassicalLibrary(coords, [coords.qd[0], sp.sin(th)],
                                  mask=np.array([[True, False], [True, True]])).fit()
    assert library.get_feature_names() == ["C_x[x_dot]", "C_x[sin(theta)]",
                                           "C_theta[sin(theta)]"]
    assert library.symbolic_matrix() == sp.Matrix([[coords.qd[0], sp.sin(th), 0],
                                                   [0, 0, sp.sin(th)]])
    default = px.ClassicalLibrary(coords, [x]).fit()
    assert default.get_feature_names() == ["C_x[x]", "C_theta[x]"]
    np.testing.assert_array_equal(default.mask_, np.ones((1, 2), dtype=bool))


@pytest.mark.parametrize(
    "mask, match",
    [
        (np.ones((2, 2)), r"mask: expected shape"),
        (np.ones(2), r"mask: expected shape"),
        (np.ones((1, 3)), r"mask: expected shape"),
        (np.array([[0.5, 1.0]]), r"mask: expected booleans"),
        (np.array([[2, 0]]), r"mask: expected booleans"),
    ],
)
def test_classical_library_bad_mask(mask, match):
    coords = px.Coordinates(["x", "theta"])
    with pytest.raises(ValueError, match=match):
        px.ClassicalLibrary(coords, [coords.q[0]], mask=mask).fit()


def test_classical_library_bad_terms():
    coords = px.Coordinates(["x"])
    with pytest.raises(ValueError, match="terms.*unknown symbols.*y"):
        px.ClassicalLibrary(coords, [sp.Symbol("y")]).fit()
    with pytest.raises(ValueError, match="terms"):
        px.ClassicalLibrary(coords, []).fit()


def _check_pysindy_wrapping(ps_library, coords, expected_terms=None):
    library = px.ClassicalLibrary(coords, ps_library).fit()
    rng = np.random.default_rng(5)
    n_samples = 25
    q, qd = rng.uniform(-2, 2, (n_samples, coords.n)), rng.uniform(-2, 2, (n_samples, coords.n))
    reference = copy.deepcopy(ps_library).fit(np.hstack([q, qd])).transform(np.hstack([q, qd]))
    n_terms = reference.shape[1]
    if expected_terms is not None:
        assert library.terms_ == expected_terms
    assert len(library.terms_) == n_terms
    theta = library.transform(stack_variables(q, qd))
    assert theta.shape == (coords.n * n_samples, n_terms * coords.n)
    # feature (k, c) is column k * n + c (all equations per term, default mask)
    for k in range(n_terms):
        for c in range(coords.n):
            block = theta[c * n_samples:(c + 1) * n_samples, k * coords.n + c]
            np.testing.assert_allclose(block, reference[:, k], rtol=1e-12, atol=1e-12)
            other = 1 - c
            assert np.all(theta[other * n_samples:(other + 1) * n_samples, k * coords.n + c] == 0)


def test_classical_library_wraps_pysindy_polynomial_library():
    coords = px.Coordinates(["x", "theta"])
    (x, th), (xd, thd) = coords.q, coords.qd
    expected = [sp.Integer(1), x, th, xd, thd, x**2, x * th, x * xd, x * thd, th**2, th * xd,
                th * thd, xd**2, xd * thd, thd**2]
    _check_pysindy_wrapping(ps.PolynomialLibrary(degree=2), coords, expected)


def test_classical_library_wraps_pysindy_fourier_library():
    coords = px.Coordinates(["x", "theta"])
    x = coords.q[0]
    library = px.ClassicalLibrary(coords, ps.FourierLibrary(n_frequencies=2)).fit()
    assert library.terms_[:2] == [sp.sin(x), sp.cos(x)]
    assert sp.sin(2 * x) in library.terms_
    _check_pysindy_wrapping(ps.FourierLibrary(n_frequencies=2), coords)


class _LyingPolynomialLibrary(ps.PolynomialLibrary):
    """Polynomial names, exponential features: names that do not describe the features."""

    def transform(self, x):
        return np.exp(np.asarray(super().transform(x)))


def test_pysindy_library_whose_names_lie_is_refused():
    coords = px.Coordinates(["x", "theta"])
    with pytest.raises(ValueError, match="terms: the feature names of _LyingPolynomialLibrary "
                                         "do not describe"):
        px.ClassicalLibrary(coords, _LyingPolynomialLibrary(degree=2)).fit()


def test_custom_library_with_faithful_names_is_accepted():
    coords = px.Coordinates(["x", "theta"])
    custom = ps.CustomLibrary([lambda a: np.sin(a) ** 2],
                              function_names=[lambda a: f"sin({a})^2"])
    _check_pysindy_wrapping(custom, coords,
                            [sp.sin(s) ** 2 for s in coords.state])


def test_custom_library_with_opaque_names_is_refused():
    coords = px.Coordinates(["x", "theta"])
    opaque = ps.CustomLibrary([lambda a: a**3])  # names "f0(x)": not in the grammar
    with pytest.raises(ValueError, match="terms: cannot translate feature 'f0\\(x\\)'"):
        px.ClassicalLibrary(coords, opaque).fit()


def test_custom_library_whose_names_lie_is_refused():
    coords = px.Coordinates(["x", "theta"])
    lying = ps.CustomLibrary([lambda a: np.exp(a)], function_names=[lambda a: f"sin({a})"])
    with pytest.raises(ValueError, match="terms: the feature names .* do not describe"):
        px.ClassicalLibrary(coords, lying).fit()


# --------------------------------------------------------------------------------------------
# ExternalForces
# --------------------------------------------------------------------------------------------


def test_external_forces_default():
    coords = px.Coordinates(["x", "theta"])
    forces = px.ExternalForces(coords).fit()
    assert forces.get_feature_names() == ["F[tau]"]
    assert forces.symbolic_matrix() == sp.Matrix([[coords.tau[0]], [coords.tau[1]]])
    np.testing.assert_array_equal(forces.interlink_, np.eye(2))
    tau = np.array([[1.0, 2.0], [3.0, 4.0]])
    theta = forces.transform(stack_variables(np.zeros((2, 2)), np.zeros((2, 2)), tau=tau))
    np.testing.assert_array_equal(theta[:, 0], [1.0, 3.0, 2.0, 4.0])


def test_external_forces_interlink_matrix():
    coords = px.Coordinates(["a", "b", "c"])
    interlink = np.array([[1.0, -1.0, 0.0], [0.0, 1.0, 0.5], [0.0, 0.0, 2.0]])
    forces = px.ExternalForces(coords, interlink=interlink).fit()
    ta, tb, tc = coords.tau
    assert sp.expand(forces.symbolic_matrix()[0, 0] - (ta - tb)) == 0
    assert sp.expand(forces.symbolic_matrix()[1, 0] - (tb + tc / 2)) == 0
    assert sp.expand(forces.symbolic_matrix()[2, 0] - 2 * tc) == 0
    rng = np.random.default_rng(7)
    tau = rng.normal(size=(10, 3))
    theta = forces.transform(stack_variables(np.zeros((10, 3)), np.zeros((10, 3)), tau=tau))
    np.testing.assert_allclose(theta[:, 0], (tau @ interlink.T).T.reshape(-1), rtol=1e-14)


def test_external_forces_from_signed_indices():
    coords = px.Coordinates(["a", "b"])
    forces = px.ExternalForces.from_signed_indices(coords, [[1, -2], [2]])
    np.testing.assert_array_equal(forces.interlink, [[1.0, -1.0], [0.0, 1.0]])
    forces.fit()
    ta, tb = coords.tau
    assert forces.symbolic_matrix() == sp.Matrix([[ta - tb], [tb]])
    empty = px.ExternalForces.from_signed_indices(coords, [[], [1]])
    np.testing.assert_array_equal(empty.interlink, [[0.0, 0.0], [1.0, 0.0]])


@pytest.mark.parametrize("indices", [[[1]], [[1], [3]], [[0], [1]], [[1.0], [2]], "12",
                                     [[1], [-3]]])
def test_external_forces_bad_signed_indices(indices):
    coords = px.Coordinates(["a", "b"])
    with pytest.raises(ValueError, match="indices"):
        px.ExternalForces.from_signed_indices(coords, indices)


@pytest.mark.parametrize("interlink, match",
                         [(np.eye(3), "interlink: expected a matrix of shape"),
                          (np.ones(2), "interlink: expected a matrix of shape"),
                          ([[1, np.nan], [0, 1]], "interlink: contains NaN"),
                          ([[1, "a"], [0, 1]], "interlink: expected a numeric matrix"),
                          ([[1], [2, 3]], "interlink")])
def test_external_forces_bad_interlink(interlink, match):
    coords = px.Coordinates(["a", "b"])
    with pytest.raises(ValueError, match=match):
        px.ExternalForces(coords, interlink=interlink).fit()


# --------------------------------------------------------------------------------------------
# CatalogRepartition
# --------------------------------------------------------------------------------------------


def test_repartition_adds_forces_when_absent():
    coords = px.Coordinates(["x", "theta"])
    lagrange = px.LagrangeLibrary(coords, [coords.qd[0] ** 2, sp.cos(coords.q[1])])
    friction = px.ClassicalLibrary(coords, coords.qd, mask=np.eye(2, dtype=bool))
    library = px.CatalogRepartition([lagrange, friction]).fit()
    assert library.get_feature_names() == ["F[tau]", "L[x_dot**2]", "L[cos(theta)]",
                                           "C_x[x_dot]", "C_theta[theta_dot]"]
    assert library.force_columns_ == [0]
    assert library.slices_ == [slice(0, 1), slice(1, 3), slice(3, 5)]
    assert library.categories_ == ["forces", "lagrange", "lagrange", "classical", "classical"]
    assert isinstance(library.libraries_[0], px.ExternalForces)
    # the given list is left untouched
    assert library.libraries == [lagrange, friction]


def test_repartition_keeps_given_forces_in_place():
    coords = px.Coordinates(["x", "theta"])
    lagrange = px.LagrangeLibrary(coords, [coords.qd[0] ** 2])
    forces = px.ExternalForces(coords, interlink=[[1, 0], [1, 1]])
    library = px.CatalogRepartition([lagrange, forces]).fit()
    assert library.get_feature_names() == ["L[x_dot**2]", "F[tau]"]
    assert library.force_columns_ == [1]
    assert library.slices_ == [slice(0, 1), slice(1, 2)]
    assert library.libraries_[1] is forces


def test_repartition_matrix_is_concatenation_of_blocks():
    coords = px.Coordinates(["x", "theta"])
    library = _mixed_catalog(coords).fit()
    z = np.random.default_rng(11).normal(size=(15, 9))
    for lib, sl in zip(library.libraries_, library.slices_, strict=True):
        assert library.symbolic_matrix()[:, sl] == lib.symbolic_matrix()
        np.testing.assert_array_equal(library.transform(z)[:, sl], clone(lib).fit().transform(z))


def test_sub_libraries_transform_after_catalog_fit():
    coords = px.Coordinates(["x"])
    lagrange = px.LagrangeLibrary(coords, [coords.qd[0] ** 2])
    px.CatalogRepartition([lagrange]).fit()
    z = np.random.default_rng(0).normal(size=(4, 5))
    np.testing.assert_allclose(lagrange.transform(z)[:, 0], 2 * z[:, 2])


def test_plus_operator_builds_flat_catalogs():
    coords = px.Coordinates(["x"])
    lagrange = px.LagrangeLibrary(coords, [coords.qd[0] ** 2, coords.q[0] ** 2])
    friction = px.ClassicalLibrary(coords, [coords.qd[0]])
    cubic = px.ClassicalLibrary(coords, [coords.q[0] ** 3])
    combined = lagrange + friction
    assert isinstance(combined, px.CatalogRepartition)
    assert combined.fit().get_feature_names() == ["F[tau]", "L[x_dot**2]", "L[x**2]",
                                                  "C_x[x_dot]"]
    three = lagrange + friction + cubic
    assert three.fit().get_feature_names()[-1] == "C_x[x**3]"
    assert len(three.libraries_) == 4 and three.force_columns_ == [0]
    with_forces = px.ExternalForces(coords) + lagrange
    assert with_forces.fit().get_feature_names() == ["F[tau]", "L[x_dot**2]", "L[x**2]"]
    nested = px.CatalogRepartition([combined, cubic]).fit()
    assert nested.get_feature_names() == three.get_feature_names()


def test_repartition_errors():
    a, b = px.Coordinates(["x"]), px.Coordinates(["y"])
    lag_a = px.LagrangeLibrary(a, [a.qd[0] ** 2])
    lag_b = px.LagrangeLibrary(b, [b.qd[0] ** 2])
    with pytest.raises(ValueError, match="libraries: all libraries must share"):
        px.CatalogRepartition([lag_a, lag_b]).fit()
    with pytest.raises(TypeError, match="libraries.*PolynomialLibrary"):
        px.CatalogRepartition([lag_a, ps.PolynomialLibrary()]).fit()
    with pytest.raises(TypeError, match="libraries"):
        px.CatalogRepartition(lag_a).fit()
    with pytest.raises(ValueError, match="libraries"):
        px.CatalogRepartition([]).fit()


def _double_pendulum_catalog():
    coords = px.Coordinates(["a", "b"])
    trig = [f(q) for q in coords.q for f in (sp.sin, sp.cos)]
    terms = px.products([1, *px.monomials(trig, 2)], [1, *px.monomials(coords.qd, 2)])[1:]
    friction = px.ClassicalLibrary(coords, coords.qd, mask=np.eye(2, dtype=bool))
    return coords, px.CatalogRepartition([px.LagrangeLibrary(coords, terms), friction])


def test_ideal_coefficients_expand_cos_of_differences():
    coords, library = _double_pendulum_catalog()
    (a, b), (ad, bd) = coords.q, coords.qd
    # L = ad^2 + 1/2 bd^2 + 1/2 ad bd cos(a - b) + 2 cos(a) + cos(b)
    lagrangian = (ad**2 + sp.Rational(1, 2) * bd**2 + sp.Rational(1, 2) * ad * bd * sp.cos(a - b)
                  + 2 * sp.cos(a) + sp.cos(b) + 7)  # the constant is ignored
    xi = library.fit().ideal_coefficients(
        lagrangian=lagrangian, classical={(ad, 0): 0.2, (bd, "b"): 0.3})
    names = library.get_feature_names()
    expected = {
        "F[tau]": -1.0, "L[a_dot**2]": 1.0, "L[b_dot**2]": 0.5,
        "L[a_dot*b_dot*cos(a)*cos(b)]": 0.5, "L[a_dot*b_dot*sin(a)*sin(b)]": 0.5,
        "L[cos(a)]": 2.0, "L[cos(b)]": 1.0, "C_a[a_dot]": 0.2, "C_b[b_dot]": 0.3,
    }
    assert set(expected) <= set(names)
    got = {name: value for name, value in zip(names, xi, strict=True) if value != 0}
    assert got.keys() == expected.keys()
    for name, value in expected.items():
        assert got[name] == pytest.approx(value, rel=1e-12)
    # the Euler-Lagrange equations of the expansion equal those of the original Lagrangian
    matrix = library.symbolic_matrix()
    for i, el in enumerate(lagranges_method_columns(lagrangian, coords)):
        model = sum(sp.nsimplify(xi[j]) * matrix[i, j] for j in np.flatnonzero(xi))
        friction = [sp.Rational(1, 5) * ad, sp.Rational(3, 10) * bd][i]
        assert sp.simplify(model - (el + friction - coords.tau[i])) == 0


def test_ideal_coefficients_classical_keys_and_forces():
    coords, library = _double_pendulum_catalog()
    ad = coords.qd[0]
    library.fit()
    by_index = library.ideal_coefficients(classical={(ad, 0): 0.4})
    by_name = library.ideal_coefficients(classical={(ad, "a"): 0.4})
    by_feature = library.ideal_coefficients(classical={"C_a[a_dot]": 0.4})
    np.testing.assert_array_equal(by_index, by_name)
    np.testing.assert_array_equal(by_index, by_feature)
    j = library.get_feature_names().index("C_a[a_dot]")
    assert by_index[j] == 0.4 and by_index[0] == -1.0
    assert np.count_nonzero(by_index) == 2
    assert library.ideal_coefficients(forces=2.5)[0] == 2.5
    with pytest.raises(ValueError, match="classical: term a_dot in the equation of b"):
        library.ideal_coefficients(classical={(ad, 1): 1.0})
    with pytest.raises(ValueError, match="classical: unknown feature name"):
        library.ideal_coefficients(classical={"C_a[b_dot]": 1.0})
    with pytest.raises(ValueError, match="classical: unknown coordinate"):
        library.ideal_coefficients(classical={(ad, "c"): 1.0})
    with pytest.raises(ValueError, match="classical: expected keys"):
        library.ideal_coefficients(classical={3: 1.0})


def test_ideal_coefficients_refuse_unrepresentable_lagrangian():
    coords, library = _double_pendulum_catalog()
    a, ad = coords.q[0], coords.qd[0]
    with pytest.raises(ValueError, match="lagrangian: terms .*a\\*\\*2.* not representable"):
        library.ideal_coefficients(lagrangian=ad**2 - a**2)
    with pytest.raises(ValueError, match="lagrangian.*not representable"):
        library.ideal_coefficients(lagrangian=ad**3)
    only_classical = px.CatalogRepartition([px.ClassicalLibrary(coords, [ad])])
    with pytest.raises(ValueError, match="lagrangian.*not representable"):
        only_classical.ideal_coefficients(lagrangian=ad**2)


# --------------------------------------------------------------------------------------------
# scikit-learn contract
# --------------------------------------------------------------------------------------------


def _estimators():
    coords = px.Coordinates(["x", "theta"])
    lagrange = px.LagrangeLibrary(coords, [coords.qd[0] ** 2, sp.cos(coords.q[1])])
    classical = px.ClassicalLibrary(coords, coords.qd, mask=np.eye(2, dtype=bool))
    pysindy_classical = px.ClassicalLibrary(coords, ps.PolynomialLibrary(degree=1))
    forces = px.ExternalForces(coords, interlink=np.array([[1.0, 0.0], [-1.0, 1.0]]))
    return {
        "lagrange": lagrange,
        "classical": classical,
        "classical_pysindy": pysindy_classical,
        "forces": forces,
        "repartition": px.CatalogRepartition([forces, lagrange, classical]),
        "explicit": px.ExplicitOptimizer(method="lasso", threshold=0.05, alpha=1e-3),
        "explicit_pysindy": px.ExplicitOptimizer(method=ps.STLSQ(threshold=0.2)),
        "model": px.XLSINDy(lagrange + classical, px.ExplicitOptimizer()),
    }


@pytest.mark.parametrize("name", list(_estimators()))
def test_clone_and_get_params(name):
    estimator = _estimators()[name]
    params = estimator.get_params(deep=False)
    copy = clone(estimator)
    assert type(copy) is type(estimator)
    assert set(copy.get_params(deep=False)) == set(params)
    for key, value in params.items():
        other = copy.get_params(deep=False)[key]
        if hasattr(value, "get_params"):
            assert type(other) is type(value)
            assert other.get_params(deep=False).keys() == value.get_params(deep=False).keys()
        elif isinstance(value, np.ndarray):
            np.testing.assert_array_equal(other, value)
        elif isinstance(value, list) and value and hasattr(value[0], "get_params"):
            assert [type(v) for v in other] == [type(v) for v in value]
        else:
            assert other == value
    assert copy.set_params(**params) is copy


@pytest.mark.parametrize("name", ["lagrange", "classical", "classical_pysindy", "forces",
                                  "repartition"])
def test_clone_of_fitted_library_is_unfitted_and_refits_identically(name):
    library = _estimators()[name].fit()
    copy = clone(library)
    assert not hasattr(copy, "symbolic_matrix_")
    with pytest.raises(NotFittedError):
        copy.transform(np.zeros((2, 9)))
    z = np.random.default_rng(0).normal(size=(5, 9))
    assert copy.fit().get_feature_names() == library.get_feature_names()
    np.testing.assert_array_equal(copy.transform(z), library.transform(z))


def test_compiled_entries_factored_by_angles_match_lambdify():
    """Velocity monomials times trigonometric coefficient functions (evaluated factored, one
    angle after the other), entries equal up to a factor (evaluated once), constants and
    plain polynomials."""
    from pysindy_xl.feature_library._compile import _angle_groups, decompose
    from pysindy_xl.feature_library._plans import Plan, best_plan

    a, b, v, w, u = sp.symbols("a b v w u")
    coefficient = 1 + sp.cos(a) ** 2 * sp.sin(b) - 3 * sp.sin(a) * sp.cos(b) ** 3
    exprs = [sp.expand(v * w * coefficient), sp.expand(2 * v * w * coefficient),
             sp.expand(v**2 * sp.cos(a) + u * sp.sin(b) ** 4 + sp.tanh(10 * v)),
             sp.Integer(3), sp.expand(v * w + w**2 * a), sp.Integer(0) * v]
    terms = decompose(exprs)
    groups = _angle_groups(terms.atoms, [a, b, v, w, u])
    assert [sorted(map(str, np.array(terms.atoms)[g])) for g in groups] == [
        ["cos(b)", "sin(b)"], ["a", "cos(a)", "sin(a)"]]  # the later angle factored out first
    inner = np.any(groups, axis=0)
    plan = Plan(terms.arrays(), inner)
    assert not plan.direct and plan.index.max() + 1 < len(plan.index)  # shared
    # a product of polynomials in each angle: sums over the monomials of b of polynomials
    # of a (each once) take fewer operations than all the products
    product = sp.expand((1 + sp.sin(a) + 2 * sp.cos(a) * sp.sin(a)) ** 3
                        * (1 + 3 * sp.sin(b) - sp.cos(b)) ** 3)
    nested_terms = decompose([sp.expand(v * product), sp.expand(w * product * sp.cos(b))])
    nested_groups = _angle_groups(nested_terms.atoms, [a, b, v, w, u])
    angles = np.any(nested_groups, axis=0)
    nested = best_plan(nested_terms.arrays(), np.ones(len(angles), dtype=bool),
                       [~angles, *nested_groups])
    flat = Plan(nested_terms.arrays(), np.zeros(len(angles), dtype=bool))
    assert isinstance(nested.polynomials.polynomials, Plan)  # of b, of a
    assert nested.cost < flat.cost / 2
    atom_rows = np.random.default_rng(1).uniform(-1, 1, size=(len(angles), 50))
    np.testing.assert_allclose(nested(atom_rows), flat(atom_rows), rtol=1e-12, atol=1e-12)
    variables = [a, b, v, w, u]
    z = np.random.default_rng(0).uniform(-2, 2, size=(300, 5))
    values = px.feature_library.compile_entries(variables, exprs)(z)
    for expr, value in zip(exprs, values, strict=True):
        expected = np.broadcast_to(sp.lambdify(variables, expr, "numpy")(*z.T), (300,))
        np.testing.assert_allclose(value, expected, rtol=1e-12, atol=1e-12)


def test_compiled_arm_like_entries_match_lambdify():
    """Entries shaped like an arm's (velocity products times products of per-joint
    trigonometric factors, the same coefficient functions shared across entries up to a
    factor), evaluated through nested plans, equal the lambdified expressions."""
    from pysindy_xl.feature_library._compile import _angle_groups, decompose
    from pysindy_xl.feature_library._plans import Plan, best_plan

    rng = np.random.default_rng(3)
    q = sp.symbols("q1:4")
    qd = sp.symbols("v1:4")
    factors = [[sp.Integer(1), sp.sin(a), sp.cos(a), sp.sin(a) ** 2, sp.sin(a) * sp.cos(a)]
               for a in q]

    def chain(k):  # a random polynomial of the first k + 1 angles, as nested products
        return sp.expand(sum(rng.normal() * f * (chain(k - 1) if k else 1)
                             for f in rng.choice(factors[k], 3, replace=False)))

    shared = [chain(2) for _ in range(3)]
    exprs = [sp.expand(qd[i] * qd[j] * shared[(i + j) % 3] * (2.0 if i < j else 1.0)
                       + qd[i] * chain(1)) for i in range(3) for j in range(3)]
    terms = decompose(exprs)
    groups = _angle_groups(terms.atoms, [*q, *qd])
    angles = np.any(groups, axis=0)
    plan = best_plan(terms.arrays(), np.ones(len(angles), dtype=bool), [~angles, *groups])
    # the velocities factored out, then q3's atoms, at a fraction of the flat cost
    assert isinstance(plan.polynomials.polynomials, Plan)
    assert plan.cost < Plan(terms.arrays(), np.zeros(len(angles), dtype=bool)).cost / 2
    z = rng.uniform(-2, 2, size=(200, 6))
    values = px.feature_library.compile_entries([*q, *qd], exprs)(z)
    for expr, value in zip(exprs, values, strict=True):
        expected = sp.lambdify([*q, *qd], expr, "numpy")(*z.T)
        np.testing.assert_allclose(value, expected, rtol=1e-11, atol=1e-11)


def test_large_plans_are_stored_on_disk_and_read_back_identical(tmp_path, monkeypatch):
    """A plan is stored when first made and read back, planning impossible, with the same
    values as a fresh one and as lambdify; other terms or another planning code miss."""
    from pysindy_xl.feature_library import _plans
    from pysindy_xl.feature_library._compile import compile_terms, decompose

    monkeypatch.setenv("PYSINDY_XL_CACHE", str(tmp_path))
    monkeypatch.setattr(_plans, "STORED_TERMS", 1)  # (a small catalog stands for a large one)
    a, b, v = sp.symbols("a b v")
    exprs = [sp.expand(v * (1 + sp.sin(a) + sp.cos(a) * sp.sin(b)) ** 3),
             sp.expand(v**2 * sp.cos(b) ** 2 - 2 * sp.sin(a)), sp.Integer(4)]
    z = np.random.default_rng(0).uniform(-2, 2, size=(100, 3))
    fresh = compile_terms([a, b, v], decompose(exprs))(z, stacked=True)
    assert len(list(tmp_path.glob("plan-*.npz"))) == 1

    def fail(*args, **kwargs):
        raise AssertionError("planned although stored")

    monkeypatch.setattr(_plans, "best_plan", fail)
    stored = compile_terms([a, b, v], decompose(exprs))(z, stacked=True)
    np.testing.assert_array_equal(stored, fresh)
    for expr, value in zip(exprs, stored, strict=True):
        expected = np.broadcast_to(sp.lambdify([a, b, v], expr, "numpy")(*z.T), (100,))
        np.testing.assert_allclose(value, expected, rtol=1e-12, atol=1e-12)
    with pytest.raises(AssertionError, match="planned"):  # other terms: a miss
        compile_terms([a, b, v], decompose([sp.expand(v * sp.sin(a) ** 2)]))
    monkeypatch.setattr(_plans, "_code_digest", lambda: "other planning code")
    with pytest.raises(AssertionError, match="planned"):
        compile_terms([a, b, v], decompose(exprs))
