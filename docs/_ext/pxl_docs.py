"""Helpers of the documentation build: API pages from ``__all__`` and the gallery order.

Kept out of ``conf.py`` so that sphinx-gallery can import them by name (configuration values
must be picklable, so callables are given as ``"module.attribute"`` strings).
"""

from __future__ import annotations

import importlib
import inspect
from pathlib import Path

#: Gallery order (file names in ``examples/``); files not listed come after, alphabetically.
GALLERY_ORDER = [
    "cart_pole_explicit.py",
    "double_pendulum_implicit.py",
    "cart_double_pendulum_mixed.py",
    "recorded_data.py",
    "pysindy_components.py",
    "jax_batched.py",
    "jax_gradient.py",
    "identified_cartpole_controller.py",
]

#: Examples left out of the gallery on purpose: file -> reason. Every example runs during the
#: build, so each must stay short (under about 30 s).
GALLERY_EXCLUDED = {
    "jax_gradient.py": "too slow for the docs build (about 55 s; limit 30 s)",
}

#: Section of a module page for each kind of public object, in page order.
_SECTIONS = [
    ("class", "Classes"),
    ("function", "Functions"),
    ("exception", "Exceptions"),
    ("data", "Constants"),
]
_ROLES = {"class": "class", "function": "func", "exception": "exc", "data": "data"}


def gallery_order(filename: str) -> tuple:
    """Sort key of the gallery: :data:`GALLERY_ORDER` first, then by file name.

    Parameters
    ----------
    filename : str
        Base name of an example file.

    Returns
    -------
    tuple
        ``(rank, filename)``.
    """
    rank = GALLERY_ORDER.index(filename) if filename in GALLERY_ORDER else len(GALLERY_ORDER)
    return rank, filename


def reset_jax(gallery_conf, fname, when=None):
    """Undo global JAX settings an example may change (``jax_enable_x64``) before the next one.

    Sphinx-gallery runs every example in the same process; without this, an example that
    switches JAX to double precision would silently change the ones after it.

    Parameters
    ----------
    gallery_conf : dict
        The sphinx-gallery configuration (unused).
    fname : str
        The example file (unused).
    when : str, optional
        ``"before"`` or ``"after"`` the example (unused).

    Returns
    -------
    None
    """
    import sys

    jax = sys.modules.get("jax")
    if jax is not None:
        jax.config.update("jax_enable_x64", False)


def object_kind(obj) -> str:
    """``"exception"``, ``"class"``, ``"function"`` or ``"data"``."""
    if inspect.isclass(obj):
        return "exception" if issubclass(obj, BaseException) else "class"
    if inspect.isfunction(obj) or inspect.isbuiltin(obj) or (
        callable(obj) and hasattr(obj, "__wrapped__")
    ):
        return "function"
    return "data"


def public_objects(module_name: str) -> list[tuple[str, object]]:
    """``(name, object)`` pairs of a module's ``__all__``, in that order."""
    module = importlib.import_module(module_name)
    names = getattr(module, "__all__", None)
    if names is None:
        raise ValueError(f"{module_name} has no __all__: its public API is undefined")
    return [(name, getattr(module, name)) for name in names]


def _heading(text: str, char: str) -> list[str]:
    return [text, char * len(text), ""]


def _module_page(module_name: str, top_level: dict[int, str]) -> str:
    """reST of one module page: docstring, then an autosummary table per kind of object."""
    lines = _heading(module_name, "=") + [
        f".. automodule:: {module_name}",
        "   :no-members:",
        "",
        f".. currentmodule:: {module_name}",
        "",
    ]
    documented, elsewhere = {}, []
    for name, obj in public_objects(module_name):
        owner = top_level.setdefault(id(obj), module_name)  # the first page that lists it
        if owner != module_name:
            elsewhere.append((name, obj, owner))
        else:
            documented.setdefault(object_kind(obj), []).append(name)
    for kind, title in _SECTIONS:
        names = documented.get(kind)
        if not names:
            continue
        lines += _heading(title, "-") + [
            ".. autosummary::",
            "   :toctree: ../generated",
            "   :nosignatures:",
            "",
        ]
        lines += [f"   {name}" for name in names] + [""]
    if elsewhere:
        lines += _heading("Also exported here", "-") + [
            "Documented with the top-level package:",
            "",
        ]
        for name, obj, owner in elsewhere:
            role = _ROLES[object_kind(obj)]
            lines.append(f"* :{role}:`{module_name}.{name}` is :{role}:`{owner}.{name}`")
        lines.append("")
    return "\n".join(lines)


def write_api_pages(module_names, folder) -> list[str]:
    """Write one reference page per importable module and a toctree fragment listing them.

    Every object is documented once, on the first page that lists it (the top-level package
    first), and linked from the later ones (a name re-exported where users expect it, such as
    ``pysindy_xl.mujoco.Dataset``), so no object is described twice.

    Parameters
    ----------
    module_names : sequence of str
        Modules to document, the top-level package first.
    folder : path
        Output folder (inside the Sphinx source tree, ignored by git).

    Returns
    -------
    list of str
        Modules that could not be imported (skipped).
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    top_name = module_names[0]
    top_level = {id(obj): top_name for _, obj in public_objects(top_name)}
    written, skipped = [], []
    for module_name in module_names:
        try:
            importlib.import_module(module_name)
        except ImportError:
            skipped.append(module_name)
            continue
        page = _module_page(module_name, top_level)
        path = folder / f"{module_name}.rst"
        if not path.exists() or path.read_text(encoding="utf-8") != page:
            path.write_text(page, encoding="utf-8")
        written.append(module_name)
    toctree = [".. toctree::", "   :maxdepth: 1", ""]
    toctree += [f"   gen_modules/api/{name}" for name in written]
    fragment = folder / "toctree.rst.inc"
    fragment.write_text("\n".join(toctree) + "\n", encoding="utf-8")
    for stale in folder.glob("*.rst"):
        if stale.stem not in written:
            stale.unlink()
    return skipped


def write_cli_help(module_name: str, path) -> bool:
    """Write the ``--help`` text of the command and of each subcommand as a reST fragment.

    Parameters
    ----------
    module_name : str
        Module with a ``build_parser()`` returning the ``argparse`` parser.
    path : path
        Output file (inside the Sphinx source tree, ignored by git).

    Returns
    -------
    bool
        False when the module is not importable (the fragment then says so).
    """
    import argparse
    import os

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        parser = importlib.import_module(module_name).build_parser()
    except (ImportError, AttributeError):
        path.write_text("The command-line interface is not available in this version.\n",
                        encoding="utf-8")
        return False
    parsers = [(parser.prog, parser)]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            parsers += [(sub.prog, sub) for sub in action.choices.values()]
    previous = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "96"  # argparse wraps to the terminal width; fix it for the page
    try:
        lines = []
        for prog, sub in parsers:
            lines += _heading(f"``{prog}``", "-") + [".. code-block:: text", ""]
            lines += [f"   {line}".rstrip() for line in sub.format_help().splitlines()] + [""]
    finally:
        if previous is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = previous
    text = "\n".join(lines)
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")
    return True
