"""What the catalog optimizers share: the ``fit_catalog`` protocol and column bookkeeping.

Every optimizer of this package is a scikit-learn estimator with, besides its own ``fit``,

``fit_catalog(theta, n_coordinates, force_columns) -> self``
    ``theta`` is the stacked regression matrix ``(n_coordinates * N, F)`` (rows
    coordinate-major, see :mod:`pysindy_xl.feature_library._base`), ``force_columns`` the
    indices of the :class:`~pysindy_xl.ExternalForces` columns. It sets ``coef_`` of shape
    ``(F,)``: the full coefficient vector, force columns included, with ``theta @ coef_ ~ 0``.

This is the metadata :class:`~pysindy_xl.XLSINDy` hands over; standalone users pass the same.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
from sklearn.base import BaseEstimator

from .._validation import check_indices, check_numeric_array, check_option

__all__ = ["CatalogOptimizer", "independent_columns", "check_catalog_problem"]


def check_catalog_problem(theta, n_coordinates, force_columns):
    """Validate the arguments of ``fit_catalog``; returns ``(theta, force_columns)`` as arrays."""
    theta = check_numeric_array(theta, "theta", finite=False, min_samples=0)
    if theta.ndim != 2 or theta.shape[0] == 0 or theta.shape[1] == 0:
        raise ValueError(f"theta: expected a non-empty 2-D array, got shape {theta.shape}")
    if not np.all(np.isfinite(theta)):
        raise ValueError("theta: contains NaN or inf")
    n_coordinates = check_option("n_coordinates", n_coordinates, "int", low=1)
    if theta.shape[0] % n_coordinates:
        raise ValueError(
            f"theta: {theta.shape[0]} rows is not a multiple of n_coordinates={n_coordinates}"
        )
    force_columns = check_indices(force_columns, "force_columns", theta.shape[1])
    return theta, force_columns


def independent_columns(theta, priority=None, rtol: float = 1e-9, max_rows: int = 20_000):
    """Split the columns of ``theta`` into a linearly independent set and the rest.

    Columns are visited in ``priority`` order; a column is kept when its component orthogonal
    to the span of the columns visited before it exceeds ``rtol`` times its norm (a QR
    factorization of the column-normalized, priority-ordered matrix, on at most ``max_rows``
    evenly spaced rows: exact identities such as ``cos^2 + sin^2 = 1`` hold on any subset).

    Parameters
    ----------
    theta : array, shape (n_rows, F)
    priority : array of int, shape (F,), optional
        Visiting order, most preferred first. Default: column order.
    rtol : float
        Relative residual below which a column counts as dependent.
    max_rows : int
        Rows used for the test.

    Returns
    -------
    keep : ndarray of int
        Independent columns, sorted.
    dropped : dict of int to str
        Dropped columns with the reason (``"zero column"`` or ``"linear combination"``).

    Examples
    --------
    >>> import numpy as np
    >>> a = np.linspace(0, 1, 50)
    >>> theta = np.column_stack([a, a ** 2, 2 * a - a ** 2, np.zeros(50)])
    >>> keep, dropped = independent_columns(theta)
    >>> keep, dropped
    (array([0, 1]), {2: 'linear combination', 3: 'zero column'})
    """
    theta = np.asarray(theta, dtype=float)
    n_rows, n_cols = theta.shape
    order = np.arange(n_cols) if priority is None else np.asarray(priority, dtype=int)
    if sorted(order.tolist()) != list(range(n_cols)):
        raise ValueError("priority: expected a permutation of the column indices")
    rows = np.unique(np.linspace(0, n_rows - 1, min(n_rows, max_rows)).astype(int))
    sub = theta[rows][:, order]
    norms = np.linalg.norm(sub, axis=0)
    scale = np.max(np.abs(theta), axis=0)[order]
    dropped = {}
    nonzero = (norms > 0) & (norms > 1e-14 * np.max(norms, initial=0.0))
    for j in order[~nonzero]:
        dropped[int(j)] = "zero column"
    if not np.any(scale > 0):
        return np.array([], dtype=int), dropped
    candidates = order[nonzero]
    sub = sub[:, nonzero] / norms[nonzero]
    r = scipy.linalg.qr(sub, mode="r", check_finite=False)[0]
    diag = np.abs(np.diag(r))
    if len(diag) < len(candidates):  # fewer rows than columns: the tail is dependent
        diag = np.concatenate([diag, np.zeros(len(candidates) - len(diag))])
    for j, d in zip(candidates, diag, strict=True):
        if d <= rtol:
            dropped[int(j)] = "linear combination"
    keep = np.array(sorted(set(range(n_cols)) - set(dropped)), dtype=int)
    return keep, dict(sorted(dropped.items()))


class CatalogOptimizer(BaseEstimator):
    """Base class of the catalog optimizers (see the module docstring for the protocol).

    Examples
    --------
    A least-squares solver with the force coefficient fixed to -1:

    >>> import numpy as np
    >>> class LeastSquares(CatalogOptimizer):
    ...     def fit_catalog(self, theta, n_coordinates, force_columns):
    ...         rest = np.setdiff1d(np.arange(theta.shape[1]), force_columns)
    ...         sol = np.linalg.lstsq(theta[:, rest], theta[:, force_columns].sum(1))[0]
    ...         self.coef_ = np.full(theta.shape[1], -1.0)
    ...         self.coef_[rest] = sol
    ...         return self
    >>> theta = np.column_stack([[1.0, 2.0, 3.0], [0.5, 1.0, 1.5]])
    >>> LeastSquares().fit_catalog(theta, 1, [0]).coef_
    array([-1.,  2.])
    """

    def fit_catalog(self, theta, n_coordinates, force_columns):  # pragma: no cover - abstract
        """Solve the catalog problem ``theta @ coef_ = 0``.

        Parameters
        ----------
        theta : array, shape (n_coordinates * N, F)
            Stacked regression matrix, rows coordinate-major.
        n_coordinates : int
        force_columns : sequence of int
            Columns of the external forces.

        Returns
        -------
        self
        """
        raise NotImplementedError
