"""The MJCF's actuator law: the forces MuJoCo's actuators apply, as a function of time and state.

For an actuator with a joint transmission (gear ``g`` on joint ``j``), no activation dynamics,
a fixed or affine gain and no or an affine bias (``mj_fwdActuation``):

.. math::

    \\ell = g\\,q_j, \\quad v = g\\,\\dot q_j, \\quad
    c = \\mathrm{clip}(\\mathrm{ctrl}, \\mathrm{ctrlrange}), \\\\
    F = \\mathrm{clip}\\big((p_0 + p_1 \\ell + p_2 v)\\,c + b_0 + b_1 \\ell + b_2 v,
        \\mathrm{forcerange}\\big), \\quad
    \\mathrm{qfrc\\_actuator}_j = \\mathrm{clip}\\big(\\textstyle\\sum_a g_a F_a,
        \\mathrm{actuatorfrcrange}_j\\big)

(``p``: ``gainprm``, ``b``: ``biasprm``; a ``position`` servo: ``p = (kp, 0, 0)``,
``b = (0, -kp, -kv)``). Joint damping, armature, springs and dry friction belong to the
identified model; :func:`~pysindy_xl.mujoco.validate_model` drives a model by this law.
"""

from __future__ import annotations

import numpy as np

from ..._optional import import_mujoco
from .registry import get_system

__all__ = ["ActuatorLaw", "actuator_law", "start_on_reference"]


def supported_actuator(model, a: int) -> bool:
    """Whether actuator ``a`` follows the law of the module docstring."""
    mujoco = import_mujoco()
    return (int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT)
            and int(model.actuator_dyntype[a]) == int(mujoco.mjtDyn.mjDYN_NONE)
            and int(model.actuator_gaintype[a]) in (int(mujoco.mjtGain.mjGAIN_FIXED),
                                                    int(mujoco.mjtGain.mjGAIN_AFFINE))
            and int(model.actuator_biastype[a]) in (int(mujoco.mjtBias.mjBIAS_NONE),
                                                    int(mujoco.mjtBias.mjBIAS_AFFINE)))


