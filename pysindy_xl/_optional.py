"""Optional back ends: import on first use, with an error that names the extra to install.

The core (catalogs, optimizers, :class:`~pysindy_xl.XLSINDy`) needs NumPy, SciPy, SymPy,
scikit-learn, PySINDy and cvxpy (imported on first use: the physically consistent fit of
kinematic catalogs, the admissible starts of unforced fits, ``ImplicitOptimizer(
solver="cvxpy")``). Heavier back ends are optional and imported only where used:

- ``jax``: :meth:`XLSINDy.to_jax`, :mod:`pysindy_xl.export.jax_dynamics`;
  ``pip install "pysindy-xl[jax]"``
- ``mujoco``: simulation in :mod:`pysindy_xl.mujoco`; ``pip install "pysindy-xl[mujoco]"``
- ``gymnasium``: :meth:`XLSINDy.to_gymnasium`; ``pip install "pysindy-xl[gym]"``
- ``dask``: the grid's Dask backend; ``pip install "pysindy-xl[dask]"``
- ``pandas``: DataFrames in :mod:`pysindy_xl.data.tables`; ``pip install pandas``
"""

from __future__ import annotations

import importlib
import sys

__all__ = ["EXTRAS", "MissingExtraError", "import_optional", "lazy_attributes"]

#: extra of ``pyproject.toml`` that installs each optional top-level module
EXTRAS = {
    "cvxpy": "cvxpy",
    "jax": "jax",
    "jaxlib": "jax",
    "mujoco": "mujoco",
    "gymnasium": "gym",
    "dask": "dask",
    "distributed": "dask",
    "rosbags": "ros",
}


class MissingExtraError(ImportError):
    """An optional dependency is not installed; the message names the pip extra.

    A subclass of :class:`ImportError`, so ``except ImportError`` catches it.

    Examples
    --------
    >>> issubclass(MissingExtraError, ImportError)
    True
    """


def import_optional(name: str, purpose: str | None = None, extra: str | None = None):
    """Import an optional module, or raise an ImportError naming the extra that installs it.

    Parameters
    ----------
    name : str
        Module to import (``"jax.numpy"``, ``"cvxpy"``...); its top-level package decides
        the extra (see :data:`EXTRAS`).
    purpose : str, optional
        What needs it, for the message (default: ``name``).
    extra : str, optional
        The ``pysindy-xl[...]`` extra to name (default: from :data:`EXTRAS`; for a module
        without an extra the message says ``pip install <package>``).

    Returns
    -------
    module
        The imported module.

    Raises
    ------
    MissingExtraError
        If the module (or one of its own dependencies) cannot be imported.

    Examples
    --------
    >>> import_optional("json").__name__
    'json'
    >>> import_optional("no_such_backend_xyz", purpose="the test", extra="all")
    Traceback (most recent call last):
    ...
    pysindy_xl._optional.MissingExtraError: the test needs the optional package \
'no_such_backend_xyz', which is not installed (No module named 'no_such_backend_xyz'); \
install it with: pip install "pysindy-xl[all]"
    """
    top = name.split(".", 1)[0]
    try:
        return importlib.import_module(name)
    except ImportError as error:
        extra = extra or EXTRAS.get(top)
        how = f'pip install "pysindy-xl[{extra}]"' if extra else f"pip install {top}"
        raise MissingExtraError(
            f"{purpose or name} needs the optional package {top!r}, which is not installed "
            f"({error}); install it with: {how}"
        ) from error


def lazy_attributes(package: str, table: dict):
    """``__getattr__`` and ``__dir__`` (PEP 562) of a package whose public names are loaded on
    first use: ``table`` maps each name to the submodule that defines it (relative to
    ``package``; a leading dot goes further up), and a loaded name is cached in the package.

    Examples
    --------
    >>> import pysindy_xl
    >>> getattr_, dir_ = lazy_attributes("pysindy_xl", {"monomials": "symbols"})
    >>> getattr_("monomials").__name__, "monomials" in dir_()
    ('monomials', True)
    """
    namespace = sys.modules[package].__dict__

    def __getattr__(name):
        module = table.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        relative = module if module.startswith(".") else f".{module}"
        value = getattr(importlib.import_module(relative, package), name)
        namespace[name] = value  # later accesses skip __getattr__
        return value

    def __dir__():
        return sorted(set(namespace) | set(namespace.get("__all__", table)))

    return __getattr__, __dir__
