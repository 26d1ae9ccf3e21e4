"""Functions of single coordinates that automatic catalogs multiply into Lagrangian terms.

Per coordinate kind:

- ``"linear"``: the monomials ``x, x^2, ..., x^d``;
- ``"angle"``: the trigonometric monomials ``sin^a cos^b`` with ``b <= 1`` and
  ``1 <= a + b <= d`` (``cos^2 = 1 - sin^2`` would be an exact dependency), and optionally the
  polynomials ``theta, ..., theta^p`` (torsion springs, which no sine or cosine states);
- any kind, for laws that no family states, cubic splines of the coordinate on uniform knots
  built from cubic B-splines (:func:`bspline`), in two continuations beyond the end knots:

  - :func:`natural_splines`: combined at each end so that the curvature vanishes there, and
    continued linearly beyond (a potential with a constant slope, i.e. a constant force,
    outside the data: a well that flattens, as ``log cosh x``);
  - :func:`quadratic_end_splines`: every cubic spline on the knots, continued beyond by its
    quadratic Taylor polynomial at the end knot (a constant stiffness outside the data: a
    wall that keeps rising, as the repulsive side of a Morse well).

  Which continuation the data support is for a held-out criterion to judge (the automatic
  catalog's growth tries both);
- a linear coordinate, for exponential laws (Morse and Born-Mayer walls, exponential springs):
  :func:`exponential_pair`, ``exp(a x)`` and ``exp(2 a x)`` with one signed rate ``a``
  (fitted on data by :mod:`.rates`);
- either kind, for a spring anchored off the coordinate's path: :func:`anchored_spring`, the
  spring's length (fitted on data by :mod:`.anchors`).

  :func:`truncated_power_splines` writes either span in another basis: a few polynomials and,
  per interior knot, the truncated cube ``(q - xi_j)_+^3`` made to respect the ends. Its
  functions are not local, but leaving one out removes a knot (the spline stays cubic across
  it), where leaving out a B-spline cuts a dip into the potential: a sparse selection over
  these columns chooses the knots the data need, and the fewer knots, the steadier the
  spline's end slope and curvature, which set its continuation beyond the data.

Splines are written with ``Abs`` (truncated powers ``z_+ = (z + |z|) / 2``), which the
package's grammar, its NumPy and JAX back ends and :meth:`XLSINDy.simulate
<pysindy_xl.XLSINDy.simulate>` handle like any term.
"""

from __future__ import annotations

import functools

import numpy as np
import sympy as sp

__all__ = ["KINDS", "anchored_spring", "bspline", "bspline_centers", "exponential_pair",
           "factor_functions",
           "natural_splines", "quadratic_end_splines", "truncated_power_splines", "SPLINE_BASES"]

#: The two ways of writing a coordinate's splines: ``"bspline"`` (each function a local bump,
#: :func:`natural_splines`, :func:`quadratic_end_splines`) or ``"truncated"`` (each function but
#: a few polynomials one interior knot's jump of the third derivative,
#: :func:`truncated_power_splines`). Both span the same functions.
SPLINE_BASES = ("bspline", "truncated")

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


