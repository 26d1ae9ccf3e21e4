"""A MuJoCo integration that is stable and faithful, chosen from the model; checks of every run.

Implicit steps (``implicit``, ``implicitfast``; ``Euler`` for joint damping) bias the inertia:
the positions obey ``(M + h D) qdd = f``. RK4 is stable only while ``h |lambda|`` stays small,
``lambda`` the eigenvalues of ``A = [[0, 1], [-M^-1 K, -M^-1 D]]`` (``K``, ``D``: the servos'
gains, joint stiffness and damping; ``M``: ``mj_fullM``). :func:`choose_integration` prices
both remedies in substeps (``RK4_BOUND``, ``BIAS_TOLERANCE``, ``RK4_COST``) and takes the
cheaper, but keeps RK4 (no inertia bias) up to ``RK4_MAX_SUBSTEPS`` even where it costs more.
A run driven by a time-varying control holds it over each step, which a stiff servo turns
into an error of order ``(h |lambda|)^2`` in the positions: there RK4 keeps the tighter
``RK4_HELD_BOUND`` (``choose_integration(held_control=True)``, as
:func:`~pysindy_xl.mujoco.generate_dataset` asks for forced runs), and with it the larger
ceiling ``RK4_HELD_MAX_SUBSTEPS``: the same model stiffness ``timestep |lambda|`` as the
ceiling of an unforced run, so a tighter bound does not hand a model to the biased implicit
step. :func:`check_run` raises :class:`UnstableSimulationError` on a run that left the
physics. :doc:`/robot_arms` explains the choice.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from .._optional import import_mujoco

__all__ = ["Integration", "choose_integration", "linear_modes", "UnstableSimulationError",
           "INTEGRATORS", "RK4_BOUND", "RK4_HELD_BOUND", "BIAS_TOLERANCE", "RK4_COST",
           "RK4_MAX_SUBSTEPS", "RK4_HELD_MAX_SUBSTEPS", "MAX_HINGE_VELOCITY",
           "MAX_SLIDE_VELOCITY"]

#: MuJoCo's integrators by name.
INTEGRATORS = {"Euler": 0, "RK4": 1, "implicit": 2, "implicitfast": 3}

#: Largest ``h |lambda|`` of an RK4 step: inside its stability region, and small enough that
#: a constant control does not ring the stiff servo modes.
RK4_BOUND = 0.25
#: Largest ``h |lambda|`` of an RK4 step under a time-varying control (``held_control``): the
#: control is held over each step, and the positions a stiff servo drives then depart from
#: the continuous equations under the recorded forces by 0.1-1 % of the
#: inertial force at ``RK4_BOUND``, falling as ``(h |lambda|)^2``; a fitted arm's inertias
#: absorb it.
RK4_HELD_BOUND = 0.05
#: Largest inertia bias ``h max_i D_ii`` of an implicit step, relative to ``max |M_ij|``.
BIAS_TOLERANCE = 5e-3
#: Cost of an RK4 step in implicit steps (four evaluations against one and a factorization),
#: measured in :func:`~pysindy_xl.simulation.generate.simulate_trajectory`'s loop (``mj_step``
#: and the control's update): 2.8-3.8 over two runs, median 3.2, on nine published 6-7 joint
#: arms (``benchmarks/integration_cost.py``). A constant, not a timing at run time, so that
#: the choice, and with it the data, do not depend on the machine or its load.
RK4_COST = 3.3
#: RK4 (no inertia bias at all) is kept up to this many substeps even where it costs more.
RK4_MAX_SUBSTEPS = 64
#: The same under a held control (``held_control``): the ceiling of the same model stiffness
#: ``timestep |lambda| <= RK4_MAX_SUBSTEPS RK4_BOUND`` as without one (320 = 64 x 0.25 / 0.05).
#: There the implicit step's inertia bias (up to ``BIAS_TOLERANCE``) is the larger error: on
#: published arms whose stiffest servo mode needs 80-243 RK4 substeps it raises the identified
#: mass matrix's error by up to 0.3 points, at 1 % noise (``benchmarks/published_arms.py``).
RK4_HELD_MAX_SUBSTEPS = round(RK4_MAX_SUBSTEPS * RK4_BOUND / RK4_HELD_BOUND)
#: Velocity bound of a sane run: hinge joints (rad/s) and slide joints (m/s).
MAX_HINGE_VELOCITY = 100.0
MAX_SLIDE_VELOCITY = 20.0


class UnstableSimulationError(RuntimeError):
    """A MuJoCo run that left the physics (NaN, huge accelerations or velocities, energy growth).

    Examples
    --------
    A run that leaves the physics raises it; it is a :class:`RuntimeError`:

    >>> issubclass(UnstableSimulationError, RuntimeError)
    True
    """


@dataclass
class Integration:
    """How a MuJoCo model is integrated: integrator, substeps per model step, and why.

    ``integrator`` is a key of :data:`INTEGRATORS`; ``reason`` is kept in the dataset
    metadata; ``rate`` and ``damping_rate`` are those of :func:`linear_modes`; ``timestep``
    the model's (s).

    Parameters
    ----------
    integrator : str
        A key of :data:`INTEGRATORS` (``"RK4"``, ``"implicit"``...).
    substeps : int
        Internal steps per model step.
    reason : str
        Why this integration was chosen (kept in the dataset metadata).
    rate : float
        Largest ``|lambda|`` of the linearized joint dynamics (1/s; :func:`linear_modes`).
    damping_rate : float
        Largest ``max_i D_ii / max |M_ij|`` (1/s; :func:`linear_modes`).
    timestep : float
        The model's time step (s).

    Examples
    --------
    >>> Integration("RK4", 3, "example", 2.7e3, 150.0, 0.002).step
    0.0006666666666666666
    """

    integrator: str
    substeps: int
    reason: str
    rate: float
    damping_rate: float
    timestep: float

    @property
    def step(self) -> float:
        """The internal step ``timestep / substeps`` (s)."""
        return self.timestep / self.substeps

    @property
    def stability(self) -> float:
        """``h |lambda|`` of the internal step (RK4 is stable below about 2.8)."""
        return self.step * self.rate

    @property
    def bias(self) -> float:
        """Inertia bias ``h max D_ii / max |M_ij|`` an implicit step would add at this step."""
        return self.step * self.damping_rate

    def to_dict(self) -> dict:
        """JSON-serializable description (the fields plus ``step``, ``stability``, ``bias``).

        Returns
        -------
        dict
            The fields plus ``step``, ``stability`` and ``bias``.
        """
        return {**asdict(self), "step": self.step, "stability": self.stability, "bias": self.bias}


def _stiffness(model, data) -> tuple[np.ndarray, np.ndarray]:
    """``K``, ``D`` (nv x nv) of the servos, joint springs and damping at ``data``'s pose."""
    mujoco = import_mujoco()
    mujoco.mj_forward(model, data)
    moments = np.zeros((model.nu, model.nv))
    if model.nu:
        mujoco.mju_sparse2dense(moments, data.actuator_moment, data.moment_rownnz,
                                data.moment_rowadr, data.moment_colind)
    affine = model.actuator_biastype == int(mujoco.mjtBias.mjBIAS_AFFINE)
    kp = np.where(affine, -model.actuator_biasprm[:, 1], 0.0)
    kv = np.where(affine, -model.actuator_biasprm[:, 2], 0.0)
    stiffness = np.diag(model.jnt_stiffness[model.dof_jntid])
    damping = np.diag(model.dof_damping.copy())
    return (stiffness + moments.T @ (kp[:, None] * moments),
            damping + moments.T @ (kv[:, None] * moments))


