"""Loading a hostile model file is refused quickly with a clear error, never a hang or crash;
saving to a path that cannot hold the file is a clear error too."""

import json
import os
import time

import numpy as np
import pytest

import pysindy_xl as px

COORDS = px.Coordinates(["x", "theta"])
X, TH = COORDS.q
XD, THD = COORDS.qd


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """A valid model file of a forced two-coordinate system, and its JSON document."""
    t = np.linspace(0, 10, 1001)
    x = np.column_stack([np.sin(t) + 0.3 * t, np.cos(1.3 * t) + 0.4 * np.sin(0.5 * t)])
    xd = np.column_stack([np.cos(t) + 0.3, -1.3 * np.sin(1.3 * t) + 0.2 * np.cos(0.5 * t)])
    xdd = np.column_stack([-np.sin(t), -1.69 * np.cos(1.3 * t) - 0.1 * np.sin(0.5 * t)])
    u = xdd + 2 * x  # L = (x_dot**2 + theta_dot**2) / 2 - x**2 - theta**2
    lib = px.LagrangeLibrary(COORDS, [XD**2, THD**2, X**2, TH**2])
    model = px.XLSINDy(lib, px.ExplicitOptimizer()).fit(x, t, xd, xdd, u)
    path = tmp_path_factory.mktemp("models") / "model.json"
    model.save(path)
    with open(path) as fh:
        document = json.load(fh)
    return model, path, document


def _write(tmp_path, document):
    path = tmp_path / "hostile.json"
    path.write_text(json.dumps(document))
    return path


def _with_term(document, term):
    doc = json.loads(json.dumps(document))
    lagrange = next(s for s in doc["feature_library"]["libraries"]
                    if s["type"] == "LagrangeLibrary")
    lagrange["terms"][0] = term
    return doc


def test_valid_file_loads(saved):
    # guards the hostile cases: the unmodified file loads and predicts like the model
    model, path, _ = saved
    np.testing.assert_allclose(model.coefficients(), [-1, 0.5, 0.5, -1, -1], atol=1e-8)
    loaded = px.XLSINDy.load(path)
    np.testing.assert_array_equal(loaded.coefficients(), model.coefficients())


HOSTILE_TERMS = {
    "expanded_power": ("(x+x_dot+theta+theta_dot)**100", r"too large for a catalog term"),
    "power_tower": ("x**x**x**x**x**x**x**x", r"exponent .* is not a number"),
    "nested_sin": ("sin(" * 99 + "x" + ")" * 99, r"nests functions 99 deep"),
    "exp_chain": ("exp(" * 40 + "x_dot" + ")" * 40, r"nests functions 40 deep"),
    "numeric_exp_chain": ("exp(exp(exp(exp(100))))*x_dot**2", r"too large"),
    "product_of_powers": ("(x+theta)**60*(x_dot+theta_dot)**60", r"too large for a catalog"),
    "huge_number_power": ("9**9**9*x_dot**2", r"numeric power .* too large"),
    "deep_parentheses": ("(" * 150 + "x" + ")" * 150, r"nested deeper than"),
}


@pytest.mark.parametrize("case", list(HOSTILE_TERMS))
def test_hostile_terms_are_refused_quickly(case, saved, tmp_path):
    term, match = HOSTILE_TERMS[case]
    path = _write(tmp_path, _with_term(saved[2], term))
    start = time.perf_counter()
    with pytest.raises(ValueError, match=r"not a valid pysindy-xl model file") as info:
        px.XLSINDy.load(path)
    assert time.perf_counter() - start < 2.0
    assert info.match(match)


def test_too_many_terms_refused(saved, tmp_path):
    doc = json.loads(json.dumps(saved[2]))
    lagrange = next(s for s in doc["feature_library"]["libraries"]
                    if s["type"] == "LagrangeLibrary")
    lagrange["terms"] = [f"x**{k}" for k in range(1, 5_002)]
    start = time.perf_counter()
    with pytest.raises(ValueError, match="more than 5000 catalog terms"):
        px.XLSINDy.load(_write(tmp_path, doc))
    assert time.perf_counter() - start < 2.0


@pytest.mark.parametrize("optimizer", [
    {"type": "NoLawFoundError"},
    {"type": "CatalogOptimizer"},
    {"type": "independent_columns"},
    {"type": "os.system"},
    {"type": "ExplicitOptimizer", "params": {"max_iter": -3}},
    {"type": "ExplicitOptimizer", "params": {"refit": "yes"}},
    {"type": "ExplicitOptimizer", "params": {"unknown": 1}},
    {"type": "ExplicitOptimizer", "params": {"method": {"nested": 1}}},
    "ExplicitOptimizer",
])
def test_only_documented_optimizer_types_load(optimizer, saved, tmp_path):
    doc = dict(saved[2], optimizer=optimizer)
    with pytest.raises(ValueError, match=r"not a valid pysindy-xl model file: .*optimizer"):
        px.XLSINDy.load(_write(tmp_path, doc))


@pytest.mark.parametrize("name", ["ExplicitOptimizer", "ImplicitOptimizer", "MixedOptimizer",
                                  "EnsembleOptimizer"])
def test_documented_optimizer_types_load(name, saved, tmp_path):
    doc = dict(saved[2], optimizer={"type": name, "params": {}})
    assert type(px.XLSINDy.load(_write(tmp_path, doc)).optimizer_).__name__ == name


def test_save_into_a_directory_is_a_clear_error(saved, tmp_path):
    with pytest.raises(ValueError, match="path: .* is a directory"):
        saved[0].save(tmp_path)


def test_save_into_a_missing_folder_is_a_clear_error(saved, tmp_path):
    target = tmp_path / "missing" / "model.json"
    with pytest.raises(ValueError, match="path: the folder .*missing.* does not exist"):
        saved[0].save(target)
    assert not os.path.exists(target.parent)


def test_save_path_of_wrong_type(saved):
    with pytest.raises(TypeError, match="path: expected a str or os.PathLike"):
        saved[0].save(3.5)


@pytest.mark.parametrize("duration, error", [(float("inf"), ValueError), (float("nan"), ValueError),
                                             (-1.0, ValueError), (1e12, ValueError),
                                             ("10", TypeError)])
def test_generate_dataset_bad_duration(duration, error):
    generate = pytest.importorskip("pysindy_xl.mujoco").generate_dataset
    pytest.importorskip("mujoco")
    with pytest.raises(error, match="duration: "):
        generate("cart-pole", n_trajectories=1, duration=duration, progress=False)