def natural_splines(q: sp.Symbol, low: float, high: float, n_functions: int) -> list[sp.Expr]:
    """A basis of the natural cubic splines of ``q`` on ``n_functions`` uniform knots of
    ``[low, high]``, continued linearly beyond.

    With knots ``xi_1 = low, ..., xi_K = high`` (spacing ``h``) and the cubic B-splines
    ``B_j`` centred at ``xi_j`` (:func:`bspline`), the basis is

    - ``B_j`` for ``3 <= j <= K - 2`` (zero outside ``[low, high]``);
    - at each end the combinations ``B_1 + 2 B_0`` and ``B_2 - B_0`` (and their mirror images at
      ``high``), whose second derivative vanishes at the end knot, continued beyond it by their
      tangent there.

    Each function is written in truncated powers of ``s = (q - low) / h`` (knot ``j`` at
    ``s = j``), e.g. ``B_1 + 2 B_0 = 1 - s + [s_+^3 - 2 (s - 1)_+^3 + (s - 2)_+^3] / 6``.

    The span is the ``K``-dimensional space of natural cubic splines (twice continuously
    differentiable, cubic between knots, linear outside ``[low, high]``); it contains the
    constants and ``q`` itself, and the functions sum to 1.

    Parameters
    ----------
    q : sympy.Symbol
        The coordinate.
    low, high : float
        The end knots, ``low < high``.
    n_functions : int
        ``K``, the number of knots and of functions, at least 4.

    Returns
    -------
    list of sympy.Expr
        ``K`` functions, the left end's pair first.

    Examples
    --------
    >>> import sympy as sp
    >>> x = sp.Symbol("x", real=True)
    >>> basis = natural_splines(x, 0.0, 3.0, 4)
    >>> [round(float(sum(basis).subs(x, v)), 6) for v in (-1.0, 1.3, 4.0)]
    [1.0, 1.0, 1.0]
    >>> [round(float(basis[0].subs(x, v)), 6) for v in (-2.0, -1.0, 0.0)]  # slope -1 below 0
    [3.0, 2.0, 1.0]
    """
    if isinstance(n_functions, bool) or not isinstance(n_functions, (int, np.integer)) \
            or n_functions < 4:
        raise ValueError(f"splines: expected at least 4 natural splines per coordinate, got "
                         f"{n_functions!r}")
    return list(_natural_splines(q, float(low), float(high), int(n_functions)))


@functools.lru_cache(maxsize=1024)
def _natural_splines(q: sp.Symbol, low: float, high: float, k: int) -> tuple:
    """:func:`natural_splines`, built once per coordinate, end knots and count (the catalogs
    a growth tries share their splines; sympy expressions are immutable)."""
    centers, h = bspline_centers(low, high, k)
    s = (q - sp.Float(float(centers[0]))) / sp.Float(h)  # knot j at s = j

    def cubes(*pairs):
        """``sum(w (s - j)_+^3) / 6`` over ``(w, j)``."""
        return sum(w * _plus_cubed(s - j) for w, j in pairs) / 6

    # the end pairs in truncated powers (exact: the B-splines' combinations, continued by
    # their tangent at the end knot, which their vanishing curvature makes a line)
    out = [1 - s + cubes((1, 0), (-2, 1), (1, 2)),
           s + cubes((-2, 0), (5, 1), (-4, 2), (1, 3))]
    out += [cubes((1, j - 2), (-4, j - 1), (6, j), (-4, j + 1), (1, j + 2))
            for j in range(2, k - 2)]
    out += [cubes((1, k - 4), (-4, k - 3), (5, k - 2), (-2, k - 1)),
            cubes((1, k - 3), (-2, k - 2), (1, k - 1))]
    return tuple(out)


