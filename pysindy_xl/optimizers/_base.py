"""What the catalog optimizers share: the ``fit_catalog`` protocol and column bookkeeping.

Every optimizer of this package is a scikit-learn estimator with, besides its own ``fit``,

``fit_catalog(theta, n_coordinates, force_columns) -> self``
    ``theta`` is the stacked regression matrix ``(n_coordinates * N, F)`` (rows
    coordinate-major, see :mod:`pysindy_xl.feature_library._base`), ``force_columns`` the
    indices of the :class:`~pysindy_xl.ExternalForces` columns. It sets ``coef_`` of shape
    ``(F,)``: the full coefficient vector, force columns included, with ``theta @ coef_ ~ 0``.

This is the metadata :class:`~pysindy_xl.XLSINDy` hands over; standalone users pass the same.
Optimizers that can correct for errors in the columns also take
``noise_moments`` of shape ``(n_coordinates, F, F)``, ``E[E_c^T E_c]`` for the errors ``E_c``
of each coordinate's rows (the weak form's propagated position noise); XLSINDy passes it to
those whose ``fit_catalog`` has the parameter (:func:`accepts_noise_moments`). An optimizer
may also offer ``pilot()``, an unfitted cheaper optimizer of the same law for a first estimate
(:func:`pilot_optimizer`).

Units. Every row of ``theta @ coef = 0`` holds exactly, so multiplying the rows of one
coordinate block by a constant changes only how the regression weighs that block against the
others, never the true coefficients. :func:`check_catalog_problem`, through which every
``fit_catalog`` of this package goes, balances the blocks with :func:`coordinate_weights`
before solving: a coordinate in micrometres next to one in radians (blocks 1e6 apart, a
coupling column 1e12 apart between its two blocks) is then solved like the same system in
metres, and ``coef_`` keeps its meaning (physical units of the catalog columns).
:func:`independent_columns` uses the same balancing for its dependent-column test. Rows that
the caller has weighed already are fitted as given with ``fit_catalog(..., balance=False)``:
XLSINDy's rows whitened by the covariance of the residual are each in units of their own
noise (unit free too), and rebalancing them by their scales would undo the weighting.
"""

from __future__ import annotations

import inspect
import warnings

import numpy as np
import scipy.linalg
from sklearn.base import BaseEstimator, clone

from .._validation import check_indices, check_numeric_array, check_option
from ..diagnostics import UnexplainedCoordinateWarning

__all__ = [
    "accepts_fit_parameter",
    "accepts_noise_moments",
    "check_mass_matrices",
    "check_noise_moments",
    "CatalogOptimizer",
    "balance_coordinates",
    "block_weights",
    "check_catalog_problem",
    "coordinate_weights",
    "coordinates_touched",
    "independent_columns",
    "pilot_optimizer",
    "warn_unexplained",
]


def check_catalog_problem(theta, n_coordinates, force_columns, balance: bool = True):
    """Validate the arguments of ``fit_catalog``; returns ``(theta, force_columns)`` as arrays.

    With ``balance`` (the default, used by every catalog optimizer of this package) the returned
    ``theta`` has the rows of each coordinate block multiplied by its
    :func:`coordinate_weights`: the same exact solutions, a unit-free regression. A single block
    is returned unchanged.
    """
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
    if balance:
        theta = balance_coordinates(theta, int(n_coordinates), force_columns)
    return theta, force_columns


def check_noise_moments(noise_moments, n_coordinates: int, n_features: int) -> np.ndarray:
    """Validate the ``noise_moments`` of ``fit_catalog``: finite, shape (n, F, F), symmetric
    positive semidefinite blocks (sums of outer products of column errors)."""
    moments = check_numeric_array(noise_moments, "noise_moments", min_samples=0)
    if moments.shape != (n_coordinates, n_features, n_features):
        raise ValueError(f"noise_moments: expected shape {(n_coordinates, n_features, n_features)}"
                         f", got {moments.shape}")
    if not np.allclose(moments, np.swapaxes(moments, 1, 2), rtol=1e-8,
                       atol=1e-12 * np.abs(moments).max(initial=0.0)):
        raise ValueError("noise_moments: expected symmetric blocks")
    return moments