class ActuatorLaw:
    """The forces of an MJCF's actuators under given controls, as a function of time and state.

    Made by :func:`actuator_law` (parameters as there); evaluated on generalized ``q``, ``qd``,
    one state or many at once. ``state_dependent``: some force depends on the state (servo,
    affine gain or bias), so the law must run in closed loop; False for motors.

    Parameters
    ----------
    system : MuJoCoSystem
        The system whose coordinates ``q``, ``qd`` the law takes.
    signals : callable or None
        ``signals(times) -> (len(times), nu)`` controls (e.g. a :class:`SumOfSinusoids`); None:
        zero controls.
    force_input : {"tau", "u"}
        Generalized forces on the coordinates (``B @ qfrc_actuator``) or joint forces.
    mj_model : mujoco.MjModel, default=None
        Whose actuators act (default ``system.mj_model()``).

    Examples
    --------
    A position servo (``kp = 10``, ``kv = 1``) on a hinge, its reference fixed at 0.5 rad:

    >>> from pysindy_xl.mujoco import MJCFSystem, SumOfSinusoids
    >>> servo = MJCFSystem('''<mujoco><worldbody><body><joint name="hinge"/>
    ...   <geom size="0.1" mass="1"/></body></worldbody>
    ...   <actuator><position joint="hinge" kp="10" kv="1"/></actuator></mujoco>''')
    >>> law = actuator_law(servo, SumOfSinusoids([[0.0]], [[1.0]], [[0.0]], offsets=[0.5]))
    >>> law.state_dependent, law(0.0, [0.2], [1.0])  # 10 * (0.5 - 0.2) - 1 * 1.0
    (True, array([2.]))
    """

    def __init__(self, system, signals, force_input: str, mj_model=None):
        mujoco = import_mujoco()
        model = system.mj_model() if mj_model is None else mj_model
        self.n = int(system.n)
        self.signals = signals
        self.force_input = force_input
        self._nu = int(model.nu)
        dof = model.jnt_dofadr[model.actuator_trnid[:, 0]]
        gear = model.actuator_gear[:, 0].copy()
        inverse = np.linalg.inv(system.joint_to_coordinates)  # qpos = T^-1 q
        # lengths and velocities of the actuators from generalized states: ell = q @ A.T
        self._length = gear[:, None] * inverse[dof]
        fixed = model.actuator_gaintype == int(mujoco.mjtGain.mjGAIN_FIXED)
        self._gain = np.where(fixed[:, None], [1.0, 0.0, 0.0], 1.0) * model.actuator_gainprm[:, :3]
        affine = model.actuator_biastype == int(mujoco.mjtBias.mjBIAS_AFFINE)
        self._bias = np.where(affine[:, None], model.actuator_biasprm[:, :3], 0.0)
        clamp = not (model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_CLAMPCTRL))
        limited = model.actuator_ctrllimited.astype(bool) & clamp
        self._ctrl_low = np.where(limited, model.actuator_ctrlrange[:, 0], -np.inf)
        self._ctrl_high = np.where(limited, model.actuator_ctrlrange[:, 1], np.inf)
        forced = model.actuator_forcelimited.astype(bool)
        self._force_low = np.where(forced, model.actuator_forcerange[:, 0], -np.inf)
        self._force_high = np.where(forced, model.actuator_forcerange[:, 1], np.inf)
        self._moment = np.zeros((model.nv, model.nu))  # qfrc_actuator = moment @ force
        self._moment[dof, np.arange(model.nu)] = gear
        joint_limited = model.jnt_actfrclimited.astype(bool)
        dof_joint = model.dof_jntid
        self._joint_low = np.where(joint_limited, model.jnt_actfrcrange[:, 0], -np.inf)[dof_joint]
        self._joint_high = np.where(joint_limited, model.jnt_actfrcrange[:, 1], np.inf)[dof_joint]
        self._output = np.eye(model.nv) if force_input == "u" else system.force_matrix()
        if model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_ACTUATION):
            self._gain, self._bias = np.zeros_like(self._gain), np.zeros_like(self._bias)
        self.state_dependent = bool(np.any(self._gain[:, 1:] != 0)
                                    or np.any(self._bias[:, 1:] != 0))

    def controls(self, t) -> np.ndarray:
        """Clamped controls at times ``t``: shape (nu,) for a scalar, (len(t), nu) else.

        Parameters
        ----------
        t : float or array_like of shape (N,)
            Time(s).

        Returns
        -------
        numpy.ndarray of shape (nu,) or (N, nu)
            The controls, clamped to each actuator's ``ctrlrange``.
        """
        times = np.atleast_1d(np.asarray(t, dtype=float))
        if self.signals is None:
            ctrl = np.zeros((len(times), self._nu))
        else:
            ctrl = np.asarray(self.signals(times), dtype=float).reshape(len(times), self._nu)
        ctrl = np.clip(ctrl, self._ctrl_low, self._ctrl_high)
        return ctrl[0] if np.ndim(t) == 0 else ctrl

    def __call__(self, t, q=None, qd=None) -> np.ndarray:
        """The forces at time(s) ``t`` and state(s) ``(q, qd)``: (n,) for one, (N, n) else.

        ``q``, ``qd`` (shape (n,) or (N, n)) may be left out when the law is not
        ``state_dependent``; a ValueError names the one missing or misshapen.

        Parameters
        ----------
        t : float or array_like of shape (N,)
            Time(s).
        q : array_like of shape (n,) or (N, n), default=None
            Generalized positions; needed when the law is ``state_dependent``.
        qd : array_like of shape (n,) or (N, n), default=None
            Generalized velocities; needed when the law is ``state_dependent``.

        Returns
        -------
        numpy.ndarray of shape (n,) or (N, n)
            The generalized forces (``force_input="tau"``) or joint forces (``"u"``).

        Raises
        ------
        ValueError
            When a needed state is missing or misshapen.
        """
        ctrl = self.controls(t)
        gain, bias = self._gain[:, 0], self._bias[:, 0]
        single = np.ndim(t) == 0
        if self.state_dependent or q is not None or qd is not None:
            if q is None or qd is None:
                raise ValueError("q, qd: the actuator law depends on the state (a servo); give "
                                 "positions and velocities")
            q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
            for name, value in (("q", q), ("qd", qd)):
                if value.shape[-1:] != (self.n,) or value.ndim > 2:
                    raise ValueError(f"{name}: expected shape ({self.n},) or (N, {self.n}), "
                                     f"got {value.shape}")
            single = single and q.ndim == 1 and qd.ndim == 1
            length, velocity = q @ self._length.T, qd @ self._length.T
            gain = gain + self._gain[:, 1] * length + self._gain[:, 2] * velocity
            bias = bias + self._bias[:, 1] * length + self._bias[:, 2] * velocity
        force = np.clip(gain * ctrl + bias, self._force_low, self._force_high)
        joint = np.clip(force @ self._moment.T, self._joint_low, self._joint_high)
        return (joint @ self._output.T).reshape(self.n) if single else joint @ self._output.T

    def rest_state(self, t: float, q, qd, dt: float = 1e-4):
        """The state nearest ``(q, qd)`` at which every position servo follows its reference
        with no force.

        A servo with position feedback (``bias[1] < 0``, constant gain) has no force at the
        length and rate

        .. math::

            v^* = \\frac{d}{dt}\\Big(-\\frac{\\mathrm{gain}\\,\\mathrm{ctrl} + b_0}{b_1}\\Big),
            \\quad \\ell^* = -\\frac{\\mathrm{gain}\\,\\mathrm{ctrl} + b_0 + b_2 v^*}{b_1}.

        With ``ell = A q``, positions move to ``q + pinv(A) (ell* - A q)`` (the smallest change)
        and velocities likewise onto ``v*``. Starting there spares the servos a transient
        that saturates a stiff servo and makes a time-stepping integrator chatter. ``dt`` is
        the central-difference step of ``v*``; returns ``(q, qd)``, shape (n,) each.

        Parameters
        ----------
        t : float
            The time.
        q, qd : array_like of shape (n,)
            Generalized positions and velocities to start from.
        dt : float, default=1e-4
            Central-difference step of ``v*``.

        Returns
        -------
        q : numpy.ndarray of shape (n,)
            Positions of the nearest state at which every position servo exerts no force.
        qd : numpy.ndarray of shape (n,)
            Velocities of that state.

        Examples
        --------
        A servo ``kp = 100``, ``kv = 10`` whose reference moves at 1 rad/s starts 0.1 rad
        behind it, where its force ``100 * 0.1 - 10 * 1`` vanishes:

        >>> from pysindy_xl.mujoco import MJCFSystem, SumOfSinusoids
        >>> servo = MJCFSystem('''<mujoco><worldbody><body><joint name="j"/>
        ...   <geom size="0.1" mass="1"/></body></worldbody>
        ...   <actuator><position joint="j" kp="100" kv="10"/></actuator></mujoco>''')
        >>> law = actuator_law(servo, SumOfSinusoids([[0.1]], [[1 / (0.2 * np.pi)]], [[0.0]]))
        >>> q, qd = law.rest_state(0.0, [0.3], [0.0])
        >>> q.round(6), qd.round(6), law(0.0, q, qd).round(6)
        (array([-0.1]), array([1.]), array([0.]))
        """
        q, qd = np.array(q, dtype=float), np.array(qd, dtype=float)
        servo = (self._bias[:, 1] < 0) & np.all(self._gain[:, 1:] == 0, axis=1)
        if not servo.any():
            return q, qd
        lengths = self._length[servo]
        gain, bias = self._gain[servo, 0], self._bias[servo]

        def reference(times):
            return -(gain * self.controls(times)[:, servo] + bias[:, 0]) / bias[:, 1]

        rate = (reference(np.array([t + dt])) - reference(np.array([t - dt])))[0] / (2 * dt)
        target = reference(np.array([t]))[0] - bias[:, 2] * rate / bias[:, 1]
        inverse = np.linalg.pinv(lengths)
        return q + inverse @ (target - lengths @ q), qd + inverse @ (rate - lengths @ qd)

    def __repr__(self) -> str:
        kind = "state-dependent" if self.state_dependent else "time-only"
        return f"ActuatorLaw({kind}, n={self.n}, nu={self._nu}, force_input={self.force_input!r})"