def quadratic_end_splines(q: sp.Symbol, low: float, high: float,
                          n_knots: int) -> list[sp.Expr]:
    r"""A basis of the cubic splines of ``q`` on ``n_knots`` uniform knots of ``[low, high]``,
    each continued beyond the end knots by its quadratic Taylor polynomial there.

    With knots ``xi_1 = low, ..., xi_K = high`` (spacing ``h``, ``s = (q - low) / h``), the
    basis is the ``K + 2`` cubic B-splines ``B_j`` (:func:`bspline`) centred at
    ``j = 0, ..., K + 1`` (knot ``j`` at ``s = j - 1``), restricted to ``[low, high]`` and
    continued so that value, slope and curvature stay continuous at each end knot while the
    third derivative vanishes beyond it:

    .. math::

        f(s) = P(s) + p_3\,(-s)_+^3 + \sum_{0 < c < K - 1} a_c (s - c)_+^3
               - \Big(p_3 + \sum_c a_c\Big) (s - K + 1)_+^3

    where ``P`` (cubic coefficient ``p_3``) is the function's polynomial on the first knot
    interval and ``a_c`` its jumps of the cubic coefficient at the inner knots. The span holds
    every cubic spline on the knots, the constants, ``q`` and ``q^2`` everywhere (a harmonic
    potential is in the span exactly, beyond the knots too), and the functions sum to 1.

    Beyond the data a potential in this span keeps its end stiffness (a force growing
    linearly): the continuation of a wall. :func:`natural_splines` keeps the end slope (a
    constant force): the continuation of a well that flattens.

    Parameters
    ----------
    q : sympy.Symbol
        The coordinate.
    low, high : float
        The end knots, ``low < high``.
    n_knots : int
        ``K``, the number of knots, at least 4 (``K + 2`` functions).

    Returns
    -------
    list of sympy.Expr
        ``K + 2`` functions, from the left end to the right.

    Examples
    --------
    >>> import numpy as np
    >>> import sympy as sp
    >>> x = sp.Symbol("x", real=True)
    >>> basis = quadratic_end_splines(x, 0.0, 3.0, 4)
    >>> len(basis), [round(float(sum(basis).subs(x, v)), 6) for v in (-2.0, 1.3, 5.0)]
    (6, [1.0, 1.0, 1.0])
    >>> grid = np.linspace(-3.0, 6.0, 19)
    >>> columns = np.array([[float(f.subs(x, v)) for f in basis] for v in grid])
    >>> weights = np.linalg.lstsq(columns, grid ** 2, rcond=None)[0]
    >>> bool(np.allclose(columns @ weights, grid ** 2))  # x^2, beyond the knots too
    True
    """
    if isinstance(n_knots, bool) or not isinstance(n_knots, (int, np.integer)) or n_knots < 4:
        raise ValueError(f"splines: expected at least 4 knots per coordinate, got {n_knots!r}")
    return list(_quadratic_end_splines(q, float(low), float(high), int(n_knots)))


@functools.lru_cache(maxsize=1024)
def _quadratic_end_splines(q: sp.Symbol, low: float, high: float, n_knots: int) -> tuple:
    """:func:`quadratic_end_splines`, built once per coordinate, end knots and count."""
    centers, h = bspline_centers(low, high, n_knots)
    last = n_knots - 1  # the right end knot, at s = K - 1
    s = (q - sp.Float(float(centers[0]))) / sp.Float(h)
    out = []
    for j in range(-1, last + 2):  # the B-spline centred at s = j: knots j - 2, ..., j + 2
        knots = list(zip((1, -4, 6, -4, 1), range(j - 2, j + 3), strict=True))
        # left of the first knot interval the truncated powers are whole cubes
        whole = [(w, c) for w, c in knots if c <= 0]
        inner = [(w, c) for w, c in knots if 0 < c < last]
        cubic = sp.Rational(sum(w for w, _ in whole), 6)  # P's cubic coefficient p_3
        end = cubic + sp.Rational(sum(w for w, _ in inner), 6)  # the last interval's
        polynomial = sp.expand(sum((w * (s - c) ** 3 for w, c in whole), sp.Integer(0)) / 6)
        out.append(polynomial + cubic * _plus_cubed(-s)
                   + sum((sp.Rational(w, 6) * _plus_cubed(s - c) for w, c in inner),
                         sp.Integer(0))
                   - end * _plus_cubed(s - last))
    return tuple(out)


