"""The catalog regression problem that every catalog optimizer solves (:class:`CatalogProblem`)
and the balancing of its coordinate blocks."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from .._validation import check_indices, check_numeric_array, check_option
from ..physical.structure import PhysicalStructure
from ..weak.noise import draw_moments as _draw_moments

__all__ = ["CatalogProblem", "check_mass_matrices", "check_noise_moments", "check_support",
           "balance_coordinates", "coordinate_weights", "scale_blocks"]


@dataclasses.dataclass(frozen=True, eq=False)
class CatalogProblem:
    """A validated catalog regression ``theta @ coef ~ 0``; build it with :meth:`from_arrays`.

    Every row holds exactly, so scaling a coordinate block changes how the blocks are weighed,
    never the true coefficients: :meth:`balanced` makes the regression unit free.

    Parameters
    ----------
    theta : ndarray, shape (n_coordinates * N, F)
        Stacked regression matrix, rows coordinate-major.
    n_coordinates : int
        Number of coordinate blocks.
    force_columns : ndarray of int
        The :class:`~pysindy_xl.ExternalForces` columns (coefficient -1).
    noise_moments : ndarray, shape (n_coordinates, F, F), optional
        ``E[E_c^T E_c]`` of the errors in each coordinate's rows (errors in variables).
    mass_matrices : ndarray, shape (S, F, n, n), optional
        Each column's contribution to the mass matrix at ``S`` sample states.
    balance : bool
        Whether the blocks may be rescaled by :func:`coordinate_weights`.
    reference_columns : ndarray of int, optional
        The columns allowed to carry the ``+1`` of an unforced law.
    physical : PhysicalStructure, optional
        What the columns stand for physically.
    noise_draws : ndarray, shape (D, n_coordinates * N, F), optional
        Monte Carlo draws of the rows' errors: a part of the rows gets its own moments.
    row_noise : WeakNoise, optional
        Where the moments and draws come from (dropped by derived problems).
    catalog_map : CatalogMap, optional
        The map back to the catalog (dropped by sub-problems and subsamples).

    Examples
    --------
    >>> import numpy as np
    >>> theta = np.array([[1e-6, 2e-6], [3e-6, 1e-6], [1.0, 2.0], [3.0, 1.0]])
    >>> problem = CatalogProblem.from_arrays(theta, 2, [])
    >>> problem.n_samples, problem.n_features
    (2, 2)
    >>> problem.subproblem(np.array([False, True]), np.array([1])).theta
    array([[2.],
           [1.]])
    """

    theta: np.ndarray
    n_coordinates: int
    force_columns: np.ndarray
    noise_moments: np.ndarray | None = None
    mass_matrices: np.ndarray | None = None
    balance: bool = True
    reference_columns: np.ndarray | None = None
    physical: PhysicalStructure | None = None
    noise_draws: np.ndarray | None = None
    row_noise: object = None
    catalog_map: object = None

    @classmethod
    def from_arrays(cls, theta, n_coordinates, force_columns, noise_moments=None,
                    mass_matrices=None, balance=True, reference_columns=None, physical=None,
                    noise_draws=None, row_noise=None, catalog_map=None):
        """Check the arguments of ``fit_catalog`` and hold them as a problem.

        Parameters
        ----------
        theta, n_coordinates, force_columns, noise_moments, mass_matrices, balance, \
