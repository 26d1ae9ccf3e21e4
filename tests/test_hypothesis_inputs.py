"""Property-based check of the public entry points: random shapes, dtypes, NaN/inf, empty and
huge inputs either succeed with finite output or raise ``ValueError`` / ``TypeError`` naming
the argument (or the package's documented errors), quickly.

Bounded for CI: few examples per property, a deadline per example, derandomized; the whole
file runs in a few seconds. ``PYSINDY_XL_HYPOTHESIS_EXAMPLES=500`` explores further (random
seeds).
"""

import functools
import json
import os
import re
import time
import warnings

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from hypothesis.extra import numpy as hnp  # noqa: E402

import pysindy_xl as px  # noqa: E402

COORDS = px.Coordinates(["x"])
X, XD = COORDS.q[0], COORDS.qd[0]
N = 201
_EXPLORE = os.environ.get("PYSINDY_XL_HYPOTHESIS_EXAMPLES")
SETTINGS = settings(max_examples=int(_EXPLORE or 30), deadline=5000, derandomize=not _EXPLORE,
                    database=None,
                    suppress_health_check=[HealthCheck.too_slow])
TIME_BOUND = 5.0  # seconds per call
#: errors the package documents besides ValueError / TypeError
DOCUMENTED = (ValueError, TypeError, px.SimulationError, px.NoLawFoundError)
#: warnings a call may emit; anything else (RuntimeWarning overflow, ComplexWarning...) is a
#: defect: the input should have been refused or handled
ALLOWED_WARNINGS = (px.IdentificationWarning,)
NAMED = re.compile(r"^[A-Za-z_][\w\[\]]*(, [A-Za-z_][\w\[\]]*)*: ")


def _call(function, *args, **kwargs):
    """Run ``function``; return its result or the documented exception it raised, after
    checking the time bound, the warnings and that an error names its argument."""
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = function(*args, **kwargs)
        except DOCUMENTED as err:
            result = err
    elapsed = time.perf_counter() - start
    assert elapsed < TIME_BOUND, f"{function.__name__} took {elapsed:.1f} s"
    unexpected = [w for w in caught if not issubclass(w.category, ALLOWED_WARNINGS)
                  and "shorter than one test function" not in str(w.message)]
    assert not unexpected, [f"{w.category.__name__}: {w.message}" for w in unexpected]
    if isinstance(result, (ValueError, TypeError)):
        assert NAMED.match(str(result)), f"message does not name the argument: {result}"
    return result


def _finite(value):
    return all(np.all(np.isfinite(np.asarray(v, dtype=float))) for v in
               (value if isinstance(value, list) else [value]))


@functools.cache
def _reference():
    t = np.linspace(0, 8, N)
    x = (np.cos(2 * t) + 0.1 * t)[:, None]
    xd = (-2 * np.sin(2 * t) + 0.1)[:, None]
    xdd = (-4 * np.cos(2 * t))[:, None]
    data = {"x": x, "t": t, "x_dot": xd, "x_ddot": xdd, "u": xdd + 3 * x}
    model = px.XLSINDy(_library(), px.ExplicitOptimizer()).fit(**data)
    np.testing.assert_allclose(model.coefficients(), [-1.0, 0.5, -1.5, 0.0], atol=1e-8)
    return data, model


def _library():
    return px.LagrangeLibrary(COORDS, [XD**2, X**2, X**4])


# -- strategies ------------------------------------------------------------------------------
_SPECIAL = st.sampled_from([np.nan, np.inf, -np.inf, 1e200, -1e300, 0.0, 1e-300, 5e-324])
_FLOATS = st.floats(allow_nan=True, allow_infinity=True, width=64) | _SPECIAL


def _arrays(max_rows=N + 5, max_cols=3):
    shapes = hnp.array_shapes(min_dims=0, max_dims=3, min_side=0, max_side=4) | st.tuples(
        st.integers(0, max_rows), st.integers(0, max_cols))
    numeric = hnp.arrays(np.float64, shapes, elements=_FLOATS)
    others = st.one_of(
        hnp.arrays(np.int64, shapes, elements=st.integers(-10**6, 10**6)),
        hnp.arrays(np.complex128, shapes, elements=st.complex_numbers(max_magnitude=1e3)),
        hnp.arrays(np.bool_, shapes),
        hnp.arrays("U3", shapes, elements=st.text("0123456789.e-ax", max_size=3)),
        hnp.arrays("datetime64[s]", shapes, elements=st.integers(0, 10**9).map(
            lambda k: np.datetime64(k, "s"))),
    )
    scalars = st.one_of(st.none(), _FLOATS, st.text(max_size=4), st.booleans(),
                        st.just([]), st.just([None]))
    return st.one_of(numeric, numeric, others, scalars)


def _perturbed(name, length=N):
    """The reference array of ``name`` with a few random entries replaced (NaN, inf, huge),
    or scaled, or cut: close to valid, so the calls get past the first checks."""
    def build(draw_values):
        kind, index, value, scale = draw_values
        data, _ = _reference()
        array = np.array(data[name], dtype=float)
        if kind == "entry":
            array.reshape(-1)[index % array.size] = value
        elif kind == "scale":
            array = array * scale
        elif kind == "cut":
            array = array[: index % (length + 1)]
        return array
    return st.tuples(st.sampled_from(["entry", "scale", "cut", "same"]), st.integers(0, 10**6),
                     _SPECIAL, st.sampled_from([1e-300, 1e-12, 1e150, 1e300, -1.0])).map(build)