def truncated_power_splines(q: sp.Symbol, low: float, high: float, n_knots: int,
                            ends: str = "linear") -> list[sp.Expr]:
    r"""The splines of :func:`natural_splines` (``ends="linear"``) or of
    :func:`quadratic_end_splines` (``ends="quadratic"``) on ``n_knots`` uniform knots of
    ``[low, high]``, in a basis of one function per interior knot.

    With ``s = (q - low) / h`` (knot ``j`` at ``s = j``, ``j = 0, ..., m``, ``m = K - 1``) and
    ``z_+ = max(z, 0)``, the interior knot ``j`` (``0 < j < m``) has

    .. math::

        N_j(s) = (s - j)_+^3 - \Big(1 - \frac jm\Big) s_+^3 - \frac jm (s - m)_+^3,

    a cubic spline whose third derivative jumps at knot ``j`` and at the two end knots only,
    by amounts that make it linear outside ``[0, m]`` (both its cubic and its quadratic
    coefficients cancel beyond ``m``). The basis is

    - ``"linear"``: ``1, s, N_1, ..., N_{m-1}``: ``K`` functions spanning the natural cubic
      splines on the knots;
    - ``"quadratic"``: those, ``s^2`` and ``E(s) = s_+^3 - (s - m)_+^3`` (cubic on the knots'
      span, quadratic beyond): ``K + 2`` functions spanning every cubic spline on the knots
      continued by its quadratic Taylor polynomial at the end knots.

    A spline in this basis has the interior knot ``j`` exactly where ``N_j``'s coefficient is
    not zero: leaving out ``N_j`` removes the knot. With every ``N_j`` left out, what stays is
    a line (``"linear"``), or a cubic on the span continued quadratically (``"quadratic"``).

    Parameters
    ----------
    q : sympy.Symbol
        The coordinate.
    low, high : float
        The end knots, ``low < high``.
    n_knots : int
        ``K``, the number of knots, at least 4.
    ends : {"linear", "quadratic"}, default "linear"
        The continuation beyond the end knots.

    Returns
    -------
    list of sympy.Expr
        The constant ``1`` first, then ``s`` (and ``s^2``, ``E``), then ``N_1, ..., N_{m-1}``.

    Examples
    --------
    >>> import numpy as np
    >>> import sympy as sp
    >>> x = sp.Symbol("x", real=True)
    >>> basis = truncated_power_splines(x, 0.0, 3.0, 4, ends="quadratic")
    >>> len(basis)
    6
    >>> grid = np.linspace(-3.0, 6.0, 19)
    >>> columns = np.array([[float(f.subs(x, v)) for f in basis] for v in grid])
    >>> reference = np.array([[float(f.subs(x, v)) for f in quadratic_end_splines(x, 0.0, 3.0, 4)]
    ...                       for v in grid])
    >>> weights = np.linalg.lstsq(columns, reference, rcond=None)[0]
    >>> bool(np.allclose(columns @ weights, reference))  # the same span
    True
    """
    if isinstance(n_knots, bool) or not isinstance(n_knots, (int, np.integer)) or n_knots < 4:
        raise ValueError(f"splines: expected at least 4 knots per coordinate, got {n_knots!r}")
    if ends not in ("linear", "quadratic"):
        raise ValueError(f"ends: expected 'linear' or 'quadratic', got {ends!r}")
    return list(_truncated_power_splines(q, float(low), float(high), int(n_knots), ends))


@functools.lru_cache(maxsize=1024)
def _truncated_power_splines(q: sp.Symbol, low: float, high: float, n_knots: int,
                             ends: str) -> tuple:
    """:func:`truncated_power_splines`, built once per coordinate, end knots, count and ends."""
    centers, h = bspline_centers(low, high, n_knots)
    m = n_knots - 1
    s = (q - sp.Float(float(centers[0]))) / sp.Float(h)  # knot j at s = j
    out = [sp.Integer(1), s]
    if ends == "quadratic":
        out += [s ** 2, _plus_cubed(s) - _plus_cubed(s - m)]
    out += [_plus_cubed(s - j) - sp.Rational(m - j, m) * _plus_cubed(s)
            - sp.Rational(j, m) * _plus_cubed(s - m) for j in range(1, m)]
    return tuple(out)


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


