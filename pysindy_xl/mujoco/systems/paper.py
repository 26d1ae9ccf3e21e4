"""The paper's systems as MuJoCo models: cart-pole, double pendulum, double pendulum on a cart,
and a (chaotic) three-link pendulum.

Each class writes its MJCF text from its parameters and knows the same mechanism's textbook
Lagrangian (coordinate conventions: :mod:`pysindy_xl.mujoco.systems.registry`).
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from .base import MuJoCoSystem, checked_parameters, mjcf_float

__all__ = ["CartPole", "DoublePendulum", "CartDoublePendulum", "TriplePendulum"]


# -- MJCF building blocks ------------------------------------------------------------------
def _header(model: str, timestep: float, gravity: float) -> str:
    return f"""<mujoco model="{model}">
  <!-- Written by pysindy_xl.mujoco.systems; point masses via explicit inertials. -->
  <compiler angle="radian" inertiafromgeom="auto"/>
  <option timestep="{mjcf_float(timestep)}" integrator="RK4" gravity="0 0 {mjcf_float(-gravity)}">
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
      <joint name="slider" type="slide" axis="1 0 0" damping="{mjcf_float(damping)}"/>
      <inertial pos="0 0 0" mass="{mjcf_float(mass)}" diaginertia="0.01 0.01 0.01"/>
      <geom type="box" size="0.2 0.1 0.05" rgba="0.3 0.3 0.8 1"/>
{inner}    </body>
"""


def _link(body: str, joint: str, mass, length, damping, inertia, pos, inner="", indent=6):
    # axis 0 -1 0: a positive angle moves the bob towards +x (textbook convention).
    pad = " " * indent
    return (f'{pad}<body name="{body}" pos="{pos}">\n'
            f'{pad}  <joint name="{joint}" type="hinge" axis="0 -1 0" '
            f'damping="{mjcf_float(damping)}"/>\n'
            f'{pad}  <inertial pos="0 0 {mjcf_float(-length)}" mass="{mjcf_float(mass)}" '
            f'diaginertia="{mjcf_float(inertia)} {mjcf_float(inertia)} {mjcf_float(inertia)}"/>\n'
            f'{pad}  <geom type="capsule" fromto="0 0 0 0 0 {mjcf_float(-length)}" size="0.01" '
            f'rgba="0.6 0.6 0.6 1"/>\n'
            f'{pad}  <geom type="sphere" pos="0 0 {mjcf_float(-length)}" size="0.04" '
            f'rgba="0.8 0.3 0.3 1"/>\n'
            f"{inner}{pad}</body>\n")


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
    cart_mass : float, default=1.0
        Cart mass (kg).
    pole_mass : float, default=0.5
        Bob mass (kg).
    length : float, default=0.8
        Rod length (m).
    cart_damping : float, default=0.5
        Viscous friction of the slider (N s/m).
    pole_damping : float, default=0.1
        Viscous friction of the hinge (N m s/rad).
    gravity : float, default=9.81
        Gravitational acceleration (m/s^2), along -z.
    point_inertia : float, default=1e-6
        Rotational inertia of the bob about its center (kg m^2; tiny, exact in the
        Lagrangian).
    timestep : float, default=1e-3
        MuJoCo time step (s), RK4 integrator.

    Raises
    ------
    TypeError
        When a parameter is not a real number.
    ValueError
        When a parameter is negative (zero allowed for gravity and dampings only).

    See Also
    --------
    get_system : The same system by its registry name, ``"cart-pole"``.

    Notes
    -----
    With cart mass :math:`M`, bob mass :math:`m`, rod length :math:`l` and point inertia
    :math:`I`, the Lagrangian is

    .. math::

        L = \\tfrac12 (M + m)\\dot x^2 + m l \\dot x \\dot\\theta \\cos\\theta
        + \\tfrac12 (m l^2 + I)\\dot\\theta^2 + m g l \\cos\\theta ,

    with viscous friction ``-cart_damping * x_dot`` on the cart and
    ``-pole_damping * theta_dot`` on the pole.

    Examples
    --------
    >>> system = CartPole(pole_mass=0.2)
    >>> system.coords
    Coordinates(['x', 'theta'])
    >>> system.mj_model().nv
    2
    """

    name = "cart-pole"
    coordinate_names = ("x", "theta")
    joint_names = ("slider", "hinge")
    angle_coordinates = (1,)
    mixed_actuators = ("slider",)

    def __init__(self, cart_mass=1.0, pole_mass=0.5, length=0.8, cart_damping=0.5,
                 pole_damping=0.1, gravity=9.81, point_inertia=1e-6, timestep=1e-3):
        self._parameters = checked_parameters(
            cart_mass=cart_mass, pole_mass=pole_mass, length=length, cart_damping=cart_damping,
            pole_damping=pole_damping, gravity=gravity, point_inertia=point_inertia,
            timestep=timestep)

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
            The Lagrangian ``T - V`` of the cart-pole.

        Examples
        --------
        >>> CartPole(cart_mass=1.0, pole_mass=0.5, length=0.8).lagrangian()
        0.1600005*theta_dot**2 + 0.4*theta_dot*x_dot*cos(theta) + 0.75*x_dot**2 + 3.924*cos(theta)
        """
        p = self._parameters
        x, th = self.coords.q
        xd, thd = self.coords.qd
        big_m, m, l, g = p["cart_mass"], p["pole_mass"], p["length"], p["gravity"]
        kinetic = ((big_m + m) * xd**2 / 2 + m * l * xd * thd * sp.cos(th)
                   + (m * l**2 + p["point_inertia"]) * thd**2 / 2)
        potential = -m * g * l * sp.cos(th)
        return kinetic - potential

    def xml(self):
        """MJCF text of the cart-pole (see :meth:`MuJoCoSystem.xml`).

        Returns
        -------
        str
            The MJCF document of the cart-pole with the current parameters.
        """
        p = self._parameters
        link = _link("pole", "hinge", p["pole_mass"], p["length"], p["pole_damping"],
                     p["point_inertia"], "0 0 0")
        return (_header("cart_pole", p["timestep"], p["gravity"])
                + _cart(p["cart_mass"], p["cart_damping"], link)
                + _footer(self.joint_names))


def _chain_xml(p: dict, n_links: int, indent: int) -> str:
    """MJCF bodies of a pendulum chain, link ``k`` carrying link ``k + 1``."""
    inner = ""
    for k in range(n_links, 0, -1):
        pos = "0 0 0" if k == 1 else f"0 0 {mjcf_float(-p[f'length{k - 1}'])}"
        inner = _link(f"link{k}", f"hinge{k}", p[f"mass{k}"], p[f"length{k}"], p[f"damping{k}"],
                      p["point_inertia"], pos, inner=inner, indent=indent + 2 * (k - 1))
    return inner


# -- pendulum chains (``mass{k}``, ``length{k}``, ``damping{k}`` for links k = 1..n) ----------
def _chain_masses(p: dict, n_links: int) -> list:
    """``mu_k``: the mass at or beyond link ``k`` (what link ``k``'s angle carries)."""
    masses = [p[f"mass{k}"] for k in range(1, n_links + 1)]
    return [sum(masses[k:]) for k in range(n_links)]


def _chain_amplitudes(p: dict, n_links: int) -> dict:
    """Random-force amplitude of each hinge: 0.3 of the gravity torque of what it carries."""
    return {f"hinge{k + 1}": 0.3 * mu * p["gravity"] * p[f"length{k + 1}"]
            for k, mu in enumerate(_chain_masses(p, n_links))}


def _chain_dampings(p: dict, n_links: int) -> list:
    """The hinges' viscous dampings, in joint order."""
    return [p[f"damping{k}"] for k in range(1, n_links + 1)]


def _chain_lagrangian(p: dict, th, thd, xd=None):
    r"""Lagrangian of a chain of point masses in absolute angles ``th``, on a cart moving at
    ``xd`` (None: a fixed pivot):

    .. math:: T = \sum_i \frac{\mu_i l_i^2 \dot\theta_i^2}{2}
              + \sum_{i<j} \mu_j l_i l_j \dot\theta_i \dot\theta_j \cos(\theta_i - \theta_j)
              + \frac{I}{2} \sum_i \dot\theta_i^2, \qquad
              V = -g \sum_i \mu_i l_i \cos\theta_i

    (``mu_i``: the mass at or beyond link ``i``; ``I``: each bob's tiny rotational inertia), and
    with a cart ``(M + sum m) xd^2 / 2 + sum_i mu_i l_i xd thd_i cos(th_i)``.
    """
    n = len(th)
    mu, g = _chain_masses(p, n), p["gravity"]
    lengths = [p[f"length{k}"] for k in range(1, n + 1)]
    kinetic = sum(mu[i] * lengths[i] ** 2 * thd[i] ** 2 / 2 for i in range(n))
    for i in range(n):
        for j in range(i + 1, n):
            kinetic += mu[j] * lengths[i] * lengths[j] * thd[i] * thd[j] * sp.cos(th[i] - th[j])
    # each bob's body rotates with its absolute angle
    kinetic += p["point_inertia"] * sum(w**2 for w in thd) / 2
    if xd is not None:
        masses = [p[f"mass{k}"] for k in range(1, n + 1)]
        kinetic += sum(masses, p["cart_mass"]) * xd**2 / 2
        for i in range(n):
            kinetic += mu[i] * lengths[i] * xd * thd[i] * sp.cos(th[i])
    potential = -sum(mu[i] * g * lengths[i] * sp.cos(th[i]) for i in range(n))
    return kinetic - potential


class DoublePendulum(MuJoCoSystem):
    """Double pendulum with point masses on massless rods, hanging from a fixed pivot.

    Coordinates ``theta1``, ``theta2``: absolute angles from the downward vertical; hinges
    ``hinge1`` and ``hinge2`` measure ``theta1`` and ``theta2 - theta1``.

    Parameters
    ----------
    mass1, mass2 : float, default=1.0, 0.8
        Bob mass of each link (kg).
    length1, length2 : float, default=1.0, 0.7
        Rod length of each link (m).
    damping1, damping2 : float, default=0.3, 0.15
        Viscous damping of each hinge (N m s/rad), on the relative angle.
    gravity : float, default=9.81
        Gravitational acceleration (m/s^2).
    point_inertia : float, default=1e-6
        Rotational inertia of each bob about its center (kg m^2).
    timestep : float, default=1e-3
        MuJoCo time step (s), RK4 integrator.

    Raises
    ------
    TypeError
        When a parameter is not a real number.
    ValueError
        When a parameter is negative (zero allowed for gravity and dampings only).

    Examples
    --------
    A motor on the second hinge acts on both absolute angles:

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
        self._parameters = checked_parameters(
            mass1=mass1, mass2=mass2, length1=length1, length2=length2, damping1=damping1,
            damping2=damping2, gravity=gravity, point_inertia=point_inertia, timestep=timestep)

    @property
    def joint_to_coordinates(self):
        return np.tril(np.ones((2, 2)))

    @property
    def joint_damping(self):
        return np.array(_chain_dampings(self._parameters, 2))

    @property
    def force_amplitudes(self):
        return _chain_amplitudes(self._parameters, 2)

    def lagrangian(self):
        """True Lagrangian of the double pendulum in absolute angles.

        Returns
        -------
        sympy.Expr
            The Lagrangian ``T - V`` of the double pendulum.
        """
        return _chain_lagrangian(self._parameters, self.coords.q, self.coords.qd)

    def xml(self):
        """MJCF text of the double pendulum (see :meth:`MuJoCoSystem.xml`).

        Returns
        -------
        str
            The MJCF document of the double pendulum with the current parameters.
        """
        p = self._parameters
        return (_header("double_pendulum", p["timestep"], p["gravity"])
                + _chain_xml(p, 2, indent=4) + _footer(self.joint_names))


class CartDoublePendulum(MuJoCoSystem):
    """Double pendulum (point masses) hanging from a cart on a horizontal rail.

    Coordinates ``x``, ``theta1``, ``theta2`` (absolute angles); MuJoCo joints ``slider``,
    ``hinge1``, ``hinge2`` (the last relative to the first link).

    Parameters
    ----------
    cart_mass : float, default=1.0
        Cart mass (kg).
    mass1, mass2 : float, default=0.5, 0.4
        Bob mass of each link (kg).
    length1, length2 : float, default=0.7, 0.5
        Rod length of each link (m).
    cart_damping : float, default=0.5
        Viscous friction of the slider (N s/m).
    damping1, damping2 : float, default=0.1, 0.05
        Viscous damping of each hinge (N m s/rad), on the relative angle.
    gravity : float, default=9.81
        Gravitational acceleration (m/s^2).
    point_inertia : float, default=1e-6
        Rotational inertia of each bob about its center (kg m^2).
    timestep : float, default=1e-3
        MuJoCo time step (s), RK4 integrator.

    Raises
    ------
    TypeError
        When a parameter is not a real number.
    ValueError
        When a parameter is negative (zero allowed for gravity and dampings only).

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
        self._parameters = checked_parameters(
            cart_mass=cart_mass, mass1=mass1, mass2=mass2, length1=length1, length2=length2,
            cart_damping=cart_damping, damping1=damping1, damping2=damping2, gravity=gravity,
            point_inertia=point_inertia, timestep=timestep)

    @property
    def joint_to_coordinates(self):
        return np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 1.0]])

    @property
    def joint_damping(self):
        p = self._parameters
        return np.array([p["cart_damping"], *_chain_dampings(p, 2)])

    @property
    def force_amplitudes(self):
        p = self._parameters
        return {"slider": 2.0 * (p["cart_mass"] + p["mass1"] + p["mass2"]),
                **_chain_amplitudes(p, 2)}

    def lagrangian(self):
        """True Lagrangian of the double pendulum on a cart.

        Returns
        -------
        sympy.Expr
            The Lagrangian ``T - V`` of the double pendulum on a cart.
        """
        xd, *thd = self.coords.qd
        return _chain_lagrangian(self._parameters, self.coords.q[1:], thd, xd=xd)

    def xml(self):
        """MJCF text of the double pendulum on a cart (see :meth:`MuJoCoSystem.xml`).

        Returns
        -------
        str
            The MJCF document of the double pendulum on a cart with the current parameters.
        """
        p = self._parameters
        link = _chain_xml(p, 2, indent=6)
        return (_header("cart_double_pendulum", p["timestep"], p["gravity"])
                + _cart(p["cart_mass"], p["cart_damping"], link)
                + _footer(self.joint_names))


