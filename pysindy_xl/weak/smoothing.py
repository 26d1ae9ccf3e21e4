"""Smoothed positions and their derivatives from noisy samples, tuned from the data.

The weak form removes accelerations from the regression, but its columns still need the state
``(q, qd)`` inside nonlinear functions (``dL/dqd``, ``dL/dq``). :class:`WhittakerSmoother` gives
both from noisy positions with no hand-set window:

* **Smoothing** (Whittaker-Henderson, the discrete smoothing spline): for each coordinate,

  .. math:: \\hat z = \\arg\\min_z \\|y - z\\|^2 + \\lambda \\|D_d z\\|^2,

  where ``D_d`` is the ``d``-th divided difference on the (possibly non-uniform) time grid,
  scaled by the mean step to the power ``d`` so that ``lambda`` is in sample units, each row
  weighted by the square root of the time it spans (the penalty is then the quadrature of
  the integral of the squared ``d``-th derivative, across gaps and bunched samples alike).
  The system ``(I + lambda D_d^T D_d) z = y`` is banded: one sparse LU solve, linear in the samples.
* **lambda from the data**: generalized cross-validation (Craven and Wahba),
  ``GCV(lambda) = N RSS(lambda) / (N - tr H(lambda))^2`` with ``H`` the smoother's hat
  matrix, estimates the noise level; the weight used by default then minimizes the unbiased
  risk estimate of the smoothed *velocity* (Stein), which GCV alone leaves too rough. On a
  uniform grid both are computed for a whole grid of ``lambda`` at once in the
  cosine-transform domain, where the smoother with reflecting boundaries is diagonal with
  gains ``H_k = 1 / (1 + lambda (2 sin(pi k / 2N))^(2d))``. On a non-uniform grid (dropped
  samples, variable logging rates) that shortcut is wrong: read in sample order, a smooth
  signal sampled at irregular times has steps that look like white noise (velocity times
  the spread of the steps), so the noise is overestimated and the velocities left too rough.
  There the smoother is solved on the actual grid for each ``lambda`` (one banded LU), with
  the traces estimated by Hutchinson's method (random sign probes, solved with the data as
  extra right-hand sides).
* **Derivatives** of the smoothed curve by five-point finite differences whose weights are
  computed per sample for the actual grid (fourth order on uniform grids, one batched solve).
"""

from __future__ import annotations

import numpy as np
import scipy.fft
import scipy.linalg
import scipy.signal
import scipy.sparse
import scipy.sparse.linalg

from .._validation import check_option

__all__ = ["WhittakerSmoother", "whittaker_smooth", "finite_difference_weights", "differentiate",
           "is_uniform"]

_LAMBDA_GRID = 10.0 ** np.arange(-4.0, 16.01, 0.25)


