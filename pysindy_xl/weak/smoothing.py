r"""Smoothed positions and their derivatives from noisy samples, tuned from the data.

:class:`WhittakerSmoother` (Whittaker-Henderson, the discrete smoothing spline) solves, per
coordinate,

.. math:: \hat z = \arg\min_z \|y - z\|^2 + \lambda \|D_d z\|^2,

with ``D_d`` the ``d``-th divided difference on the actual time grid, scaled by the mean step to the
power ``d`` (``lambda`` in sample units) and each row weighted by the square root of the time it
spans (the quadrature of the integral of the squared ``d``-th derivative); the system is banded.
Generalized cross-validation, ``GCV(lambda) = N RSS / (N - tr H)^2``, estimates the noise level; the
default weight minimizes Stein's risk of the smoothed *velocity*. On a uniform grid both are
computed in the cosine-transform domain (gains ``H_k = 1 / (1 + lambda (2 sin(pi k / 2N))^(2d))``);
on a non-uniform grid, where that shortcut mistakes jitter for noise, by banded solves with
Hutchinson trace estimates. Derivatives: five-point finite differences on the actual grid.
"""

from __future__ import annotations

import hashlib

import numpy as np
import scipy.fft
import scipy.linalg
import scipy.signal
import scipy.sparse
import scipy.sparse.linalg

from .._memo import shared_derivation
from .._validation import Interval, Options, validate_params

__all__ = ["WhittakerSmoother", "whittaker_smooth", "finite_difference_weights", "differentiate",
           "is_uniform"]

_LAMBDA_GRID = 10.0 ** np.arange(-4.0, 16.01, 0.25)


