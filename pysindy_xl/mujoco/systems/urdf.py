"""URDF robot descriptions as MJCF: what :class:`~pysindy_xl.mujoco.MJCFSystem` reads.

MuJoCo compiles URDF itself; :func:`urdf_spec` settles the rest: every ``<visual>`` and
``<collision>`` is dropped (``package://`` meshes are rarely shipped; identification needs the
inertials only), fixed joints are fused into their parents (a ``<mujoco><compiler/>`` element
still sets MuJoCo's options), and each hinge and slide joint gets a motor (gear 1, named like
its joint; an effort limit becomes ``actuatorfrcrange``). Inertia tensors no rigid body has are
balanced by MuJoCo, with a warning naming the links.
"""

from __future__ import annotations

import os
import warnings
import xml.etree.ElementTree as ET

import numpy as np

from ..._optional import import_mujoco

__all__ = ["urdf_spec", "urdf_to_mjcf", "is_urdf"]


def is_urdf(source) -> bool:
    """Whether ``source`` (a path or XML text) is a URDF robot description.

    Parameters
    ----------
    source : str or os.PathLike
        A path or XML text.

    Returns
    -------
    bool
        True for a ``.urdf`` path or text whose root element is ``<robot>``.

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
    """The URDF robot as a compilable MuJoCo spec, without meshes and with a motor per joint.

    What changes on the way: see the module docstring. Compiling the spec keeps the URDF's
    numbers exactly. ``where`` names the argument or file in errors; ``warn``: warn when
    inertias had to be balanced. ValueError when the text is not a URDF or does not compile.

    Parameters
    ----------
    text : str
        The URDF document.
    where : str, default="source"
        The argument or file named in error messages.
    warn : bool, default=True
        Warn when inertias had to be balanced.

    Returns
    -------
    mujoco.MjSpec
        The spec; ``.compile()`` gives the model.

    Raises
    ------
    ValueError
        When the text is not a URDF or does not compile.

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
            spec.add_actuator(name=joint.name, target=joint.name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
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
    """The MJCF text of a URDF robot: :func:`urdf_spec` written out (six significant digits).

    Parameters
    ----------
    text : str
        The URDF document.
    where : str, default="source"
        The argument or file named in error messages.

    Returns
    -------
    str
        The MJCF document.
    """
    return urdf_spec(text, where).to_xml()
