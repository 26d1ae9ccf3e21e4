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
"""

from __future__ import annotations

import keyword
import os
import re
from importlib import resources

import numpy as np
import sympy as sp

from .._optional import import_optional
from ..symbols import Coordinates


def _mujoco():
    """The ``mujoco`` module, imported on first use (clear error naming the extra)."""
    return import_optional("mujoco", purpose="MuJoCo simulation (pysindy_xl.mujoco)")

__all__ = [
    "MuJoCoSystem",
    "CartPole",
    "DoublePendulum",
    "CartDoublePendulum",
    "MJCFSystem",
    "SYSTEMS",
    "get_system",
    "default_xml_path",
    "equations_of_motion",
    "system_from_metadata",
]


def _positive(value, name: str) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name}: expected a positive number, got {value!r}") from None
    if not np.isfinite(value) or value <= 0:
        raise ValueError(f"{name}: expected a positive finite number, got {value!r}")
    return value


def _non_negative(value, name: str) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name}: expected a non-negative number, got {value!r}") from None
    if not np.isfinite(value) or value < 0:
        raise ValueError(f"{name}: expected a non-negative finite number, got {value!r}")
    return value


def _f(value: float) -> str:
    """Format a float for MJCF without losing precision."""
    return repr(float(value))


def equations_of_motion(lagrangian: sp.Expr, coords: Coordinates, friction=None) -> list[sp.Expr]:
    """Left-hand sides ``d/dt dL/dqd_i - dL/dq_i + friction_i`` of the equations of motion.

    The equations of motion read ``lhs_i = Q_i`` with ``Q`` the generalized external forces.
    The time derivative is taken with the chain rule over the coordinate symbols.

    Parameters
    ----------
    lagrangian : sympy.Expr
        Lagrangian in ``coords.q`` and ``coords.qd``.
    coords : Coordinates
        The generalized coordinates (positions, velocities, accelerations as symbols).
    friction : dict, optional
        ``{(term, i): c}``: adds ``c * term`` to equation ``i``.

    Returns
    -------
    list of sympy.Expr, one per coordinate

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
        d_dt = sum(
            sp.diff(momentum, qk) * qdk + sp.diff(momentum, qdk) * qddk
            for qk, qdk, qddk in zip(coords.q, coords.qd, coords.qdd, strict=True)
        )
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
        Names of the generalized coordinates (symbols of :attr:`coords`).
    joint_names : tuple of str
        MuJoCo joints, in the order of ``qpos`` / ``qvel``.
    angle_coordinates : tuple of int
        Indices of the coordinates that are angles (enter the catalogs through sin and cos).
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
        """True Lagrangian ``T - V`` in the symbols of :attr:`coords`.

        Returns
        -------
        sympy.Expr
            Kinetic minus potential energy, in ``coords.q`` and ``coords.qd``.

        Raises
        ------
        NotImplementedError
            In this base class, which describes no particular system.

        Examples
        --------
        The cart position is cyclic (absent from the Lagrangian of the cart-pole):

        >>> sorted(map(str, CartPole().lagrangian().free_symbols))
        ['theta', 'theta_dot', 'x_dot']
        """
        raise NotImplementedError

    def xml(self) -> str:
        """MJCF text of the model with the current parameters.

        Returns
        -------
        str
            A complete ``<mujoco>`` document.

        Raises
        ------
        NotImplementedError
            In this base class, which describes no particular system.

        Examples
        --------
        >>> CartPole().xml().splitlines()[0]
        '<mujoco model="cart_pole">'
        """
        raise NotImplementedError

    def mj_model(self):
        """Compiled MuJoCo model of :meth:`xml`.

        Returns
        -------
        mujoco.MjModel
            A new model at each call.

        Examples
        --------
        >>> model = DoublePendulum().mj_model()
        >>> model.nq, model.nu, model.opt.timestep
        (2, 2, 0.001)
        """
        return _mujoco().MjModel.from_xml_string(self.xml())

    # -- transforms ----------------------------------------------------------------------
    def force_matrix(self) -> np.ndarray:
        """Matrix ``B`` (n, n): generalized force on the coordinates ``= B @ u``.

        ``u`` holds one force per MuJoCo degree of freedom (``qfrc_actuator``); ``B = T^-T``
        by virtual work. Pass it as ``ExternalForces(coords, interlink=B)`` to fit with the
        joint forces ``u`` instead of the generalized forces ``tau = u @ B.T``.

        Returns
        -------
        ndarray, shape (n, n)

        Examples
        --------
        A motor on the second (relative) hinge of a double pendulum pushes the outer link
        forward and the inner one back:

        >>> import numpy as np
        >>> DoublePendulum().force_matrix() @ np.array([0.0, 1.0])
        array([-1.,  1.])
        """
        return np.linalg.inv(self.joint_to_coordinates).T

    def friction_matrix(self) -> np.ndarray:
        """Matrix ``F`` (n, n): generalized friction force ``= -F @ qd``.

        ``F = B C T^-1`` with ``C`` the diagonal of joint damping coefficients.

        Returns
        -------
        ndarray, shape (n, n)
            Symmetric; diagonal when every joint measures one coordinate.

        Examples
        --------
        >>> DoublePendulum(damping1=0.3, damping2=0.15).friction_matrix()
        array([[ 0.45, -0.15],
               [-0.15,  0.15]])
        """
        t_inv = np.linalg.inv(self.joint_to_coordinates)
        return t_inv.T @ np.diag(self.joint_damping) @ t_inv

    def friction_pattern(self) -> np.ndarray:
        """Boolean (n, n): which velocity ``j`` joint damping can put in equation ``i``.

        The structure of :meth:`friction_matrix` with every joint damped, independent of the
        damping values; the reference catalogs use it for their friction terms.

        Returns
        -------
        ndarray of bool, shape (n, n)
            ``pattern[i, j]``: the velocity of coordinate ``j`` may appear in equation ``i``.

        Examples
        --------
        >>> CartDoublePendulum().friction_pattern()
        array([[ True, False, False],
               [False,  True,  True],
               [False,  True,  True]])
        """
        t_inv = np.linalg.inv(self.joint_to_coordinates)
        return np.abs(t_inv.T @ t_inv) > 1e-12

    def friction(self) -> dict:
        """Classical friction terms ``{(qd_j, i): c}`` of the true model.

        Convention of the feature libraries: the term ``qd_j`` with coefficient ``c`` in the
        equation of coordinate ``i`` stands for the friction force ``-c * qd_j``.

        Returns
        -------
        dict
            ``{(velocity symbol, equation index): coefficient}``, the non-zero entries of
            :meth:`friction_matrix`; as ``classical=`` of ``ideal_coefficients``.

        Examples
        --------
        >>> CartPole(cart_damping=0.5, pole_damping=0.1).friction()
        {(x_dot, 0): 0.5, (theta_dot, 1): 0.1}
        """
        coords = self.coords
        matrix = self.friction_matrix()
        return {
            (coords.qd[j], i): float(matrix[i, j])
            for i in range(self.n)
            for j in range(self.n)
            if abs(matrix[i, j]) > 1e-15
        }

    def equations_of_motion(self) -> list[sp.Expr]:
        """Left-hand sides ``EL_i(L) + friction_i``; the motion satisfies ``lhs = B @ u``.

        Returns
        -------
        list of sympy.Expr
            One per coordinate (see the module function :func:`equations_of_motion`).

        Examples
        --------
        >>> CartPole().equations_of_motion()[1]
        0.320001*theta_ddot + 0.1*theta_dot + 0.4*x_ddot*cos(theta) + 3.924*sin(theta)
        """
        return equations_of_motion(self.lagrangian(), self.coords, self.friction())

    def to_generalized(self, qpos, qvel, qacc=None):
        """Map MuJoCo joint coordinates to the textbook generalized coordinates.

        Parameters
        ----------
        qpos, qvel : array, shape (N, n) or (n,)
            MuJoCo joint positions and velocities (``data.qpos``, ``data.qvel``).
        qacc : array, shape (N, n) or (n,), optional
            MuJoCo joint accelerations (``data.qacc``).

        Returns
        -------
        q, qd, qdd : ndarray
            Same shapes; ``qdd`` is None when ``qacc`` is None.

        Examples
        --------
        The second hinge of a double pendulum measures the relative angle:

        >>> DoublePendulum().to_generalized([0.1, 0.2], [1.0, 1.0])
        (array([0.1, 0.3]), array([1., 2.]), None)
        """
        matrix = self.joint_to_coordinates
        out = []
        for name, a in (("qpos", qpos), ("qvel", qvel), ("qacc", qacc)):
            if a is None:
                out.append(None)
                continue
            a = np.asarray(a, dtype=float)
            if a.shape[-1] != self.n:
                raise ValueError(f"{name}: expected last dimension {self.n}, got shape {a.shape}")
            out.append(a @ matrix.T)
        return tuple(out)

    def from_generalized(self, q, qd=None):
        """Inverse of :meth:`to_generalized` for positions and velocities.

        Parameters
        ----------
        q : array, shape (N, n) or (n,)
            Generalized positions.
        qd : array, shape (N, n) or (n,), optional
            Generalized velocities.

        Returns
        -------
        qpos, qvel : ndarray
            MuJoCo joint positions and velocities, same shapes (``qvel`` None when ``qd`` is
            None).

        Examples
        --------
        >>> DoublePendulum().from_generalized([0.1, 0.3], [1.0, 2.0])
        (array([0.1, 0.2]), array([1., 1.]))
        """
        inverse = np.linalg.inv(self.joint_to_coordinates)
        q = np.asarray(q, dtype=float)
        if q.shape[-1] != self.n:
            raise ValueError(f"q: expected last dimension {self.n}, got shape {q.shape}")
        qpos = q @ inverse.T
        if qd is None:
            return qpos, None
        qd = np.asarray(qd, dtype=float)
        if qd.shape[-1] != self.n:
            raise ValueError(f"qd: expected last dimension {self.n}, got shape {qd.shape}")
        return qpos, qd @ inverse.T

    def random_initial_state(self, rng: np.random.Generator, scale: float = 1.0):
        """Random initial positions and velocities in the generalized coordinates.

        Angles uniform in ``[-2, 2] * scale`` rad, linear positions in ``[-0.5, 0.5] * scale``
        m, velocities uniform in ``[-1, 1] * scale``.

        Parameters
        ----------
        rng : numpy.random.Generator
            Source of the random draws.
        scale : float, default 1.0
            Multiplies every range.

        Returns
        -------
        q0, qd0 : ndarray, shape (n,)

        Examples
        --------
        >>> import numpy as np
        >>> q0, qd0 = CartPole().random_initial_state(np.random.default_rng(0), scale=0.1)
        >>> bool(abs(q0[0]) <= 0.05 and abs(q0[1]) <= 0.2 and np.all(abs(qd0) <= 0.1))
        True
        """
        half_range = np.full(self.n, 0.5)
        half_range[list(self.angle_coordinates)] = 2.0
        q0 = rng.uniform(-1.0, 1.0, self.n) * half_range * scale
        qd0 = rng.uniform(-1.0, 1.0, self.n) * scale
        return q0, qd0

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self._parameters.items())
        return f"{type(self).__name__}({args})"