reference_columns, physical, noise_draws, row_noise, catalog_map
            The fields (class docstring); ``noise_moments`` default to the second moments of
            ``noise_draws``.

        Returns
        -------
        CatalogProblem
        """
        theta = check_numeric_array(theta, "theta", finite=False, min_samples=0)
        if theta.ndim != 2 or theta.shape[0] == 0 or theta.shape[1] == 0:
            raise ValueError(f"theta: expected a non-empty 2-D array, got shape {theta.shape}")
        if not np.all(np.isfinite(theta)):
            raise ValueError("theta: contains NaN or inf")
        n = int(check_option("n_coordinates", n_coordinates, "int", low=1))
        if theta.shape[0] % n:
            raise ValueError(f"theta: {theta.shape[0]} rows is not a multiple of n_coordinates={n}")
        n_features = theta.shape[1]
        force_columns = check_indices(force_columns, "force_columns", n_features)
        check_option("balance", balance, "bool")
        if noise_draws is not None:
            noise_draws = check_numeric_array(noise_draws, "noise_draws", min_samples=0)
            if noise_draws.ndim != 3 or noise_draws.shape[1:] != theta.shape \
                    or noise_draws.shape[0] == 0:
                raise ValueError(f"noise_draws: expected shape (D, {theta.shape[0]}, "
                                 f"{n_features}) with D >= 1, got {noise_draws.shape}")
            if noise_moments is None:
                noise_moments = _draw_moments(noise_draws, n)
        if noise_moments is not None:
            noise_moments = check_noise_moments(noise_moments, n, n_features)
        if mass_matrices is not None:
            mass_matrices = check_mass_matrices(mass_matrices, n, n_features)
        if reference_columns is not None:
            reference_columns = np.asarray(reference_columns, dtype=int).reshape(-1)
            if np.any((reference_columns < 0) | (reference_columns >= n_features)):
                raise ValueError(f"reference_columns: indices must lie in [0, {n_features}), "
                                 f"got {reference_columns}")
        if physical is not None:
            if not isinstance(physical, PhysicalStructure):
                raise TypeError(f"physical: expected a PhysicalStructure, got "
                                f"{type(physical).__name__}")
            used = np.concatenate([physical.base_columns, physical.friction_columns,
                                   physical.selectable_columns])
            if np.any((used < 0) | (used >= n_features)):
                raise ValueError(f"physical: column indices must lie in [0, {n_features})")
        return cls(theta, n, force_columns, noise_moments, mass_matrices, bool(balance),
                   reference_columns, physical, noise_draws, row_noise, catalog_map)

    @property
    def n_samples(self) -> int:
        """Rows of each coordinate block."""
        return self.theta.shape[0] // self.n_coordinates

    @property
    def n_features(self) -> int:
        """Catalog columns."""
        return self.theta.shape[1]

    @functools.cached_property
    def block_weights(self) -> np.ndarray:
        """Weights (n_coordinates,) of the blocks: :func:`coordinate_weights` with ``balance``,
        else 1.
        """
        if not self.balance:
            return np.ones(self.n_coordinates)
        return coordinate_weights(self.theta, self.n_coordinates, self.force_columns)

    def balanced(self) -> CatalogProblem:
        """The problem with each block's rows, moments and draws scaled by :attr:`block_weights`.

        Returns
        -------
        CatalogProblem
            The balanced problem (``balance=False``), or this one when it is not to be balanced.
        """
        if not self.balance:
            return self
        weights = self.block_weights
        moments, draws = self.noise_moments, self.noise_draws
        if moments is not None:
            moments = moments * (weights**2)[:, None, None]
        if draws is not None:
            draws = draws * np.repeat(weights, self.n_samples)[None, :, None]
        return dataclasses.replace(self, theta=scale_blocks(self.theta, weights),
                                   noise_moments=moments, noise_draws=draws, balance=False,
                                   row_noise=None)

    def pooled_moments(self) -> np.ndarray | None:
        """The noise moments of all rows together.

        Returns
        -------
        ndarray, shape (F, F) or None
            ``sum_c E[E_c^T E_c]``; None without noise moments.
        """
        return None if self.noise_moments is None else self.noise_moments.sum(axis=0)

    def rows(self, coordinates) -> np.ndarray:
        """Row indices of the blocks of some coordinates.

        Parameters
        ----------
        coordinates : array of bool, shape (n_coordinates,), or array of int
            The coordinates, as a mask or indices.

        Returns
        -------
        ndarray of int
            Their rows, block after block.

        Examples
        --------
        >>> import numpy as np
        >>> problem = CatalogProblem.from_arrays(np.zeros((6, 2)), 2, [])
        >>> problem.rows([1]).tolist()
        [3, 4, 5]
        """
        blocks = np.arange(self.n_coordinates)[coordinates]
        return (blocks[:, None] * self.n_samples + np.arange(self.n_samples)).ravel()

    def subproblem(self, coordinates, columns, force_columns=None) -> CatalogProblem:
        """The rows of ``coordinates`` and the ``columns``, with their moments and masses.

        Parameters
        ----------
        coordinates : array of bool, shape (n_coordinates,)
            The coordinates kept.
        columns : array of int
            Catalog columns kept, in this order.
        force_columns : array of int, optional
            Indices into ``columns``; default: this problem's force columns among ``columns``.

        Returns
        -------
        CatalogProblem
        """
        coordinates = np.asarray(coordinates, dtype=bool)
        columns = np.asarray(columns, dtype=int)
        if force_columns is None:
            force_columns = np.flatnonzero(np.isin(columns, self.force_columns))
        whole = coordinates.all() and np.array_equal(columns, np.arange(self.n_features))
        theta = self.theta if whole else self.theta[np.ix_(self.rows(coordinates), columns)]
        moments, mass, draws = self.noise_moments, self.mass_matrices, self.noise_draws
        if moments is not None:
            moments = moments[coordinates][:, columns][:, :, columns]
        if draws is not None and not whole:
            draws = draws[:, self.rows(coordinates)][:, :, columns]
        if mass is not None:
            mass = mass[:, columns][:, :, coordinates][:, :, :, coordinates]
        reference = self.reference_columns
        if reference is not None:
            reference = np.flatnonzero(np.isin(columns, reference))
        physical = None if self.physical is None else self.physical.select(columns)
        return dataclasses.replace(self, theta=theta, n_coordinates=int(coordinates.sum()),
                                   force_columns=np.asarray(force_columns, dtype=int),
                                   noise_moments=moments, mass_matrices=mass,
                                   reference_columns=reference, physical=physical,
                                   noise_draws=draws, row_noise=None, catalog_map=None)

    def subsample(self, samples) -> CatalogProblem:
        """The same samples of every block, with their own noise moments.

        Parameters
        ----------
        samples : array of int
            Row indices within a block.

        Returns
        -------
        CatalogProblem
            The rows ``samples`` of every block, with their own noise moments (given the draws)
            or their share of the moments; the mass matrices are kept whole.
        """
        samples = np.asarray(samples, dtype=int)
        rows = (np.arange(self.n_coordinates)[:, None] * self.n_samples + samples).ravel()
        moments, draws = self.noise_moments, self.noise_draws
        if draws is not None:
            draws = draws[:, rows]
            moments = _draw_moments(draws, self.n_coordinates)
        elif moments is not None:
            moments = moments * (len(samples) / self.n_samples)
        return dataclasses.replace(self, theta=self.theta[rows], noise_moments=moments,
                                   noise_draws=draws, row_noise=None, catalog_map=None)


def check_noise_moments(noise_moments, n_coordinates: int, n_features: int) -> np.ndarray:
    """Validate noise moments.

    Parameters
    ----------
    noise_moments : array, shape (n, F, F)
        ``E[E_c^T E_c]`` of each coordinate's block.
    n_coordinates : int
        ``n``.
    n_features : int
        ``F``.

    Returns
    -------
    ndarray, shape (n, F, F)
        The moments as floats.

    Raises
    ------
    ValueError
        When not finite, of the wrong shape, or with asymmetric blocks.
    """
    moments = check_numeric_array(noise_moments, "noise_moments", min_samples=0)
    if moments.shape != (n_coordinates, n_features, n_features):
        raise ValueError(f"noise_moments: expected shape {(n_coordinates, n_features, n_features)}"
                         f", got {moments.shape}")
    if not np.allclose(moments, np.swapaxes(moments, 1, 2), rtol=1e-8,
                       atol=1e-12 * np.abs(moments).max(initial=0.0)):
        raise ValueError("noise_moments: expected symmetric blocks")
    return moments


def check_mass_matrices(mass_matrices, n_coordinates: int, n_features: int) -> np.ndarray:
    """Validate column mass matrices.

    Parameters
    ----------
    mass_matrices : array, shape (S, F, n, n)
        Each column's mass matrix at ``S >= 1`` states.
    n_coordinates : int
        ``n``.
    n_features : int
        ``F``.

    Returns
    -------
    ndarray, shape (S, F, n, n)
        The mass matrices as floats.

    Raises
    ------
    ValueError
        When not finite or of the wrong shape.
    """
    mass = check_numeric_array(mass_matrices, "mass_matrices", min_samples=0)
    if mass.ndim != 4 or mass.shape[1:] != (n_features, n_coordinates, n_coordinates) \
            or mass.shape[0] == 0:
        raise ValueError(f"mass_matrices: expected shape (S, {n_features}, {n_coordinates}, "
                         f"{n_coordinates}) with S >= 1, got {mass.shape}")
    return mass


def check_support(support, n_features: int) -> np.ndarray:
    """Validate the ``support`` of a refit.

    Parameters
    ----------
    support : array of bool, shape (F,)
        The columns to refit.
    n_features : int
        ``F``.

    Returns
    -------
    ndarray of bool, shape (F,)
        The support.

    Raises
    ------
    TypeError, ValueError
        When not a boolean array of shape (F,).
    """
    support = np.asarray(support)
    if support.dtype != bool or support.shape != (n_features,):
        raise ValueError(f"support: expected a boolean array of shape ({n_features},), got "
                         f"{support.dtype} of shape {support.shape}")
    return support


def _block_rms(theta, n_blocks: int) -> np.ndarray:
    """RMS of every column within every row block, shape (n_blocks, F), without overflow."""
    blocks = np.asarray(theta, dtype=float).reshape(n_blocks, -1, theta.shape[1])
    top = abs_max(blocks, axis=1)
    safe = np.where((top > 0) & np.isfinite(top), top, 1.0)
    scaled = blocks / safe[:, None, :]
    np.square(scaled, out=scaled)  # (in place: one array of theta's size, not two)
    return top * np.sqrt(np.mean(scaled, axis=1))


def abs_max(values, axis: int) -> np.ndarray:
    r"""``np.max(np.abs(values), axis=axis)`` without the array of absolute values.

    .. math:: \max_k |v_k| = \max\left(\max_k v_k, \; -\min_k v_k\right),

    exact (a negation rounds nothing); NaN where a NaN is met, as ``np.max``.

    Parameters
    ----------
    values : ndarray of float
        Non-empty along ``axis``.
    axis : int
        The axis reduced.

    Returns
    -------
    ndarray
        The largest absolute value along ``axis``.

    Examples
    --------
    >>> import numpy as np
    >>> abs_max(np.array([[1.0, -4.0], [-3.0, 2.0]]), axis=0).tolist()
    [3.0, 4.0]
    """
    return np.maximum(values.max(axis=axis), -values.min(axis=axis))


def coordinate_weights(theta, n_coordinates: int, force_columns=None) -> np.ndarray:
    r"""Row weights of the coordinate blocks of ``theta`` that balance their scales.

    With :math:`M_{ij}` the RMS of column :math:`j` in block :math:`i` and :math:`P` its non-zero
    entries, solve

    .. math::

        \min_{u, v} \sum_{(i, j) \in P} \left(\log M_{ij} + u_i + v_j\right)^2
        \quad\text{s.t.}\quad v_j = 0 \text{ for the force columns } j

    (minimum norm) and return :math:`w_i = \exp(u_i - \bar u)` (geometric mean 1; a zero block
    gets 1). Force columns keep their scale (coefficient -1), so a change of units of block
    :math:`i` changes :math:`u_i` by exactly its log: the regression is unit free.

    Parameters
    ----------
    theta : array, shape (n_coordinates * N, F)
        Stacked regression matrix, rows coordinate-major.
    n_coordinates : int
        Number of coordinate blocks.
    force_columns : sequence of int, optional
        Columns whose scale is not free.

    Returns
    -------
    ndarray, shape (n_coordinates,)

    Examples
    --------
    The first coordinate in micrometres:

    >>> import numpy as np
    >>> block = np.random.default_rng(0).normal(size=(50, 3))
    >>> theta = np.vstack([block * 1e-6, block])
    >>> w = coordinate_weights(theta, 2, force_columns=[2])
    >>> np.round(w[0] / w[1])
    np.float64(1000000.0)
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
    return np.exp(np.where(active, u - u[active].mean(), 0.0))


def balance_coordinates(theta, n_coordinates: int, force_columns=None) -> np.ndarray:
    """``theta`` with each block's rows multiplied by its :func:`coordinate_weights`.

    Parameters
    ----------
    theta, n_coordinates, force_columns
        As in :func:`coordinate_weights`.

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
    """Multiply the rows of each coordinate block by a weight.

    Parameters
    ----------
    theta : array, shape (n * N, F)
        Rows in ``n`` equal blocks.
    weights : array, shape (n,)
        Weight of each block.

    Returns
    -------
    ndarray, shape (n * N, F)
        The rows of block ``i`` times ``weights[i]``.

    Examples
    --------
    >>> import numpy as np
    >>> scale_blocks(np.ones((4, 1)), [1.0, 3.0]).ravel().tolist()
    [1.0, 1.0, 3.0, 3.0]
    """
    weights = np.asarray(weights, dtype=float)
    return theta * np.repeat(weights, theta.shape[0] // len(weights))[:, None]
