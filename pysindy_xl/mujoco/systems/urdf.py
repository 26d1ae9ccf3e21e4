"""URDF robot descriptions as MJCF: what :class:`~pysindy_xl.mujoco.MJCFSystem` reads.

MuJoCo compiles URDF itself (its parser keeps the ``<inertial>`` of every link, the joint
axes, origins, limits, ``damping`` and ``friction``); three things stand between a robot's
URDF and a model the package can use, and :func:`urdf_to_mjcf` settles them:

- **Meshes.** A URDF names its visual and collision meshes (``package://...`` files that
  travel with the robot's ROS package, rarely with the URDF). Identification needs the
  inertials only, so every ``<visual>`` and ``<collision>`` element is dropped: the URDF
  loads without its meshes, and the compiled model has no geometry (no contacts, and a
  link without ``<inertial>`` is massless, as URDF says).
- **Fixed joints.** A link attached by a fixed joint is fused into its parent (MuJoCo's
  ``fusestatic``, on by default for URDF): its mass and inertia load the parent body, and
  the mass matrix is unchanged; a ``<mujoco><compiler .../></mujoco>`` element in the URDF
  still sets MuJoCo's options (``fusestatic="false"`` keeps such links as welded bodies).
- **Actuators.** URDF has none; a robot's joints are torque-driven, so each hinge and slide
  joint gets a motor (gear 1, named like its joint; an effort limit becomes MuJoCo's
  ``actuatorfrcrange``), and the joint torques of a log are its controls.

Published URDFs sometimes carry inertia tensors that no rigid body has (principal moments
violating ``A + B >= C``); MuJoCo refuses them, and the conversion then lets MuJoCo balance
them (``balanceinertia``: all three principal moments set to their mean) and warns, naming the
links. The kinematic catalog does not depend on the inertias (its terms come from the
kinematics alone), only the model's reference parameter values do.
"""

from __future__ import annotations

import os
import warnings
import xml.etree.ElementTree as ET

import numpy as np

from .. import import_mujoco

__all__ = ["urdf_spec", "urdf_to_mjcf", "is_urdf"]


def is_urdf(source) -> bool:
    """Whether ``source`` (a path or XML text) is a URDF robot description.

    Examples
    --------
    >>> is_urdf("arm.urdf"), is_urdf('<robot name="r"><link name="a"/></robot>')
    (True, True)
    >>> is_urdf("<mujoco/>"), is_urdf("arm.xml")
    (False, False)
    """
    if isinstance(source, os.PathLike):
        source = os.fspath(source)
    if not isinstance(source, str):
        return False
    text = source.lstrip()
    if text.startswith("<"):
        body = text
        while body.startswith(("<?", "<!--")):  # declaration and leading comments
            end = body.find("?>" if body.startswith("<?") else "-->")
            if end < 0:
                return False
            body = body[end + (2 if body.startswith("<?") else 3):].lstrip()
        return body.startswith("<robot")
    return source.lower().endswith(".urdf")


def _violating_links(root) -> list:
    """Links whose inertia tensor has principal moments with ``A + B < C``."""
    names = []
    for link in root.iter("link"):
        inertia = link.find("inertial/inertia")
        if inertia is None:
            continue
        value = {k: float(inertia.get(k, 0.0)) for k in
                 ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")}
        tensor = np.array([[value["ixx"], value["ixy"], value["ixz"]],
                           [value["ixy"], value["iyy"], value["iyz"]],
                           [value["ixz"], value["iyz"], value["izz"]]])
        moments = np.linalg.eigvalsh(tensor)
        if moments[0] + moments[1] < moments[2] * (1 - 1e-9):
            names.append(link.get("name"))
    return names


def urdf_spec(text: str, where: str = "source", warn: bool = True):
    """The URDF robot as a MuJoCo spec, without meshes and with a motor on every joint.

    See the module documentation for what changes on the way (meshes, fixed joints,
    actuators, inertias that no rigid body has). Compiling the spec keeps the URDF's numbers
    exactly; :func:`urdf_to_mjcf` writes them as MJCF text (to six significant digits).

    Parameters
    ----------
    text : str
        The URDF text.
    where : str, default "source"
        Name of the argument or file in error messages.
    warn : bool, default True
        Warn when inertias had to be balanced.

    Returns
    -------
    mujoco.MjSpec
        A spec that compiles (``spec.compile()``).

    Raises
    ------
    ValueError
        If the text is not a URDF or MuJoCo cannot compile it.

    Examples
    --------
    >>> urdf = '''<robot name="arm">
    ...   <link name="base"/>
    ...   <link name="upper"><inertial><origin xyz="0 0 -0.5"/><mass value="1"/>
    ...     <inertia ixx="0.02" iyy="0.02" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    ...     <visual><geometry><mesh filename="package://arm/upper.stl"/></geometry></visual>
    ...   </link>
    ...   <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    ...     <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="10" velocity="3"/></joint>
    ... </robot>'''
    >>> model = urdf_spec(urdf).compile()
    >>> model.njnt, model.nu, model.ngeom, round(float(model.body_mass[1]), 6)
    (1, 1, 0, 1.0)
    >>> '<general name="shoulder" joint="shoulder"/>' in urdf_to_mjcf(urdf)  # a motor
    True
    """
    mujoco = import_mujoco()
    try:
        root = ET.fromstring(text)
    except ET.ParseError as error:
        raise ValueError(f"{where}: not valid URDF XML ({error})") from None
    if root.tag != "robot":
        raise ValueError(f"{where}: expected a URDF <robot> element, got <{root.tag}>")
    for link in root.iter("link"):
        for child in [c for c in link if c.tag in ("visual", "collision")]:
            link.remove(child)
    try:
        spec = mujoco.MjSpec.from_string(ET.tostring(root, encoding="unicode"))
    except ValueError as error:
        raise ValueError(f"{where}: MuJoCo cannot read the URDF: {error}") from None
    for joint in spec.joints:
        if joint.type in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
            spec.add_actuator(name=joint.name, target=joint.name,
                              trntype=mujoco.mjtTrn.mjTRN_JOINT)
    try:
        spec.compile()
    except ValueError as error:
        if "balanceinertia" not in str(error):
            raise ValueError(f"{where}: MuJoCo cannot compile the URDF: {error}") from None
        spec.compiler.balanceinertia = True
        try:
            spec.compile()
        except ValueError as again:
            raise ValueError(f"{where}: MuJoCo cannot compile the URDF: {again}") from None
        if warn:
            warnings.warn(
                f"{where}: the inertia tensors of links {_violating_links(root)} are no rigid "
                "body's (principal moments with A + B < C); MuJoCo balanced them (each set to "
                "the mean of its principal moments). The kinematic catalog does not depend on "
                "them; the model's reference inertias do",
                UserWarning, stacklevel=3)
    return spec


def urdf_to_mjcf(text: str, where: str = "source") -> str:
    """The MJCF text of a URDF robot: :func:`urdf_spec` written out (MuJoCo writes its numbers
    to six significant digits).

    Parameters
    ----------
    text : str
        The URDF text.
    where : str, default "source"
        Name of the argument or file in error messages.

    Returns
    -------
    str
    """
    return urdf_spec(text, where).to_xml()