# -- MJCF building blocks ------------------------------------------------------------------
def _header(model: str, timestep: float, gravity: float) -> str:
    return f"""<mujoco model="{model}">
  <!-- Written by pysindy_xl.mujoco.systems; point masses via explicit inertials. -->
  <compiler angle="radian" inertiafromgeom="auto"/>
  <option timestep="{_f(timestep)}" integrator="RK4" gravity="0 0 {_f(-gravity)}">
    <flag contact="disable"/>
  </option>
  <default>
    <geom contype="0" conaffinity="0"/>
    <joint armature="0" frictionloss="0"/>
  </default>
  <worldbody>
    <light pos="0 -3 3" dir="0 1 -1"/>
"""


def _cart(mass: float, damping: float, inner: str) -> str:
    return f"""    <body name="cart" pos="0 0 0">
      <joint name="slider" type="slide" axis="1 0 0" damping="{_f(damping)}"/>
      <inertial pos="0 0 0" mass="{_f(mass)}" diaginertia="0.01 0.01 0.01"/>
      <geom type="box" size="0.2 0.1 0.05" rgba="0.3 0.3 0.8 1"/>
{inner}    </body>
"""


def _link(body: str, joint: str, mass, length, damping, inertia, pos, inner="", indent=6):
    # axis 0 -1 0: a positive angle moves the bob towards +x (textbook convention).
    pad = " " * indent
    return (
        f'{pad}<body name="{body}" pos="{pos}">\n'
        f'{pad}  <joint name="{joint}" type="hinge" axis="0 -1 0" damping="{_f(damping)}"/>\n'
        f'{pad}  <inertial pos="0 0 {_f(-length)}" mass="{_f(mass)}" '
        f'diaginertia="{_f(inertia)} {_f(inertia)} {_f(inertia)}"/>\n'
        f'{pad}  <geom type="capsule" fromto="0 0 0 0 0 {_f(-length)}" size="0.01" '
        f'rgba="0.6 0.6 0.6 1"/>\n'
        f'{pad}  <geom type="sphere" pos="0 0 {_f(-length)}" size="0.04" rgba="0.8 0.3 0.3 1"/>\n'
        f"{inner}"
        f"{pad}</body>\n"
    )