class TriplePendulum(MuJoCoSystem):
    """Three-link pendulum with point masses on massless rods, hanging from a fixed pivot.

    Coordinates ``theta1``, ``theta2``, ``theta3``: absolute angles from the downward
    vertical; hinges ``hinge1``, ``hinge2``, ``hinge3`` measure each link's angle relative to
    the previous one. Chaotic at moderate energies.

    Parameters
    ----------
    mass1, mass2, mass3 : float, default=1.0, 0.8, 0.6
        Bob mass of each link (kg).
    length1, length2, length3 : float, default=0.8, 0.6, 0.5
        Rod length of each link (m).
    damping1, damping2, damping3 : float, default=0.2, 0.1, 0.05
        Viscous damping of each hinge (N m s/rad), on the relative angle.
    gravity : float, default=9.81
        Gravitational acceleration (m/s^2).
    point_inertia : float, default=1e-6
        Rotational inertia of each bob about its center (kg m^2).
    timestep : float, default=1e-3
        MuJoCo time step (s), RK4 integrator.

    Raises
    ------
    TypeError
        When a parameter is not a real number.
    ValueError
        When a parameter is negative (zero allowed for gravity and dampings only).

    Examples
    --------
    >>> TriplePendulum().coords.names
    ('theta1', 'theta2', 'theta3')
    """

    name = "triple-pendulum"
    coordinate_names = ("theta1", "theta2", "theta3")
    joint_names = ("hinge1", "hinge2", "hinge3")
    angle_coordinates = (0, 1, 2)
    mixed_actuators = ("hinge1",)

    def __init__(self, mass1=1.0, mass2=0.8, mass3=0.6, length1=0.8, length2=0.6, length3=0.5,
                 damping1=0.2, damping2=0.1, damping3=0.05, gravity=9.81, point_inertia=1e-6,
                 timestep=1e-3):
        self._parameters = checked_parameters(
            mass1=mass1, mass2=mass2, mass3=mass3, length1=length1, length2=length2,
            length3=length3, damping1=damping1, damping2=damping2, damping3=damping3,
            gravity=gravity, point_inertia=point_inertia, timestep=timestep)

    @property
    def joint_to_coordinates(self):
        return np.tril(np.ones((3, 3)))

    @property
    def joint_damping(self):
        return np.array(_chain_dampings(self._parameters, 3))

    @property
    def force_amplitudes(self):
        return _chain_amplitudes(self._parameters, 3)

    def lagrangian(self):
        """True Lagrangian of the three-link pendulum in absolute angles.

        ``T = 1/2 sum_ij mu_ij l_i l_j thd_i thd_j cos(th_i - th_j)`` with ``mu_ij`` the mass
        at or beyond link ``max(i, j)``, ``V = -g sum_i mu_ii l_i cos th_i``, plus each bob's
        tiny rotational inertia.

        Returns
        -------
        sympy.Expr
            The Lagrangian ``T - V`` of the three-link pendulum.
        """
        return _chain_lagrangian(self._parameters, self.coords.q, self.coords.qd)

    def xml(self):
        """MJCF text of the three-link pendulum (see :meth:`MuJoCoSystem.xml`).

        Returns
        -------
        str
            The MJCF document of the three-link pendulum with the current parameters.
        """
        p = self._parameters
        return (_header("triple_pendulum", p["timestep"], p["gravity"]) + _chain_xml(p, 3, 4)
                + _footer(self.joint_names))
