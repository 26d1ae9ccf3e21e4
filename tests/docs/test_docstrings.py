"""The public API's docstrings pass the documentation's own checker (docs/check_docstrings.py):
every parameter documented, a Returns section where the code returns a value, an Examples
section (or a gallery example) for every class and function, public methods included."""

import importlib
import importlib.util
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]

#: Packages whose objects are held to the checker, wherever the API reference lists them (an
#: inherited method counts for the package that defines it). The package root and the core
#: subpackages join as their docstrings are completed; this then becomes ``("pysindy_xl",)``.
OWNERS = (
    "pysindy_xl.mujoco",
    "pysindy_xl.data",
    "pysindy_xl.export",
    "pysindy_xl.benchmark",
    "pysindy_xl.cli",
    "pysindy_xl.simulation",
    "pysindy_xl.evaluation.validation",  # held_out and quality join with the core
    "pysindy_xl.evaluation.runs",
    "pysindy_xl.evaluation.physics",
    "pysindy_xl.evaluation.plots",
    "pysindy_xl.fitted.equations",
    "pysindy_xl.fitted.inspection",
)


def _checker():
    pytest.importorskip("numpydoc")
    spec = importlib.util.spec_from_file_location("check_docstrings",
                                                  ROOT / "docs" / "check_docstrings.py")
    checker = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(checker)
    return checker


def _defined_in(path: str) -> str:
    """The module that defines the object at import path ``path``."""
    parts = path.split(".")
    for cut in range(len(parts) - 1, 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for name in parts[cut:]:
            obj = getattr(obj, name)
        return getattr(obj, "__module__", "")
    raise ValueError(path)


def _owned(module: str) -> bool:
    return any(module == owner or module.startswith(owner + ".") for owner in OWNERS)


def test_api_docstrings_are_complete():
    checker = _checker()
    found = checker.find_problems(checker.API_MODULES, methods=True)
    assert found["checked"] > 300  # the classes, functions and methods of the reference
    incomplete = {path: [checker.SECTION_NAMES[code] for code in codes]
                  for path, codes in found["problems"].items() if _owned(_defined_in(path))}
    assert incomplete == {}


def test_the_checker_finds_missing_sections(tmp_path, monkeypatch):
    checker = _checker()
    (tmp_path / "pxl_probe.py").write_text(
        'def area(width, height=1.0):\n'
        '    """Area of a rectangle."""\n'
        '    return width * height\n'
        '\n'
        '\n'
        'def documented(width):\n'
        '    """Twice the width.\n'
        '\n'
        '    Parameters\n'
        '    ----------\n'
        '    width : float\n'
        '        The width.\n'
        '\n'
        '    Returns\n'
        '    -------\n'
        '    float\n'
        '        Twice the width.\n'
        '\n'
        '    Examples\n'
        '    --------\n'
        '    >>> documented(1.5)\n'
        '    3.0\n'
        '    """\n'
        '    return 2 * width\n')
    monkeypatch.syspath_prepend(str(tmp_path))
    assert sorted(checker.missing_sections("pxl_probe.area", checker.CHECKED)) == [
        "EX01", "PR01", "RT01"]
    assert checker.missing_sections("pxl_probe.documented", checker.CHECKED) == []
    assert _owned(_defined_in("pysindy_xl.mujoco.get_system"))
    assert not _owned(_defined_in("pysindy_xl.XLSINDy.fit"))
