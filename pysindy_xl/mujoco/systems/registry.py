"""The registry of MuJoCo systems, and their conventions.

Angles are absolute, from the downward vertical (``theta = 0`` hanging down); cart positions
``x`` are horizontal. MuJoCo's hinge angles along a chain are relative: every system maps
``q = T @ qpos`` (:attr:`MuJoCoSystem.joint_to_coordinates`); by virtual work a joint force
``u`` is the generalized force ``B @ u``, ``B = T^-T`` (:meth:`MuJoCoSystem.force_matrix`),
and joint damping the friction ``-B C T^-1 qd`` (:meth:`MuJoCoSystem.friction`). Point masses
have explicit ``<inertial>`` elements (a tiny ``point_inertia``); contacts are off.
"""

from __future__ import annotations

import os
from importlib import resources

import numpy as np

from ...symbols import Coordinates
from .base import MuJoCoSystem, equations_of_motion
from .mjcf import MJCFSystem
from .paper import CartDoublePendulum, CartPole, DoublePendulum, TriplePendulum

__all__ = ["MuJoCoSystem", "coordinate_system", "CartPole", "DoublePendulum",
           "CartDoublePendulum", "TriplePendulum", "MJCFSystem", "SYSTEMS", "get_system",
           "default_xml_path", "equations_of_motion", "system_from_metadata"]


SYSTEMS = {cls.name: cls for cls in (CartPole, DoublePendulum, CartDoublePendulum, TriplePendulum)}


def get_system(name, **parameters) -> MuJoCoSystem:
    """A system by registry name, or a :class:`MJCFSystem` for a path to an MJCF file.

    Parameters
    ----------
    name : str, os.PathLike or MuJoCoSystem
        ``"cart-pole"``, ``"double-pendulum"``, ``"cart-double-pendulum"``,
        ``"triple-pendulum"`` (underscores accepted), a path to an MJCF ``.xml`` or URDF
        ``.urdf`` file (any other existing file is read as MJCF), MJCF text, or a system
        (returned as is).
    **parameters
        Passed to the system's constructor.

    Returns
    -------
    MuJoCoSystem
        A new system: :class:`CartPole`, :class:`DoublePendulum`, :class:`CartDoublePendulum`,
        :class:`TriplePendulum` or :class:`MJCFSystem` (``name`` itself when it is a system).

    Raises
    ------
    ValueError
        When ``name`` is neither a registry name, an existing file nor MJCF text.

    Examples
    --------
    >>> get_system("cart_pole", pole_mass=0.3).parameters["pole_mass"]
    0.3
    """
    if isinstance(name, MuJoCoSystem):
        if parameters:
            raise ValueError("parameters: cannot be given together with a system instance")
        return name
    if isinstance(name, os.PathLike) or (isinstance(name, str) and (
            name.lower().endswith((".xml", ".urdf")) or name.lstrip().startswith("<"))):
        return MJCFSystem(name, **parameters)
    if not isinstance(name, str):
        raise TypeError(f"name: expected a system name or an MJCF path, got {type(name).__name__}")
    key = name.strip().lower().replace("_", "-")
    if key in SYSTEMS:
        return SYSTEMS[key](**parameters)
    if os.path.isfile(name):
        return MJCFSystem(name, **parameters)
    raise ValueError(f"name: unknown system {name!r}; expected one of {sorted(SYSTEMS)} or a "
                     "path to an MJCF .xml or URDF .urdf file")