def check_support(support, n_features: int) -> np.ndarray:
    """Validate the ``support`` of ``fit_support``: a boolean array of shape (F,)."""
    support = np.asarray(support)
    if support.dtype != bool or support.shape != (n_features,):
        raise ValueError(f"support: expected a boolean array of shape ({n_features},), got "
                         f"{support.dtype} of shape {support.shape}")
    return support


def accepts_noise_moments(optimizer) -> bool:
    """Whether ``optimizer.fit_catalog`` takes ``noise_moments`` (as scikit-learn's
    ``has_fit_parameter`` does for ``sample_weight``)."""
    return accepts_fit_parameter(optimizer, "noise_moments")


def accepts_fit_parameter(optimizer, name: str, method: str = "fit_catalog") -> bool:
    """Whether ``optimizer.<method>`` (by default ``fit_catalog``) takes the keyword
    ``name``."""
    return name in inspect.signature(getattr(optimizer, method)).parameters


def pilot_optimizer(optimizer):
    """An unfitted optimizer for a first estimate of the law that ``optimizer`` would find.

    Where the law only prepares the real fit (the residual covariance of
    :class:`~pysindy_xl.XLSINDy`), an optimizer may offer a cheaper stand-in through a
    ``pilot()`` method (an ensemble: one fit of its base optimizer instead of
    ``n_models``); otherwise the pilot is a clone of ``optimizer``.
    """
    pilot = getattr(optimizer, "pilot", None)
    return pilot() if callable(pilot) else clone(optimizer)


def check_mass_matrices(mass_matrices, n_coordinates: int, n_features: int) -> np.ndarray:
    """Validate the ``mass_matrices`` of ``fit_catalog``: finite, shape (S, F, n, n)."""
    mass = check_numeric_array(mass_matrices, "mass_matrices", min_samples=0)
    if mass.ndim != 4 or mass.shape[1:] != (n_features, n_coordinates, n_coordinates) \
            or mass.shape[0] == 0:
        raise ValueError(f"mass_matrices: expected shape (S, {n_features}, {n_coordinates}, "
                         f"{n_coordinates}) with S >= 1, got {mass.shape}")
    return mass


def _block_rms(theta, n_blocks: int) -> np.ndarray:
    """RMS of every column within every row block, shape (n_blocks, F), without overflow."""
    blocks = np.asarray(theta, dtype=float).reshape(n_blocks, -1, theta.shape[1])
    top = np.max(np.abs(blocks), axis=1)
    safe = np.where((top > 0) & np.isfinite(top), top, 1.0)
    return top * np.sqrt(np.mean((blocks / safe[:, None, :]) ** 2, axis=1))


def coordinates_touched(theta, n_coordinates: int, rtol: float = 1e-10) -> np.ndarray:
    """Which coordinate equations each column enters (is not identically zero in).

    Parameters
    ----------
    theta : array, shape (n_coordinates * N, F)
        Stacked regression matrix, rows coordinate-major.
    n_coordinates : int
    rtol : float
        A block counts as zero when its norm is at most ``rtol`` times the column's largest
        block norm.

    Returns
    -------
    ndarray of bool, shape (n_coordinates, F)

    Examples
    --------
    >>> import numpy as np
    >>> theta = np.array([[1.0, 0.0], [2.0, 0.0], [0.0, 1.0], [3.0, 1.0]])
    >>> coordinates_touched(theta, 2)
    array([[ True, False],
           [ True,  True]])
    """
    theta = np.asarray(theta, dtype=float)
    blocks = theta.reshape(n_coordinates, -1, theta.shape[1])
    block_norms = np.linalg.norm(blocks, axis=1)
    top = block_norms.max(axis=0, initial=0.0)
    return (block_norms > 0) & (block_norms > rtol * top)


