r"""An identified robot model as a MuJoCo model: physically consistent inertials.

A kinematic catalog's base parameters ``beta`` are linear images of the bodies' inertial
parameters ``pi`` (per body: mass ``m``, first moment ``h = m c`` and inertia ``I`` about
the body frame's origin; per joint: armature), ``beta = C pi``. Rigid bodies realize ``pi``
exactly when each body's pseudo-inertia matrix is positive semidefinite (Wensing, Kim and
Slotine, 2017),

.. math:: J_b = \begin{pmatrix} \tfrac12 \operatorname{tr}(I_b) \mathbb 1 - I_b & h_b \\
          h_b^T & m_b \end{pmatrix} \succeq 0,

and armatures are non-negative. :func:`consistent_parameters` solves the semidefinite program

.. math:: \min_\pi \; \|C \pi - \beta\|^2 / \|\beta\|^2 + \epsilon \|\pi - \pi_0\|^2 /
          \|\pi_0\|^2 \quad \text{s.t.} \quad J_b(\pi) \succeq 0, \; a_j \ge 0

(cvxpy, :func:`pysindy_xl.physical.realize`): the consistent parameters that reproduce
``beta`` (exactly when it is realizable), among them the closest to the template's ``pi_0``.
:func:`write_mjcf` writes them into the template's MJCF with the identified viscous and dry
friction of each joint (``damping`` and ``frictionloss``; the asymmetric, Stribeck and
torque-offset models of real joints have no MJCF attribute and are left out).
"""

from __future__ import annotations

import numpy as np

__all__ = ["consistent_parameters", "write_mjcf", "to_mjcf"]

#: Joint models MJCF cannot state (left out of the file, listed in ``dropped``).
_NOT_IN_MJCF = ("asymmetric", "stribeck", "offset")


def consistent_parameters(catalog, beta, closeness: float = 1e-6):
    """Physically consistent inertial parameters reproducing base parameters ``beta``.

    Parameters
    ----------
    catalog : KinematicCatalog
        Its ``combination`` ``C`` and ``physical_values`` (the template's ``pi_0``).
    beta : array, shape (len(catalog.lagrange_terms),)
    closeness : float, default 1e-6
        Weight ``epsilon`` of the distance to the template's parameters.

    Returns
    -------
    pi : ndarray, shape (len(catalog.physical_names),)
    residual : float
        ``|C pi - beta| / |beta|``: zero (to the solver's tolerance) when ``beta`` is
        realizable by rigid bodies.
    """
    from ..physical import PhysicalStructure, realize

    structure = PhysicalStructure.from_combination(list(catalog.physical_names),
                                                   catalog.combination)
    return realize(structure, beta, reference=catalog.physical_values, closeness=closeness)


