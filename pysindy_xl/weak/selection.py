r"""Which noise model a weak fit of measured forces uses, chosen by held-out force error.

**Position noise**: rows weighted by the covariance the positions' noise propagates into
them (:meth:`~pysindy_xl.weak.WeakNoise.whitener`), test functions as wide as the motion's
spectrum allows. **Force noise** (nearly exact encoders, noisy torques): rows fitted as they
are, narrow test functions at :data:`SCORING_BANDWIDTH`. Each candidate is fitted on time
blocks and predicts the others (:func:`choose_noise_model`), scored on one common set of
narrow rows :math:`\Theta_\text{ref}`: for a law ``xi`` with force columns ``f``,

.. math::

    e = \frac{\| \Theta_\text{ref} \xi \|}{\| \Theta_{\text{ref}, f} \xi_f \|},

with the expected share of the positions' noise, :math:`\xi^T \mathrm{E}[E^T E] \xi`, taken
out of each residual (a law shrunk towards zero predicts noisy rows better than the true one).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

__all__ = ["SCORING_BANDWIDTH", "NoiseModel", "bandwidth_half_width", "choose_noise_model",
           "time_folds"]

#: Bandwidth (Hz) at which held-out forces are compared: the torque signal of a robot joint
#: (:mod:`pysindy_xl.held_out` bounds its scoring derivatives at the same frequency).
SCORING_BANDWIDTH = 10.0

#: A candidate replaces the first (the default) only when its held-out error is lower by this
#: fraction, and on most of the blocks.
MARGIN = 0.05

#: Largest share of the first candidate's held-out residual that the positions' noise may make
#: up for another candidate to replace it: beyond it the smoother's bias (shared by the narrow
#: candidate and the scoring rows) would favour the narrow candidate by itself.
NOISE_SHARE = 0.1

#: Time blocks per trajectory, tried in turn until every candidate can be fitted outside each.
BLOCK_COUNTS = (5, 3)


def bandwidth_half_width(bandwidth: float, power: int = 6) -> float:
    """Half-width (s) of the bump ``(1 - s^2)^power`` whose response falls by 3 dB at ``bandwidth``.

    The bump is close to a Gaussian of standard deviation ``sigma = h / sqrt(2 power + 3)``,
    whose response is ``1/sqrt(2)`` at ``sqrt(ln 2) / (2 pi sigma)``.

    Parameters
    ----------
    bandwidth : float
        The 3 dB frequency, in Hz.
    power : int, default 6
        Exponent of the bump.

    Returns
    -------
    float
        ``h = sqrt(ln 2 (2 power + 3)) / (2 pi bandwidth)``.

    Examples
    --------
    >>> round(bandwidth_half_width(10.0), 4)
    0.0513
    """
    return math.sqrt(math.log(2.0) * (2 * power + 3)) / (2 * math.pi * bandwidth)


@dataclass(frozen=True)
class NoiseModel:
    """One way to read the data: test-function half-width and whether rows are weighted.

    Parameters
    ----------
    name : str
        Label in reports.
    half_width : float
        Test-function half-width, in seconds.
    weigh : bool
        Whether the rows are weighted by their propagated noise.
    """

    name: str
    half_width: float
    weigh: bool


def time_folds(supports: np.ndarray, spans: np.ndarray, n_blocks: int):
    """Contiguous time blocks of every trajectory, as masks over the test functions.

    Parameters
    ----------
    supports : ndarray, shape (K, 3)
        Each test function's trajectory and first and last time (``weak_info_["supports"]``).
    spans : ndarray, shape (T, 2)
        Each trajectory's first and last time.
    n_blocks : int
        Blocks per trajectory.

    Returns
    -------
    fit : ndarray of bool, shape (n_blocks, K)
        The test functions whose support misses block ``k``.
    held : ndarray of bool, shape (n_blocks, K)
        Those inside it.
    """
    trajectory = supports[:, 0].astype(int)
    start, stop = spans[trajectory, 0], spans[trajectory, 1]
    fractions = np.linspace(0.0, 1.0, n_blocks + 1)
    edges = start[None, :] + fractions[:, None] * (stop - start)[None, :]  # (B + 1, K)
    first, last = supports[None, :, 1], supports[None, :, 2]
    held = (first >= edges[:-1]) & (last <= edges[1:])
    fit = (last < edges[:-1]) | (first > edges[1:])
    return fit, held


def choose_noise_model(candidates, reference, spans, force_columns, solve, n_blocks=BLOCK_COUNTS):
    """The candidate whose fits predict held-out time blocks best, if clearly better than the first.

    Of several ``n_blocks``, the first at which every candidate can be fitted outside each block
    (and every block holds scoring rows) is used, else the first at which some candidate can.

    Parameters
    ----------
    candidates : list of tuple
        ``(NoiseModel, rows, supports, noise)``: weak rows (coordinate-major, the same columns
        for all), test-function supports (:func:`time_folds`) and propagated row noise
        (:class:`~pysindy_xl.weak.WeakNoise` or None).
    reference : tuple
        The common scoring ``(rows, supports, noise)``.
    spans : ndarray, shape (T, 2)
        Each trajectory's first and last time.
    force_columns : sequence of int
        The force columns (the held-out error is relative to the forces).
    solve : callable
        ``solve(rows, noise, weigh) -> coef``: one candidate's fit.
    n_blocks : tuple of int, default BLOCK_COUNTS
        Block counts tried in turn.

    Returns
    -------
    best : int or None
        The candidate of smallest held-out error among those that beat the first by
        :data:`MARGIN` in total and on most blocks, while the positions' noise makes up less
        than :data:`NOISE_SHARE` of the first's residual, else 0; None when the data are too
        short to hold out blocks. A first candidate too wide to be fitted outside the blocks
        is judged as the zero law (error 1, each block's residual its forces): another
        replaces it only by predicting the held-out forces.
    errors : list of float
        Each candidate's held-out relative error (``inf`` where a fold's fit failed).
    """
    rows_ref, supports_ref, noise_ref = reference
    n_coordinates = rows_ref.shape[0] // len(supports_ref)

    def feasible(count):  # which candidates can be fitted outside every block
        if not time_folds(supports_ref, spans, count)[1].any(axis=1).all():
            return np.zeros(len(candidates), dtype=bool)
        return np.array([(time_folds(supports, spans, count)[0].sum(axis=1) * n_coordinates
                          >= rows.shape[1]).all() for _, rows, supports, _ in candidates])

    counts = [int(count) for count in np.atleast_1d(n_blocks)]
    usable = [feasible(count) for count in counts]
    n_blocks, fits = next(((c, u) for c, u in zip(counts, usable, strict=True) if u.all()),
                          next(((c, u) for c, u in zip(counts, usable, strict=True)
                                if u.any()), (None, None)))
    if n_blocks is None:
        return None, []
    _, held = time_folds(supports_ref, spans, n_blocks)
    held_rows = np.tile(held, n_coordinates)
    force = np.asarray(force_columns, dtype=int)
    residuals = np.full((len(candidates), n_blocks), np.inf)
    forces = np.ones((len(candidates), n_blocks))
    noisy = np.zeros((len(candidates), n_blocks))
    for c, (model, rows, supports, noise) in enumerate(candidates):
        if not fits[c]:  # too few rows outside the blocks: as good as unfitted
            continue
        fit, _ = time_folds(supports, spans, n_blocks)
        fit_rows = np.tile(fit, n_coordinates)
        for k in range(n_blocks):
            try:
                with warnings.catch_warnings():  # a fold's fit speaks through its score
                    warnings.simplefilter("ignore")
                    coef = solve(rows[fit_rows[k]],
                                 None if noise is None else noise.rows(fit_rows[k]), model.weigh)
            except (ValueError, RuntimeError, np.linalg.LinAlgError):
                break
            scored = rows_ref[held_rows[k]]
            residuals[c, k] = np.sum((scored @ coef) ** 2)
            if noise_ref is not None:  # the noise of the positions in the scoring rows
                noisy[c, k] = np.mean(np.sum(
                    (noise_ref.draws[:, held_rows[k]] @ coef) ** 2, axis=1))
            forces[c, k] = np.sum((scored[:, force] @ coef[force]) ** 2)
    clean = residuals - noisy
    with np.errstate(invalid="ignore", divide="ignore"):
        errors = np.sqrt(np.maximum(clean.sum(axis=1), 0.0) / forces.sum(axis=1))
        # the noise share is read off the first candidate, or the best fitted one when the
        # first could not be fitted on the blocks
        base = 0 if np.isfinite(errors[0]) else int(np.argmin(errors))
        audible = noisy[base].sum() < NOISE_SHARE * residuals[base].sum()
    # a first candidate that could not be fitted on the blocks is judged as the zero law
    # (no evidence against it, no prediction either): relative error 1, block residuals the
    # blocks' forces. Another replaces it only by predicting the held-out forces: a narrow fit
    # of noisy positions, shrunk by the errors in its variables, does not
    if fits[0]:
        first, first_blocks = errors[0], clean[:1]
    else:
        first, first_blocks = 1.0, forces
    wins = (clean < first_blocks).sum(axis=1)
    better = np.flatnonzero(np.isfinite(errors) & (errors < (1 - MARGIN) * first)
                            & (wins > n_blocks / 2) & audible)
    best = int(better[np.argmin(errors[better])]) if better.size else 0
    return best, errors.tolist()
