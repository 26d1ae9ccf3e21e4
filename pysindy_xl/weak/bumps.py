r"""Test functions of the weak formulation: smooth bumps with compact support in time.

A bump ``phi(t) = (1 - s^2)^p``, ``s = (t - c) / h`` on ``[c - h, c + h]``, vanishes with its
first ``p - 1`` derivatives at both ends, so integration by parts leaves no boundary term.
:class:`BumpTestFunctions` returns the bumps as quadrature-weighted sparse matrices ``Phi``
and ``dPhi`` (test functions x samples): ``int phi_k f dt ~ (Phi @ f)[k]``; the half-width
``h`` comes from the corner frequency of the positions' spectrum (as in WSINDy).
"""

from __future__ import annotations

import numpy as np
import scipy.fft
import scipy.signal
import scipy.sparse

from .._validation import Collection, Interval, validate_params
from .smoothing import is_uniform

__all__ = ["BumpTestFunctions", "corner_frequency", "quadrature_weights"]


def quadrature_weights(t) -> np.ndarray:
    """Quadrature weights of a strictly increasing grid: ``int f dt ~ weights @ f``.

    The trapezoidal rule on a uniform grid (of very high order for integrands vanishing smoothly
    at both ends); otherwise each interval is integrated exactly on the cubic through the four
    nearest samples, except where nearly coincident samples make that cubic's weights large and
    of both signs (those keep the trapezoid).

    Parameters
    ----------
    t : array, shape (N,)
        Strictly increasing sample times.

    Returns
    -------
    ndarray, shape (N,)
        The weights.

    Examples
    --------
    >>> quadrature_weights([0.0, 1.0, 2.0])
    array([0.5, 1. , 0.5])
    >>> t = np.array([0.0, 0.1, 0.3, 0.4, 0.7, 1.0])
    >>> float(quadrature_weights(t) @ t**3)    # exact for cubics: 1/4
    0.25
    """
    t = np.asarray(t, dtype=float)
    if len(t) < 4 or is_uniform(t):
        gaps = np.diff(t)
        weights = np.zeros_like(t)
        weights[:-1] += gaps / 2
        weights[1:] += gaps / 2
        return weights
    return _cubic_weights(t)


def _cubic_weights(t) -> np.ndarray:
    """Piecewise-cubic weights: interval ``i`` integrated on the cubic through samples
    ``i - 1 .. i + 2`` (shifted inside the grid at its ends).
    """
    n_samples = len(t)
    left = np.arange(n_samples - 1)
    index = np.clip(left - 1, 0, n_samples - 4)[:, None] + np.arange(4)
    scale = np.mean(np.diff(t))
    offsets = (t[index] - t[left, None]) / scale  # O(1), for conditioning
    powers = np.arange(4)
    # weights w with sum_j w_j s_j^k = int_0^b s^k ds for k = 0..3 (exact for cubics)
    moments = ((t[left + 1] - t[left]) / scale)[:, None] ** (powers + 1) / (powers + 1)
    vandermonde_t = offsets[:, None, :] ** powers[None, :, None]  # (interval, power, node)
    local = np.linalg.solve(vandermonde_t, moments[..., None])[..., 0] * scale
    # weights summing in absolute value to over 4 widths (7/6 on a uniform grid) amplify the
    # noise: such an interval falls back to the trapezoid, positive on any grid
    width = t[left + 1] - t[left]
    rough = np.abs(local).sum(axis=1) > 4.0 * width
    position = left[rough] - index[rough, 0]
    local[rough] = 0.0
    for shift in (0, 1):
        local[np.flatnonzero(rough), position + shift] = width[rough] / 2
    return np.bincount(index.ravel(), weights=local.ravel(), minlength=n_samples)


#: Median of a chi-square variable with one degree of freedom (its mean is 1).
_CHI2_1_MEDIAN = 0.454936423119572