def _footer(joints) -> str:
    motors = "".join(
        f'    <motor name="{j}_motor" joint="{j}" gear="1" ctrllimited="false"/>\n' for j in joints
    )
    return f"""  </worldbody>
  <actuator>
{motors}  </actuator>
</mujoco>
"""


class CartPole(MuJoCoSystem):
    """Cart on a horizontal rail with a pendulum (point mass on a massless rod).

    Coordinates ``x`` (cart position) and ``theta`` (pole angle, 0 hanging down); MuJoCo joints
    ``slider`` and ``hinge`` coincide with them.

    Parameters
    ----------
    cart_mass, pole_mass, length : float
        Cart mass (kg), bob mass (kg), rod length (m).
    cart_damping, pole_damping : float
        Viscous friction of the slider (N s/m) and of the hinge (N m s/rad).
    gravity : float
    point_inertia : float
        Rotational inertia of the bob about its center (kept tiny; exact in the Lagrangian).
    timestep : float
        MuJoCo time step (RK4).

    Examples
    --------
    >>> system = CartPole(pole_mass=0.2)
    >>> system.coords
    Coordinates(['x', 'theta'])
    """

    name = "cart-pole"
    coordinate_names = ("x", "theta")
    joint_names = ("slider", "hinge")
    angle_coordinates = (1,)
    mixed_actuators = ("slider",)

    def __init__(self, cart_mass=1.0, pole_mass=0.5, length=0.8, cart_damping=0.5,
                 pole_damping=0.1, gravity=9.81, point_inertia=1e-6, timestep=1e-3):
        self._parameters = {
            "cart_mass": _positive(cart_mass, "cart_mass"),
            "pole_mass": _positive(pole_mass, "pole_mass"),
            "length": _positive(length, "length"),
            "cart_damping": _non_negative(cart_damping, "cart_damping"),
            "pole_damping": _non_negative(pole_damping, "pole_damping"),
            "gravity": _non_negative(gravity, "gravity"),
            "point_inertia": _positive(point_inertia, "point_inertia"),
            "timestep": _positive(timestep, "timestep"),
        }

    @property
    def joint_damping(self):
        p = self._parameters
        return np.array([p["cart_damping"], p["pole_damping"]])

    @property
    def force_amplitudes(self):
        p = self._parameters
        return {"slider": 2.0 * (p["cart_mass"] + p["pole_mass"]),
                "hinge": 0.5 * p["pole_mass"] * p["gravity"] * p["length"]}

    def lagrangian(self):
        """True Lagrangian of the cart-pole (cart, point mass with its tiny inertia, gravity).

        Returns
        -------
        sympy.Expr

        Examples
        --------
        >>> CartPole(cart_mass=1.0, pole_mass=0.5, length=0.8).lagrangian()
        0.1600005*theta_dot**2 + 0.4*theta_dot*x_dot*cos(theta) + 0.75*x_dot**2 + 3.924*cos(theta)
        """
        p = self._parameters
        x, th = self.coords.q
        xd, thd = self.coords.qd
        big_m, m, l, g = p["cart_mass"], p["pole_mass"], p["length"], p["gravity"]
        kinetic = (
            (big_m + m) * xd**2 / 2
            + m * l * xd * thd * sp.cos(th)
            + (m * l**2 + p["point_inertia"]) * thd**2 / 2
        )
        potential = -m * g * l * sp.cos(th)
        return kinetic - potential

    def xml(self):
        """MJCF text of the cart-pole with the current parameters.

        Returns
        -------
        str

        Examples
        --------
        >>> 'name="slider"' in CartPole().xml()
        True
        """
        p = self._parameters
        link = _link("pole", "hinge", p["pole_mass"], p["length"], p["pole_damping"],
                     p["point_inertia"], "0 0 0")
        return (_header("cart_pole", p["timestep"], p["gravity"])
                + _cart(p["cart_mass"], p["cart_damping"], link)
                + _footer(self.joint_names))


