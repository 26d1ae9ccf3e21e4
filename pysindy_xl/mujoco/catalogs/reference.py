"""Reference catalogs of the paper's comparison, built for any system.

Kinds, all with the force column first: ``lagrange`` (velocity monomials of degree <=
``velocity_degree`` times monomials of the angles' ``sin``/``cos`` of degree <=
``trig_degree``), ``classical`` (each monomial of their Euler-Lagrange expansion, plus viscous
friction), ``mixed`` (``lagrange`` plus viscous friction) and ``kinematic``
(:func:`~pysindy_xl.mujoco.kinematic_catalog`). A joint with ``frictionloss`` adds the smooth
Coulomb ``tanh(qd_i / eps)``; viscous terms follow ``friction`` (``"auto"``:
:meth:`~pysindy_xl.mujoco.MuJoCoSystem.friction_pattern`; ``"diagonal"``; ``"full"``).
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from ...symbols import monomials, products
from ..systems.registry import MuJoCoSystem, equations_of_motion, get_system

__all__ = ["CATALOG_KINDS", "lagrange_terms", "classical_terms", "reference_catalog",
           "true_coefficients"]

CATALOG_KINDS = ("lagrange", "classical", "mixed", "kinematic")


def _check_degree(value, name):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ValueError(f"{name}: expected an integer >= 0, got {value!r}")
    return int(value)


def lagrange_terms(system, velocity_degree: int = 2, trig_degree: int = 2) -> list[sp.Expr]:
    """Candidate Lagrangian terms: velocity monomials times trigonometric monomials.

    ``velocity_degree`` and ``trig_degree`` are the monomials' maximal degrees.

    Parameters
    ----------
    system : MuJoCoSystem or str
        A system or a registry name.
    velocity_degree : int, default=2
        Maximal degree of the velocity monomials.
    trig_degree : int, default=2
        Maximal degree of the monomials in ``sin`` and ``cos`` of the angles (the other
        positions do not enter).

    Returns
    -------
    list of sympy.Expr
        The candidate terms (no constant).

    Examples
    --------
    >>> len(lagrange_terms("cart-pole"))
    35
    """
    system = get_system(system)
    velocity_degree = _check_degree(velocity_degree, "velocity_degree")
    trig_degree = _check_degree(trig_degree, "trig_degree")
    coords = system.coords
    trig = [f(coords.q[i]) for i in system.angle_coordinates for f in (sp.sin, sp.cos)]
    velocity_part = [sp.Integer(1)]
    if velocity_degree:
        velocity_part += monomials(coords.qd, velocity_degree)
    trig_part = [sp.Integer(1)]
    if trig and trig_degree:
        trig_part += monomials(trig, trig_degree)
    terms = [t for t in products(velocity_part, trig_part) if t.free_symbols]
    if not terms:
        raise ValueError("velocity_degree, trig_degree: the catalog would be empty")
    return terms


def _monomials_of(expr: sp.Expr) -> list[tuple[sp.Expr, float]]:
    """``expr`` expanded, as (monomial without numeric factor, coefficient) pairs."""
    pairs = (term.as_coeff_Mul() for term in sp.Add.make_args(sp.expand(expr)) if term != 0)
    return [(monomial, float(coefficient)) for coefficient, monomial in pairs]


def classical_terms(system, terms) -> tuple[list[sp.Expr], np.ndarray]:
    """Distinct monomials of the Euler-Lagrange expansion of ``terms``, per equation.

    Parameters
    ----------
    system : MuJoCoSystem or str
        A system or a registry name.
    terms : sequence of sympy.Expr
        Lagrangian terms in the system's coordinates.

    Returns
    -------
    monomials : list of sympy.Expr
        The distinct monomials, without numeric factor, in order of first appearance.
    mask : numpy.ndarray of bool, shape (n_monomials, n)
        ``mask[k, i]``: monomial ``k`` appears in equation ``i``.

    Examples
    --------
    Returns the monomials (no numeric factors, in order of first appearance) and ``mask``
    (n_monomials, n): ``mask[k, i]``, monomial ``k`` appears in equation ``i``. The coupling
    term of the cart-pole expands into three classical monomials:

    >>> import sympy as sp
    >>> coords = get_system("cart-pole").coords
    >>> x_dot, theta_dot = coords.qd
    >>> found, mask = classical_terms("cart-pole", [x_dot * theta_dot * sp.cos(coords.q[1])])
    >>> found
    [theta_ddot*cos(theta), theta_dot**2*sin(theta), x_ddot*cos(theta)]
    >>> mask  # columns: equations of x and theta
    array([[ True, False],
           [ True, False],
           [False,  True]])
    """
    system = get_system(system)
    coords = system.coords
    order: dict = {}
    for term in terms:
        for i, lhs in enumerate(equations_of_motion(term, coords)):
            for monomial, _ in _monomials_of(lhs):
                order.setdefault(monomial, set()).add(i)
    found = list(order)
    mask = np.zeros((len(found), coords.n), dtype=bool)
    for k, monomial in enumerate(found):
        mask[k, sorted(order[monomial])] = True
    return found, mask


def _friction_mask(system: MuJoCoSystem, friction) -> np.ndarray:
    n = system.n
    patterns = {"auto": system.friction_pattern, "diagonal": lambda: np.eye(n, dtype=bool),
                "full": lambda: np.ones((n, n), dtype=bool)}
    if not isinstance(friction, str) or friction not in patterns:
        raise ValueError(f"friction: expected 'auto', 'diagonal' or 'full', got {friction!r}")
    return patterns[friction]().T  # mask[k, i]: velocity k in the equation of i


def dry_friction_terms(system, eps: float = 1e-3) -> tuple[list[sp.Expr], np.ndarray]:
    """Smooth Coulomb candidates ``tanh(qd_i / eps)`` for the joints with ``frictionloss``.

    Returns the terms and their mask (n_terms, n), each term in its own coordinate's
    equation. ``eps`` is much smaller than typical velocities: MuJoCo's frictionloss is
    close to an exact sign, and a wider smoothing leaks friction into the damping.

    Parameters
    ----------
    system : MuJoCoSystem
        The system; joints with ``frictionloss`` get a term.
    eps : float, default=1e-3
        Velocity scale of the smoothing.

    Returns
    -------
    terms : list of sympy.Expr
        One ``tanh(qd_i / eps)`` per joint with dry friction.
    mask : numpy.ndarray of bool, shape (n_terms, n)
        Each term in its own coordinate's equation.

    Examples
    --------
    >>> from pysindy_xl.mujoco import MJCFSystem
    >>> xml = ('<mujoco><worldbody><body><joint name="x" type="slide" frictionloss="0.3"/>'
    ...        '<geom size="0.1"/></body></worldbody></mujoco>')
    >>> dry_friction_terms(MJCFSystem(xml))
    ([tanh(1000.0*x_dot)], array([[ True]]))
    """
    system = get_system(system)
    eps = float(eps)
    if not (np.isfinite(eps) and eps > 0):
        raise ValueError(f"eps: expected a positive number, got {eps!r}")
    loss = np.asarray(getattr(system, "frictionloss", np.zeros(system.n)), dtype=float)
    joints = np.flatnonzero(loss > 0)
    terms = [sp.tanh(system.coords.qd[i] / eps) for i in joints]
    mask = np.zeros((len(terms), system.n), dtype=bool)
    mask[np.arange(len(terms)), joints] = True
    return terms, mask


def reference_catalog(system, kind: str = "mixed", velocity_degree: int = 2,
                      trig_degree: int = 2, friction: str = "auto", interlink=None,
                      dry_friction: bool | None = None, dry_friction_eps: float = 1e-3,
                      joint_models=None, coulomb_law: str = "smooth"):
    """The paper's reference catalog of a system (see the module docstring).

    Parameters
    ----------
    system : MuJoCoSystem or str
        A system, a registry name or an MJCF path.
    kind : {"lagrange", "classical", "mixed", "kinematic"}, default="mixed"
        Candidate Lagrangian terms, their Newtonian expansion, both, or the kinematic
        catalog (:func:`~pysindy_xl.mujoco.kinematic_catalog`).
    velocity_degree : int, default=2
        Maximal degree of the velocity monomials of the candidate Lagrangian terms
        (:func:`lagrange_terms`).
    trig_degree : int, default=2
        Maximal degree of their trigonometric monomials.
    friction : {"auto", "diagonal", "full"}, default="auto"
        Which velocities enter which equation as friction terms: "auto" follows the
        system's :meth:`~MuJoCoSystem.friction_pattern`.
    interlink : array_like of shape (n, n), default=None
        Passed to :class:`~pysindy_xl.ExternalForces` (``system.force_matrix()`` to fit with
        MuJoCo joint forces ``u``).
    dry_friction : bool or None, default=None
        Add :func:`dry_friction_terms`; None: when the model has ``frictionloss``.
    dry_friction_eps : float, default=1e-3
        Velocity scale of the dry friction terms.
    joint_models : sequence of str or "all", default=None
        ``"kinematic"`` only (which takes no degree or friction option): the ``friction``
        joint models of :func:`~pysindy_xl.mujoco.kinematic_catalog`.
    coulomb_law : {"smooth", "mujoco"}, default="smooth"
        ``"kinematic"`` only: the ``coulomb_law`` of
        :func:`~pysindy_xl.mujoco.kinematic_catalog`.

    Returns
    -------
    CatalogRepartition
        Libraries in the order forces, Lagrange, classical.

    Raises
    ------
    ValueError
        When ``kind`` or ``friction`` is unknown, or an option does not apply to ``kind``.

    Examples
    --------
    >>> reference_catalog("cart-pole", "mixed").fit().n_output_features_
    38
    >>> reference_catalog("cart-pole", "kinematic").fit().n_output_features_
    9
    """
    from ...feature_library import (
        CatalogRepartition,
        ClassicalLibrary,
        ExternalForces,
        LagrangeLibrary,
    )
    system = get_system(system)
    if kind not in CATALOG_KINDS:
        raise ValueError(f"kind: expected one of {CATALOG_KINDS}, got {kind!r}")
    if kind == "kinematic":
        from .kinematic import kinematic_catalog
        return kinematic_catalog(system, friction=joint_models,
                                 coulomb_law=coulomb_law).library(interlink=interlink)
    if joint_models is not None:
        raise ValueError(f"joint_models: only the 'kinematic' catalog offers joint models, not "
                         f"{kind!r}")
    if coulomb_law != "smooth":
        raise ValueError(f"coulomb_law: only the 'kinematic' catalog has other laws, not {kind!r}")
    coords = system.coords
    friction_mask = _friction_mask(system, friction)
    terms = lagrange_terms(system, velocity_degree, trig_degree)
    libraries = [ExternalForces(coords, interlink=interlink)]
    if kind in ("lagrange", "mixed"):
        libraries.append(LagrangeLibrary(coords, terms))
    if kind == "mixed":
        libraries.append(ClassicalLibrary(coords, list(coords.qd), mask=friction_mask))
    if kind == "classical":
        found, mask = classical_terms(system, terms)
        for k, velocity in enumerate(coords.qd):
            if velocity in found:
                mask[found.index(velocity)] |= friction_mask[k]
            else:
                found.append(velocity)
                mask = np.vstack([mask, friction_mask[k]])
        libraries.append(ClassicalLibrary(coords, found, mask=mask))
    dry_terms, dry_mask = dry_friction_terms(system, dry_friction_eps)
    if dry_friction is None:
        dry_friction = bool(dry_terms)
    if dry_friction:
        if not dry_terms:  # asked for: every coordinate
            dry_terms = [sp.tanh(v / float(dry_friction_eps)) for v in coords.qd]
            dry_mask = np.eye(coords.n, dtype=bool)
        libraries.append(ClassicalLibrary(coords, dry_terms, mask=dry_mask))
    return CatalogRepartition(libraries)


def _kinematic_truth(system, catalog, names, forces):
    """The MJCF model's exact vector when ``catalog`` is the system's kinematic catalog (its
    friction terms are joint velocities, which the generic matching would miss)."""
    from ._kinematic_build import COULOMB_LAWS
    from .kinematic import PolynomialLagrangeLibrary, kinematic_catalog
    if not any(isinstance(lib, PolynomialLagrangeLibrary) for lib in catalog.libraries_):
        return None
    forces_library = next(lib for lib in catalog.libraries_ if lib.category == "forces")
    for law in COULOMB_LAWS:
        kinematic = kinematic_catalog(system, coulomb_law=law)
        reference = kinematic.library(interlink=forces_library.interlink)
        if reference.fit().get_feature_names() == names:
            return kinematic.true_coefficients(forces=forces)
    return None


def true_coefficients(system, catalog, strict: bool = False, forces: float = -1.0):
    """Coefficient vector ``xi`` (F,) of the system's true model in a catalog, and ``missing``.

    The Lagrangian goes to the Lagrange terms when the catalog has any, otherwise its
    Euler-Lagrange expansion goes to the classical terms; friction goes to classical terms.
    ``system`` has a known Lagrangian, or ``catalog`` is its kinematic catalog; ``catalog``
    (e.g. :func:`reference_catalog`) is fitted here when needed; ``forces`` is the force
    column's coefficient. ``missing`` lists the parts of the true model the catalog cannot
    hold; with ``strict`` they raise a ValueError instead, as does a system with no known
    model.

    Parameters
    ----------
    system : MuJoCoSystem or str
        A system or a registry name.
    catalog : pysindy_xl.CatalogRepartition
        The catalog (e.g. :func:`reference_catalog`); fitted here when needed.
    strict : bool, default=False
        Raise a ValueError when the catalog cannot hold the whole true model.
    forces : float, default=-1.0
        Coefficient of the force column.

    Returns
    -------
    xi : numpy.ndarray of shape (n_features,)
        The true coefficient of each feature of the catalog.
    missing : list of str
        The parts of the true model the catalog cannot hold (empty with ``strict``).

    Raises
    ------
    ValueError
        When the system has no known model, or with ``strict`` when something is missing.

    Examples
    --------
    >>> catalog = reference_catalog("cart-pole", "mixed", trig_degree=1)
    >>> xi, missing = true_coefficients("cart-pole", catalog)
    >>> {name: round(float(v), 4) for name, v in zip(catalog.get_feature_names(), xi) if v}
    {'F[tau]': -1.0, 'L[cos(theta)]': 3.924, 'L[x_dot**2]': 0.75,
     'L[theta_dot*x_dot*cos(theta)]': 0.4, 'L[theta_dot**2]': 0.16, 'C_x[x_dot]': 0.5,
     'C_theta[theta_dot]': 0.1}
    >>> _, missing = true_coefficients("cart-pole", reference_catalog("cart-pole", "lagrange"))
    >>> missing
    ['+0.5*x_dot in the equation of x', '+0.1*theta_dot in the equation of theta']
    """
    system = get_system(system)
    if not hasattr(catalog, "ideal_coefficients"):
        raise TypeError("catalog: expected a CatalogRepartition")
    if not hasattr(catalog, "entry_index_"):
        catalog.fit()
    coords = system.coords
    names = catalog.get_feature_names()
    # the kinematic catalog is exact for any MJCF model: its values are the MJCF's
    kinematic = _kinematic_truth(system, catalog, names, forces)
    if kinematic is not None:
        return kinematic, []
    if not system.has_ground_truth:
        raise ValueError(f"system: {system!r} has no known true model")
    has_lagrange = any(lib.category == "lagrange" for lib in catalog.libraries_)
    classical = dict(system.friction())
    if not has_lagrange:
        for i, lhs in enumerate(equations_of_motion(system.lagrangian(), coords)):
            for monomial, value in _monomials_of(sp.expand_trig(lhs)):
                classical[(monomial, i)] = classical.get((monomial, i), 0.0) + value
    keyed, missing = {}, []
    for (term, i), value in classical.items():
        name = f"C_{coords.names[i]}[{term}]"
        if name in names:
            keyed[name] = keyed.get(name, 0.0) + value
        elif abs(value) > 1e-14:
            missing.append(f"{value:+.4g}*{term} in the equation of {coords.names[i]}")
    if missing and strict:
        raise ValueError(f"catalog: the true model needs terms it lacks: {missing}")
    try:
        xi = catalog.ideal_coefficients(lagrangian=system.lagrangian() if has_lagrange else None,
                                        classical=keyed, forces=forces)
    except ValueError as error:
        if strict:
            raise
        missing.append(str(error))
        xi = catalog.ideal_coefficients(classical=keyed, forces=forces)
    return xi, missing
