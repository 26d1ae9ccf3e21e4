r"""An identified robot model as a MuJoCo model: physically consistent inertials.

A kinematic catalog's base parameters are linear images ``beta = C pi`` of the inertial
parameters ``pi`` (per body: mass ``m``, first moment ``h = m c``, inertia ``I`` about the
body frame's origin; per joint: armature). Rigid bodies realize ``pi`` exactly when each
pseudo-inertia is positive semidefinite and the armatures non-negative (Wensing, Kim and
Slotine, 2017),

.. math:: J_b = \begin{pmatrix} \tfrac12 \operatorname{tr}(I_b) \mathbb 1 - I_b & h_b \\
          h_b^T & m_b \end{pmatrix} \succeq 0.

:func:`consistent_parameters` solves the semidefinite program

.. math:: \min_\pi \; \|C \pi - \beta\|^2 / \|\beta\|^2 + \epsilon \|\pi - \pi_0\|^2 /
          \|\pi_0\|^2 \quad \text{s.t.} \quad J_b(\pi) \succeq 0, \; a_j \ge 0

and :func:`write_mjcf` writes the result into the template's MJCF with each joint's viscous
and dry friction. :func:`identified_mj_model` instead puts the least relative change
``pi = pi_0 + W (C W)^+ (beta - C pi_0)``, ``W = diag(|pi_0|)``, into a compiled copy of the
template and accepts it only where MuJoCo reproduces the identified equations.
"""

from __future__ import annotations

import numpy as np

__all__ = ["consistent_parameters", "write_mjcf", "to_mjcf", "identified_mj_model"]

#: Joint models MJCF cannot state (left out of the file, listed in ``dropped``).
_NOT_IN_MJCF = ("asymmetric", "stribeck", "offset")


def consistent_parameters(catalog, beta, closeness: float = 1e-6):
    """Physically consistent ``pi`` reproducing ``beta`` (module docstring): returns ``(pi,
    residual)``, ``residual = |C pi - beta| / |beta|`` zero when ``beta`` is realizable.
    ``closeness`` weighs the distance to the template's ``pi_0``.

    Parameters
    ----------
    catalog : KinematicCatalog
        The kinematic catalog of the template system
        (:func:`~pysindy_xl.mujoco.kinematic_catalog`).
    beta : array_like of shape (len(catalog.lagrange_terms),)
        Identified base parameters (:meth:`KinematicCatalog.lagrange_coefficients`).
    closeness : float, default=1e-6
        Weight of the distance to the template's physical parameters ``pi_0``.

    Returns
    -------
    pi : numpy.ndarray of shape (len(catalog.physical_names),)
        Physically consistent inertial parameters and armatures.
    residual : float
        ``|C pi - beta| / |beta|``, zero when ``beta`` is realizable.
    """
    from ..physical import PhysicalStructure, realize
    structure = PhysicalStructure.from_combination(list(catalog.physical_names),
                                                   catalog.combination)
    return realize(structure, beta, reference=catalog.physical_values, closeness=closeness)