def exponential_pair(q: sp.Symbol, rate: float) -> list[sp.Expr]:
    r"""The exponential functions ``exp(a q)`` and ``exp(2 a q)`` of one rate ``a``.

    Together with the constant they span the exponential potentials of one rate that mechanics
    writes down: a Morse well :math:`D (1 - e^{-a q})^2 = D (1 - 2 e^{-a q} + e^{-2 a q})`,
    a Born-Mayer or exponential wall :math:`A e^{a q}`, and, with the powers of ``q``
    beside them, a Buckingham-like mix of an exponential wall and a polynomial.

    Parameters
    ----------
    q : sympy.Symbol
        The coordinate.
    rate : float
        ``a``, finite and nonzero; its sign says on which side the wall rises.

    Returns
    -------
    list of sympy.Expr
        ``[exp(a q), exp(2 a q)]``.

    Examples
    --------
    >>> import sympy as sp
    >>> x = sp.Symbol("x", real=True)
    >>> exponential_pair(x, -1.5)
    [exp(-1.5*x), exp(-3.0*x)]
    """
    rate = _check_rate(rate, "exponentials")
    return [sp.exp(sp.Float(rate) * q), sp.exp(sp.Float(2 * rate) * q)]


def anchored_spring(q: sp.Symbol, kind: str, anchor) -> sp.Expr:
    r"""The length of a spring between a point moved by ``q`` and an anchor off its path.

    A linear spring of rest length :math:`l_0` has the potential
    :math:`\tfrac{k}{2}(d - l_0)^2 = \tfrac{k}{2} d^2 - k l_0 d + \text{const}`; ``d^2`` is
    a quadratic (or a first-degree sine and cosine) of ``q``, the length ``d`` is not, and no
    polynomial, trigonometric or spline family continues it beyond the data. Up to a factor:

    - ``"angle"`` (a point on a circle, an anchor at distance ``r`` from its centre, at the
      angle ``phi``): :math:`d \propto \sqrt{1 - e \cos(q - \varphi)}`, ``0 < e < 1``;
    - ``"linear"`` (a point on a line, an anchor at the distance ``h`` from it, beside the
      position ``c``): :math:`d = \sqrt{(q - c)^2 + h^2}`, ``h > 0``.

    Parameters
    ----------
    q : sympy.Symbol
        The coordinate.
    kind : {"linear", "angle"}
        The coordinate's kind.
    anchor : tuple of 2 float
        ``(e, phi)`` of an angle, ``(c, h)`` of a linear coordinate.

    Returns
    -------
    sympy.Expr

    Examples
    --------
    >>> import sympy as sp
    >>> theta, x = sp.symbols("theta x", real=True)
    >>> anchored_spring(theta, "angle", (0.85, 0.46))
    sqrt(1 - 0.85*cos(theta - 0.46))
    >>> anchored_spring(x, "linear", (0.0, 1.0))
    sqrt(x**2 + 1.0)
    """
    if kind not in KINDS:
        raise ValueError(f"kind: expected one of {KINDS}, got {kind!r}")
    if isinstance(anchor, (str, bytes)) or not hasattr(anchor, "__len__") or len(anchor) != 2:
        raise ValueError(f"anchors: expected a pair of numbers per coordinate, got {anchor!r}")
    a, b = (float(v) for v in anchor)
    if not (np.isfinite(a) and np.isfinite(b)):
        raise ValueError(f"anchors: expected finite numbers, got {anchor!r}")
    if kind == "angle":
        if not 0 < a < 1:
            raise ValueError(f"anchors: an angle's e must lie in (0, 1), got {a!r}")
        return sp.sqrt(1 - sp.Float(a) * sp.cos(q - sp.Float(b)))
    if not b > 0:
        raise ValueError(f"anchors: a linear coordinate's h must be positive, got {b!r}")
    return sp.sqrt((q - sp.Float(a)) ** 2 + sp.Float(b) ** 2)


def _check_rate(rate, name: str) -> float:
    """``rate`` as a finite nonzero float, or a ValueError/TypeError naming ``name``."""
    if isinstance(rate, bool) or not isinstance(rate, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name}: expected a real rate, got {type(rate).__name__} {rate!r}")
    rate = float(rate)
    if not (np.isfinite(rate) and rate != 0):
        raise ValueError(f"{name}: expected a finite nonzero rate, got {rate!r}")
    return rate