def _poses(model, n_poses: int, seed) -> np.ndarray:
    """The reference pose and ``n_poses - 1`` random poses inside the joint ranges."""
    mujoco = import_mujoco()
    rng = np.random.default_rng(seed)
    poses = np.tile(model.qpos0, (n_poses, 1))
    for j in range(model.njnt):
        kind = int(model.jnt_type[j])
        if kind not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            continue
        low, high = model.jnt_range[j] if model.jnt_limited[j] else (-np.pi, np.pi)
        poses[1:, model.jnt_qposadr[j]] = rng.uniform(low, high, n_poses - 1)
    return poses


def _linearized(model, n_poses: int, seed):
    """``K``, ``D`` (:func:`_stiffness`) and ``M`` (``mj_fullM``) at each pose of :func:`_poses`."""
    mujoco = import_mujoco()
    data = mujoco.MjData(model)
    for pose in _poses(model, max(int(n_poses), 1), seed):
        data.qpos[:] = pose
        stiffness, damping = _stiffness(model, data)
        mass = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, mass)
        yield stiffness, damping, mass


def linear_modes(model, n_poses: int = 8, seed=0) -> tuple[float, float]:
    """Stiffness of a model's linearized joint dynamics over ``qpos0`` and random poses.

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.
    n_poses : int, default=8
        Poses examined: ``qpos0`` and ``n_poses - 1`` random poses inside the joint ranges.
    seed : int, default=0
        Seed of the random poses.

    Returns
    -------
    rate : float
        The largest ``|lambda|`` (1/s).
    damping_rate : float
        The largest ``max_i D_ii / max |M_ij|`` (1/s).

    Examples
    --------
    Returns ``rate``, the largest ``|lambda|`` (1/s) of ``A`` (module docstring), and
    ``damping_rate``, the largest ``max_i D_ii / max |M_ij|`` (1/s), over ``n_poses`` poses.
    A 1e-3 kg m^2 link under a servo with kp = 100, kv = 10 (lambda = -1e4 and -10 1/s):

    >>> import mujoco
    >>> model = mujoco.MjModel.from_xml_string('''<mujoco><worldbody><body>
    ...   <joint name="j" axis="0 0 1"/>
    ...   <inertial pos="0 0 0" mass="1" diaginertia="1e-3 1e-3 1e-3"/></body></worldbody>
    ...   <actuator><position joint="j" kp="100" kv="10"/></actuator></mujoco>''')
    >>> rate, damping_rate = linear_modes(model)
    >>> round(rate), round(damping_rate)
    (9990, 10000)
    """
    nv = model.nv
    rate = damping_rate = 0.0
    for stiffness, damping, mass in _linearized(model, n_poses, seed):
        state = np.block([[np.zeros((nv, nv)), np.eye(nv)],
                          [-np.linalg.solve(mass, stiffness), -np.linalg.solve(mass, damping)]])
        rate = max(rate, float(np.abs(np.linalg.eigvals(state)).max()))
        damping_rate = max(damping_rate, float(damping.diagonal().max() / np.abs(mass).max()))
    return rate, damping_rate