def write_mjcf(catalog, pi, friction, path, joint_friction=None) -> str:
    """Write the catalog's system (its ``system``, an MJCF template) to ``path`` with inertial
    parameters ``pi`` (in the order of ``catalog.physical_names``) and joint friction; returns
    the MJCF text. ``friction`` is ``{coordinate: {"viscous", "dry"}}`` (as
    :meth:`XLSINDy.physical_parameters <pysindy_xl.XLSINDy.physical_parameters>` gives);
    ``joint_friction``, ``{joint: {"viscous", "coulomb"}}`` of a catalog built with
    ``friction=``, replaces it where a joint has them.

    Parameters
    ----------
    catalog : KinematicCatalog
        The kinematic catalog of the template system
        (:func:`~pysindy_xl.mujoco.kinematic_catalog`).
    pi : array_like of shape (len(catalog.physical_names),)
        Inertial parameters and armatures, in the order of ``catalog.physical_names``.
    friction : dict
        ``{coordinate: {"viscous": float, "dry": float}}`` (as
        :meth:`XLSINDy.physical_parameters <pysindy_xl.XLSINDy.physical_parameters>` gives).
    path : str or os.PathLike
        The file to write.
    joint_friction : dict, default=None
        ``{joint: {"viscous": float, "coulomb": float}}`` of a catalog built with ``friction=``;
        replaces ``friction`` where a joint has them.

    Returns
    -------
    str
        The MJCF text written.
    """
    from .._optional import import_mujoco
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
        inertia = _inertia_at_centre(values, body.name, mass, centre)
        body.explicitinertial = True
        body.mass = max(mass, 1e-9)
        body.ipos = centre
        body.iquat, body.inertia = _principal_axes(inertia)
        body.fullinertia = [np.nan] * 6  # unset: the principal axes state it
    for joint_name, coordinate in zip(system.joint_names, system.coordinate_names,
                                      strict=True):
        joint = spec.joint(joint_name)
        joint.armature = max(values.get(f"{joint_name}.armature", joint.armature), 0.0)
        viscous, dry = _joint_friction(joint_name, coordinate, joint_friction or {}, friction)
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


def _inertia_at_centre(values, body: str, mass, centre):
    """Inertia (3, 3) about the centre of mass (where MJCF states it) from the ``{body}.Ixx``,
    ``.Ixy``... of ``values`` about the body frame's origin (parallel-axis theorem)."""
    about_origin = np.array([[values[f"{body}.I{a}{b}" if f"{body}.I{a}{b}" in values
                                     else f"{body}.I{b}{a}"] for b in "xyz"] for a in "xyz"])
    return about_origin - mass * (centre @ centre * np.eye(3) - np.outer(centre, centre))


def _joint_friction(joint: str, coordinate: str, joint_friction: dict, friction: dict):
    """``(viscous, dry)`` of a joint: its own joint models where it has them, else the
    friction identified on its coordinate."""
    own = joint_friction.get(joint)
    if own is not None:
        return own.get("viscous", 0.0), own.get("coulomb", 0.0)
    return friction[coordinate]["viscous"], friction[coordinate]["dry"]


def _principal_axes(inertia):
    """``(quaternion, diagonal)`` of a symmetric inertia ``R diag(d) R^T`` (the form every MJCF
    template can take); moments are raised to a billionth of the largest, since MuJoCo refuses
    zero moments on a moving body."""
    from .._optional import import_mujoco
    mujoco = import_mujoco()

    moments, axes = np.linalg.eigh((inertia + inertia.T) / 2)
    if np.linalg.det(axes) < 0:
        axes[:, 0] = -axes[:, 0]
    floor = 1e-9 * max(float(moments.max()), 1e-12)
    quaternion = np.zeros(4)
    mujoco.mju_mat2Quat(quaternion, np.ascontiguousarray(axes).reshape(-1))
    return quaternion, np.maximum(moments, floor)


def to_mjcf(model, path, template) -> dict:
    """The body of :meth:`XLSINDy.to_mjcf <pysindy_xl.XLSINDy.to_mjcf>`.

    Parameters
    ----------
    model : pysindy_xl.XLSINDy
        A model fitted with ``kinematic_catalog(template).library()``.
    path : str or os.PathLike
        The MJCF file to write.
    template : str, os.PathLike or MuJoCoSystem
        The MJCF file (or system) whose kinematic tree the model was identified on; required
        (None raises a ValueError).

    Returns
    -------
    dict
        ``physical_parameters`` (``{name: value}``), ``residual`` (of
        :func:`consistent_parameters`) and ``dropped`` (joint friction models MJCF cannot
        state, by joint).

    Raises
    ------
    ValueError
        When ``template`` is None or does not match the model's catalog.
    """
    from ..mujoco.catalogs.kinematic import kinematic_catalog
    from ..mujoco.systems.mjcf import MJCFSystem
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