def warn_unexplained(owner: str, theta, n_coordinates: int, coef, force_columns=(),
                     stacklevel: int = 2, rtol: float = 1e-8) -> np.ndarray:
    """Warn when no identified term other than the forces enters some coordinate's equation.

    Such a coordinate's equation says only ``forces = 0`` (or nothing): the model cannot
    predict it, however small its residual. Fits on noisy data end there when the candidate
    terms of a weakly excited coordinate are all pruned.

    Parameters
    ----------
    owner : str
        Who warns (the optimizer's name).
    theta : array, shape (n_coordinates * N, F)
    n_coordinates : int
    coef : array, shape (F,)
    force_columns : sequence of int
    stacklevel : int, default 2
        As for :func:`warnings.warn`, counted from the caller (2: the caller's caller).
    rtol : float, default 1e-8
        A term explains a coordinate when its contribution there (the norm of its column
        block times its coefficient) exceeds ``rtol`` times the largest contribution of any
        identified term or force to any coordinate.

    Returns
    -------
    ndarray of int
        The unexplained coordinates (empty when every coordinate is explained).
    """
    coef = np.asarray(coef, dtype=float)
    used = np.flatnonzero(coef)
    # each term's contribution to each coordinate's equation: a term whose coefficient came
    # out at round-off level (a refit on terms that cannot reach the forced equations) is
    # no explanation
    contribution = np.linalg.norm(
        (np.asarray(theta)[:, used] * coef[used]).reshape(n_coordinates, -1, len(used)), axis=1)
    terms = ~np.isin(used, np.asarray(force_columns, dtype=int))
    scale = contribution.max(initial=0.0)
    explained = (contribution[:, terms] > rtol * scale).any(axis=1)
    unexplained = np.flatnonzero(~explained)
    if unexplained.size:
        besides = " besides the forces" if len(force_columns) else ""
        warnings.warn(
            f"{owner}: no identified term{besides} enters the equation of coordinate(s) "
            f"{unexplained.tolist()}; the model cannot predict them",
            UnexplainedCoordinateWarning, stacklevel=stacklevel + 1)
    return unexplained


def coordinate_weights(theta, n_coordinates: int, force_columns=None) -> np.ndarray:
    r"""Row weights of the coordinate blocks of ``theta`` that balance their scales.

    With :math:`M_{ij}` the RMS of column :math:`j` within block :math:`i` (rows
    coordinate-major) and :math:`P = \{(i, j) : M_{ij} > 0\}` the entries that are not
    exactly zero, solve the small least-squares problem

    .. math::

        \min_{u, v} \sum_{(i, j) \in P} \left(\log M_{ij} + u_i + v_j\right)^2
        \quad\text{s.t.}\quad v_j = 0 \text{ for the force columns } j

    (minimum-norm solution where it is not unique) and return
    :math:`w_i = \exp(u_i - \bar u)`, :math:`\bar u` the mean of :math:`u` over the blocks
    with an entry in :math:`P` (geometric mean 1; a block that is exactly zero gets 1).
    :math:`\exp(u_i)` and :math:`\exp(v_j)` are row and column scalings that bring every
    block of every column as close as possible to 1 in the log sense.

    Force columns carry the coefficient -1 (the units of their equation), so they are not
    rescaled (:math:`v_j = 0`): a change of units that multiplies block :math:`i` by
    :math:`a_i` and column :math:`j` by :math:`b_j` (coefficient :math:`c_j \to c_j / b_j`,
    forces kept at -1) changes :math:`u_i` by exactly :math:`-\log a_i` (up to a common
    constant that the normalization removes), so the weighted matrix is the same up to column
    scales: the regression is unit free. The pinned columns also fix the otherwise free common
    shift of :math:`u` against :math:`v`. Balancing a balanced matrix returns ones.

    Parameters
    ----------
    theta : array, shape (n_coordinates * N, F)
        Stacked regression matrix, rows coordinate-major.
    n_coordinates : int
    force_columns : sequence of int, optional
        Columns whose scale is not free (their coefficient is fixed).

    Returns
    -------
    ndarray, shape (n_coordinates,)

    Examples
    --------
    The first coordinate in micrometres: its block, force included, is 1e6 times too small.

    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> block = rng.normal(size=(50, 3))
    >>> theta = np.vstack([block * 1e-6, block])
    >>> w = coordinate_weights(theta, 2, force_columns=[2])
    >>> np.round(w[0] / w[1])
    np.float64(1000000.0)
    >>> balanced = balance_coordinates(theta, 2, [2])
    >>> np.allclose(coordinate_weights(balanced, 2, [2]), 1.0)
    True
    """
    theta = np.asarray(theta, dtype=float)
    n = int(n_coordinates)
    n_features = theta.shape[1]
    if n == 1:
        return np.ones(1)
    rms = _block_rms(theta, n)
    present = (rms > 0) & np.isfinite(rms)
    blocks, columns = np.nonzero(present)
    if blocks.size == 0:
        return np.ones(n)
    pinned = np.zeros(n_features, dtype=bool)
    if force_columns is not None:
        pinned[np.asarray(force_columns, dtype=int).reshape(-1)] = True
    free = np.flatnonzero(~pinned)
    slot = np.full(n_features, -1)
    slot[free] = n + np.arange(free.size)
    design = np.zeros((blocks.size, n + free.size))
    rows = np.arange(blocks.size)
    design[rows, blocks] = 1.0
    unpinned = slot[columns] >= 0
    design[rows[unpinned], slot[columns[unpinned]]] = 1.0
    solution = np.linalg.lstsq(design, -np.log(rms[blocks, columns]), rcond=None)[0]
    u = solution[:n]
    active = present.any(axis=1)
    log_w = np.where(active, u - u[active].mean(), 0.0)
    return np.exp(log_w)