def choose_integration(model, integrator: str = "auto", substeps: int | None = None,
                       n_poses: int = 8, held_control: bool = False) -> Integration:
    """The integration of a MuJoCo model: stable and faithful to the continuous equations.

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.
    integrator : str, default="auto"
        ``"auto"``, ``"model"`` or an integrator name.
    substeps : int or None, default=None
        With ``"auto"`` a lower bound, otherwise the number (None: 1).
    n_poses : int, default=8
        Poses of :func:`linear_modes`.
    held_control : bool, default=False
        With ``"auto"``: the run is driven by a time-varying control, held over each step.
        RK4 then also keeps ``h |lambda| <= RK4_HELD_BOUND`` (accuracy, not only stability:
        module constants) and is kept up to ``RK4_HELD_MAX_SUBSTEPS`` substeps instead of
        ``RK4_MAX_SUBSTEPS``.

    Returns
    -------
    Integration
        The integrator, substeps and the reason for them.

    Examples
    --------
    ``integrator``: ``"auto"``, the cheaper of RK4 and the model's implicit step that is
    stable and faithful (module docstring); ``"model"``, as authored; a name, that integrator.
    ``substeps``: with ``"auto"`` a lower bound, otherwise the number (default 1).
    ``n_poses``: poses of :func:`linear_modes`. A stiff servo (kv = 300) on a light link
    (1e-3 kg m^2) at MuJoCo's 2 ms step:

    >>> import mujoco
    >>> model = mujoco.MjModel.from_xml_string('''<mujoco><option integrator="implicitfast"/>
    ...   <worldbody><body><joint name="j" axis="0 0 1"/>
    ...   <inertial pos="0 0 0" mass="1" diaginertia="1e-3 1e-3 1e-3"/></body></worldbody>
    ...   <actuator><position joint="j" kp="3000" kv="300"/></actuator></mujoco>''')
    >>> choice = choose_integration(model)
    >>> choice.integrator, choice.substeps, choice.stability <= RK4_BOUND
    ('RK4', 2400, True)
    """
    from .._validation import check_option
    check_option("integrator", integrator, "choice", choices=("auto", "model", *INTEGRATORS))
    if substeps is not None:
        substeps = check_option("substeps", substeps, "int", low=1)
    timestep = float(model.opt.timestep)
    authored = next(name for name, value in INTEGRATORS.items()
                    if value == int(model.opt.integrator))
    rate, damping_rate = linear_modes(model, n_poses)
    if integrator != "auto":
        name = authored if integrator == "model" else integrator
        return Integration(name, substeps or 1, f"{name} as requested", rate, damping_rate,
                           timestep)
    floor = substeps or 1
    bound, ceiling = ((RK4_HELD_BOUND, RK4_HELD_MAX_SUBSTEPS) if held_control
                      else (RK4_BOUND, RK4_MAX_SUBSTEPS))
    rk4 = max(floor, math.ceil(timestep * rate / bound))
    if damping_rate == 0 and authored in ("RK4", "Euler"):
        if authored == "RK4" or timestep * rate / floor < 1.0:
            return Integration(authored, floor, f"the model's {authored}: no velocity-"
                               "dependent force to bias, stable at the model's step", rate,
                               damping_rate, timestep)
    implicit = authored if authored in ("implicit", "implicitfast") else "implicitfast"
    implicit_steps = max(floor, math.ceil(timestep * damping_rate / BIAS_TOLERANCE))
    while not _implicit_stable(model, timestep / implicit_steps, n_poses):
        implicit_steps *= 2
    step = timestep * 1e3
    if rk4 <= ceiling or RK4_COST * rk4 <= implicit_steps:
        reason = (f"RK4 at {step:g} ms / {rk4}: the stiffest mode (|lambda| = {rate:.3g} 1/s, "
                  f"servo gains and damping over the inertia) keeps h |lambda| <= {bound:g}; "
                  f"the {implicit} step would need {implicit_steps} substeps to keep its inertia "
                  f"bias h (kv + damping) below {BIAS_TOLERANCE:.1%} of the mass matrix")
        return Integration("RK4", rk4, reason, rate, damping_rate, timestep)
    reason = (f"{implicit} at {step:g} ms / {implicit_steps}: its inertia bias h (kv + damping)"
              f" stays below {BIAS_TOLERANCE:.1%} of the mass matrix; RK4 would need {rk4} "
              f"substeps (|lambda| = {rate:.3g} 1/s)")
    return Integration(implicit, implicit_steps, reason, rate, damping_rate, timestep)


