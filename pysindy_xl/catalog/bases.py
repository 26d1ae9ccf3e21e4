"""Functions of single coordinates that automatic catalogs multiply into Lagrangian terms.

Per coordinate kind:

- ``"linear"``: the monomials ``x, x^2, ..., x^d``;
- ``"angle"``: the trigonometric monomials ``sin^a cos^b`` with ``b <= 1`` and
  ``1 <= a + b <= d`` (``cos^2 = 1 - sin^2`` would be an exact dependency), and optionally the
  polynomials ``theta, ..., theta^p`` (torsion springs, which no sine or cosine states);
- any kind: cubic B-splines of the coordinate on uniform knots (:func:`bspline`), for laws that
  no family states.

A B-spline is written with ``Abs`` (truncated powers ``z_+ = (z + |z|) / 2``), which the
package's grammar, its NumPy and JAX back ends and :meth:`XLSINDy.simulate
<pysindy_xl.XLSINDy.simulate>` handle like any term.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

__all__ = ["KINDS", "bspline", "bspline_centers", "factor_functions"]

#: The coordinate kinds an automatic catalog knows.
KINDS = ("linear", "angle")


def _plus_cubed(z: sp.Expr) -> sp.Expr:
    """``max(z, 0)^3`` as ``((z + |z|) / 2)^3``."""
    return ((z + sp.Abs(z)) / 2) ** 3


def bspline(q: sp.Symbol, center: float, width: float) -> sp.Expr:
    """The uniform cubic B-spline of ``q`` centred at ``center`` with knot spacing ``width``.

    .. math::

        B(s) = \\tfrac16 \\left[(s+2)_+^3 - 4 (s+1)_+^3 + 6 s_+^3 - 4 (s-1)_+^3
        + (s-2)_+^3\\right], \\qquad s = (q - c) / h

    is twice continuously differentiable, nonzero on ``(c - 2h, c + 2h)`` only, and peaks at
    ``B(0) = 2/3``; translates by ``h`` sum to 1 (a partition of unity).

    Parameters
    ----------
    q : sympy.Symbol
        The coordinate.
    center, width : float
        ``c`` and ``h > 0``.

    Returns
    -------
    sympy.Expr

    Examples
    --------
    >>> import sympy as sp
    >>> x = sp.Symbol("x", real=True)
    >>> b = bspline(x, 0.0, 1.0)
    >>> [round(float(b.subs(x, v)), 6) for v in (-2.0, -1.0, 0.0, 0.5, 2.5)]
    [0.0, 0.166667, 0.666667, 0.479167, 0.0]
    """
    width = float(width)
    if not (np.isfinite(width) and width > 0):
        raise ValueError(f"width: expected a positive number, got {width!r}")
    s = (q - sp.Float(float(center))) / sp.Float(width)
    return (_plus_cubed(s + 2) - 4 * _plus_cubed(s + 1) + 6 * _plus_cubed(s)
            - 4 * _plus_cubed(s - 1) + _plus_cubed(s - 2)) / 6


def bspline_centers(low: float, high: float, n_functions: int) -> tuple[np.ndarray, float]:
    """Centres and spacing of ``n_functions`` uniform B-splines covering ``[low, high]``.

    The centres run from ``low`` to ``high`` in equal steps ``h``; the splines of the two end
    centres reach ``2 h`` beyond the interval.

    Parameters
    ----------
    low, high : float
        The interval to cover, ``low < high``.
    n_functions : int
        Number of splines, at least 2.

    Returns
    -------
    centers : ndarray, shape (n_functions,)
    spacing : float
        ``h = (high - low) / (n_functions - 1)``.

    Examples
    --------
    >>> bspline_centers(-1.0, 1.0, 5)
    (array([-1. , -0.5,  0. ,  0.5,  1. ]), 0.5)
    """
    if isinstance(n_functions, bool) or not isinstance(n_functions, (int, np.integer)) \
            or n_functions < 2:
        raise ValueError(f"splines: expected at least 2 functions per coordinate, got "
                         f"{n_functions!r}")
    low, high = float(low), float(high)
    if not (np.isfinite(low) and np.isfinite(high) and high > low):
        raise ValueError(f"bounds: expected finite low < high, got ({low!r}, {high!r})")
    centers = np.linspace(low, high, int(n_functions))
    return centers, float(centers[1] - centers[0])


def factor_functions(q: sp.Symbol, kind: str, degree: int, trig_degree: int,
                     angle_degree: int) -> list[sp.Expr]:
    """The non-constant functions of one coordinate (see the module docstring).

    Parameters
    ----------
    q : sympy.Symbol
    kind : {"linear", "angle"}
    degree : int
        Highest power of a linear coordinate.
    trig_degree : int
        Highest degree of the trigonometric monomials of an angle.
    angle_degree : int
        Highest power of an angle itself (0: none).

    Returns
    -------
    list of sympy.Expr

    Examples
    --------
    >>> import sympy as sp
    >>> th = sp.Symbol("theta", real=True)
    >>> factor_functions(th, "angle", 0, 2, 1)
    [sin(theta), cos(theta), sin(theta)**2, sin(theta)*cos(theta), theta]
    """
    if kind == "linear":
        return [q ** k for k in range(1, degree + 1)]
    out = []
    for total in range(1, trig_degree + 1):
        for b in (0, 1):
            if total - b >= 0:
                out.append(sp.sin(q) ** (total - b) * sp.cos(q) ** b)
    return out + [q ** k for k in range(1, angle_degree + 1)]