def finite_difference_weights(t, derivative: int, stencil: int = 5, degree=None):
    """Per-sample finite-difference stencils of the ``derivative``-th derivative.

    Each sample uses the ``stencil`` nearest samples (centred inside the grid, shifted at its
    ends); the weights solve the Taylor conditions on the actual offsets, so any strictly
    increasing grid works. With ``degree < stencil - 1`` they are those of the least-squares
    polynomial of that degree through the stencil (Savitzky-Golay on the actual times;
    ``derivative=0`` smooths).

    Parameters
    ----------
    t : array, shape (N,)
        Strictly increasing sample times, ``N >= stencil``.
    derivative : int
        Order of the derivative, smaller than ``stencil``.
    stencil : int, default 5
        Points per stencil.
    degree : int, optional
        Degree of the local polynomial, at least ``derivative`` (default ``stencil - 1``:
        interpolation).

    Returns
    -------
    index : ndarray of int, shape (N, stencil)
        Samples used for each output sample.
    weights : ndarray, shape (N, stencil)
        ``derivative of f at t[i] ~ sum_j weights[i, j] * f[index[i, j]]``.

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


def differentiate(t, values, derivative: int = 1, stencil: int = 5,
                  degree=None) -> np.ndarray:
    """Derivative of smooth sampled ``values`` (N, ...) along axis 0 (five-point stencils).

    Parameters
    ----------
    t : array, shape (N,)
    values : array, shape (N, ...)
    derivative : int, default 1
    stencil, degree : optional
        As in :func:`finite_difference_weights` (a smoothing local polynomial when
        ``degree < stencil - 1``).

    Returns
    -------
    ndarray, same shape as ``values``

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 50)
    >>> float(np.abs(differentiate(t, np.sin(t)) - np.cos(t)).max()) < 1e-6
    True
    """
    index, weights = finite_difference_weights(t, derivative, stencil, degree)
    values = np.asarray(values, dtype=float)
    gathered = values[index]  # (N, stencil, ...)
    return np.einsum("ij,ij...->i...", weights, gathered)


def _divided_difference_matrix(t: np.ndarray, order: int,
                               weighted: bool = False) -> scipy.sparse.csr_matrix:
    """``D`` (N - order, N): ``order``-th divided differences times ``order! * mean_step^order``.

    On a uniform grid this is the plain ``order``-th difference matrix. With ``weighted``
    each row is also multiplied by ``sqrt(span / (order * mean_step))``, ``span`` the time
    its samples cover, so that ``||D z||^2`` is the quadrature of the integral of the squared
    ``order``-th derivative on the actual grid (a row across a gap stands for the whole gap,
    a row of bunched samples for its short span); on a uniform grid every factor is 1.
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
    return scipy.sparse.csr_matrix(
        (weights.ravel(), (rows, index.ravel())), shape=(n_samples - order, n_samples)
    )


#: Relative spread of the time steps below which a grid counts as uniform (timestamps
#: rounded to microseconds at 100 Hz spread by 1e-4; the error of reading them as uniform
#: is then far below any noise).
_UNIFORM_TOLERANCE = 1e-3
#: Probes of the trace estimates on non-uniform grids (random signs in colours,
#: :func:`_colored_probes`); the error comes from entries of the smoother this many samples
#: apart.
_TRACE_PROBES = 16


def is_uniform(t) -> bool:
    """Whether the steps of ``t`` are equal up to ``1e-3`` of their mean.

    Examples
    --------
    >>> import numpy as np
    >>> is_uniform(np.arange(0, 1, 0.01)), is_uniform([0.0, 0.01, 0.03, 0.04])
    (True, False)
    """
    steps = np.diff(np.asarray(t, dtype=float))
    return bool(np.ptp(steps) <= _UNIFORM_TOLERANCE * np.mean(steps))


def _choose_lambda(t: np.ndarray, y: np.ndarray, order: int,
                   target: str) -> tuple[float, float]:
    """Smoothing weight for one series on a uniform grid, in the cosine-transform domain.

    Returns ``(lambda, sigma)``. ``sigma`` is the noise level of the GCV fit (residual RMS
    corrected for the smoother's degrees of freedom). ``target="gcv"`` returns the GCV weight;
    ``target="velocity"`` the weight that minimizes the unbiased risk estimate (SURE) of the
    smoothed *velocity*, ``sum_k w_k^2 [(1 - H_k)^2 (P_k - sigma^2) + H_k^2 sigma^2]`` with
    ``w_k`` the frequency and ``P_k`` the power of mode ``k``: GCV targets the positions and
    leaves their derivatives too rough. Non-uniform grids: :func:`_choose_lambdas_on_grid`.
    """
    n_samples = len(y)
    s = np.linspace(-1.0, 1.0, n_samples)
    trend = np.polynomial.polynomial.polyfit(s, y, order - 1)  # unpenalized by D_order
    detrended = y - np.polynomial.polynomial.polyval(s, trend)
    # A taper removes the slope mismatch at the ends, whose leakage would otherwise pass for
    # broadband signal; dividing by its mean square keeps the noise power per mode at sigma^2.
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
    """``D^T D`` of the weighted divided differences in LAPACK band storage (row
    ``order - k``: the ``k``-th diagonal, aligned by column, as the DIA format stores it)."""
    penalty = _divided_difference_matrix(t, order, weighted=True)
    penalty = (penalty.T @ penalty).todia()
    banded = np.zeros((2 * order + 1, len(t)))
    for offset, diagonal in zip(penalty.offsets, penalty.data, strict=True):
        banded[order - offset] = diagonal
    return banded