def start_on_reference(system, signals, q0, qd0, mj_model=None):
    """Move a random initial state onto the position servos' reference (driven runs only).

    Returns ``(q0, qd0)`` by :meth:`ActuatorLaw.rest_state`; unchanged when ``signals`` is None
    (an undriven run) or there is no position servo. Parameters as in :func:`actuator_law`.

    A servo (``kp = 100``, ``kv = 10``) whose reference holds 0.5 rad: the run starts there.

    Parameters
    ----------
    system : MuJoCoSystem
        The driven system.
    signals : callable or None
        ``signals(times) -> (len(times), nu)`` controls (e.g. a :class:`SumOfSinusoids`); None: an
        undriven run (the state is returned unchanged).
    q0, qd0 : array_like of shape (n,)
        Initial generalized positions and velocities.
    mj_model : mujoco.MjModel, default=None
        Whose actuators act (default ``system.mj_model()``).

    Returns
    -------
    q0 : numpy.ndarray of shape (n,)
        Initial positions on the servos' reference.
    qd0 : numpy.ndarray of shape (n,)
        Initial velocities on the servos' reference.

    Examples
    --------
    >>> from pysindy_xl.mujoco import MJCFSystem, SumOfSinusoids
    >>> servo = MJCFSystem('''<mujoco><worldbody><body><joint name="j"/>
    ...   <geom size="0.1" mass="1"/></body></worldbody>
    ...   <actuator><position joint="j" kp="100" kv="10"/></actuator></mujoco>''')
    >>> hold = SumOfSinusoids([[0.0]], [[1.0]], [[0.0]], offsets=[0.5])
    >>> start_on_reference(servo, hold, [0.2], [1.0])
    (array([0.5]), array([0.]))
    """
    law = None if signals is None else actuator_law(system, signals, mj_model=mj_model)
    if law is None or not law.state_dependent:
        return np.asarray(q0, dtype=float), np.asarray(qd0, dtype=float)
    return law.rest_state(0.0, q0, qd0)


