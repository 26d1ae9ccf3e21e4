"""MuJoCo models of the paper's mechanical systems and of user-supplied MJCF files.

Every system couples an MJCF model with the textbook description of the same mechanism:
generalized coordinates, Lagrangian, friction and the map between MuJoCo's joint coordinates
and the textbook ones.

Coordinate conventions
----------------------
Angles are absolute and measured from the downward vertical (``theta = 0`` hanging down,
positive counter-clockwise seen from the front, so a bob sits at ``(l sin theta, -l cos theta)``
in the plane ``x``-up); cart positions ``x`` are along the horizontal axis.

MuJoCo's hinge angles along a chain are *relative*: the second hinge of a double pendulum
measures ``phi2 = theta2 - theta1``. All our systems use a linear map ``q = T @ qpos``
(:attr:`MuJoCoSystem.joint_to_coordinates`), applied alike to velocities and accelerations.

Forces and friction follow from virtual work. A joint force vector ``u`` (one entry per MuJoCo
degree of freedom, what actuators and joint damping produce) does the work ``u . dphi =
u . T^-1 dq``, so the generalized force on the textbook coordinates is ``B @ u`` with
``B = T^-T`` (:meth:`MuJoCoSystem.force_matrix`). A motor between two links (relative hinge)
therefore pushes the outer link forward and the inner one back: ``B`` for the double pendulum is
``[[1, -1], [0, 1]]``. Joint damping ``-c_k dphi_k/dt`` on a relative hinge likewise becomes the
generalized friction ``-B C T^-1 qd``: it couples the absolute coordinates (the equation of
``theta1`` feels ``theta2_dot``). :meth:`MuJoCoSystem.friction` returns these terms with the
library's sign convention (the term ``qd_j`` in the equation of ``i`` with coefficient
``(B C T^-1)[i, j]``, so that ``EL(L) + friction = B @ u``).

Point masses are modelled with explicit ``<inertial>`` elements (a tiny rotational inertia
``point_inertia``, which the Lagrangian includes exactly) so that the geoms, drawn only for
visualisation, add no mass. Contacts are disabled and the integrator is RK4 with a small time
step, so that MuJoCo's trajectories follow the continuous equations closely.

The base class and its conventions are in ``_system_base``, the paper's systems in
:mod:`pysindy_xl.mujoco.systems.paper`, user MJCF files in :mod:`pysindy_xl.mujoco.systems.mjcf`;
this module is the registry and keeps every name importable from here.
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


SYSTEMS = {
    CartPole.name: CartPole,
    DoublePendulum.name: DoublePendulum,
    CartDoublePendulum.name: CartDoublePendulum,
    TriplePendulum.name: TriplePendulum,
}


def get_system(name, **parameters) -> MuJoCoSystem:
    """A system by registry name, or a :class:`MJCFSystem` for a path to an MJCF file.

    Parameters
    ----------
    name : str, os.PathLike or MuJoCoSystem
        ``"cart-pole"``, ``"double-pendulum"``, ``"cart-double-pendulum"``,
        ``"triple-pendulum"`` (underscores accepted), a path to an MJCF ``.xml`` or a URDF
        ``.urdf`` file (or to any existing file, read as MJCF), MJCF text, or a system
        (returned as is).
    **parameters
        Passed to the system's constructor.

    Returns
    -------
    MuJoCoSystem

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
    raise ValueError(
        f"name: unknown system {name!r}; expected one of {sorted(SYSTEMS)} or a path to an "
        "MJCF .xml or URDF .urdf file"
    )


def system_from_metadata(metadata: dict, **parameters) -> MuJoCoSystem:
    """The system a dataset was generated with, from its metadata.

    Registry systems are rebuilt with their recorded parameters; a user's MJCF from its
    recorded path when the file still exists, otherwise from the embedded XML, with the same
    joint selection.

    Parameters
    ----------
    metadata : dict
        ``Dataset.metadata`` (keys ``system``, ``parameters``, and for MJCF models
        ``model_path``, ``model_xml``, ``joints``).
    **parameters
        Override recorded constructor parameters.

    Returns
    -------
    MuJoCoSystem

    Raises
    ------
    ValueError
        If the metadata name no system, or an MJCF dataset records neither path nor XML.

    Examples
    --------
    >>> system_from_metadata({"system": "cart-pole", "parameters": {"pole_mass": 0.3}})
    CartPole(cart_mass=1.0, pole_mass=0.3, length=0.8, cart_damping=0.5, pole_damping=0.1, \
gravity=9.81, point_inertia=1e-06, timestep=0.001)
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
        raise ValueError(
            "metadata: the dataset comes from a user's MJCF but records neither an existing "
            f"model path ({path!r}) nor the model's XML; pass --system PATH.xml"
        )
    recorded = dict(metadata.get("parameters") or {})
    if isinstance(name, str) and name.strip().lower().replace("_", "-") in SYSTEMS:
        recorded.update(parameters)
        try:
            return get_system(name, **recorded)
        except TypeError:
            return get_system(name, **parameters)
    return get_system(name, **parameters)


def default_xml_path(name: str):
    """Path of the packaged MJCF file of a system with default parameters.

    Parameters
    ----------
    name : str
        ``"cart-pole"``, ``"double-pendulum"``, ``"cart-double-pendulum"`` or
        ``"triple-pendulum"`` (underscores
        accepted).

    Returns
    -------
    importlib.resources.abc.Traversable
        The file inside the installed package (a :class:`pathlib.Path` for a regular install).

    Raises
    ------
    ValueError
        If ``name`` is not a packaged system.

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

    What :func:`pysindy_xl.mujoco.reference_catalog` and ``pysindy-xl identify`` need from a
    system when there is no MJCF file: the coordinates, which of them are angles (they enter
    the catalog through ``sin`` and ``cos``) and friction ``qd_i`` in the equation of ``i``.
    No true model, no simulation.

    Parameters
    ----------
    names : list of str or str
        Coordinate names (``["x", "theta"]`` or ``"x,theta"``).
    angles : list of str or str, default ()
        The names among ``names`` that are angles.

    Returns
    -------
    MuJoCoSystem
        With ``name`` "coordinates", ``has_ground_truth`` False.

    Raises
    ------
    ValueError
        If an angle is not among the coordinates, or a name is not a valid symbol name.

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
