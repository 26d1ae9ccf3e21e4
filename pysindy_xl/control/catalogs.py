"""Catalogs for the learning loop: a catalog is a factory ``catalog(system) -> library``.

``"generic"`` is built from the coordinates and their kinds only (which are angles), as for a
rig without a model file: Lagrangian candidates ``qd^a * trig(theta)^b`` (degrees <= 2) plus
the potentials ``p`` and ``p^2`` of the linear coordinates, viscous friction of every velocity
in every equation, and the forces. ``"kinematic"`` is the catalog the MJCF's kinematic tree
gives (:func:`~pysindy_xl.mujoco.kinematic_catalog`), nearly the true structure. Any callable
``f(system) -> library`` (for example an automatic catalog) can stand in for both."""

from __future__ import annotations

import numpy as np

__all__ = ["CATALOGS", "generic_catalog", "kinematic_catalog_of", "resolve_catalog"]


def generic_catalog(system, velocity_degree: int = 2, trig_degree: int = 2):
    """A catalog from the coordinates and their kinds only (module docstring).

    Parameters
    ----------
    system : MuJoCoSystem or str
        Only its ``coords`` and ``angle_coordinates`` are read.
    velocity_degree, trig_degree : int, default 2
        Degrees of the Lagrangian candidates.

    Returns
    -------
    CatalogRepartition

    Examples
    --------
    >>> generic_catalog("cart-pole").fit().n_output_features_
    42
    """

    from ..feature_library import (
        CatalogRepartition,
        ClassicalLibrary,
        ExternalForces,
        LagrangeLibrary,
    )
    from ..mujoco import get_system, lagrange_terms
    system = get_system(system)
    coords = system.coords
    terms = lagrange_terms(system, velocity_degree, trig_degree)
    linear = [coords.q[i] for i in range(coords.n) if i not in system.angle_coordinates]
    terms += linear + [p ** 2 for p in linear]
    friction = np.ones((coords.n, coords.n), dtype=bool)
    return CatalogRepartition([ExternalForces(coords), LagrangeLibrary(coords, terms),
                               ClassicalLibrary(coords, list(coords.qd), mask=friction)])


def kinematic_catalog_of(system):
    """The kinematic catalog of the system's MJCF (its structure given).

    Parameters
    ----------
    system : MuJoCoSystem or str
        The system or its registry name (:func:`pysindy_xl.mujoco.get_system`).

    Returns
    -------
    CatalogRepartition

    Examples
    --------
    >>> kinematic_catalog_of("cart-pole").fit().n_output_features_
    9
    """
    from ..mujoco import get_system, reference_catalog
    return reference_catalog(get_system(system), "kinematic")


#: Catalogs by name.
CATALOGS = {"generic": generic_catalog, "kinematic": kinematic_catalog_of}


def resolve_catalog(catalog):
    """A catalog given by name (:data:`CATALOGS`) or as a callable.

    Parameters
    ----------
    catalog : str or callable
        ``"generic"``, ``"kinematic"`` or ``f(system) -> library``.

    Returns
    -------
    tuple
        ``(name, factory)``.

    Examples
    --------
    >>> resolve_catalog("generic")[0]
    'generic'
    >>> resolve_catalog("mjcf")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: catalog: expected one of ['generic', 'kinematic'] or a callable ..., got 'mjcf'
    """
    if isinstance(catalog, str):
        if catalog not in CATALOGS:
            raise ValueError(f"catalog: expected one of {sorted(CATALOGS)} or a callable system "
                             f"-> library, got {catalog!r}")
        return catalog, CATALOGS[catalog]
    if callable(catalog):
        return getattr(catalog, "__name__", type(catalog).__name__), catalog
    raise TypeError(f"catalog: expected a name or a callable system -> library, got "
                    f"{type(catalog).__name__}")