def system_from_metadata(metadata: dict, **parameters) -> MuJoCoSystem:
    """The system a dataset was generated with, from its ``Dataset.metadata``.

    Registry systems are rebuilt with their recorded parameters (``parameters`` override
    them); a user's MJCF from its recorded ``model_path`` when the file exists, otherwise from
    the embedded ``model_xml``, with the same ``joints``. ValueError when the metadata name
    no system, or an MJCF dataset records neither path nor XML.

    Parameters
    ----------
    metadata : dict
        A dataset's metadata (:attr:`pysindy_xl.data.Dataset.metadata`): ``"system"`` and
        ``"parameters"``, and for an MJCF system ``"model_path"``, ``"model_xml"`` and
        ``"joints"``.
    **parameters
        Override the recorded parameters of a registry system.

    Returns
    -------
    MuJoCoSystem
        The system the dataset was generated with.

    Raises
    ------
    ValueError
        When the metadata names no known system, or an MJCF dataset records neither path nor
        XML.

    Examples
    --------
    >>> xml = ('<mujoco><worldbody><body><joint name="a" type="slide"/>'
    ...        '<geom size="0.1"/></body></worldbody></mujoco>')
    >>> system_from_metadata({"system": "mjcf", "model_xml": xml}).coords
    Coordinates(['a'])
    """
    if not isinstance(metadata, dict):
        raise TypeError(f"metadata: expected a dict, got {type(metadata).__name__}")
    name = metadata.get("system")
    if not name:
        raise ValueError("metadata: the dataset names no system")
    if name == MJCFSystem.name:
        path, xml = metadata.get("model_path"), metadata.get("model_xml")
        options = {"joints": metadata.get("joints")}
        recorded = metadata.get("parameters") or {}
        if "force_amplitude" in recorded:
            options["force_amplitude"] = recorded["force_amplitude"]
        options.update(parameters)
        if path and os.path.isfile(path):
            return MJCFSystem(path, **options)
        if xml:
            return MJCFSystem(xml, **options)
        raise ValueError("metadata: the dataset comes from a user's MJCF but records neither an "
                         f"existing model path ({path!r}) nor the model's XML; pass --system "
                         "PATH.xml")
    recorded = dict(metadata.get("parameters") or {})
    if isinstance(name, str) and name.strip().lower().replace("_", "-") in SYSTEMS:
        recorded.update(parameters)
        try:
            return get_system(name, **recorded)
        except TypeError:
            return get_system(name, **parameters)
    return get_system(name, **parameters)


def default_xml_path(name: str):
    """Path (a Traversable inside the package) of a registry system's packaged MJCF file.

    Parameters
    ----------
    name : str
        Registry name (``"cart-pole"``...; underscores accepted).

    Returns
    -------
    importlib.resources.abc.Traversable
        The packaged ``.xml`` file.

    Examples
    --------
    >>> default_xml_path("cart-pole").name
    'cart_pole.xml'
    """
    key = name.strip().lower().replace("_", "-")
    if key not in SYSTEMS:
        raise ValueError(f"name: unknown system {name!r}; expected one of {sorted(SYSTEMS)}")
    return resources.files("pysindy_xl.mujoco") / "models" / f"{key.replace('-', '_')}.xml"


# -- coordinates without an MJCF file ----------------------------------------------------------
def coordinate_system(names, angles=()):
    """A system description from coordinate names alone, for the reference catalogs.

    What :func:`pysindy_xl.mujoco.reference_catalog` and ``pysindy-xl identify`` need when
    there is no MJCF file: the coordinates (``["x", "theta"]`` or ``"x,theta"``), which are
    ``angles`` (through ``sin`` and ``cos``) and friction ``qd_i`` in equation ``i``. No true
    model (``has_ground_truth`` False), no simulation.

    Parameters
    ----------
    names : str or sequence of str
        Coordinate names, a sequence or one comma-separated string.
    angles : str or sequence of str, default=()
        The coordinates that are angles, by name (a sequence or one comma-separated string).

    Returns
    -------
    MuJoCoSystem
        A description without MJCF model (``has_ground_truth`` False): it cannot be simulated.

    Raises
    ------
    ValueError
        When a name is not a valid coordinate name, or an angle is not among the coordinates.

    Examples
    --------
    >>> from pysindy_xl.mujoco import reference_catalog
    >>> system = coordinate_system("x,theta", angles="theta")
    >>> system.coordinate_names, system.angle_coordinates
    (('x', 'theta'), (1,))
    >>> reference_catalog(system, "mixed", trig_degree=1).fit().n_output_features_
    20
    """
    if isinstance(names, str):
        names = [c.strip() for c in names.split(",") if c.strip()]
    if isinstance(angles, str):
        angles = [c.strip() for c in angles.split(",") if c.strip()]
    names, angles = tuple(names), tuple(angles)
    Coordinates(list(names))
    unknown = [a for a in angles if a not in names]
    if unknown:
        raise ValueError(f"angles: {unknown} not among the coordinates {list(names)}")

    class CoordinateSystem(MuJoCoSystem):
        name = "coordinates"
        has_ground_truth = False
        coordinate_names = names
        angle_coordinates = tuple(names.index(a) for a in angles)

        def __init__(self):
            self._parameters = {"coordinates": list(names), "angles": list(angles)}

        def friction_pattern(self):
            return np.eye(len(names), dtype=bool)

        def __repr__(self):
            return f"coordinate_system({list(names)}, angles={list(angles)})"

    return CoordinateSystem()