def actuator_law(system, signals=None, force_input: str = "tau",
                 mj_model=None) -> ActuatorLaw | None:
    """The MJCF's actuator law driven by ``signals``, or None when MuJoCo's is another.

    Parameters
    ----------
    system : MuJoCoSystem or str
    signals : callable, optional
        ``signals(times) -> (len(times), nu)`` controls (e.g. a :class:`SumOfSinusoids`, the
        ``info["signals"]`` of a trajectory); None: zero controls.
    force_input : {"tau", "u"}, default "tau"
        Generalized forces on the coordinates (``B @ qfrc_actuator``) or joint forces.
    mj_model : mujoco.MjModel, optional
        Whose actuators act (default ``system.mj_model()``).

    Returns
    -------
    ActuatorLaw or None
        None when some actuator is outside the module's law (tendon or site transmission,
        activation dynamics, muscle, gravity compensation).

    Examples
    --------
    >>> from pysindy_xl.mujoco import SumOfSinusoids
    >>> law = actuator_law("cart-pole", SumOfSinusoids([[1.0], [0.0]], [[1.0], [1.0]],
    ...                                                [[0.0], [0.0]]))
    >>> law.state_dependent, law(0.25)  # a motor on the cart: a function of time
    (False, array([1., 0.]))
    """
    system = get_system(system)
    if force_input not in ("tau", "u"):
        raise ValueError(f"force_input: expected 'tau' or 'u', got {force_input!r}")
    if signals is not None and not callable(signals):
        raise TypeError(f"signals: expected a function of time or None, got "
                        f"{type(signals).__name__}")
    model = system.mj_model() if mj_model is None else mj_model
    if not all(supported_actuator(model, a) for a in range(model.nu)):
        return None
    if np.any(getattr(model, "jnt_actgravcomp", 0)):
        return None  # gravity compensation routed through the actuators
    return ActuatorLaw(system, signals, force_input, model)