def corner_frequency(t, x, energy: float = 0.99) -> float:
    """Frequency (Hz) below which a share ``energy`` of the signal part of the spectrum lies.

    Each coordinate is detrended, tapered and cosine-transformed (as if sampled uniformly at
    the mean step). The noise floor is the median power of the upper half of the modes over the
    median of a chi-square variable of one degree of freedom; the signal power above it is
    summed without clipping, so the corner does not move with the noise level.

    Parameters
    ----------
    t : array, shape (N,)
        Sample times.
    x : array, shape (N, n)
        Positions.
    energy : float, default 0.99
        Share of the signal power below the corner.

    Returns
    -------
    float
        The largest corner over the coordinates, in Hz.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 20, 2001)
    >>> x = np.sin(2 * np.pi * 0.5 * t)[:, None]
    >>> bool(0.4 < corner_frequency(t, x) < 0.7)
    True
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float).reshape(len(t), -1)
    n_samples = len(t)
    step = (t[-1] - t[0]) / (n_samples - 1)
    s = np.linspace(-1, 1, n_samples)
    taper = scipy.signal.windows.tukey(n_samples, 0.2)  # leakage would pass for signal
    corners = []
    for column in x.T:
        trend = np.polynomial.polynomial.polyfit(s, column, 1)
        detrended = column - np.polynomial.polynomial.polyval(s, trend)
        power = scipy.fft.dct(detrended * taper, norm="ortho") ** 2
        floor = np.median(power[n_samples // 2:]) / _CHI2_1_MEDIAN
        signal = np.cumsum(power - floor)
        if not signal[-1] > 0:
            continue
        k = int(np.argmax(signal >= energy * signal[-1]))
        corners.append((k + 1) / (2 * n_samples * step))  # DCT index k <-> k / (2 N dt) Hz
    return max(corners) if corners else 1.0 / (2 * step)


class BumpTestFunctions:
    r"""Bumps ``(1 - s^2)^p`` placed along each trajectory, width chosen from the data.

    Test function ``k``, centred at ``c_k`` with half-width ``h``, is
    ``phi_k(t) = (1 - s^2)^p`` for ``s = (t - c_k) / h`` in ``[-1, 1]``, zero outside. Its
    integral against an Euler-Lagrange column ``E = d/dt P - Q`` needs no acceleration:

    .. math:: \int \phi_k E \, dt = -\int \dot\phi_k P \, dt - \int \phi_k Q \, dt.

    Parameters
    ----------
    width : float or "auto", default "auto"
        Half-width ``h`` of the support in time units. ``"auto"``: ``width_factor`` periods of
        the corner frequency (:func:`corner_frequency`), at least ``min_samples`` samples.
    n_functions : int or "auto", default "auto"
        Test functions per trajectory, evenly spaced; ``"auto"``: enough for every sample to be
        covered ``overlap`` times.
    power : int, default 6
        Exponent ``p``; the bump and its first ``p - 1`` derivatives vanish at the ends.
    width_factor : float, default 1.0
        Half-width in periods of the corner frequency when ``width="auto"``.
    overlap : float, default 8
        Average number of test functions covering each sample when ``n_functions="auto"``.
    min_samples : int, default 12
        Smallest half-width in samples (quadrature needs a resolved bump).
    width_multiples : float or sequence of float, optional
        Stack the rows of half-width ``m h`` for each multiple ``m``; a width that does not
        fit inside the trajectory is left out. Default: ``h`` alone.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 10, 1001)
    >>> phi, dphi, half_width = BumpTestFunctions(width=1.0, n_functions=5).matrices(t)
    >>> phi.shape, half_width
    ((5, 1001), 1.0)
    >>> float(abs(phi @ np.cos(t) + dphi @ np.sin(t)).max()) < 1e-10   # int phi q' = -int phi' q
    True

    Two widths, 5 bumps of each, ordered by their centres:

    >>> phi, _, _ = BumpTestFunctions(width=1.0, n_functions=5,
    ...                               width_multiples=(1.0, 2.0)).matrices(t)
    >>> phi.shape, np.count_nonzero(phi[:2].toarray(), axis=1).tolist()
    ((10, 1001), [199, 399])
    """

    _parameter_constraints = {
        "width": ["auto", Interval("real", 0, low_open=True)],
        "n_functions": ["auto", Interval("int", 1)],
        "power": [Interval("int", 1)],
        "width_factor": [Interval("real", 0, low_open=True)],
        "overlap": [Interval("real", 0, low_open=True)],
        "min_samples": [Interval("int", 1)],
        "width_multiples": [None, Interval("real", 0, low_open=True),
                            Collection("a sequence of positive numbers")],
    }

    def __init__(self, width="auto", n_functions="auto", power=6, width_factor=1.0,
                 overlap=8.0, min_samples=12, width_multiples=None):
        self.width = width
        self.n_functions = n_functions
        self.power = power
        self.width_factor = width_factor
        self.overlap = overlap
        self.min_samples = min_samples
        self.width_multiples = width_multiples

    def _check_params(self):
        validate_params(self)
        multiples = self._multiples()
        if multiples.size == 0 or not np.all(np.isfinite(multiples) & (multiples > 0)):
            raise ValueError("width_multiples: expected positive numbers, got "
                             f"{self.width_multiples!r}")

    def half_width(self, t, x=None) -> float:
        """Half-width ``h`` of the test functions for one trajectory.

        ``width`` when given, else ``width_factor`` periods of the corner frequency
        (:func:`corner_frequency`); at least ``min_samples`` mean steps.

        Parameters
        ----------
        t : array, shape (N,)
            Sample times.
        x : array, shape (N, n), optional
            Positions, needed when ``width="auto"``; default None.

        Returns
        -------
        float
            ``h``, in time units.

        Raises
        ------
        ValueError
            When the trajectory is shorter than one test function, or ``x`` is missing for an
            automatic width.

        Examples
        --------
        >>> import numpy as np
        >>> BumpTestFunctions(width=0.5).half_width(np.linspace(0, 10, 1001))
        0.5
        """
        self._check_params()
        t = np.asarray(t, dtype=float)
        # the floor resolves the bump at (nearly) every step: usual steps are never gaps
        step = float(np.quantile(np.diff(t), 0.99)) if len(t) > 2 else t[-1] - t[0]
        if self.width != "auto":
            h = float(self.width)
        else:
            if x is None:
                raise ValueError("x: positions are needed to choose the width automatically")
            h = self.width_factor / corner_frequency(t, x)
        h = max(h, self.min_samples * step)
        duration = t[-1] - t[0]
        if 2 * h > duration:
            raise ValueError(
                f"t: the trajectory ({duration:.4g} s) is shorter than one test function "
                f"(support {2 * h:.4g} s); record longer trajectories or set a smaller width")
        return h

    def max_gap(self, half_width) -> float:
        """Longest step a test function of a given half-width may span.

        ``half_width / min_samples``: trajectories are cut at longer steps
        (:mod:`~pysindy_xl.weak.timegrid`).

        Parameters
        ----------
        half_width : float
            The test functions' half-width.

        Returns
        -------
        float
            The longest step, in time units.

        Examples
        --------
        >>> BumpTestFunctions(min_samples=10).max_gap(0.5)
        0.05
        """
        self._check_params()
        return float(half_width / self.min_samples)

    def matrices(self, t, x=None, half_width=None, n_functions=None):
        """Quadrature-weighted test-function matrices of one trajectory.

        Parameters
        ----------
        t : array, shape (N,)
            Strictly increasing sample times.
        x : array, shape (N, n), optional
            Positions, for the automatic width; default None.
        half_width : float, optional
            Overrides the width rule (one width shared across trajectories); default None.
        n_functions : int, optional
            Overrides the count rule; default None.

        Returns
        -------
        phi, dphi : scipy.sparse.csr_matrix, shape (K, N)
            ``phi[k, i] = phi_k(t_i) w_i`` and ``dphi[k, i] = phi_k'(t_i) w_i`` with the weights
            ``w`` of :func:`quadrature_weights`; several ``width_multiples``: ordered by centres.
        half_width : float
            ``h``, before the multiples.
        """
        t = np.asarray(t, dtype=float)
        self._check_params()
        h = self.half_width(t, x) if half_width is None else float(half_width)
        if not 0 < 2 * h <= t[-1] - t[0]:
            raise ValueError(f"half_width: the support {2 * h:.4g} s must be positive and fit "
                             f"inside the trajectory ({t[-1] - t[0]:.4g} s)")
        if n_functions is None:
            n_functions = self.n_functions
        widths = [m * h for m in self._multiples() if 2 * m * h <= t[-1] - t[0]] or [h]
        if len(widths) == 1:
            phi, dphi, _ = self._bumps(t, widths[0], n_functions)
            return phi, dphi, h
        parts = [self._bumps(t, width, n_functions) for width in widths]
        # by centre (stable: equal centres keep the order of the widths)
        order = np.argsort(np.concatenate([centers for *_, centers in parts]), kind="stable")
        return (scipy.sparse.vstack([phi for phi, *_ in parts]).tocsr()[order],
                scipy.sparse.vstack([dphi for _, dphi, _ in parts]).tocsr()[order], h)

    def _multiples(self) -> np.ndarray:
        if self.width_multiples is None:
            return np.ones(1)
        return np.atleast_1d(np.asarray(self.width_multiples, dtype=float))

    def _bumps(self, t, h, n_functions):
        """``(phi, dphi, centers)`` of the bumps of half-width ``h`` (see :meth:`matrices`)."""
        duration = t[-1] - t[0]
        if n_functions == "auto":
            n_functions = int(np.ceil(self.overlap * duration / (2 * h)))
        n_functions = max(int(n_functions), 1)
        centers = np.linspace(t[0] + h, t[-1] - h, n_functions)
        first = np.searchsorted(t, centers - h, side="right")
        last = np.searchsorted(t, centers + h, side="left")  # exclusive: open support
        counts = last - first
        rows = np.repeat(np.arange(n_functions), counts)
        cols = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        cols += np.repeat(first, counts)
        s = (t[cols] - centers[rows]) / h
        base = 1.0 - s**2
        p = int(self.power)
        weights = quadrature_weights(t)[cols]
        values = base**p * weights
        slopes = -2.0 * p * s * base ** (p - 1) / h * weights
        shape = (n_functions, len(t))
        phi = scipy.sparse.csr_matrix((values, (rows, cols)), shape=shape)
        dphi = scipy.sparse.csr_matrix((slopes, (rows, cols)), shape=shape)
        return phi, dphi, centers