def block_weights(theta, n_coordinates: int, force_columns=None, balance=True) -> np.ndarray:
    """Weights of the coordinate blocks of a ``fit_catalog`` problem: those of
    :func:`coordinate_weights` with ``balance`` (checked: a bool), ones without (the caller
    has weighed the blocks, e.g. whitened them by the covariance of the residual)."""
    check_option("balance", balance, "bool")
    if balance:
        return coordinate_weights(theta, n_coordinates, force_columns)
    return np.ones(int(n_coordinates))


def balance_coordinates(theta, n_coordinates: int, force_columns=None) -> np.ndarray:
    """``theta`` with the rows of each coordinate block multiplied by its
    :func:`coordinate_weights` (a new array; ``theta`` itself for a single block).

    Parameters
    ----------
    theta : array, shape (n_coordinates * N, F)
        Stacked regression matrix, rows coordinate-major.
    n_coordinates : int
    force_columns : sequence of int, optional
        Columns whose scale is not free (see :func:`coordinate_weights`).

    Returns
    -------
    ndarray, shape (n_coordinates * N, F)

    Examples
    --------
    >>> import numpy as np
    >>> theta = np.array([[1e-6, 2e-6], [3e-6, 1e-6], [1.0, 2.0], [3.0, 1.0]])
    >>> balance_coordinates(theta, 2).round(6)
    array([[0.001, 0.002],
           [0.003, 0.001],
           [0.001, 0.002],
           [0.003, 0.001]])
    """
    theta = np.asarray(theta, dtype=float)
    if int(n_coordinates) == 1:
        return theta
    return scale_blocks(theta, coordinate_weights(theta, n_coordinates, force_columns))