def _implicit_stable(model, step: float, n_poses: int) -> bool:
    """Whether MuJoCo's implicit step (damping implicit, springs explicit) is stable at ``step``.

    The linearized step is ``v' = v + h (M + h D)^-1 (-K x - D v)``, ``x' = x + h v'``.
    """
    nv = model.nv
    for stiffness, damping, mass in _linearized(model, n_poses, 0):
        solve = np.linalg.solve(mass + step * damping, np.hstack([stiffness, damping]))
        velocity = np.hstack([-step * solve[:, :nv], np.eye(nv) - step * solve[:, nv:]])
        position = np.hstack([np.eye(nv), np.zeros((nv, nv))]) + step * velocity
        radius = np.abs(np.linalg.eigvals(np.vstack([position, velocity]))).max()
        if radius > 1 + 1e-9:
            return False
    return True


def check_run(model, qpos, qvel, qacc, energy=None, bad_accelerations: int = 0,
              integration: Integration | None = None, label: str = "MuJoCo run") -> dict:
    """Check a finished MuJoCo run; raise on any sign of a numerical instability.

    ``qpos, qvel, qacc`` (T, nq), (T, nv), (T, nv) are the recorded states; ``energy``
    (T, 2), of an unforced run, MuJoCo's potential and kinetic energy (growth of their sum
    beyond 5 % of the largest kinetic energy plus the potential's range is an instability);
    ``bad_accelerations`` MuJoCo's ``mjWARN_BADQACC`` count; ``integration`` and ``label``
    are named in the :class:`UnstableSimulationError`, with the option to change.
    Returns ``peak_velocity`` (the largest ``|qvel|``) and ``velocity_bound`` by joint.

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.
    qpos : numpy.ndarray of shape (T, nq)
        Recorded positions.
    qvel, qacc : numpy.ndarray of shape (T, nv)
        Recorded velocities and accelerations.
    energy : numpy.ndarray of shape (T, 2), default=None
        Potential and kinetic energy of an unforced run; None skips the energy check.
    bad_accelerations : int, default=0
        MuJoCo's ``mjWARN_BADQACC`` count.
    integration : Integration or None, default=None
        Named in the error, with the option to change.
    label : str, default="MuJoCo run"
        Names the run in the error.

    Returns
    -------
    dict
        ``{"peak_velocity": {joint: float}, "velocity_bound": {joint: float}}``.

    Raises
    ------
    UnstableSimulationError
        On NaN, huge accelerations or velocities, or energy growth.

    Examples
    --------
    >>> import mujoco
    >>> model = mujoco.MjModel.from_xml_string(
    ...     '<mujoco><worldbody><body><joint name="j"/><geom size="0.1"/></body></worldbody>'
    ...     '</mujoco>')
    >>> check_run(model, np.zeros((3, 1)), np.array([[0.0], [1.0], [2.0]]), np.zeros((3, 1)))
    {'peak_velocity': {'j': 2.0}, 'velocity_bound': {'j': 100.0}}
    """
    mujoco = import_mujoco()
    qvel = np.asarray(qvel, dtype=float)
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"
             for j in model.dof_jntid]
    slide = model.jnt_type[model.dof_jntid] == int(mujoco.mjtJoint.mjJNT_SLIDE)
    bound = np.where(slide, MAX_SLIDE_VELOCITY, MAX_HINGE_VELOCITY)
    finite = all(np.all(np.isfinite(a)) for a in (qpos, qvel, qacc))
    peak = np.max(np.abs(qvel), axis=0) if finite and len(qvel) else np.full(model.nv, np.inf)
    how = ("" if integration is None else
           f" (integrated with {integration.integrator} at {integration.step * 1e3:.3g} ms, "
           f"h |lambda| = {integration.stability:.3g})")
    advice = ("; pass integrator='auto' (a stable step chosen from the servo gains, damping "
              "and inertia) or more substeps")
    if not finite or bad_accelerations:
        raise UnstableSimulationError(
            f"{label} became unstable (NaN or huge accelerations){how}{advice}, or reduce the "
            "forces and initial velocities")
    over = np.flatnonzero(peak > bound)
    if len(over):
        joints = ", ".join(f"{names[i]} {peak[i]:.3g}" for i in over)
        raise UnstableSimulationError(
            f"{label} is not physical: velocities up to {joints} (bound {bound[over[0]]:g}, "
            f"rad/s or m/s){how}{advice}, or lower the forcing amplitude")
    if energy is not None and len(energy) > 1:
        energy = np.asarray(energy, dtype=float).reshape(len(energy), -1)
        total = energy.sum(axis=1)
        growth = float(np.max(total) - total[0])
        scale = float(np.max(energy[:, -1]) + np.ptp(energy[:, 0])) if energy.shape[1] > 1 \
            else float(np.ptp(total))
        if growth > 0.05 * scale + 1e-12:
            raise UnstableSimulationError(
                f"{label}: the energy of an unforced run grew by {growth:.3g} J{how}{advice}")
    return {"peak_velocity": {name: float(p) for name, p in zip(names, peak, strict=True)},
            "velocity_bound": {name: float(b) for name, b in zip(names, bound, strict=True)}}