def _pendulum_chain_xml(p: dict, indent: int) -> str:
    """MJCF bodies of the two-link chain (link1 carrying link2), shared by both pendulums."""
    inner = _link("link2", "hinge2", p["mass2"], p["length2"], p["damping2"],
                  p["point_inertia"], f"0 0 {_f(-p['length1'])}", indent=indent + 2)
    return _link("link1", "hinge1", p["mass1"], p["length1"], p["damping1"],
                 p["point_inertia"], "0 0 0", inner=inner, indent=indent)


class DoublePendulum(MuJoCoSystem):
    """Double pendulum with point masses on massless rods, hanging from a fixed pivot.

    Coordinates ``theta1``, ``theta2``: absolute angles from the downward vertical. MuJoCo's
    hinges ``hinge1`` and ``hinge2`` measure ``theta1`` and ``theta2 - theta1``.

    Parameters
    ----------
    mass1, mass2, length1, length2 : float
    damping1, damping2 : float
        Viscous damping of the two hinges (the second one acts on the relative angle).
    gravity, point_inertia, timestep : float
        See :class:`CartPole`.

    Examples
    --------
    >>> DoublePendulum().force_matrix()
    array([[ 1., -1.],
           [ 0.,  1.]])
    """

    name = "double-pendulum"
    coordinate_names = ("theta1", "theta2")
    joint_names = ("hinge1", "hinge2")
    angle_coordinates = (0, 1)
    mixed_actuators = ("hinge1",)

    def __init__(self, mass1=1.0, mass2=0.8, length1=1.0, length2=0.7, damping1=0.3,
                 damping2=0.15, gravity=9.81, point_inertia=1e-6, timestep=1e-3):
        self._parameters = {
            "mass1": _positive(mass1, "mass1"),
            "mass2": _positive(mass2, "mass2"),
            "length1": _positive(length1, "length1"),
            "length2": _positive(length2, "length2"),
            "damping1": _non_negative(damping1, "damping1"),
            "damping2": _non_negative(damping2, "damping2"),
            "gravity": _non_negative(gravity, "gravity"),
            "point_inertia": _positive(point_inertia, "point_inertia"),
            "timestep": _positive(timestep, "timestep"),
        }

    @property
    def joint_to_coordinates(self):
        return np.array([[1.0, 0.0], [1.0, 1.0]])

    @property
    def joint_damping(self):
        p = self._parameters
        return np.array([p["damping1"], p["damping2"]])

    @property
    def force_amplitudes(self):
        p = self._parameters
        g = p["gravity"]
        return {"hinge1": 0.3 * (p["mass1"] + p["mass2"]) * g * p["length1"],
                "hinge2": 0.3 * p["mass2"] * g * p["length2"]}

    def lagrangian(self):
        """True Lagrangian of the double pendulum in absolute angles.

        Returns
        -------
        sympy.Expr

        Examples
        --------
        >>> L = DoublePendulum().lagrangian()
        >>> sorted(map(str, L.free_symbols))
        ['theta1', 'theta1_dot', 'theta2', 'theta2_dot']
        """
        p = self._parameters
        th1, th2 = self.coords.q
        thd1, thd2 = self.coords.qd
        return _pendulum_chain_lagrangian(p, th1, th2, thd1, thd2, xd=None)

    def xml(self):
        """MJCF text of the double pendulum with the current parameters.

        Returns
        -------
        str

        Examples
        --------
        >>> DoublePendulum().xml().splitlines()[0]
        '<mujoco model="double_pendulum">'
        """
        p = self._parameters
        return (_header("double_pendulum", p["timestep"], p["gravity"])
                + _pendulum_chain_xml(p, indent=4) + _footer(self.joint_names))