def identified_mj_model(model, system, tolerance: float = 1e-6, n_states: int = 6, seed=0):
    """The system's compiled MuJoCo model with a fitted model's parameters, or why not.

    Bodies get the identified inertials of least relative change (module docstring), joints
    their armature, stiffness, damping and ``frictionloss``. The result is accepted only if
    MuJoCo's ``mj_fullM`` and passive minus bias forces (minus ``frictionloss sign(qd)``) equal
    the model's ``M`` and ``f`` within ``tolerance`` at ``n_states`` random sliding states
    (drawn from ``seed``), with ``M`` positive definite: terms MJCF cannot state (other
    catalogs, held coordinates, asymmetric friction...) are refused.

    ``model`` is fitted with ``kinematic_catalog(system).library()`` on the
    :class:`~pysindy_xl.mujoco.MJCFSystem` ``system``. Returns ``(mj_model, None)`` or
    ``(None, reason)``.

    Parameters
    ----------
    model : pysindy_xl.XLSINDy
        A model fitted with ``kinematic_catalog(system).library()``.
    system : MJCFSystem
        The system the model was identified on.
    tolerance : float, default=1e-6
        Largest relative difference accepted between MuJoCo's and the model's ``M`` and ``f``.
    n_states : int, default=6
        Random sliding states at which they are compared.
    seed : int, default=0
        Seed of the states.

    Returns
    -------
    mj_model : mujoco.MjModel or None
        The model with the identified parameters, or None.
    reason : str or None
        None when accepted, else why MJCF cannot state the model.

    Examples
    --------
    >>> import pysindy_xl as px
    >>> from pysindy_xl.mujoco import MJCFSystem, generate_dataset, kinematic_catalog
    >>> system = MJCFSystem('''<mujoco><worldbody><body><joint name="j" axis="0 1 0"
    ...   damping="0.1" stiffness="0.5"/><geom type="capsule" fromto="0 0 0 0.3 0 0"
    ...   size="0.03"/></body></worldbody><actuator><motor joint="j"/></actuator></mujoco>''')
    >>> data = generate_dataset(system, n_trajectories=1, duration=1.0, seed=0,
    ...                         progress=False)
    >>> fitted = px.XLSINDy(kinematic_catalog(system).library(), px.ExplicitOptimizer())
    >>> mj_model, reason = identified_mj_model(fitted.fit(**data.fit_arguments()), system)
    >>> reason, round(float(mj_model.dof_damping[0]), 3), round(float(mj_model.jnt_stiffness[0]), 3)
    (None, 0.1, 0.5)
    """
    from .._optional import import_mujoco
    from ..mujoco.catalogs.kinematic import kinematic_catalog
    from ..mujoco.systems.friction import sliding_velocities
    from ..symbols import stack_variables
    mujoco = import_mujoco()

    try:
        catalog = kinematic_catalog(system)
        beta = catalog.lagrange_coefficients(model)
        dynamics = model._require_dynamics()
    except (ValueError, TypeError, AttributeError) as error:
        return None, f"not a kinematic-catalog model of this system ({error})"
    pi0 = np.asarray(catalog.physical_values, dtype=float)
    combination = np.asarray(catalog.combination, dtype=float)
    # the least change relative to each template value: a base parameter's correction lands
    # on the parameters it is made of in proportion to their size (not on a mass it barely
    # depends on, which the plain least-norm correction can drive negative)
    weight = np.abs(pi0) + 1e-6 * np.abs(pi0).max()
    pi = pi0 + weight * np.linalg.lstsq(combination * weight, beta - combination @ pi0,
                                        rcond=None)[0]
    values = dict(zip(catalog.physical_names, pi, strict=True))
    mj = system.mj_model()
    n = system.n
    if mj.nv != n or mj.nq != n or mj.neq:
        return None, "the MJCF has free, ball or equality-constrained joints"
    for body in range(1, mj.nbody):
        name = mujoco.mj_id2name(mj, mujoco.mjtObj.mjOBJ_BODY, body)
        if f"{name}.m" not in values:
            continue
        mass = values[f"{name}.m"]  # MuJoCo's algebra is linear in it: any sign will do
        if not abs(mass) > 1e-9 * max(abs(pi0).max(), 1.0):
            return None, f"body {name!r}: identified mass {mass:.3g} is zero"
        centre = np.array([values[f"{name}.mc{axis}"] for axis in "xyz"]) / mass
        inertia = _inertia_at_centre(values, name, mass, centre)
        moments, axes = np.linalg.eigh(inertia)  # a rotation: MuJoCo's principal axes
        if np.linalg.det(axes) < 0:
            axes[:, 0] = -axes[:, 0]
        mujoco.mju_mat2Quat(mj.body_iquat[body], np.ascontiguousarray(axes).reshape(-1))
        mj.body_mass[body], mj.body_ipos[body], mj.body_inertia[body] = mass, centre, moments
        # the inertial frame is no longer the body's own, nor is the inertia diagonal
        mj.body_sameframe[body] = mj.body_simple[body] = 0
    mj.dof_simplenum[:] = 0
    parameters = model.physical_parameters()
    joints = parameters.get("joint_friction", {})
    for joint, own in joints.items():
        extra = [m for m, v in own.items() if m in _NOT_IN_MJCF and v != 0]
        if extra:
            return None, f"joint {joint!r}: {', '.join(extra)} friction has no MJCF attribute"
    names = list(model.get_feature_names())
    scale = -1.0 / next(c for c, name in zip(model.coefficients(), names, strict=True)
                        if name.startswith("F["))
    for joint, coordinate in zip(system.joint_names, system.coordinate_names, strict=True):
        index = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_JOINT, joint)
        dof = mj.jnt_dofadr[index]
        viscous, dry = _joint_friction(joint, coordinate, joints, parameters["friction"])
        mj.dof_armature[dof] = values.get(f"{joint}.armature", mj.dof_armature[dof])
        mj.dof_damping[dof], mj.dof_frictionloss[dof] = viscous, dry
        spring = f"C_{coordinate}[{coordinate}]"  # a classical stiffness column, -k q
        mj.jnt_stiffness[index] = (model.coefficients()[names.index(spring)] * scale
                                   if spring in names else 0.0)
    # the template's derived constants are kept (mj_setConst not called): the constraint
    # softness of frictionloss scales with them, as in the reference run
    data = mujoco.MjData(mj)
    # the check: MuJoCo's M and f against the model's at random states
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, (n_states, n))
    qd = rng.uniform(0.5, 1.5, (n_states, n)) * rng.choice([-1.0, 1.0], (n_states, n))
    # where every joint slides, for the template's and the identified friction's scales
    qd = sliding_velocities(system, mj, q, sliding_velocities(system, system.mj_model(), q, qd))
    mass, force = dynamics.mass_and_forcing(stack_variables(q, qd, None, np.zeros((n_states, n)),
                                                            np.zeros(n_states)))
    if not np.all(np.linalg.eigvalsh(mass)[:, 0] > 0):
        return None, ("the identified mass matrix is not positive definite: MuJoCo cannot "
                      "factor it")
    matrix = system.force_matrix()
    qpos, qvel = system.from_generalized(q, qd)
    full = np.zeros((n, n))
    for k in range(n_states):
        data.qpos[:], data.qvel[:] = qpos[k], qvel[k]
        mujoco.mj_forward(mj, data)
        mujoco.mj_fullM(mj, data, full)
        mj_force = (data.qfrc_passive - data.qfrc_bias
                    - mj.dof_frictionloss * np.sign(data.qvel))
        mass_gap = np.abs(matrix @ full @ matrix.T - mass[k]).max() / np.abs(mass[k]).max()
        force_gap = np.abs(matrix @ mj_force - force[k]).max() / max(
            np.abs(force[k]).max(), 1e-12)
        if not (mass_gap <= tolerance and force_gap <= tolerance):
            return None, (f"MuJoCo with the identified parameters differs from the model "
                          f"(mass matrix {mass_gap:.2g}, forces {force_gap:.2g}): a term "
                          "MJCF cannot state")
    return mj, None