def settling_time(model, forced: bool = True) -> float:
    """Seconds after which the stiff servo modes excited by a start on the reference are gone.

    20 time constants of the fastest servo's bandwidth, at most 0.1 s, in whole model steps;
    zero without position servos or when the run is not ``forced``.

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.
    forced : bool, default=True
        Whether the run is driven (an undriven run needs no settling).

    Returns
    -------
    float
        The settling time (s), a whole number of model steps.
    """
    from ..mujoco.systems.actuation import servo_bandwidths
    bandwidth = servo_bandwidths(model)
    if not forced or not np.any(np.isfinite(bandwidth)):
        return 0.0
    steps = np.ceil(min(0.1, 20.0 / np.nanmax(bandwidth)) / model.opt.timestep)
    return float(steps * model.opt.timestep)


def settled(trajectory, settle: float):
    """The trajectory from time ``settle`` (s) on, recorded in ``info["settle"]``; times kept
    (the controls are functions of time).

    Parameters
    ----------
    trajectory : Trajectory
        A simulated trajectory.
    settle : float
        Time (s) from which the trajectory is kept.

    Returns
    -------
    Trajectory
        The trajectory without its first ``settle`` seconds.
    """
    from ..data.dataset import Trajectory
    if settle <= 0:
        return trajectory
    keep = trajectory.t >= trajectory.t[0] + settle - 1e-12
    fields = {key: (value[keep] if isinstance(value, np.ndarray) and value.ndim
                    and len(value) == len(keep) else value)
              for key, value in vars(trajectory).items()}
    fields["info"] = dict(trajectory.info, settle=settle)
    return Trajectory(**fields)
