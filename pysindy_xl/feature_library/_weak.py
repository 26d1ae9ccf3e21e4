r"""Weak form of a catalog entry: ``E = d/dt P - Q`` with ``P`` and ``Q`` free of accelerations.

Against a test function ``phi`` that vanishes at both ends of its support,

.. math:: \int \phi E \, dt = -\int \dot\phi P \, dt - \int \phi Q \, dt.

Lagrange columns come split (``P = dL/dqd_i``, ``Q = dL/dq_i``); :func:`integrate_by_parts`
splits any other entry.
"""

from __future__ import annotations

import mpmath
import numpy as np
import sympy as sp

from ..symbols import Coordinates

__all__ = ["integrate_by_parts", "time_derivative"]


def time_derivative(expr: sp.Expr, coords: Coordinates) -> sp.Expr:
    """Total time derivative of ``expr(q, qd, t)`` by the chain rule (accelerations appear).

    >>> import sympy as sp, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> time_derivative(c.qd[0] * sp.cos(c.q[0]), c)
    x_ddot*cos(x) - x_dot**2*sin(x)
    """
    out = sp.diff(expr, coords.t)
    for q, qd, qdd in zip(coords.q, coords.qd, coords.qdd, strict=True):
        out += sp.diff(expr, q) * qd + sp.diff(expr, qd) * qdd
    return sp.expand(out)


def integrate_by_parts(expr: sp.Expr, coords: Coordinates) -> tuple[sp.Expr, sp.Expr]:
    r"""Split a catalog entry ``E`` into ``E = d/dt P - Q`` with ``P``, ``Q`` free of accelerations.

    The weak form integrates each entry against a test function ``phi`` that vanishes at the
    ends of its support, moving the time derivative onto ``phi``:

    .. math:: \int \phi E \, dt = -\int \dot\phi P \, dt - \int \phi Q \, dt,

    so no acceleration is needed. Rules:

    * ``a(q, t) * qdd_j`` gives ``P = a qd_j``, the rest of its time derivative going to ``Q``;
    * ``g(q_j) * qd_j`` with ``g`` a polynomial is exact: ``P = int g dq_j``;
    * ``sum_j c_j(q, qd) qdd_j`` with ``c_j = dG/dqd_j`` for one ``G(q, qd)`` (a dry friction's
      lead) gives ``P = G`` and ``Q = dG/dq . qd + dG/dt``;
    * everything else goes to ``Q = -E``.

    Parameters
    ----------
    expr : sympy.Expr
        The entry, in ``coords.variables``.
    coords : Coordinates
        The generalized coordinates.

    Returns
    -------
    P, Q : sympy.Expr
        The two parts.

    Raises
    ------
    ValueError
        When an acceleration's coefficient depends on forces or accelerations, or
        velocity-dependent coefficients are not one function's velocity gradient.

    Examples
    --------
    >>> import sympy as sp, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> integrate_by_parts(c.qd[0], c)
    (x, 0)
    >>> integrate_by_parts(sp.cos(c.q[0]) * c.qdd[0], c)
    (x_dot*cos(x), -x_dot**2*sin(x))
    >>> integrate_by_parts(c.qd[0] ** 2 * c.qdd[0], c)
    (x_dot**3/3, 0)
    """
    expr = sp.expand(sp.sympify(expr))
    positions = set(coords.q) | {coords.t}
    momentum = sp.Integer(0)
    rest = expr
    velocity_dependent = {}  # qd_j: the coefficient of qdd_j, a function of (q, qd, t)
    for qd, qdd in zip(coords.qd, coords.qdd, strict=True):
        if qdd not in rest.free_symbols:
            continue
        coefficient = sp.expand(sp.diff(rest, qdd))
        if coefficient.free_symbols <= positions:
            momentum += coefficient * qd
        elif coefficient.free_symbols <= positions | set(coords.qd):
            velocity_dependent[qd] = coefficient
        else:
            raise ValueError(f"terms: the acceleration {qdd} in {expr} has a coefficient that "
                             "depends on forces or accelerations, so the weak form cannot "
                             "integrate it by parts; use formulation='strong' or rewrite the term")
        rest = sp.expand(rest - coefficient * qdd)
    exact = sp.Integer(0)
    velocities = dict(zip(coords.qd, coords.q, strict=True))
    for term in sp.Add.make_args(rest):
        present = [v for v in term.free_symbols if v in velocities]
        if len(present) != 1 or term.as_powers_dict().get(present[0]) != 1:
            continue  # not linear in exactly one velocity
        q = velocities[present[0]]
        factor = term / present[0]
        if factor.free_symbols <= {q} and factor.is_polynomial(q):
            exact += sp.integrate(factor, q)
            rest -= term
    momentum = sp.expand(momentum + exact)
    # E = d/dt P - Q: the time derivative of the acceleration part's P has no acceleration
    # left after subtracting E's own acceleration terms, and the exact part is E's term.
    q_part = sp.expand(time_derivative(momentum, coords) - expr)
    if not velocity_dependent:
        return momentum, q_part
    potential = _velocity_potential(velocity_dependent, coords)
    if potential is None:
        raise ValueError(
            f"terms: the accelerations in {expr} have velocity-dependent coefficients that are "
            "not the velocity gradient of one function, so the weak form cannot integrate "
            "them by parts; use formulation='strong' or rewrite the term")
    # d/dt G = dG/dq . qd + dG/dt + sum_j c_j qdd_j: its acceleration part is E's own
    moved = sum((c * qdd for qd, qdd in zip(coords.qd, coords.qdd, strict=True)
                 if (c := velocity_dependent.get(qd)) is not None), sp.Integer(0))
    q_part = sp.expand(q_part + moved + sp.diff(potential, coords.t) + sum(
        (sp.diff(potential, q) * qd for q, qd in zip(coords.q, coords.qd, strict=True)),
        sp.Integer(0)))
    return momentum + potential, q_part


def _velocity_potential(coefficients: dict, coords: Coordinates):
    """``G(q, qd, t)`` with ``dG/dqd_j = coefficients[qd_j]`` (zero where absent), or None: built
    one velocity at a time, its gradient checked at 30 digits on states over orders of magnitude
    (piecewise coefficients have no identity sympy proves reliably).
    """
    variables = [*coords.q, *coords.qd, coords.t]
    rng = np.random.default_rng(0)
    states = rng.choice([-1.0, 1.0], (24, len(variables))) * 10.0 ** rng.uniform(
        -3, 1, (24, len(variables)))

    def vanishes(gap, scale):
        gap_at = sp.lambdify(variables, gap, "mpmath")
        scale_at = sp.lambdify(variables, scale, "mpmath")
        with mpmath.workdps(30):
            return all(abs(gap_at(*state)) <= 1e-12 * (1 + abs(scale_at(*state)))
                       for state in states)

    potential = sp.Integer(0)
    for qd in coords.qd:
        target = coefficients.get(qd, sp.Integer(0))
        residual = target - sp.diff(potential, qd)
        if not vanishes(residual, target):
            potential += sp.integrate(residual, qd)
            if potential.has(sp.Integral) or not vanishes(target - sp.diff(potential, qd), target):
                return None
    if all(vanishes(c - sp.diff(potential, qd), c) for qd, c in coefficients.items()):
        return potential
    return None