def _pendulum_chain_lagrangian(p, th1, th2, thd1, thd2, xd=None, cart_mass=0.0):
    m1, m2, l1, l2, g = p["mass1"], p["mass2"], p["length1"], p["length2"], p["gravity"]
    inertia = p["point_inertia"]
    kinetic = (
        (m1 + m2) * l1**2 * thd1**2 / 2
        + m2 * l2**2 * thd2**2 / 2
        + m2 * l1 * l2 * thd1 * thd2 * sp.cos(th1 - th2)
        # each bob's body rotates with its absolute angle
        + inertia * (thd1**2 + thd2**2) / 2
    )
    if xd is not None:
        kinetic += (
            (cart_mass + m1 + m2) * xd**2 / 2
            + (m1 + m2) * l1 * xd * thd1 * sp.cos(th1)
            + m2 * l2 * xd * thd2 * sp.cos(th2)
        )
    potential = -(m1 + m2) * g * l1 * sp.cos(th1) - m2 * g * l2 * sp.cos(th2)
    return kinetic - potential


class CartDoublePendulum(MuJoCoSystem):
    """Double pendulum (point masses) hanging from a cart on a horizontal rail.

    Coordinates ``x``, ``theta1``, ``theta2`` (absolute angles); MuJoCo joints ``slider``,
    ``hinge1``, ``hinge2`` (the last relative to the first link).

    Parameters
    ----------
    cart_mass, mass1, mass2, length1, length2 : float
    cart_damping, damping1, damping2 : float
    gravity, point_inertia, timestep : float
        See :class:`CartPole`.

    Examples
    --------
    >>> CartDoublePendulum().coords.names
    ('x', 'theta1', 'theta2')
    """

    name = "cart-double-pendulum"
    coordinate_names = ("x", "theta1", "theta2")
    joint_names = ("slider", "hinge1", "hinge2")
    angle_coordinates = (1, 2)
    mixed_actuators = ("slider",)

    def __init__(self, cart_mass=1.0, mass1=0.5, mass2=0.4, length1=0.7, length2=0.5,
                 cart_damping=0.5, damping1=0.1, damping2=0.05, gravity=9.81,
                 point_inertia=1e-6, timestep=1e-3):
        self._parameters = {
            "cart_mass": _positive(cart_mass, "cart_mass"),
            "mass1": _positive(mass1, "mass1"),
            "mass2": _positive(mass2, "mass2"),
            "length1": _positive(length1, "length1"),
            "length2": _positive(length2, "length2"),
            "cart_damping": _non_negative(cart_damping, "cart_damping"),
            "damping1": _non_negative(damping1, "damping1"),
            "damping2": _non_negative(damping2, "damping2"),
            "gravity": _non_negative(gravity, "gravity"),
            "point_inertia": _positive(point_inertia, "point_inertia"),
            "timestep": _positive(timestep, "timestep"),
        }

    @property
    def joint_to_coordinates(self):
        return np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 1.0]])

    @property
    def joint_damping(self):
        p = self._parameters
        return np.array([p["cart_damping"], p["damping1"], p["damping2"]])

    @property
    def force_amplitudes(self):
        p = self._parameters
        g = p["gravity"]
        return {"slider": 2.0 * (p["cart_mass"] + p["mass1"] + p["mass2"]),
                "hinge1": 0.3 * (p["mass1"] + p["mass2"]) * g * p["length1"],
                "hinge2": 0.3 * p["mass2"] * g * p["length2"]}

    def lagrangian(self):
        """True Lagrangian of the double pendulum on a cart.

        Returns
        -------
        sympy.Expr

        Examples
        --------
        >>> L = CartDoublePendulum().lagrangian()
        >>> sorted(map(str, L.free_symbols))
        ['theta1', 'theta1_dot', 'theta2', 'theta2_dot', 'x_dot']
        """
        p = self._parameters
        _, th1, th2 = self.coords.q
        xd, thd1, thd2 = self.coords.qd
        return _pendulum_chain_lagrangian(p, th1, th2, thd1, thd2, xd=xd,
                                          cart_mass=p["cart_mass"])

    def xml(self):
        """MJCF text of the double pendulum on a cart with the current parameters.

        Returns
        -------
        str

        Examples
        --------
        >>> CartDoublePendulum().xml().splitlines()[0]
        '<mujoco model="cart_double_pendulum">'
        """
        p = self._parameters
        link = _pendulum_chain_xml(p, indent=6)
        return (_header("cart_double_pendulum", p["timestep"], p["gravity"])
                + _cart(p["cart_mass"], p["cart_damping"], link)
                + _footer(self.joint_names))


