"""Weak form of a catalog entry: ``E = d/dt P - Q`` with ``P`` and ``Q`` free of accelerations.

Against a test function ``phi`` that vanishes at both ends of its support,

.. math:: \\int \\phi E \\, dt = -\\int \\dot\\phi P \\, dt - \\int \\phi Q \\, dt,

so a catalog column needs no acceleration once each entry is split this way. Lagrange columns
come split by construction (``P = dL/dqd_i``, ``Q = dL/dq_i``); :func:`integrate_by_parts`
splits any other entry (classical terms, forces).
"""

from __future__ import annotations

import sympy as sp

from ..symbols import Coordinates

__all__ = ["integrate_by_parts", "time_derivative"]


def time_derivative(expr: sp.Expr, coords: Coordinates) -> sp.Expr:
    """Total time derivative of ``expr(q, qd, t)`` by the chain rule (accelerations appear).

    Parameters
    ----------
    expr : sympy.Expr
    coords : Coordinates

    Returns
    -------
    sympy.Expr

    Examples
    --------
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
    """Split a catalog entry into ``E = d/dt P - Q`` with ``P``, ``Q`` free of accelerations.

    * ``a(q) * qdd_j`` (coefficient a function of the positions and time only) becomes
      ``P = a qd_j`` and the remainder of its time derivative goes to ``Q``;
    * ``g(q_j) * qd_j`` with ``g`` a polynomial (viscous friction ``qd_j`` is the common case)
      is an exact time derivative: ``P = int g dq_j``, so the weak column needs no velocity;
    * everything else, a function of ``(q, qd, tau, t)``, goes to ``Q = -E``.

    Parameters
    ----------
    expr : sympy.Expr
        Entry in ``coords.variables``.
    coords : Coordinates

    Returns
    -------
    P, Q : sympy.Expr

    Raises
    ------
    ValueError
        When an acceleration has a coefficient that depends on velocities, forces or
        accelerations (a nonlinear acceleration term): no integration by parts removes it.

    Examples
    --------
    >>> import sympy as sp, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> integrate_by_parts(c.qd[0], c)
    (x, 0)
    >>> integrate_by_parts(sp.cos(c.q[0]) * c.qdd[0], c)
    (x_dot*cos(x), -x_dot**2*sin(x))
    """
    expr = sp.expand(sp.sympify(expr))
    positions = set(coords.q) | {coords.t}
    momentum = sp.Integer(0)
    rest = expr
    for qd, qdd in zip(coords.qd, coords.qdd, strict=True):
        if qdd not in rest.free_symbols:
            continue
        coefficient = sp.expand(sp.diff(rest, qdd))
        if not coefficient.free_symbols <= positions:
            raise ValueError(
                f"terms: the acceleration {qdd} in {expr} has a coefficient that is not a "
                "function of the positions, so the weak form cannot integrate it by parts; "
                "use formulation='strong' or rewrite the term"
            )
        momentum += coefficient * qd
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
    return momentum, q_part