# -- fit -------------------------------------------------------------------------------------
@SETTINGS
@given(name=st.sampled_from(["x", "t", "x_dot", "x_ddot", "u"]),
       value=st.one_of(_arrays(), _perturbed("x")))
def test_fit_random_argument(name, value):
    data, _ = _reference()
    kwargs = dict(data, **{name: value})
    result = _call(px.XLSINDy(_library(), px.ExplicitOptimizer()).fit, **kwargs)
    if not isinstance(result, Exception):
        assert _finite(result.coefficients())


@SETTINGS
@given(name=st.sampled_from(["x", "x_dot", "x_ddot", "u"]), value=_perturbed("x"))
def test_fit_near_valid_data(name, value):
    data, _ = _reference()
    if name != "x":
        value = np.broadcast_to(value[:, :1], value.shape) if value.ndim == 2 else value
    kwargs = dict(data, **{name: value})
    result = _call(px.XLSINDy(_library(), px.ExplicitOptimizer()).fit, **kwargs)
    if not isinstance(result, Exception):
        assert _finite(result.coefficients())


# -- predict / score -------------------------------------------------------------------------
@SETTINGS
@given(x=st.one_of(_arrays(), _perturbed("x")), x_dot=st.one_of(_arrays(), _perturbed("x_dot")),
       u=st.one_of(st.none(), _arrays(), _perturbed("u")))
def test_predict_random(x, x_dot, u):
    _, model = _reference()
    result = _call(model.predict, x, x_dot, u)
    if not isinstance(result, Exception):
        assert _finite(result)
        assert np.shape(result) == np.shape(np.atleast_2d(np.asarray(x, dtype=float).T).T)


# -- simulate --------------------------------------------------------------------------------
_OPTION_VALUES = st.one_of(_FLOATS, st.integers(-5, 10**7), st.text(max_size=3), st.booleans(),
                           st.none())


@SETTINGS
@given(x0=st.one_of(_arrays(), st.lists(_FLOATS, min_size=2, max_size=2)),
       t=st.one_of(_arrays(), hnp.arrays(np.float64, st.integers(0, 30), elements=st.floats(
           -1e3, 1e3)).map(np.sort)),
       option=st.sampled_from(["rtol", "atol", "divergence_bound", "max_evaluations",
                               "timeout", "method", None]),
       value=_OPTION_VALUES)
def test_simulate_random(x0, t, option, value):
    _, model = _reference()
    options = {"timeout": 1.0, "max_evaluations": 20_000}
    if option is not None:
        options[option] = value
        if option in ("timeout", "max_evaluations") and not isinstance(value, str):
            options.setdefault("timeout", 1.0)
            if option == "timeout":  # keep the call bounded
                options["max_evaluations"] = 20_000
            else:
                options["timeout"] = 1.0
    result = _call(model.simulate, x0, t, **options)
    if not isinstance(result, Exception):
        assert _finite(result)
        assert result.shape == (len(t), 2)


# -- the libraries ---------------------------------------------------------------------------
@SETTINGS
@given(z=st.one_of(_arrays(max_cols=6), hnp.arrays(np.float64, st.tuples(
    st.integers(0, 6), st.just(5)), elements=_FLOATS)))
def test_library_transform_random(z):
    library = _library().fit()
    result = _call(library.transform, z)
    if not isinstance(result, Exception):
        assert _finite(result)
        assert result.shape == (np.shape(z)[0], 3)


# -- save / load -----------------------------------------------------------------------------
_JSON = st.recursive(
    st.none() | st.booleans() | st.integers(-10**20, 10**20) | st.floats(allow_nan=False)
    | st.text(max_size=12),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(
        st.text(max_size=8), children, max_size=4), max_leaves=12)
_TERMS = st.text("x_dotheta()+-*/^ 0123456789.expsincolgqrtabE", min_size=1, max_size=40)


def _paths(document):
    """Every (container, key) of a JSON document."""
    stack, out = [document], []
    while stack:
        node = stack.pop()
        items = node.items() if isinstance(node, dict) else enumerate(node) \
            if isinstance(node, list) else []
        for key, child in items:
            out.append((node, key))
            stack.append(child)
    return out


@SETTINGS
@given(choice=st.integers(0, 10**6), replacement=st.one_of(_JSON, _TERMS))
def test_load_mutated_file(tmp_path_factory, choice, replacement):
    _, model = _reference()
    folder = tmp_path_factory.mktemp("load")
    model.save(folder / "model.json")
    document = json.loads((folder / "model.json").read_text())
    node, key = (paths := _paths(document))[choice % len(paths)]
    node[key] = replacement
    (folder / "mutated.json").write_text(json.dumps(document))
    result = _call(px.XLSINDy.load, folder / "mutated.json")
    if not isinstance(result, Exception):
        assert _finite(result.coefficients())
    else:
        assert isinstance(result, ValueError)


@SETTINGS
@given(path=st.one_of(st.text(max_size=20), st.integers(), st.none(), st.just("")))
def test_save_random_path(tmp_path_factory, path):
    _, model = _reference()
    folder = tmp_path_factory.mktemp("save")
    target = folder / path if isinstance(path, str) and path else path
    result = _call(model.save, target)
    if not isinstance(result, Exception):
        loaded = px.XLSINDy.load(target)
        np.testing.assert_array_equal(loaded.coefficients(), model.coefficients())