def _colored_probes(n_samples: int, n_probes: int, rng) -> np.ndarray:
    """Probe vectors of a trace estimate: probe ``j`` holds random signs on the samples
    ``i = j mod n_probes`` and zeros elsewhere.

    ``sum_j r_j^T A r_j`` is then ``tr A`` plus only the entries of ``A`` between samples a
    multiple of ``n_probes`` apart, each with a random sign (probing with colours, Tang and
    Saad 2012): for the smoother, whose entries decay within about ``lambda^(1/(2d))``
    samples, far less variance than the same number of dense random-sign probes, whose
    estimate sums every off-diagonal entry.
    """
    probes = np.zeros((n_samples, n_probes))
    probes[np.arange(n_samples), np.arange(n_samples) % n_probes] = rng.choice(
        [-1.0, 1.0], size=n_samples)
    return probes


def _choose_lambdas_on_grid(t, y, order, target, n_probes=_TRACE_PROBES):
    """GCV and the velocity risk of the smoother solved on the actual (non-uniform) grid, for
    every column of ``y`` (N, n) at once.

    For each ``lambda`` of the grid, ``Z = H Y`` with ``H = (I + lambda D^T D)^-1``, one
    banded LU for all columns (``H`` depends on the grid, not on the data);
    ``tr H ~ mean_p r_p^T H r_p`` over random sign vectors ``r_p`` (the same probes for all
    columns, coloured: :func:`_colored_probes`), and the Stein risk of the velocity (first
    divided differences ``D_1``, in sample units, weighted by the square root of the Tukey
    taper of the uniform path, ``W``: the error at the ends, which grows with the weight
    where the test functions vanish, would otherwise choose a weight 100 times too small) is
    ``||W D_1 (z - y)||^2 + sigma^2 (2 tr(W D_1 H D_1^T W) - ||W D_1||_F^2)``, whose trace is
    estimated with the probes ``D_1^T W r_p``. The weights are searched a decade
    apart, then on the grid's full resolution around each column's best of each criterion.
    The probes are drawn from a fixed seed: the same data give the same weights.

    Returns
    -------
    lams, sigmas : ndarray, shape (n,)
    """
    n_samples, n_columns = y.shape
    # An LU with pivoting, not Cholesky: at the largest weights the identity is lost to
    # rounding next to lambda D^T D, which is only semi-definite.
    banded = _banded_penalty(t, order)
    # the velocity's error is weighed with the taper of the uniform path: the smoother's
    # ends, where its error grows with the weight, are where the test functions vanish
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
            solved = scipy.linalg.solve_banded((order, order), system, rhs,
                                               check_finite=False)
            residual = y - solved[:, :n_columns]
            rss = np.sum(residual**2, axis=0)
            trace = float(np.sum(probes * solved[:, n_columns:n_columns + n_probes]))
            trace_velocity = float(np.sum(velocity_probes * solved[:, n_columns + n_probes:]))
            gcv = (n_samples * rss / (n_samples - trace) ** 2 if trace < n_samples - 1
                   else np.full(n_columns, np.inf))
            scores[k] = (gcv, rss, trace, np.sum((first @ residual) ** 2, axis=0),
                         trace_velocity)
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
    """Whittaker-Henderson smoothing of each column with a given weight, and derivatives.

    Parameters
    ----------
    t : array, shape (N,)
        Strictly increasing sample times.
    x : array, shape (N, n)
    lams : array, shape (n,)
        Weight of each column in sample units (0: the column is used as is); the columns of
        one weight share one factorization of the smoothing system.
    order : int, default 3
        Order of the penalized divided difference.

    Returns
    -------
    q, qd, qdd : ndarray, shape (N, n)
        Smoothed columns and their first and second derivatives (five-point stencils).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 201)
    >>> q, qd, _ = whittaker_smooth(t, np.column_stack([t**2, t]), [1e3, 0.0])
    >>> bool(np.allclose(qd[:, 1], 1.0))
    True
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    penalty = _divided_difference_matrix(t, order, weighted=True)
    penalty = (penalty.T @ penalty).tocsc()
    identity = scipy.sparse.identity(len(t), format="csc")
    smoothed = x.copy()
    lams = np.asarray(lams, dtype=float)
    for lam in np.unique(lams[lams > 0]):  # one factorization per weight, for its columns
        columns = np.flatnonzero(lams == lam)
        smoothed[:, columns] = scipy.sparse.linalg.splu(identity + lam * penalty).solve(
            np.ascontiguousarray(x[:, columns]))
    return smoothed, differentiate(t, smoothed, 1), differentiate(t, smoothed, 2)


class WhittakerSmoother:
    """Discrete smoothing spline with its smoothness chosen by generalized cross-validation.

    See the module documentation for the objective. Used by :class:`~pysindy_xl.XLSINDy` to
    estimate ``q`` and ``qd`` from noisy positions (weak formulation) and ``qd``, ``qdd``
    (strong formulation) when it is given as ``smoother``.

    Parameters
    ----------
    order : int, default 3
        Order ``d`` of the penalized divided difference (3: the penalty of a quintic
        smoothing spline, which keeps velocities and accelerations smooth).
    lam : float, "velocity" or "gcv", default "velocity"
        Smoothing weight in sample units, or how to choose it per coordinate from the data:
        ``"velocity"`` minimizes the estimated error of the smoothed velocity (the quantity
        the weak columns need), ``"gcv"`` that of the positions (generalized
        cross-validation); both estimate the noise level by GCV.

    Attributes
    ----------
    lam_ : ndarray, shape (n,)
        Weight used for each coordinate by the last :meth:`smooth`.
    noise_ : ndarray, shape (n,)
        Noise standard deviation estimated for each coordinate (residual RMS corrected for
        the smoother's degrees of freedom).

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

    def __init__(self, order=3, lam="velocity"):
        self.order = order
        self.lam = lam

    def _check_params(self):
        check_option("order", self.order, "int", low=1, high=4)
        if isinstance(self.lam, str):
            check_option("lam", self.lam, "choice", choices=("velocity", "gcv"))
        else:
            check_option("lam", self.lam, "real", low=0)

    def smooth(self, t, x):
        """Smoothed positions, velocities and accelerations.

        Parameters
        ----------
        t : array, shape (N,)
            Strictly increasing sample times (N >= 5).
        x : array, shape (N, n)
            Noisy positions.

        Returns
        -------
        q, qd, qdd : ndarray, shape (N, n)
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
                lams[c], noise[c] = _choose_lambda(t, x[:, c], self.order, self.lam)
        else:  # one banded solve per weight for all coordinates
            lams, noise = _choose_lambdas_on_grid(t, x, self.order, self.lam)
        self.lam_, self.noise_ = lams, noise
        return whittaker_smooth(t, x, lams, self.order)

    def resmooth(self, t, x):
        """Smooth with the weights the last :meth:`smooth` chose, without choosing again.

        The protocol of a smoother that propagates the noise of the positions into the weak
        columns (:func:`~pysindy_xl.weak.propagated_draws`): with the weights fixed the
        smoother is one linear map, so fresh noise of the estimated level ``noise_`` smoothed
        by it has the spread of the original noise's error. A smoother without ``resmooth``
        and ``noise_`` is used without that propagation (and a warning).

        Parameters
        ----------
        t : array, shape (N,)
            The sample times of the last :meth:`smooth`.
        x : array, shape (N, k * n)
            ``k`` copies of the ``n`` coordinates side by side (e.g. noisy draws).

        Returns
        -------
        q, qd, qdd : ndarray, shape (N, k * n)

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
