"""The base class of every MuJoCo system: an MJCF model with the textbook description of the
same mechanism (conventions: :mod:`pysindy_xl.mujoco.systems.registry`)."""

from __future__ import annotations

import numpy as np
import sympy as sp

from ..._optional import import_mujoco
from ..._validation import check_option
from ...symbols import Coordinates

__all__ = ["MuJoCoSystem", "equations_of_motion"]


def checked_parameters(**values) -> dict:
    """Physical parameters checked by name: numbers (never a string or a bool), positive but
    for gravity and dampings, which may be zero.

    Parameters
    ----------
    **values
        Parameter values by name.

    Returns
    -------
    dict
        The same values.

    Raises
    ------
    TypeError
        When a value is not a real number (a string, a bool...).
    ValueError
        When a value is negative (zero is refused except for gravity and dampings).
    """
    return {name: check_option(name, value, "real", low=0,
                               low_open=name != "gravity" and "damping" not in name)
            for name, value in values.items()}


def mjcf_float(value: float) -> str:
    """Format a float for MJCF without losing precision.

    Parameters
    ----------
    value : float
        The number.

    Returns
    -------
    str
        Its shortest exact representation.
    """
    return repr(float(value))


def equations_of_motion(lagrangian: sp.Expr, coords: Coordinates, friction=None) -> list[sp.Expr]:
    """Left-hand sides ``d/dt dL/dqd_i - dL/dq_i + friction_i`` of the equations of motion.

    The equations read ``lhs_i = Q_i`` (generalized external forces); ``friction`` is
    ``{(term, i): c}``, adding ``c * term`` to equation ``i``.

    Parameters
    ----------
    lagrangian : sympy.Expr
        The Lagrangian ``L(q, qd)`` in the symbols of ``coords``.
    coords : pysindy_xl.Coordinates
        The generalized coordinates; their ``q``, ``qd`` and ``qdd`` symbols are used.
    friction : dict or None, default=None
        Classical friction terms ``{(term, i): c}``: ``c * term`` is added to equation ``i``.
        None adds none.

    Returns
    -------
    list of sympy.Expr
        One expanded left-hand side per coordinate, in the order of ``coords``.

    Notes
    -----
    Equation ``i`` is the Euler-Lagrange equation

    .. math::

        \\frac{d}{dt}\\frac{\\partial L}{\\partial \\dot q_i}
        - \\frac{\\partial L}{\\partial q_i} + \\sum_j c_{ij}\\,\\mathrm{term}_j = Q_i ,

    with the total time derivative expanded by the chain rule over every coordinate.

    Examples
    --------
    >>> import pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> lhs = equations_of_motion(c.qd[0] ** 2 / 2, c, {(c.qd[0], 0): 0.5})
    >>> lhs[0] == c.qdd[0] + 0.5 * c.qd[0]
    True
    """
    out = []
    for i, (qi, qdi) in enumerate(zip(coords.q, coords.qd, strict=True)):
        momentum = sp.diff(lagrangian, qdi)
        d_dt = sum(sp.diff(momentum, qk) * qdk + sp.diff(momentum, qdk) * qddk
                   for qk, qdk, qddk in zip(coords.q, coords.qd, coords.qdd, strict=True))
        lhs = d_dt - sp.diff(lagrangian, qi)
        for (term, c), value in (friction or {}).items():
            if c == i:
                lhs += value * term
        out.append(sp.expand(lhs))
    return out


