r"""Dry friction laws of a joint (``tanh(v / eps)`` or ``sign(v)``, and MuJoCo's regularized
``frictionloss``, :func:`regularized_dry_friction`), and recognizing them in a catalog's terms
(:func:`dry_friction_law`).
"""

from __future__ import annotations

import numpy as np
import sympy as sp

__all__ = ["dry_friction_law", "regularized_dry_friction"]


def regularized_dry_friction(velocity, acceleration, scale: float, lead: float) -> sp.Expr:
    r"""MuJoCo's unit dry friction ``sat((v + tau a) / s)`` to first order in its lead.

    .. math:: \mathrm{sat}\Big(\frac{v + \tau a}{s}\Big) \approx \mathrm{sat}(v / s)
              + \tau \frac{d}{dt} \mathrm{sat}(v / s),
              \qquad \mathrm{sat}(x) = \frac{|x + 1| - |x - 1|}{2}.

    Exact inside or outside the sticking zone; the lead is a time derivative, integrated by
    parts in the weak form.

    Parameters
    ----------
    velocity, acceleration : sympy.Expr
        ``v`` and ``a``.
    scale, lead : float
        ``s`` (positive) and ``tau`` (s, non-negative).

    Returns
    -------
    sympy.Expr
        The term.

    Examples
    --------
    >>> import sympy as sp
    >>> v, a = sp.symbols("v a", real=True)
    >>> term = regularized_dry_friction(v, a, 0.5, 0.01)
    >>> float(term.subs({v: 0.25, a: 3.0})), float(term.subs({v: 2.0, a: 3.0}))
    (0.56, 1.0)
    """
    x = velocity / sp.Float(scale)
    inside = (sp.sign(x + 1) - sp.sign(x - 1)) / 2
    return (sp.Abs(x + 1) - sp.Abs(x - 1)) / 2 + sp.Float(lead / scale) * inside * acceleration


def dry_friction_law(term, velocity, acceleration=None) -> str | None:
    """Which unit dry friction law ``term`` is in ``velocity``.

    Parameters
    ----------
    term : sympy.Expr
        The term.
    velocity : sympy.Symbol
        The velocity.
    acceleration : sympy.Symbol, optional
        The acceleration (for a regularized law); default None.

    Returns
    -------
    {"smooth", "regularized"} or None
        ``tanh(k v)`` or ``sign(v)``; :func:`regularized_dry_friction` at some scale and lead;
        any other term.

    Examples
    --------
    >>> import sympy as sp
    >>> v, a = sp.symbols("v a", real=True)
    >>> dry_friction_law(sp.tanh(100 * v), v), dry_friction_law(v, v)
    ('smooth', None)
    >>> dry_friction_law(regularized_dry_friction(v, a, 0.3, 0.01), v, a)
    'regularized'
    """
    if term.func in (sp.tanh, sp.sign) and term.free_symbols == {velocity}:
        return "smooth"
    if not (term.has(sp.Abs) and velocity in term.free_symbols
            and term.free_symbols <= {velocity, acceleration}):
        return None
    # the scale from the saturation's kinks |v / s +- 1|, the lead from the inertia at rest
    kinks = set()
    for atom in term.atoms(sp.Abs):
        if atom.args[0].free_symbols != {velocity}:
            return None
        try:
            slope, _ = sp.Poly(atom.args[0], velocity).all_coeffs()
            kinks.add(abs(float(slope)))
        except (sp.PolynomialError, TypeError, ValueError):  # not affine in v
            return None
    if len(kinks) != 1:
        return None
    scale = 1.0 / kinks.pop()
    lead = float(sp.diff(term, acceleration).subs(velocity, 0)) * scale if (
        acceleration in term.free_symbols) else 0.0
    law = sp.lambdify((velocity, acceleration), regularized_dry_friction(
        velocity, acceleration, scale, lead) - term, "numpy")
    v = scale * np.array([-3.0, -1.5, -0.7, -0.2, 0.1, 0.4, 0.9, 2.5])
    if np.allclose(law(v, np.linspace(-2.0, 3.0, v.size)), 0.0, rtol=0, atol=1e-12):
        return "regularized"
    return None
