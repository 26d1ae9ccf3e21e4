"""Optional back ends (jax, mujoco, gymnasium, dask, rosbags, pandas): imported on first use,
with an error that names the ``pysindy-xl[...]`` extra to install.
"""

from __future__ import annotations

import importlib
import sys

__all__ = ["EXTRAS", "MissingExtraError", "import_optional", "import_mujoco",
           "lazy_attributes"]

#: extra of ``pyproject.toml`` that installs each optional top-level module
EXTRAS = {"cvxpy": "cvxpy", "jax": "jax", "jaxlib": "jax", "mujoco": "mujoco",
          "gymnasium": "gym", "dask": "dask", "distributed": "dask", "rosbags": "ros"}


class MissingExtraError(ImportError):
    """An optional dependency is not installed (an ``ImportError`` naming the pip extra)."""


def import_optional(name: str, purpose: str | None = None, extra: str | None = None):
    """Import module ``name``, or raise a :class:`MissingExtraError` saying what needs it
    (``purpose``) and the ``extra`` that installs it (default: from :data:`EXTRAS` by the
    top-level package; without one, ``pip install <package>``).

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
        raise MissingExtraError(f"{purpose or name} needs the optional package {top!r}, which is "
                                f"not installed ({error}); install it with: {how}") from error


def import_mujoco():
    """The ``mujoco`` module, imported on first use: the one way this package imports MuJoCo.

    Returns
    -------
    module
        The ``mujoco`` package.

    Raises
    ------
    ImportError
        ``pysindy_xl._optional.MissingExtraError``, naming the ``pysindy-xl[mujoco]`` extra,
        when MuJoCo is not installed.

    Examples
    --------
    >>> hasattr(import_mujoco(), "MjModel")
    True
    """
    return import_optional("mujoco", purpose="MuJoCo simulation (pysindy_xl.mujoco)")


def lazy_attributes(package: str, table: dict):
    """``__getattr__`` and ``__dir__`` (PEP 562) of a package whose public names are loaded on
    first use: ``table`` maps each name to the submodule that defines it (relative to
    ``package``; a leading dot goes further up), and a loaded name is cached in the package.

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
