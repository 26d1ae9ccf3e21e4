"""The coordinates' kinds, and options given per coordinate (one value, a sequence, a mapping
by name) spread over them."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .bases import KINDS

__all__ = ["coordinate_kinds", "coordinate_names", "per_coordinate"]


def coordinate_names(coordinates) -> list[str]:
    """The coordinates' names, checked.

    Parameters
    ----------
    coordinates : list of str, str or Coordinates
        Names (``"r,theta"`` also works), or :class:`~pysindy_xl.Coordinates`.

    Returns
    -------
    list of str

    Raises
    ------
    ValueError, TypeError
        Naming ``coordinates``: no names, a name that is not a string, a name twice.

    Examples
    --------
    >>> coordinate_names("r, theta")
    ['r', 'theta']
    """
    names = getattr(coordinates, "names", coordinates)  # (a Coordinates object)
    if isinstance(names, str):
        names = [c.strip() for c in names.split(",") if c.strip()]
    if not isinstance(names, (list, tuple)) or not names:
        raise ValueError(f"coordinates: expected a non-empty list of names, got {coordinates!r}")
    for name in names:
        if not isinstance(name, str):
            raise TypeError(f"coordinates: expected names (str), got the "
                            f"{type(name).__name__} {name!r}")
    twice = sorted({name for name in names if names.count(name) > 1})
    if twice:
        raise ValueError(f"coordinates: the names {twice} are given more than once")
    return list(names)


def coordinate_kinds(names, kinds) -> tuple[str, ...]:
    """One kind per coordinate from ``kinds``.

    Parameters
    ----------
    names : sequence of str
        The coordinates' names.
    kinds : None, str, sequence or mapping
        None (all linear), one kind for all, one per coordinate, or ``{name: kind}``
        (coordinates not named are linear); kinds from :data:`~pysindy_xl.catalog.KINDS`.

    Returns
    -------
    tuple of str

    Examples
    --------
    >>> coordinate_kinds(["r", "theta"], {"theta": "angle"})
    ('linear', 'angle')
    """
    names = list(names)
    if kinds is None:
        out = ["linear"] * len(names)
    elif isinstance(kinds, str):
        out = [kinds] * len(names)
    elif isinstance(kinds, Mapping):
        unknown = [k for k in kinds if k not in names]
        if unknown:
            raise ValueError(f"kinds: {unknown} are not among the coordinates {names}")
        out = [kinds.get(name, "linear") for name in names]
    else:
        out = list(kinds)
        if len(out) != len(names):
            raise ValueError(f"kinds: expected one kind per coordinate ({len(names)}), got "
                             f"{len(out)}")
    for name, kind in zip(names, out, strict=True):
        if kind not in KINDS:
            raise ValueError(f"kinds: coordinate {name!r} has the unknown kind {kind!r}; "
                             f"expected one of {KINDS}")
    return tuple(out)


def per_coordinate(value, names, name, default=None) -> list:
    """``value`` spread over the coordinates.

    Parameters
    ----------
    value : None, mapping, sequence or object
        A mapping by name (coordinates not named get ``default``), a sequence of one value per
        coordinate, or one value for all (None: ``default`` for all).
    names : sequence of str
        The coordinates' names.
    name : str
        The option's name, for the error message.
    default : object, optional
        The value of coordinates that ``value`` does not name.

    Returns
    -------
    list
        One value per coordinate.

    Examples
    --------
    >>> per_coordinate({"theta": 3}, ["r", "theta"], "degree", default=2)
    [2, 3]
    """
    if value is None:
        return [default] * len(names)
    if isinstance(value, Mapping):
        unknown = [k for k in value if k not in names]
        if unknown:
            raise ValueError(f"{name}: {unknown} are not among the coordinates {list(names)}")
        return [value.get(n, default) for n in names]
    if isinstance(value, (list, tuple, np.ndarray)) and len(value) == len(names) and (
            name != "bounds" or all(v is None or np.ndim(v) == 1 for v in value)):
        return list(value)
    return [value] * len(names)