def scale_blocks(theta, weights) -> np.ndarray:
    """``theta`` with the rows of block ``i`` (rows coordinate-major) multiplied by
    ``weights[i]``.

    Examples
    --------
    >>> import numpy as np
    >>> scale_blocks(np.ones((4, 1)), [1.0, 3.0]).ravel().tolist()
    [1.0, 1.0, 3.0, 3.0]
    """
    weights = np.asarray(weights, dtype=float)
    return theta * np.repeat(weights, theta.shape[0] // len(weights))[:, None]


def independent_columns(theta, priority=None, rtol: float = 1e-9, max_rows: int = 20_000,
                        n_blocks: int = 1, force_columns=None):
    """Split the columns of ``theta`` into a linearly independent set and the rest.

    Columns are visited in ``priority`` order; a column is kept when its component orthogonal
    to the span of the columns visited before it exceeds ``rtol`` times its norm (a QR
    factorization of the column-normalized, priority-ordered matrix, on at most ``max_rows``
    evenly spaced rows: exact identities such as ``cos^2 + sin^2 = 1`` hold on any subset).
    With ``n_blocks > 1`` the coordinate blocks of rows are first balanced by
    :func:`coordinate_weights` (a coupling column whose blocks differ by 1e12 because one
    coordinate is in micrometres stays independent of the columns of either block alone).

    The test is scale free: only a column that is exactly zero on the rows used (or not
    finite) is dropped without the QR test, whatever the scales of the other columns.

    Parameters
    ----------
    theta : array, shape (n_rows, F)
    priority : array of int, shape (F,), optional
        Visiting order, most preferred first. Default: column order.
    rtol : float
        Relative residual below which a column counts as dependent.
    max_rows : int
        Rows used for the test.
    n_blocks : int
        Coordinate blocks of rows (``theta`` stacked coordinate-major); 1: no balancing.
    force_columns : sequence of int, optional
        Force columns, passed to :func:`coordinate_weights`.

    Returns
    -------
    keep : ndarray of int
        Independent columns, sorted.
    dropped : dict of int to str
        Dropped columns with the reason (``"zero column"``, ``"non-finite column"`` or
        ``"linear combination"``).

    Examples
    --------
    >>> import numpy as np
    >>> a = np.linspace(0, 1, 50)
    >>> theta = np.column_stack([a, a ** 2, 2 * a - a ** 2, np.zeros(50)])
    >>> keep, dropped = independent_columns(theta)
    >>> keep, dropped
    (array([0, 1]), {2: 'linear combination', 3: 'zero column'})

    Scales do not matter, only exact zeros do:

    >>> keep, dropped = independent_columns(theta * [1e-30, 1.0, 1e30, 1.0])
    >>> keep, dropped
    (array([0, 1]), {2: 'linear combination', 3: 'zero column'})
    """
    theta = np.asarray(theta, dtype=float)
    n_rows, n_cols = theta.shape
    order = np.arange(n_cols) if priority is None else np.asarray(priority, dtype=int)
    if sorted(order.tolist()) != list(range(n_cols)):
        raise ValueError("priority: expected a permutation of the column indices")
    n_blocks = int(n_blocks)
    if n_blocks < 1 or n_rows % n_blocks:
        raise ValueError(f"n_blocks: {n_rows} rows is not a multiple of n_blocks={n_blocks}")
    finite_columns = np.all(np.isfinite(theta), axis=0)
    if n_blocks > 1:
        # balance on the finite columns; the others are dropped below anyway
        finite = np.where(finite_columns, theta, 0.0)
        theta = scale_blocks(theta, coordinate_weights(finite, n_blocks, force_columns))
    rows = np.unique(np.linspace(0, n_rows - 1, min(n_rows, max_rows)).astype(int))
    sub = theta[rows][:, order]
    top = np.max(np.abs(sub), axis=0, initial=0.0)
    finite = np.isfinite(top) & finite_columns[order]
    nonzero = finite & (top > 0)
    dropped = {}
    for j in order[~finite]:
        dropped[int(j)] = "non-finite column"
    for j in order[finite & ~nonzero]:
        dropped[int(j)] = "zero column"
    if not np.any(nonzero):
        return np.array([], dtype=int), dict(sorted(dropped.items()))
    candidates = order[nonzero]
    sub = sub[:, nonzero] / top[nonzero]  # max-scaled first: no overflow in the norms
    sub /= np.linalg.norm(sub, axis=0)
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
