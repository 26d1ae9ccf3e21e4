"""Optional back ends: lazy imports and errors naming the extra to install."""

import importlib
import sys

import pytest

import pysindy_xl
from pysindy_xl._optional import MissingExtraError, import_optional


def test_public_names_load_on_first_use():
    assert set(pysindy_xl.__all__) <= set(dir(pysindy_xl))
    for name in pysindy_xl.__all__:
        value = getattr(pysindy_xl, name)
        if name.isupper():  # a constant of the API (FRICTION_MODELS)
            module = importlib.import_module(f"pysindy_xl.{pysindy_xl._LAZY[name]}")
            assert value is getattr(module, name)
        else:
            assert value.__name__ == name
    with pytest.raises(AttributeError, match="has no attribute 'NoSuchThing'"):
        pysindy_xl.NoSuchThing  # noqa: B018


def test_missing_jax_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "jax", None)  # makes `import jax` fail
    monkeypatch.delitem(sys.modules, "pysindy_xl.export.jax_dynamics", raising=False)
    with pytest.raises(MissingExtraError, match=r'pip install "pysindy-xl\[jax\]"'):
        importlib.import_module("pysindy_xl.export.jax_dynamics")
    with pytest.raises(ImportError, match=r"XLSINDy.to_jax"):
        importlib.import_module("pysindy_xl.export.jax_dynamics")


def test_missing_mujoco_names_the_extra(monkeypatch):
    from pysindy_xl.mujoco import MJCFSystem, get_system

    system = get_system("cart-pole")  # describing a system needs no MuJoCo
    monkeypatch.setitem(sys.modules, "mujoco", None)
    with pytest.raises(MissingExtraError, match=r'pip install "pysindy-xl\[mujoco\]"'):
        system.mj_model()
    with pytest.raises(MissingExtraError, match=r"pysindy-xl\[mujoco\]"):
        MJCFSystem("<mujoco/>")


@pytest.mark.parametrize("module, extra", [("cvxpy", "cvxpy"), ("gymnasium", "gym"),
                                           ("distributed", "dask")])
def test_extras_named(monkeypatch, module, extra):
    monkeypatch.setitem(sys.modules, module, None)
    with pytest.raises(MissingExtraError, match=rf'pip install "pysindy-xl\[{extra}\]"'):
        import_optional(module, purpose="this test")
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(MissingExtraError, match="pip install pandas$"):
        import_optional("pandas")
