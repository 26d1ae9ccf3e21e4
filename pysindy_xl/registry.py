"""Named types for persistence: what a model file may name, and how a name is resolved.

Catalog libraries and optimizers register themselves when their class is defined (here or in
a user's code); a model file names them by ``spec_type``, so loading imports nothing.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["register_type", "is_plain", "json_finite"]


def register_type(registry: dict, cls: type) -> None:
    """Put ``cls`` in ``registry`` under its ``spec_type``.

    A class sets ``spec_type`` in its own body to choose the name; otherwise it is
    ``module.QualifiedName`` (never inherited). The same class defined again (a re-run notebook
    cell) replaces itself.

    Parameters
    ----------
    registry : dict of str to type
        The registry (the library or the optimizer types a model file may name); updated in
        place.
    cls : type
        The class to register; its ``spec_type`` attribute is set to the name used.

    Raises
    ------
    TypeError
        When the name is already taken by another class.

    Examples
    --------
    >>> registry = {}
    >>> class Solver:
    ...     spec_type = "my_solver"
    >>> register_type(registry, Solver)
    >>> registry["my_solver"] is Solver
    True
    """
    name = cls.__dict__.get("spec_type") or f"{cls.__module__}.{cls.__qualname__}"
    known = registry.get(name)
    if known is not None and (known.__module__, known.__qualname__) != (cls.__module__,
                                                                         cls.__qualname__):
        raise TypeError(f"spec_type: {name!r} is already the name of {known.__module__}."
                        f"{known.__qualname__}; give {cls.__qualname__} another spec_type")
    cls.spec_type = name
    registry[name] = cls


def is_plain(value) -> bool:
    """Whether JSON holds ``value`` as it is: None, a bool, an int, a str or a finite float.

    Parameters
    ----------
    value : object
        Any value.

    Returns
    -------
    bool
        True for None, bool, int, str and finite float; False otherwise (containers included).

    Examples
    --------
    >>> [is_plain(v) for v in (None, True, 3, 0.5, "a", float("nan"), [1])]
    [True, True, True, True, True, False, False]
    """
    return value is None or (isinstance(value, (bool, int, float, str))
                             and not (isinstance(value, float) and not math.isfinite(value)))


def json_finite(value):
    """JSON-safe copy: non-finite floats become None, numpy scalars plain numbers.

    Parameters
    ----------
    value : object
        A value, dict, list or tuple (nested); dict keys become str, tuples lists.

    Returns
    -------
    object
        The copy, with every float finite or None.

    Examples
    --------
    >>> json_finite({"rmse": float("inf"), "n": np.int64(3), "x": [np.float64(0.5)]})
    {'rmse': None, 'n': 3, 'x': [0.5]}
    """
    if isinstance(value, dict):
        return {str(k): json_finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_finite(v) for v in value]
    if isinstance(value, (np.floating, float)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value
