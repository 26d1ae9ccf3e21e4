r"""The noise of the weak rows: Monte Carlo draws, their moments and the residual's covariance.

Fresh noise of the estimated level, added to the recorded positions and smoothed again,
changes the rows by ``Delta``, distributed (to first order) as their error due to the original
noise (:func:`~pysindy_xl.weak.propagated_noise`). The draws of ``Delta`` give:

* the moments ``E[E_c^T E_c]`` of each coordinate's rows, for the errors-in-variables
  correction of the optimizers (:meth:`WeakNoise.moments`);
* the covariance ``Sigma = C C^T`` of a law's residual ``r = Theta xi``, correlated over about
  one test-function support (overlapping test functions, the smoother's spread), for
  generalized least squares on ``C^{-1} Theta``: the reweighting of WENDy (Bortz, Messenger
  and Dukic, *Bull. Math. Biol.* 85, 2023) with the covariance taken from the draws.

The covariance (:meth:`WeakNoise.whitener`) is stationary per run of consecutive test
functions of one coordinate and trajectory: its autocovariance, pooled over the runs and
draws, is tapered (Bartlett) to zero beyond twice the test functions' overlap, which keeps it
positive definite and banded (whitening costs ``O(rows x bandwidth)`` per column). The
whitening is partial (the tapered estimate fills in the residual's nearly empty low and high
frequencies): a regularized generalized least squares.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg

__all__ = ["WeakNoise", "RowWhitener", "draw_moments"]

#: Taper length of the residual's autocovariance, in test-function overlaps.
_TAPER_OVERLAPS = 2


@dataclasses.dataclass(frozen=True)
class RowWhitener:
    """``C^{-1}`` of a block-diagonal banded covariance ``Sigma = C C^T`` of the weak rows.

    Called on rows (R, ...), returns ``C^{-1} rows``: rows of identity covariance. Each
    parameter is stored as the attribute of the same name.

    Parameters
    ----------
    runs : ndarray, shape (S, 2)
        ``(start, stop)`` of the row runs; every row belongs to one run.
    factors : tuple of ndarray
        Per run, its lower Cholesky factor in banded form (``scipy.linalg.cholesky_banded``
        with ``lower=True``), shape (bandwidth + 1, stop - start).

    Examples
    --------
    One run whose covariance is the identity times 4: whitening halves the rows.

    >>> import numpy as np
    >>> whiten = RowWhitener(np.array([[0, 3]]), (np.full((1, 3), 2.0),))
    >>> whiten(np.ones((3, 2)))
    array([[0.5, 0.5],
           [0.5, 0.5],
           [0.5, 0.5]])
    """

    runs: np.ndarray
    factors: tuple

    def __call__(self, rows: np.ndarray) -> np.ndarray:
        """Whiten ``rows``, shape (R, ...): the rows of ``theta`` (R, F) or of draws moved
        to the front."""
        rows = np.asarray(rows, dtype=float)
        flat = rows.reshape(rows.shape[0], -1)
        out = np.empty_like(flat)
        for (start, stop), factor in zip(self.runs, self.factors, strict=True):
            out[start:stop] = scipy.linalg.solve_banded((factor.shape[0] - 1, 0), factor,
                                                        flat[start:stop], check_finite=False)
        return out.reshape(rows.shape)


@dataclasses.dataclass(frozen=True)
class WeakNoise:
    """Monte Carlo draws of the errors of the weak rows, with the structure of the rows.

    Each parameter is stored as the attribute of the same name.

    Parameters
    ----------
    draws : ndarray, shape (D, R, F)
        ``D`` draws of the change of the weak matrix (R rows, coordinate-major as the weak
        matrix) under fresh position noise of the estimated level.
    n_coordinates : int
        Number of coordinate blocks of the rows.
    runs : ndarray, shape (S, 4)
        Runs of consecutive test functions: ``(start, stop, group, overlap)``, rows
        ``start:stop`` of one coordinate and trajectory (the ``group``) between masked
        stretches; ``overlap``: the largest row lag at which that trajectory's test functions
        overlap.

    Examples
    --------
    >>> import numpy as np
    >>> draws = np.random.default_rng(0).normal(size=(8, 40, 3))
    >>> noise = WeakNoise(draws, 2, np.array([[0, 20, 0, 2], [20, 40, 1, 2]]))
    >>> noise.moments().shape, noise.columns([0, 2]).draws.shape
    ((2, 3, 3), (8, 40, 2))
    """

    draws: np.ndarray
    n_coordinates: int
    runs: np.ndarray

    def moments(self) -> np.ndarray:
        """``E[E_c^T E_c]`` of each coordinate's rows.

        Returns
        -------
        ndarray, shape (n_coordinates, F, F)
            The second moments (:func:`draw_moments`).
        """
        return draw_moments(self.draws, self.n_coordinates)

    def columns(self, keep) -> WeakNoise:
        """The draws of some columns only.

        Parameters
        ----------
        keep : array of int or bool, shape (F,)
            The columns kept.

        Returns
        -------
        WeakNoise
            The same rows and runs.
        """
        return dataclasses.replace(self, draws=self.draws[:, :, keep])

    def coordinates(self, keep) -> WeakNoise:
        """The draws of the rows of some coordinates only, with their runs renumbered.

        Parameters
        ----------
        keep : array of bool, shape (n_coordinates,)
            The coordinates kept.

        Returns
        -------
        WeakNoise
            The rows of those coordinates.

        Examples
        --------
        >>> import numpy as np
        >>> runs = np.array([[0, 5, 0, 1], [5, 10, 1, 1], [10, 15, 2, 1]])
        >>> part = WeakNoise(np.zeros((2, 15, 1)), 3, runs).coordinates([True, False, True])
        >>> part.draws.shape, part.runs[:, :2].tolist()
        ((2, 10, 1), [[0, 5], [5, 10]])
        """
        keep = np.asarray(keep, dtype=bool)
        per = self.draws.shape[1] // self.n_coordinates
        chosen = np.flatnonzero(keep)
        rows = (chosen[:, None] * per + np.arange(per)).ravel()
        block = self.runs[:, 0] // per
        runs = self.runs[keep[block]].copy()
        shift = (np.cumsum(keep)[block[keep[block]]] - 1 - block[keep[block]]) * per
        runs[:, :2] += shift[:, None]
        return dataclasses.replace(self, draws=self.draws[:, rows],
                                   n_coordinates=int(chosen.size), runs=runs)

    def rows(self, keep) -> WeakNoise:
        """The draws of some rows only, with the runs cut where rows are left out.

        Parameters
        ----------
        keep : array of bool, shape (R,)
            The rows kept (the same test functions for every coordinate).

        Returns
        -------
        WeakNoise
            The kept rows.

        Examples
        --------
        >>> import numpy as np
        >>> noise = WeakNoise(np.zeros((2, 10, 1)), 2, np.array([[0, 5, 0, 1], [5, 10, 1, 1]]))
        >>> part = noise.rows(np.tile([True, True, False, True, True], 2))
        >>> part.draws.shape, part.runs[:, :2].tolist()
        ((2, 8, 1), [[0, 2], [2, 4], [4, 6], [6, 8]])
        """
        keep = np.asarray(keep, dtype=bool)
        index = np.cumsum(keep) - 1
        runs = []
        for start, stop, group, overlap in self.runs:
            kept = np.flatnonzero(keep[start:stop]) + start
            runs += [(index[piece[0]], index[piece[-1]] + 1, group, overlap)
                     for piece in np.split(kept, np.flatnonzero(np.diff(kept) > 1) + 1)
                     if piece.size]
        return dataclasses.replace(self, draws=self.draws[:, keep],
                                   runs=np.array(runs, dtype=int).reshape(-1, 4))

    def whitened(self, whiten: RowWhitener) -> WeakNoise:
        """The draws of the whitened rows.

        Parameters
        ----------
        whiten : RowWhitener
            The whitening (:meth:`whitener`).

        Returns
        -------
        WeakNoise
            Draws of ``C^{-1} E``.
        """
        moved = whiten(np.moveaxis(self.draws, 1, 0))
        return dataclasses.replace(self, draws=np.moveaxis(moved, 0, 1))

    def whitener(self, coef) -> RowWhitener | None:
        """Whitening of the rows by the covariance of the residual ``Theta @ coef``.

        Parameters
        ----------
        coef : array, shape (F,)
            The pilot law (its scale does not matter for a regression on the whitened rows).

        Returns
        -------
        RowWhitener or None
            None when some coordinate's residual carries no noise under ``coef`` (a law
            that leaves it out): its rows could not be weighed against the others.

        Examples
        --------
        Draws of independent rows: the whitener only rescales them.

        >>> import numpy as np
        >>> draws = np.random.default_rng(0).normal(size=(200, 30, 2))
        >>> noise = WeakNoise(draws, 1, np.array([[0, 30, 0, 1]]))
        >>> whiten = noise.whitener(np.array([1.0, 0.0]))
        >>> float(np.var(whiten(draws[:, :, 0].T)).round(1))
        1.0
        """
        residual = self.draws @ np.asarray(coef, dtype=float)  # (D, R)
        autocovariances = _pooled_autocovariances(residual, self.runs)
        variance_scale = max(a[0] for a in autocovariances.values())
        factors = []
        for start, stop, group, _ in self.runs:
            autocovariance = autocovariances[group]
            if not autocovariance[0] > 1e-12 * variance_scale:
                return None
            factors.append(_banded_cholesky(autocovariance, stop - start))
        return RowWhitener(self.runs[:, :2].copy(), tuple(factors))


def draw_moments(draws, n_coordinates: int) -> np.ndarray:
    """``E[E_c^T E_c]`` of each coordinate's block of rows from draws of the errors.

    Parameters
    ----------
    draws : array, shape (D, n_coordinates * K, F)
        Rows coordinate-major.
    n_coordinates : int
        Number of coordinate blocks.

    Returns
    -------
    ndarray, shape (n_coordinates, F, F)
        The mean of ``E_c^T E_c`` over the draws.

    Examples
    --------
    >>> import numpy as np
    >>> draw_moments(np.ones((2, 4, 1)), 2)
    array([[[2.]],
    <BLANKLINE>
           [[2.]]])
    """
    n_draws, _, n_columns = draws.shape
    # each coordinate's rows of all draws stacked: one matrix product (BLAS) per coordinate
    blocks = np.moveaxis(np.asarray(draws, dtype=float).reshape(
        n_draws, n_coordinates, -1, n_columns), 1, 0).reshape(n_coordinates, -1, n_columns)
    return np.matmul(blocks.transpose(0, 2, 1), blocks) / n_draws


def _pooled_autocovariances(residual, runs) -> dict:
    """Per group of runs, the autocovariance of ``residual`` (D, R) pooled over its runs and
    draws (biased, so positive definite) and tapered (Bartlett) to zero at
    ``_TAPER_OVERLAPS`` times the group's overlap."""
    sums, counts = {}, {}
    for start, stop, group, overlap in runs:
        span = int(_TAPER_OVERLAPS * max(overlap, 1))
        part = residual[:, start:stop]
        lags = np.arange(min(span, stop - start))
        sums.setdefault(group, np.zeros(span))[lags] += [
            np.sum(part[:, : part.shape[1] - lag] * part[:, lag:]) for lag in lags]
        counts[group] = counts.get(group, 0) + part.size
    return {group: total / counts[group] * (1 - np.arange(len(total)) / len(total))
            for group, total in sums.items()}


def _banded_cholesky(autocovariance, length: int) -> np.ndarray:
    """Lower banded Cholesky factor of the ``length`` x ``length`` Toeplitz matrix of
    ``autocovariance`` (zero beyond its last lag)."""
    bandwidth = min(len(autocovariance), length)
    banded = np.zeros((bandwidth, length))
    for lag in range(bandwidth):
        banded[lag, : length - lag] = autocovariance[lag]
    banded[0] *= 1 + 1e-8  # round-off margin on the diagonal
    return scipy.linalg.cholesky_banded(banded, lower=True, check_finite=False)