def write_mjcf(catalog, pi, friction, path, joint_friction=None) -> str:
    """Write the catalog's system with inertial parameters ``pi`` and joint friction.

    Parameters
    ----------
    catalog : KinematicCatalog
        Its ``system`` (an :class:`~pysindy_xl.mujoco.MJCFSystem`) is the template.
    pi : array
        In the order of ``catalog.physical_names``.
    friction : dict
        ``{coordinate name: {"viscous": ..., "dry": ...}}`` (as
        :meth:`XLSINDy.physical_parameters <pysindy_xl.XLSINDy.physical_parameters>` gives).
    path : str or os.PathLike
    joint_friction : dict, optional
        ``{joint name: {"viscous": ..., "coulomb": ...}}``, the joint models of a catalog
        built with ``friction=``: where a joint has them they give its ``damping`` and
        ``frictionloss`` instead of ``friction``.

    Returns
    -------
    str
        The MJCF text written.
    """
    from ..mujoco import import_mujoco

    mujoco = import_mujoco()

    system = catalog.system
    spec = mujoco.MjSpec.from_string(system.xml())
    values = dict(zip(catalog.physical_names, np.asarray(pi, dtype=float), strict=True))
    for body in spec.bodies:
        if f"{body.name}.m" not in values:
            continue
        mass = values[f"{body.name}.m"]
        moment = np.array([values[f"{body.name}.mc{axis}"] for axis in "xyz"])
        centre = moment / mass if mass > 0 else np.zeros(3)
        about_origin = np.array([[values[f"{body.name}.Ixx"], values[f"{body.name}.Ixy"],
                                  values[f"{body.name}.Ixz"]],
                                 [values[f"{body.name}.Ixy"], values[f"{body.name}.Iyy"],
                                  values[f"{body.name}.Iyz"]],
                                 [values[f"{body.name}.Ixz"], values[f"{body.name}.Iyz"],
                                  values[f"{body.name}.Izz"]]])
        # parallel-axis theorem back to the centre of mass, where MJCF states the inertia
        inertia = about_origin - mass * (centre @ centre * np.eye(3) - np.outer(centre, centre))
        body.explicitinertial = True
        body.mass = max(mass, 1e-9)
        body.ipos = centre
        body.iquat, body.inertia = _principal_axes(inertia)
        body.fullinertia = [np.nan] * 6  # unset: the principal axes state it
    for joint_name, coordinate in zip(system.joint_names, system.coordinate_names,
                                      strict=True):
        joint = spec.joint(joint_name)
        joint.armature = max(values.get(f"{joint_name}.armature", joint.armature), 0.0)
        own = (joint_friction or {}).get(joint_name)
        viscous, dry = ((own.get("viscous", 0.0), own.get("coulomb", 0.0)) if own is not None
                        else (friction[coordinate]["viscous"], friction[coordinate]["dry"]))
        damping = max(viscous, 0.0)
        if np.ndim(joint.damping):  # MuJoCo >= 4: a vector (its first entry: linear)
            joint.damping = [damping, *np.asarray(joint.damping)[1:]]
        else:
            joint.damping = damping
        joint.frictionloss = max(dry, 0.0)
    spec.compile()  # a model MuJoCo refuses is an error here, not when it is read
    text = spec.to_xml()
    with open(path, "w", encoding="utf-8") as handle:
        handle.write(text)
    return text


def _principal_axes(inertia):
    """``(quaternion, diagonal)`` of a symmetric inertia ``R diag(d) R^T`` (``R`` a proper
    rotation): the form every MJCF template can take, whichever way it stated its inertia
    (``diaginertia`` or ``fullinertia``, which MuJoCo refuses together). Moments below a
    billionth of the largest, a point mass's or a rod's, are raised to it: MuJoCo refuses
    zero moments on a moving body."""
    from ..mujoco import import_mujoco

    mujoco = import_mujoco()

    moments, axes = np.linalg.eigh((inertia + inertia.T) / 2)
    if np.linalg.det(axes) < 0:
        axes[:, 0] = -axes[:, 0]
    floor = 1e-9 * max(float(moments.max()), 1e-12)
    quaternion = np.zeros(4)
    mujoco.mju_mat2Quat(quaternion, np.ascontiguousarray(axes).reshape(-1))
    return quaternion, np.maximum(moments, floor)


def to_mjcf(model, path, template) -> dict:
    """The body of :meth:`XLSINDy.to_mjcf <pysindy_xl.XLSINDy.to_mjcf>`."""
    from ..mujoco import MJCFSystem, kinematic_catalog

    if template is None:
        raise ValueError("template: the MJCF file (or MuJoCo system) whose kinematic tree "
                         "the model was identified on is needed to place the inertials")
    system = template if hasattr(template, "mj_model") else MJCFSystem(template)
    catalog = kinematic_catalog(system)
    beta = catalog.lagrange_coefficients(model)
    pi, residual = consistent_parameters(catalog, beta)
    parameters = model.physical_parameters()
    joints = parameters.get("joint_friction", {})
    write_mjcf(catalog, pi, parameters["friction"], path, joints)
    # MJCF joints have damping and a symmetric frictionloss, nothing else
    dropped = {joint: {m: v for m, v in values.items() if m in _NOT_IN_MJCF and v != 0}
               for joint, values in joints.items()}
    return {"physical_parameters": dict(zip(catalog.physical_names, pi.tolist(), strict=True)),
            "residual": residual,
            "dropped": {joint: values for joint, values in dropped.items() if values}}