def actuator_force_function(system, signals, force_input: str = "tau"):
    """The forces MuJoCo's actuators apply under ``signals``, as a function of time.

    ``f(t) -> (n,)`` for a scalar ``t``, ``(len(t), n)`` for an array; exact for plain motors
    on joints. None when the forces depend on the state (servos; see :func:`actuator_law`) or
    an actuator is outside its law. Parameters as in :func:`actuator_law`.

    Parameters
    ----------
    system : MuJoCoSystem or str
        The system (or its registry name).
    signals : callable
        ``signals(times) -> (len(times), nu)`` controls.
    force_input : {"tau", "u"}, default="tau"
        Generalized forces on the coordinates or joint forces.

    Returns
    -------
    callable or None
        ``f(t)``; None when the forces depend on the state or an actuator is outside the law.

    Examples
    --------
    >>> from pysindy_xl.mujoco import SumOfSinusoids
    >>> force = SumOfSinusoids([[1.0], [0.0]], [[1.0], [1.0]], [[0.0], [0.0]])
    >>> actuator_force_function("cart-pole", force)(0.25)
    array([1., 0.])
    """
    law = actuator_law(system, signals, force_input)
    return None if law is None or law.state_dependent else law


def servo_bandwidths(model) -> np.ndarray:
    """The bandwidth (rad/s) of each position servo of a MuJoCo model, shape (nu,); NaN else.

    A position servo (``biasprm[1] < 0``) of gains ``kp``, ``kv`` on a joint of effective
    inertia ``m`` (``mj_fullM``'s diagonal, armature included) and damping ``d`` closes the loop
    ``m s^2 + (kv + d) s + kp``; its slower pole is how fast it can follow its reference.

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.

    Returns
    -------
    numpy.ndarray of shape (nu,)
        The slower closed-loop pole (rad/s) of each position servo; NaN for other actuators.

    Examples
    --------
    >>> import mujoco
    >>> model = mujoco.MjModel.from_xml_string('''<mujoco><worldbody><body>
    ...   <joint name="j" axis="0 0 1"/>
    ...   <inertial pos="0 0 0" mass="1" diaginertia="1e-2 1e-2 1e-2"/></body></worldbody>
    ...   <actuator><position joint="j" kp="100" kv="20"/><motor joint="j"/></actuator>
    ...   </mujoco>''')
    >>> servo_bandwidths(model).round(3)  # overdamped: nearly kp / kv
    array([5.013,   nan])
    """
    mujoco = import_mujoco()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    mass = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, mass)
    out = np.full(model.nu, np.nan)
    for a in range(model.nu):
        kp, kv = -model.actuator_biasprm[a, 1], -model.actuator_biasprm[a, 2]
        if not (supported_actuator(model, a) and kp > 0):
            continue
        dof = model.jnt_dofadr[model.actuator_trnid[a, 0]]
        gear = model.actuator_gear[a, 0]
        roots = np.roots([mass[dof, dof], gear**2 * kv + model.dof_damping[dof], gear**2 * kp])
        out[a] = float(np.min(np.abs(roots)))
    return out