def finite_difference_weights(t, derivative: int, stencil: int = 5, degree=None):
    """Per-sample finite-difference stencils on an arbitrary grid.

    ``f^(derivative)(t[i]) ~ sum_j weights[i, j] f[index[i, j]]``. Each sample uses the
    ``stencil`` nearest samples (shifted at the grid's ends); the weights solve the Taylor
    conditions on the actual offsets. With ``degree < stencil - 1`` they are those of the
    least-squares polynomial of that degree (Savitzky-Golay on the actual times).

    Parameters
    ----------
    t : array, shape (N,)
        Strictly increasing times.
    derivative : int
        Order of the derivative.
    stencil : int, default 5
        Samples per stencil.
    degree : int, optional
        Degree of the local polynomial; default None: ``stencil - 1`` (interpolation).

    Returns
    -------
    index : ndarray of int, shape (N, stencil)
        The samples of each stencil.
    weights : ndarray, shape (N, stencil)
        Their weights.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.sort(np.random.default_rng(0).uniform(0, 1, 40))
    >>> index, weights = finite_difference_weights(t, 1)
    >>> bool(np.allclose((weights * t[index] ** 3).sum(1), 3 * t ** 2))
    True
    """
    t = np.asarray(t, dtype=float)
    n_samples = len(t)
    if n_samples < stencil:
        raise ValueError(f"t: expected at least {stencil} samples, got {n_samples}")
    start = np.clip(np.arange(n_samples) - stencil // 2, 0, n_samples - stencil)
    index = start[:, None] + np.arange(stencil)
    scale = np.mean(np.diff(t))
    offsets = (t[index] - t[:, None]) / scale  # (N, stencil), O(1) for conditioning
    powers = np.arange(stencil if degree is None else int(degree) + 1)
    taylor = offsets[:, None, :] ** powers[None, :, None]  # (N, power, point)
    rhs = np.zeros((n_samples, len(powers), 1))
    rhs[:, derivative, 0] = float(np.prod(np.arange(1, derivative + 1)))
    if len(powers) < stencil:  # least squares: the minimum-norm weights of the conditions
        gram = taylor @ np.swapaxes(taylor, 1, 2)
        weights = (np.swapaxes(taylor, 1, 2) @ np.linalg.solve(gram, rhs))[..., 0]
    else:
        weights = np.linalg.solve(taylor, rhs)[..., 0]
    return index, weights / scale**derivative


def differentiate(t, values, derivative: int = 1, stencil: int = 5, degree=None) -> np.ndarray:
    """Derivative of smooth sampled values along axis 0, on an arbitrary grid.

    Parameters
    ----------
    t : array, shape (N,)
        Strictly increasing times.
    values : array, shape (N, ...)
        Samples.
    derivative : int, default 1
        Order of the derivative.
    stencil : int, default 5
        Samples per stencil (:func:`finite_difference_weights`).
    degree : int, optional
        Degree of the local polynomial; default None (interpolation).

    Returns
    -------
    ndarray, shape (N, ...)
        The derivative at each sample.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 50)
    >>> float(np.abs(differentiate(t, np.sin(t)) - np.cos(t)).max()) < 1e-6
    True
    """
    t = np.ascontiguousarray(t, dtype=float)
    index, weights = shared_derivation(
        (_grid_key(t), derivative, stencil, degree),
        lambda: finite_difference_weights(t, derivative, stencil, degree),
        _STENCILS, _REMEMBERED_GRIDS)
    values = np.asarray(values, dtype=float)
    gathered = values[index]  # (N, stencil, ...)
    return np.einsum("ij,ij...->i...", weights, gathered)


#: Factorizations of the smoothing systems and finite-difference stencils of grids met before
#: (:func:`whittaker_smooth`, :func:`differentiate`), most recently used last: the noise
#: propagation smooths draws on the grids and with the weights of the positions.
_FACTORS: dict = {}
_STENCILS: dict = {}
_REMEMBERED_GRIDS = 64


def _grid_key(t: np.ndarray) -> tuple:
    """A key of the times ``t`` (C-contiguous floats): their count and digest."""
    return len(t), hashlib.sha1(t).digest()


def _divided_difference_matrix(t: np.ndarray, order: int,
                               weighted: bool = False) -> scipy.sparse.csr_matrix:
    """``D`` (N - order, N): ``order``-th divided differences times ``order! * mean_step^order``;
    ``weighted``: rows times ``sqrt(span / (order * mean_step))`` (the integral's quadrature).
    """
    n_samples = len(t)
    index = np.arange(n_samples - order)[:, None] + np.arange(order + 1)
    window = t[index]  # (rows, order + 1)
    gaps = window[:, :, None] - window[:, None, :]
    gaps[:, np.arange(order + 1), np.arange(order + 1)] = 1.0
    weights = 1.0 / np.prod(gaps, axis=2)
    mean_step = np.mean(np.diff(t))
    weights *= np.prod(np.arange(1, order + 1)) * mean_step ** order
    if weighted and not is_uniform(t):  # (factors 1 up to rounding on a uniform grid)
        weights *= np.sqrt((window[:, -1] - window[:, 0]) / (order * mean_step))[:, None]
    rows = np.repeat(np.arange(n_samples - order), order + 1)
    return scipy.sparse.csr_matrix((weights.ravel(), (rows, index.ravel())),
                                   shape=(n_samples - order, n_samples))


#: Relative spread of the time steps below which a grid counts as uniform.
_UNIFORM_TOLERANCE = 1e-3
#: Probes of the trace estimates on non-uniform grids (:func:`_colored_probes`).
_TRACE_PROBES = 16


def is_uniform(t) -> bool:
    """Whether the steps of ``t`` are equal up to ``1e-3`` of their mean.

    Parameters
    ----------
    t : array, shape (N,)
        Times.

    Returns
    -------
    bool
        True for a uniform grid.

    Examples
    --------
    >>> import numpy as np
    >>> is_uniform(np.arange(0, 1, 0.01)), is_uniform([0.0, 0.01, 0.03, 0.04])
    (True, False)
    """
    steps = np.diff(np.asarray(t, dtype=float))
    return bool(np.ptp(steps) <= _UNIFORM_TOLERANCE * np.mean(steps))


def choose_lambda(t: np.ndarray, y: np.ndarray, order: int, target: str) -> tuple[float, float]:
    """``(lambda, sigma)`` of one series on a uniform grid (cosine-transform domain), ``sigma``
    the GCV fit's noise level; ``target="velocity"`` minimizes the velocity's risk
    ``sum_k w_k^2 [(1 - H_k)^2 (P_k - sigma^2) + H_k^2 sigma^2]`` (mode ``k``: frequency ``w_k``,
    power ``P_k``) instead of GCV.
    """
    n_samples = len(y)
    s = np.linspace(-1.0, 1.0, n_samples)
    trend = np.polynomial.polynomial.polyfit(s, y, order - 1)  # unpenalized by D_order
    detrended = y - np.polynomial.polynomial.polyval(s, trend)
    # a taper against the ends' leakage; over its mean square: noise power per mode sigma^2
    taper = scipy.signal.windows.tukey(n_samples, 0.2)
    power = scipy.fft.dct(detrended * taper, norm="ortho") ** 2 / np.mean(taper**2)
    modes = 2 * np.sin(np.pi * np.arange(n_samples) / (2 * n_samples))
    gains = 1.0 / (1.0 + _LAMBDA_GRID[:, None] * modes ** (2 * order))  # (grid, N)
    rss = ((1.0 - gains) ** 2) @ power
    dof = gains.sum(axis=1)
    valid = dof < n_samples - 1
    gcv = np.where(valid, n_samples * rss / np.maximum(n_samples - dof, 1.0) ** 2, np.inf)
    best = int(np.argmin(gcv))
    sigma2 = rss[best] / (n_samples - dof[best])
    if target == "gcv":
        return float(_LAMBDA_GRID[best]), float(np.sqrt(sigma2))
    risk = ((1.0 - gains) ** 2 * (power - sigma2) + gains**2 * sigma2) @ modes**2
    return float(_LAMBDA_GRID[int(np.argmin(risk))]), float(np.sqrt(sigma2))


def _banded_penalty(t: np.ndarray, order: int) -> np.ndarray:
    """``D^T D`` of the weighted divided differences in LAPACK band storage (row ``order - k``:
    the ``k``-th diagonal).
    """
    penalty = _divided_difference_matrix(t, order, weighted=True)
    penalty = (penalty.T @ penalty).todia()
    banded = np.zeros((2 * order + 1, len(t)))
    for offset, diagonal in zip(penalty.offsets, penalty.data, strict=True):
        banded[order - offset] = diagonal
    return banded


def _colored_probes(n_samples: int, n_probes: int, rng) -> np.ndarray:
    """Trace-estimate probes (N, n_probes): random signs on the samples ``i = j mod n_probes``
    in probe ``j`` (probing with colours, Tang and Saad 2012): far less variance for a smoother
    whose entries decay fast.
    """
    probes = np.zeros((n_samples, n_probes))
    probes[np.arange(n_samples), np.arange(n_samples) % n_probes] = rng.choice(
        [-1.0, 1.0], size=n_samples)
    return probes


def _choose_lambdas_on_grid(t, y, order, target, n_probes=_TRACE_PROBES):
    """``(lams, sigmas)`` (n,) of all columns of ``y`` (N, n) on the actual grid: per ``lambda``
    one banded LU and the probes' traces ``tr H``, ``tr(W D_1 H D_1^T W)`` (``W``: root of a
    Tukey taper, as test functions vanish at the ends); the velocity risk is
    ``||W D_1 (z - y)||^2 + sigma^2 (2 tr(W D_1 H D_1^T W) - ||W D_1||_F^2)``.
    """
    n_samples, n_columns = y.shape
    # LU, not Cholesky: at the largest weights I + lambda D^T D is semi-definite in rounding
    banded = _banded_penalty(t, order)
    taper = np.sqrt(scipy.signal.windows.tukey(n_samples - 1, 0.2))
    first = scipy.sparse.diags(taper) @ _divided_difference_matrix(t, 1)
    rng = np.random.default_rng(0)
    probes = _colored_probes(n_samples, n_probes, rng)
    velocity_probes = first.T @ _colored_probes(n_samples - 1, n_probes, rng)
    rhs = np.column_stack([y, probes, velocity_probes])
    first_norm = float(first.multiply(first).sum())
    scores = {}  # grid index -> (gcv (n,), rss (n,), tr H, ||D_1 (Z - Y)||^2 (n,), tr D_1 H D_1^T)

    def score(k):
        if k not in scores:
            system = _LAMBDA_GRID[k] * banded
            system[order] += 1.0
            solved = scipy.linalg.solve_banded((order, order), system, rhs, check_finite=False)
            residual = y - solved[:, :n_columns]
            rss = np.sum(residual**2, axis=0)
            trace = float(np.sum(probes * solved[:, n_columns:n_columns + n_probes]))
            trace_velocity = float(np.sum(velocity_probes * solved[:, n_columns + n_probes:]))
            gcv = (n_samples * rss / (n_samples - trace) ** 2 if trace < n_samples - 1
                   else np.full(n_columns, np.inf))
            scores[k] = (gcv, rss, trace, np.sum((first @ residual) ** 2, axis=0), trace_velocity)
        return scores[k]

    def minimize(criterion):
        """Per column, the grid index of the smallest ``criterion(score) -> (n,)``."""
        coarse = np.arange(0, len(_LAMBDA_GRID), 4)  # a decade apart
        best = coarse[np.argmin([criterion(score(k)) for k in coarse], axis=0)]
        fine = best[:, None] + np.arange(-3, 4)
        fine = np.clip(fine, 0, len(_LAMBDA_GRID) - 1)
        values = np.array([[criterion(score(k))[c] for k in row] for c, row in enumerate(fine)])
        return fine[np.arange(n_columns), np.argmin(values, axis=1)]

    best = minimize(lambda s: s[0])
    rss = np.array([scores[k][1][c] for c, k in enumerate(best)])
    trace = np.array([scores[k][2] for k in best])
    sigma2 = rss / (n_samples - trace)
    if target == "gcv":
        return _LAMBDA_GRID[best], np.sqrt(sigma2)
    chosen = minimize(lambda s: s[3] + sigma2 * (2 * s[4] - first_norm))
    return _LAMBDA_GRID[chosen], np.sqrt(sigma2)


def whittaker_smooth(t, x, lams, order: int = 3):
    r"""Whittaker-Henderson smoothing of each column, and the first two derivatives.

    Column ``x_c`` is smoothed to the ``q`` that minimizes

    .. math:: \|x_c - q\|^2 + \lambda_c \|D_d q\|^2,

    ``D_d`` the ``d``-th divided difference on the actual times (in sample units); the
    derivatives follow by five-point stencils. Columns of one weight share one factorization.

    Parameters
    ----------
    t : array, shape (N,)
        Strictly increasing times.
    x : array, shape (N, n)
        Samples.
    lams : array, shape (n,)
        Weight ``lambda`` of each column (0: used as is).
    order : int, default 3
        Order ``d`` of the penalized divided difference.

    Returns
    -------
    q, qd, qdd : ndarray, shape (N, n)
        Smoothed values and their first two derivatives.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 201)
    >>> q, qd, _ = whittaker_smooth(t, np.column_stack([t**2, t]), [1e3, 0.0])
    >>> bool(np.allclose(qd[:, 1], 1.0))
    True
    """
    t = np.ascontiguousarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    built = []  # the penalty, built when a factorization is not remembered

    def factorization(lam):
        if not built:
            penalty = _divided_difference_matrix(t, order, weighted=True)
            built.append(((penalty.T @ penalty).tocsc(),
                          scipy.sparse.identity(len(t), format="csc")))
        penalty, identity = built[0]
        return scipy.sparse.linalg.splu(identity + lam * penalty)

    smoothed = x.copy()
    lams = np.asarray(lams, dtype=float)
    grid = _grid_key(t)
    for lam in np.unique(lams[lams > 0]):  # one factorization per weight, for its columns
        columns = np.flatnonzero(lams == lam)
        # (remembered: the noise propagation smooths draws again with the same weights)
        factor = shared_derivation((grid, order, float(lam)),
                                   lambda lam=lam: factorization(lam), _FACTORS,
                                   _REMEMBERED_GRIDS)
        smoothed[:, columns] = factor.solve(np.ascontiguousarray(x[:, columns]))
    return smoothed, differentiate(t, smoothed, 1), differentiate(t, smoothed, 2)


class WhittakerSmoother:
    """Discrete smoothing spline with its smoothness chosen from the data.

    Each coordinate is smoothed by :func:`whittaker_smooth`,
    ``min_q |x - q|^2 + lambda |D_d q|^2``, with ``lambda`` chosen per coordinate.

    Used by :class:`~pysindy_xl.XLSINDy` for ``q`` and ``qd`` from noisy positions (weak form)
    and, given as ``smoother``, for ``qd`` and ``qdd`` (strong form); see the module docstring.

    Parameters
    ----------
    order : int, default 3
        Order ``d`` of the penalized divided difference (3: a quintic smoothing spline).
    lam : float, "velocity" or "gcv", default "velocity"
        Weight in sample units, or how to choose it per coordinate: ``"velocity"`` minimizes
        the estimated error of the smoothed velocity, ``"gcv"`` that of the positions
        (generalized cross-validation).

    Attributes
    ----------
    lam_ : ndarray, shape (n,)
        Weight of each coordinate in the last :meth:`smooth`.
    noise_ : ndarray, shape (n,)
        Estimated noise standard deviation of each coordinate.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 10, 1001)
    >>> rng = np.random.default_rng(0)
    >>> y = np.sin(t)[:, None] + 0.01 * rng.normal(size=(1001, 1))
    >>> q, qd, qdd = WhittakerSmoother().smooth(t, y)
    >>> bool(np.abs(qd[100:-100, 0] - np.cos(t[100:-100])).max() < 0.05)
    True
    """

    _parameter_constraints = {
        "order": [Interval("int", 1, 4)],
        "lam": [Options(("velocity", "gcv")), Interval("real", 0)],
    }

    def __init__(self, order=3, lam="velocity"):
        self.order = order
        self.lam = lam

    def _check_params(self):
        validate_params(self)

    def smooth(self, t, x):
        """Smoothed positions, velocities and accelerations of noisy positions.

        Chooses the weight of each coordinate (``lam``), sets ``lam_`` and ``noise_``, and smooths
        (:func:`whittaker_smooth`).

        Parameters
        ----------
        t : array, shape (N,)
            Strictly increasing times.
        x : array, shape (N, n)
            Noisy positions, at least 5 samples.

        Returns
        -------
        q, qd, qdd : ndarray, shape (N, n)
            Smoothed positions, velocities and accelerations.
        """
        self._check_params()
        t = np.asarray(t, dtype=float)
        x = np.asarray(x, dtype=float)
        if x.ndim != 2 or x.shape[0] != len(t):
            raise ValueError(f"x: expected shape ({len(t)}, n), got {x.shape}")
        n_samples = len(t)
        if n_samples < max(5, self.order + 2):
            raise ValueError(f"x: expected at least {max(5, self.order + 2)} samples")
        lams, noise = np.full(x.shape[1], np.nan), np.full(x.shape[1], np.nan)
        if not isinstance(self.lam, str):
            lams[:] = float(self.lam)
        elif is_uniform(t):
            for c in range(x.shape[1]):  # a few coordinates, each with its own lambda
                lams[c], noise[c] = choose_lambda(t, x[:, c], self.order, self.lam)
        else:  # one banded solve per weight for all coordinates
            lams, noise = _choose_lambdas_on_grid(t, x, self.order, self.lam)
        self.lam_, self.noise_ = lams, noise
        return whittaker_smooth(t, x, lams, self.order)

    def resmooth(self, t, x):
        """Smooth with the weights the last :meth:`smooth` chose.

        The protocol of a smoother that propagates the positions' noise
        (:func:`~pysindy_xl.weak.propagated_draws`): with fixed weights the smoother is linear, so
        fresh noise of level ``noise_`` smoothed by it has the spread of the original noise's error.

        Parameters
        ----------
        t : array, shape (N,)
            The times of the last :meth:`smooth`.
        x : array, shape (N, k * n)
            ``k`` copies of the coordinates side by side.

        Returns
        -------
        q, qd, qdd : ndarray, shape (N, k * n)
            Smoothed values and their derivatives.

        Examples
        --------
        >>> import numpy as np
        >>> t = np.linspace(0, 10, 1001)
        >>> y = np.sin(t)[:, None] + 0.01 * np.random.default_rng(0).normal(size=(1001, 1))
        >>> smoother = WhittakerSmoother()
        >>> q = smoother.smooth(t, y)[0]
        >>> twice = smoother.resmooth(t, np.hstack([y, y]))[0]
        >>> bool(np.allclose(twice, np.hstack([q, q])))
        True
        """
        if not hasattr(self, "lam_"):
            raise ValueError("resmooth: call smooth first (it chooses the weights)")
        x = np.asarray(x, dtype=float)
        if x.ndim != 2 or x.shape[1] % len(self.lam_):
            raise ValueError(f"x: expected copies of the {len(self.lam_)} smoothed coordinates "
                             f"side by side, got shape {x.shape}")
        return whittaker_smooth(t, x, np.resize(self.lam_, x.shape[1]), self.order)
