"""Vectorizable sine and cosine for JAX (XLA's CPU versions are scalar code).

The argument is reduced by multiples of pi/2, split into pieces whose products with the
multiple are exact (Cody-Waite), then Taylor polynomials run on [-pi/4, pi/4]: within a few
ulp of libm for ``|x| < 1e5`` (float32) or ``1.6e6`` (float64), where the multiples of pi/2
stay below 2**16 / 2**20; beyond, about one digit is lost per decade of ``|x|``."""

from __future__ import annotations

import math

import numpy as np

from .._optional import import_optional

jax = import_optional("jax", purpose="pysindy_xl.export.jax_dynamics (XLSINDy.to_jax)")
jnp = import_optional("jax.numpy", purpose="pysindy_xl.export.jax_dynamics (XLSINDy.to_jax)")

__all__ = ["fast_sin", "fast_cos"]


# pi/2 = sum of the pieces (float64: two 33-bit pieces and a tail; float32: three 8-bit
# pieces and a tail), computed with mpmath at 200 bits.
_HALF_PI_PIECES = {
    np.dtype(np.float64): (1.5707963267341256, 6.077100506303966e-11, 2.0222662487959506e-21),
    np.dtype(np.float32): (1.5703125, 4.84466552734375e-04, -6.407499313354492e-07,
                           9.92093629470503e-10),
}
# Taylor coefficients, highest degree first: (-1)^k / (2k+1)! and (-1)^k / (2k)!. Degrees
# 15 / 16 (float64) and 9 / 10 (float32) leave a truncation error below half an ulp on
# [-pi/4, pi/4].
_SIN_COEFFICIENTS = {
    dtype: tuple((-1) ** k / float(math.factorial(2 * k + 1)) for k in range(top, 0, -1))
    for dtype, top in ((np.dtype(np.float64), 7), (np.dtype(np.float32), 4))
}
_COS_COEFFICIENTS = {
    dtype: tuple((-1) ** k / float(math.factorial(2 * k)) for k in range(top, 0, -1))
    for dtype, top in ((np.dtype(np.float64), 8), (np.dtype(np.float32), 5))
}


def _horner(coefficients, x):
    acc = coefficients[0]
    for c in coefficients[1:]:
        acc = acc * x + c
    return acc


def _sincos(x):
    """(sin x, cos x) of a floating array, vectorizable (module docstring)."""
    dtype = np.dtype(x.dtype)
    if dtype not in _HALF_PI_PIECES:  # float16, bfloat16: nothing to gain
        return jnp.sin(x), jnp.cos(x)
    k = jnp.round(x * (2.0 / np.pi))
    r = x
    for piece in _HALF_PI_PIECES[dtype]:
        r = r - k * piece
    r2 = r * r
    sin_r = r + r * r2 * _horner(_SIN_COEFFICIENTS[dtype], r2)
    cos_r = 1.0 + r2 * _horner(_COS_COEFFICIENTS[dtype], r2)
    quadrant = k - 4.0 * jnp.floor(k * 0.25)  # k mod 4, exact in floating point
    swap = (quadrant == 1.0) | (quadrant == 3.0)
    sin_x = jnp.where(swap, cos_r, sin_r)
    cos_x = jnp.where(swap, sin_r, cos_r)
    sin_x = jnp.where(quadrant >= 2.0, -sin_x, sin_x)
    cos_x = jnp.where((quadrant == 1.0) | (quadrant == 2.0), -cos_x, cos_x)
    return sin_x, cos_x


def _float_operand(x):
    x = jnp.asarray(x)
    return x if jnp.issubdtype(x.dtype, jnp.floating) else x.astype(jnp.result_type(float))


@jax.custom_jvp
def fast_sin(x):
    """Sine of angles ``x`` through a vectorizable polynomial (module docstring); integers are
    promoted to the default float type, infinite or NaN input gives NaN, and the derivative
    is :func:`fast_cos`.

    Parameters
    ----------
    x : jax.Array or array_like
        Angles (rad); integers are promoted to the default float type.

    Returns
    -------
    jax.Array
        ``sin(x)``, NaN where ``x`` is infinite or NaN.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from pysindy_xl.export.jax_dynamics import fast_sin
    >>> fast_sin(jnp.array([0.0, jnp.pi / 6, jnp.pi / 2])).round(6)
    Array([0. , 0.5, 1. ], dtype=float32)
    """
    return _sincos(_float_operand(x))[0]


@jax.custom_jvp
def fast_cos(x):
    """Cosine through a vectorizable polynomial, as :func:`fast_sin`.

    Parameters
    ----------
    x : jax.Array or array_like
        Angles (rad); integers are promoted to the default float type.

    Returns
    -------
    jax.Array
        ``cos(x)``, NaN where ``x`` is infinite or NaN.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from pysindy_xl.export.jax_dynamics import fast_cos
    >>> fast_cos(jnp.array([0.0, jnp.pi / 3, jnp.pi])).round(6)
    Array([ 1. ,  0.5, -1. ], dtype=float32)
    """
    return _sincos(_float_operand(x))[1]


@fast_sin.defjvp
def _fast_sin_jvp(primals, tangents):
    (x,), (dx,) = primals, tangents
    sin_x, cos_x = _sincos(_float_operand(x))
    return sin_x, cos_x * dx


@fast_cos.defjvp
def _fast_cos_jvp(primals, tangents):
    (x,), (dx,) = primals, tangents
    sin_x, cos_x = _sincos(_float_operand(x))
    return cos_x, -sin_x * dx