class MuJoCoSystem:
    """A mechanical system simulated by MuJoCo and described in textbook coordinates.

    Subclasses define the coordinate names, the MuJoCo joints (in degree-of-freedom order), the
    linear map ``q = T @ qpos`` (:attr:`joint_to_coordinates`), the MJCF text (:meth:`xml`)
    and the Lagrangian (:meth:`lagrangian`).

    Attributes
    ----------
    name : str
        Registry name (``"cart-pole"``...).
    coordinate_names : tuple of str
    joint_names : tuple of str
        MuJoCo joints, in the order of ``qpos`` / ``qvel``.
    angle_coordinates : tuple of int
        Coordinates that are angles (enter the catalogs through sin and cos).
    mixed_actuators : tuple of str
        Joints driven in the ``mixed`` forcing mode by default.
    has_ground_truth : bool
        Whether :meth:`lagrangian` and :meth:`friction` give the true model.

    Examples
    --------
    The smallest system, a point mass on a damped rail (see :class:`CartPole` for a full one):

    >>> import numpy as np
    >>> class Rail(MuJoCoSystem):
    ...     name, coordinate_names, joint_names = "rail", ("x",), ("slider",)
    ...     def __init__(self, mass=2.0, damping=0.3):
    ...         self._parameters = {"mass": mass, "damping": damping}
    ...     @property
    ...     def joint_damping(self):
    ...         return np.array([self._parameters["damping"]])
    ...     @property
    ...     def force_amplitudes(self):
    ...         return {"slider": 1.0}
    ...     def lagrangian(self):
    ...         return self._parameters["mass"] * self.coords.qd[0] ** 2 / 2
    ...     def xml(self):
    ...         p = self._parameters
    ...         return (f'<mujoco><worldbody><body><joint name="slider" type="slide" '
    ...                 f'axis="1 0 0" damping="{p["damping"]}"/><inertial pos="0 0 0" '
    ...                 f'mass="{p["mass"]}" diaginertia="1 1 1"/></body></worldbody>'
    ...                 '<actuator><motor joint="slider"/></actuator></mujoco>')
    >>> rail = Rail()
    >>> rail.equations_of_motion()
    [2.0*x_ddot + 0.3*x_dot]
    >>> rail.mj_model().nv, rail.friction()
    (1, {(x_dot, 0): 0.3})
    """

    name = "system"
    coordinate_names: tuple[str, ...] = ()
    joint_names: tuple[str, ...] = ()
    angle_coordinates: tuple[int, ...] = ()
    mixed_actuators: tuple[str, ...] = ()
    has_ground_truth = True

    # -- description ---------------------------------------------------------------------
    @property
    def coords(self) -> Coordinates:
        """The generalized coordinates (:class:`pysindy_xl.Coordinates`)."""
        return Coordinates(self.coordinate_names)

    @property
    def n(self) -> int:
        """Number of generalized coordinates."""
        return len(self.coordinate_names)

    @property
    def parameters(self) -> dict:
        """Physical and numerical parameters (JSON-serializable)."""
        return dict(self._parameters)

    @property
    def joint_to_coordinates(self) -> np.ndarray:
        """Matrix ``T`` (n, n) of the map ``q = T @ qpos`` (also velocities, accelerations)."""
        return np.eye(self.n)

    @property
    def actuated_joints(self) -> tuple[str, ...]:
        """Joints that carry a motor in :meth:`xml` (every joint for our systems)."""
        return self.joint_names

    @property
    def joint_damping(self) -> np.ndarray:
        """Viscous damping coefficient of each MuJoCo joint, shape (n,)."""
        raise NotImplementedError

    @property
    def force_amplitudes(self) -> dict[str, float]:
        """Typical amplitude of the random force of each actuated joint (N or N m)."""
        raise NotImplementedError

    def lagrangian(self) -> sp.Expr:
        """True Lagrangian ``T - V`` in ``coords.q`` and ``coords.qd`` (subclasses define it).

        Returns
        -------
        sympy.Expr
            The Lagrangian in the symbols of :attr:`coords`.

        Examples
        --------
        The cart position is cyclic (absent from the Lagrangian of the cart-pole):

        >>> from pysindy_xl.mujoco import CartPole
        >>> sorted(map(str, CartPole().lagrangian().free_symbols))
        ['theta', 'theta_dot', 'x_dot']
        """
        raise NotImplementedError

    def xml(self) -> str:
        """MJCF text (a complete ``<mujoco>`` document) of the model with current parameters.

        Returns
        -------
        str
            The MJCF document.

        Examples
        --------
        >>> from pysindy_xl.mujoco import CartPole
        >>> CartPole().xml().splitlines()[0]
        '<mujoco model="cart_pole">'
        """
        raise NotImplementedError

    def mj_model(self):
        """A new compiled MuJoCo model of :meth:`xml`.

        Returns
        -------
        mujoco.MjModel
            The compiled model (a new object at each call).

        Examples
        --------
        >>> from pysindy_xl.mujoco import DoublePendulum
        >>> model = DoublePendulum().mj_model()
        >>> model.nq, model.nu, model.opt.timestep
        (2, 2, 0.001)
        """
        return import_mujoco().MjModel.from_xml_string(self.xml())

    # -- transforms ----------------------------------------------------------------------
    def force_matrix(self) -> np.ndarray:
        """Matrix ``B`` (n, n): generalized force on the coordinates ``= B @ u``.

        Returns
        -------
        numpy.ndarray of shape (n, n)
            The matrix ``B = T^-T``.

        Examples
        --------
        ``u`` holds one force per MuJoCo degree of freedom (``qfrc_actuator``); ``B = T^-T``
        by virtual work. ``ExternalForces(coords, interlink=B)`` fits with ``u``. A motor on
        the second (relative) hinge of a double pendulum pushes the outer link forward and
        the inner one back:

        >>> from pysindy_xl.mujoco import DoublePendulum
        >>> DoublePendulum().force_matrix() @ np.array([0.0, 1.0])
        array([-1.,  1.])
        """
        return np.linalg.inv(self.joint_to_coordinates).T

    def friction_matrix(self) -> np.ndarray:
        """Matrix ``F`` (n, n), symmetric: generalized friction force ``= -F @ qd``.

        ``F = B C T^-1`` with ``C`` the diagonal of joint damping coefficients.

        Returns
        -------
        numpy.ndarray of shape (n, n)
            The symmetric matrix ``F = T^-T C T^-1``.

        Examples
        --------
        >>> from pysindy_xl.mujoco import DoublePendulum
        >>> DoublePendulum(damping1=0.3, damping2=0.15).friction_matrix()
        array([[ 0.45, -0.15],
               [-0.15,  0.15]])
        """
        t_inv = np.linalg.inv(self.joint_to_coordinates)
        return t_inv.T @ np.diag(self.joint_damping) @ t_inv

    def friction_pattern(self) -> np.ndarray:
        """Boolean (n, n): which velocity ``j`` joint damping can put in equation ``i``.

        The structure of :meth:`friction_matrix` with every joint damped (used by the
        reference catalogs' friction terms).

        Returns
        -------
        numpy.ndarray of bool, shape (n, n)
            True where velocity ``j`` may enter equation ``i`` through joint damping.

        Examples
        --------
        >>> from pysindy_xl.mujoco import CartDoublePendulum
        >>> CartDoublePendulum().friction_pattern()
        array([[ True, False, False],
               [False,  True,  True],
               [False,  True,  True]])
        """
        t_inv = np.linalg.inv(self.joint_to_coordinates)
        return np.abs(t_inv.T @ t_inv) > 1e-12

    def friction(self) -> dict:
        """Classical friction terms ``{(qd_j, i): c}`` of the true model.

        The non-zero entries of :meth:`friction_matrix`: the term ``qd_j`` with coefficient
        ``c`` in equation ``i`` stands for the force ``-c * qd_j`` (``classical=`` of
        ``ideal_coefficients``).

        Returns
        -------
        dict
            ``{(qd_j, i): c}`` for the non-zero entries ``c = F[i, j]``.

        Examples
        --------
        >>> from pysindy_xl.mujoco import CartPole
        >>> CartPole(cart_damping=0.5, pole_damping=0.1).friction()
        {(x_dot, 0): 0.5, (theta_dot, 1): 0.1}
        """
        matrix = self.friction_matrix()
        return {(self.coords.qd[j], i): float(matrix[i, j]) for i in range(self.n)
                for j in range(self.n) if abs(matrix[i, j]) > 1e-15}

    def equations_of_motion(self) -> list[sp.Expr]:
        """Left-hand sides ``EL_i(L) + friction_i``; the motion satisfies ``lhs = B @ u``.

        Returns
        -------
        list of sympy.Expr
            One left-hand side per coordinate (see :func:`equations_of_motion`).

        Examples
        --------
        >>> from pysindy_xl.mujoco import CartPole
        >>> CartPole().equations_of_motion()[1]
        0.320001*theta_ddot + 0.1*theta_dot + 0.4*x_ddot*cos(theta) + 3.924*sin(theta)
        """
        return equations_of_motion(self.lagrangian(), self.coords, self.friction())

    def to_generalized(self, qpos, qvel, qacc=None):
        """Map MuJoCo ``qpos``, ``qvel`` (and ``qacc``), shape (N, n) or (n,), to ``q, qd, qdd``.

        Parameters
        ----------
        qpos : array_like of shape (N, n) or (n,)
            MuJoCo joint positions.
        qvel : array_like of shape (N, n) or (n,)
            MuJoCo joint velocities.
        qacc : array_like of shape (N, n) or (n,), default=None
            MuJoCo joint accelerations, or None.

        Returns
        -------
        q : numpy.ndarray
            Generalized positions, shaped as the input.
        qd : numpy.ndarray
            Generalized velocities, shaped as the input.
        qdd : numpy.ndarray or None
            Generalized accelerations, or None when ``qacc`` is None.

        Raises
        ------
        ValueError
            When an input's last dimension is not ``n``.

        Examples
        --------
        ``qdd`` is None when ``qacc`` is. The second hinge of a double pendulum measures the
        relative angle:

        >>> from pysindy_xl.mujoco import DoublePendulum
        >>> DoublePendulum().to_generalized([0.1, 0.2], [1.0, 1.0])
        (array([0.1, 0.3]), array([1., 2.]), None)
        """
        return tuple(None if a is None else self._checked(name, a) @ self.joint_to_coordinates.T
                     for name, a in (("qpos", qpos), ("qvel", qvel), ("qacc", qacc)))

    def from_generalized(self, q, qd=None):
        """Inverse of :meth:`to_generalized`: ``(qpos, qvel)`` (``qvel`` None when ``qd`` is).

        Parameters
        ----------
        q : array_like of shape (N, n) or (n,)
            Generalized positions.
        qd : array_like of shape (N, n) or (n,), default=None
            Generalized velocities, or None.

        Returns
        -------
        qpos : numpy.ndarray
            MuJoCo joint positions, shaped as ``q``.
        qvel : numpy.ndarray or None
            MuJoCo joint velocities, or None when ``qd`` is None.

        Examples
        --------
        >>> from pysindy_xl.mujoco import DoublePendulum
        >>> DoublePendulum().from_generalized([0.1, 0.3], [1.0, 2.0])
        (array([0.1, 0.2]), array([1., 1.]))
        """
        inverse = np.linalg.inv(self.joint_to_coordinates)
        return (self._checked("q", q) @ inverse.T,
                None if qd is None else self._checked("qd", qd) @ inverse.T)

    def _checked(self, name, a) -> np.ndarray:
        a = np.asarray(a, dtype=float)
        if a.shape[-1] != self.n:
            raise ValueError(f"{name}: expected last dimension {self.n}, got shape {a.shape}")
        return a

    def random_initial_state(self, rng: np.random.Generator, scale: float = 1.0):
        """Random initial ``(q0, qd0)``, each shape (n,), in the generalized coordinates.

        Angles uniform in ``[-2, 2] * scale`` rad, linear positions in ``[-0.5, 0.5] * scale``
        m, velocities in ``[-1, 1] * scale``.

        Parameters
        ----------
        rng : numpy.random.Generator
            The random generator.
        scale : float, default=1.0
            Factor on every range.

        Returns
        -------
        q0 : numpy.ndarray of shape (n,)
            Initial generalized positions.
        qd0 : numpy.ndarray of shape (n,)
            Initial generalized velocities.

        Examples
        --------
        >>> from pysindy_xl.mujoco import CartPole
        >>> q0, qd0 = CartPole().random_initial_state(np.random.default_rng(0), scale=0.1)
        >>> bool(abs(q0[0]) <= 0.05 and abs(q0[1]) <= 0.2 and np.all(abs(qd0) <= 0.1))
        True
        """
        half_range = np.full(self.n, 0.5)
        half_range[list(self.angle_coordinates)] = 2.0
        return (rng.uniform(-1.0, 1.0, self.n) * half_range * scale,
                rng.uniform(-1.0, 1.0, self.n) * scale)

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self._parameters.items())
        return f"{type(self).__name__}({args})"