# -- user-supplied models ------------------------------------------------------------------
def _identifier(name: str, index: int, taken: set) -> str:
    ident = re.sub(r"\W", "_", name or "") or f"q{index}"
    if ident[0].isdigit() or keyword.iskeyword(ident) or ident == "t":
        ident = f"q_{ident}"
    if ident.startswith("tau_") or ident.endswith(("_dot", "_ddot")):
        ident = f"{ident}_q"
    base, k = ident, 1
    while ident in taken:
        ident, k = f"{base}_{k}", k + 1
    taken.add(ident)
    return ident


class MJCFSystem(MuJoCoSystem):
    """A user's MJCF model: coordinates are MuJoCo's joint coordinates.

    Only hinge and slide joints are supported (each joint one coordinate, ``q = qpos``);
    hinge angles count as angles for the catalogs. The true Lagrangian is unknown, so
    :meth:`lagrangian` raises; joint damping is read from the model as diagonal friction.

    Parameters
    ----------
    source : str or os.PathLike
        Path to an MJCF file, or the MJCF text itself (a string starting with ``<``).
    force_amplitude : float, default 1.0
        Amplitude of the random force of an actuator without ``ctrlrange``.
    joints : list of str, optional
        Identify these joints only. The other joints are **locked** at their reference pose
        (the pose written in the MJCF, ``qpos = ref``): they are removed from the model with
        the actuators that drive them, and their bodies move rigidly with their parents. A
        passive body decoupled from the rest (e.g. a target on two slide joints) thus simply
        leaves the problem; the mass of a locked body still loads its parent, as in the real
        mechanism with that joint blocked. Default: every joint.

    Attributes
    ----------
    path : str or None
        Absolute path of the MJCF file (None for MJCF text).
    excluded_joints : tuple of str
        Joints locked by ``joints``.

    Examples
    --------
    >>> xml = '''<mujoco><worldbody><body><joint name="a" type="hinge" axis="0 1 0"/>
    ... <geom type="sphere" size="0.1" pos="0 0 -1"/></body></worldbody></mujoco>'''
    >>> MJCFSystem(xml).coords
    Coordinates(['a'])

    Leave a passive target on two slide joints out:

    >>> xml = '''<mujoco><worldbody>
    ... <body><joint name="swing" axis="0 1 0"/><geom size="0.1" pos="0 0 -1"/></body>
    ... <body pos="2 0 0"><joint name="tx" type="slide" axis="1 0 0"/>
    ... <joint name="ty" type="slide" axis="0 1 0"/><geom size="0.1"/></body>
    ... </worldbody></mujoco>'''
    >>> system = MJCFSystem(xml, joints=["swing"])
    >>> system.coords, system.excluded_joints, system.mj_model().nq
    (Coordinates(['swing']), ('tx', 'ty'), 1)
    """

    name = "mjcf"
    has_ground_truth = False

    def __init__(self, source, force_amplitude=1.0, joints=None):
        mujoco = _mujoco()
        if isinstance(source, os.PathLike) or (
            isinstance(source, str) and not source.lstrip().startswith("<")
        ):
            path = os.fspath(source)
            if not os.path.isfile(path):
                raise ValueError(f"source: MJCF file {path!r} does not exist")
            try:
                model = mujoco.MjModel.from_xml_path(path)
            except ValueError as error:
                raise ValueError(f"source: cannot load MJCF file {path!r}: {error}") from None
            with open(path, encoding="utf-8") as handle:
                self._xml = handle.read()
            self.path = os.path.abspath(path)
        elif isinstance(source, str):
            try:
                model = mujoco.MjModel.from_xml_string(source)
            except ValueError as error:
                raise ValueError(f"source: cannot compile MJCF text: {error}") from None
            self._xml, self.path = source, None
        else:
            raise TypeError(f"source: expected a path or MJCF text, got {type(source).__name__}")
        allowed = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
        if model.njnt == 0:
            raise ValueError("source: the model has no joint, nothing to identify")
        for j in range(model.njnt):
            if int(model.jnt_type[j]) not in allowed:
                jname = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"#{j}"
                raise ValueError(
                    f"source: joint {jname!r} is not a hinge or slide joint; only those are "
                    "supported (one coordinate per joint)"
                )
        self._spec = None
        self.excluded_joints = ()
        if joints is not None:
            model = self._select_joints(model, joints)
        self._model = model
        taken: set = set()
        raw = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or "" for j in
               range(model.njnt)]
        self.joint_names = tuple(raw[j] or f"joint{j}" for j in range(model.njnt))
        self.coordinate_names = tuple(_identifier(raw[j], j, taken) for j in range(model.njnt))
        hinge = int(mujoco.mjtJoint.mjJNT_HINGE)
        self.angle_coordinates = tuple(
            j for j in range(model.njnt) if int(model.jnt_type[j]) == hinge
        )
        self.mixed_actuators = self.actuated_joints[:1]
        self._parameters = {"source": self.path or "<string>",
                            "force_amplitude": _positive(force_amplitude, "force_amplitude"),
                            "timestep": float(model.opt.timestep)}
        if joints is not None:
            self._parameters["joints"] = list(self.joint_names)

    def _select_joints(self, model, joints):
        if isinstance(joints, str):
            joints = [joints]
        try:
            joints = list(joints)
        except TypeError:
            raise TypeError(f"joints: expected a list of joint names, got {joints!r}") from None
        mujoco = _mujoco()
        names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"
                 for j in range(model.njnt)]
        unknown = [j for j in joints if j not in names]
        if unknown or not joints or not all(isinstance(j, str) for j in joints):
            raise ValueError(
                f"joints: expected a non-empty list of joint names among {names}, got {joints!r}"
            )
        if not hasattr(mujoco, "MjSpec"):
            raise ValueError(f"joints: selecting joints needs MuJoCo >= 3.3 (MjSpec), found "
                             f"{mujoco.__version__}")
        spec = (mujoco.MjSpec.from_file(self.path) if self.path is not None
                else mujoco.MjSpec.from_string(self._xml))
        excluded = [name for name in names if name not in joints]
        for name in excluded:
            joint = spec.joint(name)
            if joint is None:
                raise ValueError(f"joints: cannot lock the unnamed joint {name!r}; name it")
            for actuator in list(spec.actuators):
                if actuator.target == name:
                    spec.delete(actuator)
            spec.delete(joint)
        self._spec, self.excluded_joints = spec, tuple(excluded)
        try:
            return spec.compile()
        except ValueError as error:
            raise ValueError(f"joints: the model with {excluded} locked does not compile: "
                             f"{error}") from None

    @property
    def frictionloss(self) -> np.ndarray:
        """Dry friction (``frictionloss``) of each joint, shape (n,).

        Examples
        --------
        >>> xml = ('<mujoco><worldbody><body><joint type="slide" frictionloss="0.3"/>'
        ...        '<geom size="0.1"/></body></worldbody></mujoco>')
        >>> MJCFSystem(xml).frictionloss
        array([0.3])
        """
        model = self._model
        return np.array([model.dof_frictionloss[model.jnt_dofadr[j]] for j in range(model.njnt)],
                        dtype=float)

    def random_initial_state(self, rng: np.random.Generator, scale: float = 1.0):
        """Random initial state inside the joint ranges, around the reference pose.

        A joint with a range starts uniformly between its reference position (``ref``,
        clipped to the range) and ``scale`` x 90 % of the way to each end of the range, with
        a velocity of at most ``scale`` x min(1, half the range width) per second; a joint
        without range as in :meth:`MuJoCoSystem.random_initial_state`, around ``ref``.

        Parameters
        ----------
        rng : numpy.random.Generator
            Source of the random draws.
        scale : float, default 1.0
            Fraction of the ranges used.

        Returns
        -------
        q0, qd0 : ndarray, shape (n,)

        Examples
        --------
        >>> import numpy as np
        >>> xml = ('<mujoco><compiler angle="radian"/><worldbody><body>'
        ...        '<joint type="slide" range="0 0.2" ref="0.05"/><geom size="0.1"/>'
        ...        '</body></worldbody></mujoco>')
        >>> q0 = np.array([MJCFSystem(xml).random_initial_state(np.random.default_rng(k))[0]
        ...                for k in range(200)])
        >>> bool(q0.min() >= 0.0 and q0.max() <= 0.2)
        True
        """
        model = self._model
        ref = np.array([model.qpos0[model.jnt_qposadr[j]] for j in range(model.njnt)])
        limited = np.asarray(model.jnt_limited, dtype=bool)
        low, high = np.asarray(model.jnt_range, dtype=float).T
        half = np.full(self.n, 0.5)
        half[list(self.angle_coordinates)] = 2.0
        draw = rng.uniform(-1.0, 1.0, self.n)
        center = np.where(limited, np.clip(ref, low, high), ref)
        reach = np.where(draw > 0, high - center, center - low)
        q0 = np.where(limited, center + 0.9 * scale * draw * reach, ref + draw * half * scale)
        margin = 0.05 * (high - low)
        q0 = np.where(limited, np.clip(q0, low + margin, high - margin), q0)
        speed = np.where(limited, np.minimum(1.0, (high - low) / 2), 1.0)
        qd0 = rng.uniform(-1.0, 1.0, self.n) * speed * scale
        return q0, qd0

    def metadata(self) -> dict:
        """What a dataset records to rebuild this system (:func:`system_from_metadata`).

        Returns
        -------
        dict
            ``model_path`` (absolute, or None), ``model_xml`` (the MJCF text, flattened when
            it uses ``<include>``) and ``joints`` (None for every joint).

        Examples
        --------
        >>> xml = ('<mujoco><worldbody><body><joint name="a" type="slide"/>'
        ...        '<geom size="0.1"/></body></worldbody></mujoco>')
        >>> sorted(MJCFSystem(xml).metadata())
        ['joints', 'model_path', 'model_xml']
        """
        text = self._xml
        if "<include " in text and self.path is not None:
            text = _mujoco().MjSpec.from_file(self.path).to_xml()
        return {"model_path": self.path, "model_xml": text,
                "joints": self._parameters.get("joints")}

    @property
    def actuated_joints(self):
        model = self._model
        names = []
        for a in range(model.nu):
            if int(model.actuator_trntype[a]) == int(_mujoco().mjtTrn.mjTRN_JOINT):
                names.append(self.joint_names[model.actuator_trnid[a, 0]])
        return tuple(dict.fromkeys(names))

    @property
    def joint_damping(self):
        return np.array([self._model.dof_damping[self._model.jnt_dofadr[j]]
                         for j in range(self._model.njnt)], dtype=float)

    @property
    def force_amplitudes(self):
        return {j: self._parameters["force_amplitude"] for j in self.actuated_joints}

    def lagrangian(self):
        """Not available: the true Lagrangian of a user's model is unknown.

        Returns
        -------
        sympy.Expr
            Never returns.

        Raises
        ------
        NotImplementedError
            Always; subclass :class:`MuJoCoSystem` to describe a model with a known Lagrangian.

        Examples
        --------
        >>> xml = ('<mujoco><worldbody><body><joint type="slide"/><geom size="0.1"/>'
        ...        '</body></worldbody></mujoco>')
        >>> MJCFSystem(xml).lagrangian()
        Traceback (most recent call last):
        ...
        NotImplementedError: MJCFSystem: the true Lagrangian of a user's model is unknown; ...
        """
        raise NotImplementedError(
            "MJCFSystem: the true Lagrangian of a user's model is unknown; subclass "
            "MuJoCoSystem to provide one"
        )

    def xml(self):
        """The MJCF text given (or read from the file given); with ``joints``, the reduced model.

        Returns
        -------
        str

        Examples
        --------
        >>> xml = ('<mujoco><worldbody><body><joint type="slide"/><geom size="0.1"/>'
        ...        '</body></worldbody></mujoco>')
        >>> MJCFSystem(xml).xml() == xml
        True
        """
        if self._spec is not None:
            return self._spec.to_xml()
        return self._xml

    def mj_model(self):
        """Compiled MuJoCo model, from the file when one was given (relative assets resolve).

        Returns
        -------
        mujoco.MjModel

        Examples
        --------
        >>> xml = ('<mujoco><worldbody><body><joint type="slide"/><geom size="0.1"/>'
        ...        '</body></worldbody></mujoco>')
        >>> MJCFSystem(xml).mj_model().njnt
        1
        """
        mujoco = _mujoco()
        if self._spec is not None:
            return self._spec.compile()
        if self.path is not None:
            return mujoco.MjModel.from_xml_path(self.path)
        return mujoco.MjModel.from_xml_string(self._xml)

    def __repr__(self):
        return f"MJCFSystem({self._parameters['source']!r})"


SYSTEMS = {
    CartPole.name: CartPole,
    DoublePendulum.name: DoublePendulum,
    CartDoublePendulum.name: CartDoublePendulum,
}


def get_system(name, **parameters) -> MuJoCoSystem:
    """A system by registry name, or a :class:`MJCFSystem` for a path to an MJCF file.

    Parameters
    ----------
    name : str, os.PathLike or MuJoCoSystem
        ``"cart-pole"``, ``"double-pendulum"``, ``"cart-double-pendulum"`` (underscores
        accepted), a path to an ``.xml`` file, or a system (returned as is).
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
    if isinstance(name, os.PathLike) or (isinstance(name, str) and name.endswith(".xml")):
        return MJCFSystem(name, **parameters)
    if not isinstance(name, str):
        raise TypeError(f"name: expected a system name or an MJCF path, got {type(name).__name__}")
    key = name.strip().lower().replace("_", "-")
    if key not in SYSTEMS:
        raise ValueError(
            f"name: unknown system {name!r}; expected one of {sorted(SYSTEMS)} or a path to an "
            "MJCF .xml file"
        )
    return SYSTEMS[key](**parameters)


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
        ``"cart-pole"``, ``"double-pendulum"`` or ``"cart-double-pendulum"`` (underscores
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
