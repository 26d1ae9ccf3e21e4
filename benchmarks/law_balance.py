"""The unforced law search with each coordinate's equation weighted by its own noise: tried for
the half-car (issue 51, ``law_paths.md``), not kept in the package.

``install()`` swaps ``pysindy_xl.optimizers.homogeneous.select_law`` at run time for
:func:`balanced_select_law`: the package's search, then, where a reference law explains every
coordinate, the same search again on the blocks weighted by :func:`noise_balance` (York's
equation weights of weighted errors-in-variables fits). The references are the admissible
lasso's starts and the first search's law where it is admissible. ``law_paths_switch.py on``
runs a benchmark with it.
"""
from __future__ import annotations

import functools

import numpy as np

from pysindy_xl.optimizers import homogeneous
from pysindy_xl.optimizers._sparse import triangular_factor
from pysindy_xl.optimizers.admissible import admissible_supports
from pysindy_xl.optimizers.laws import definite_mass, explained_coordinates
from pysindy_xl.optimizers.noise_ratio import noise_ratio_law

#: Most fixed-point steps of :func:`noise_balance` per reference support.
BALANCE_STEPS = 20

ORIGINAL = homogeneous.select_law

#: The weights set in this process, ``(n_blocks, weights)`` (for ``summary``).
WEIGHTS = []


def noise_balance(theta, noise_moments, supports, n_blocks: int, mass_matrices=None):
    r"""Block weights under which a reference law's noise is the same in every coordinate.

    The noise ratio pools the blocks, so a coordinate whose equation carries little of a
    law's noise (a light body: its terms scale with its inertia) hardly counts in it, and laws
    that leave it unfitted score as well as the system's. Weighted by the inverse standard
    deviation of its own noise, each equation counts alike (the equation weights of weighted
    errors-in-variables fits, York 1966): the pooled ratio becomes the mean of the blocks' own
    ratios. The weights are a fixed point, ``w_b^2 \propto 1 / (\xi^T S_b \xi)`` with ``xi``
    the smallest-ratio law of a reference support on the weighted blocks; of the references
    whose fixed point is reached within :data:`BALANCE_STEPS` steps (one that leaves a
    coordinate out has none: that coordinate's weight grows without bound) and whose law then
    explains every coordinate (and has a definite mass matrix where ``mass_matrices`` is given),
    the one of smallest balanced ratio sets them.

    Parameters
    ----------
    theta : array, shape (n_blocks * N, F)
        Regression matrix, rows in ``n_blocks`` equal blocks (coordinates).
    noise_moments : array, shape (n_blocks, F, F)
        ``E[E_b^T E_b]`` of each block's errors.
    supports : list of array of int
        The reference supports.
    n_blocks : int
        Number of coordinate blocks.
    mass_matrices : array, shape (S, F, n_blocks, n_blocks), optional
        Each column's contribution to the mass matrix on sample states, as
        :func:`~pysindy_xl.optimizers.homogeneous.select_law` takes them; default None
        (definiteness not judged).

    Returns
    -------
    ndarray, shape (n_blocks,) or None
        The weights (geometric mean 1), None where no reference qualifies.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> a, b = rng.normal(size=(2, 1000))
    >>> clean = np.vstack([np.column_stack([a, a + b]), np.column_stack([0.01 * b, 0.01 * b])])
    >>> theta = clean + np.repeat([0.1, 0.001], 1000)[:, None] * rng.normal(size=(2000, 2))
    >>> moments = np.array([0.01 * 1000 * np.eye(2), 1e-6 * 1000 * np.eye(2)])
    >>> weights = noise_balance(theta, moments, [np.array([0, 1])], 2)
    >>> bool(weights[1] / weights[0] > 10)
    True
    """
    theta = np.asarray(theta, dtype=float)
    moments = np.asarray(noise_moments, dtype=float)
    scale = np.sqrt(np.mean(theta**2, axis=0))
    scale[scale == 0] = 1.0
    theta = theta / scale
    moments = moments / np.outer(scale, scale)[None]
    rows = theta.shape[0] // n_blocks
    factors = [triangular_factor(theta[b * rows:(b + 1) * rows]) for b in range(n_blocks)]
    best = None
    for support in supports:
        support = np.asarray(support, dtype=int)
        block_moments = moments[:, support][:, :, support]
        weights, converged = np.ones(n_blocks), False
        for _ in range(BALANCE_STEPS):
            try:
                ratio, law = noise_ratio_law(
                    np.vstack([w * f[:, support] for w, f in zip(weights, factors, strict=True)]),
                    np.einsum("b,bij->ij", weights**2, block_moments))
            except np.linalg.LinAlgError:
                break
            noise = np.einsum("i,bij,j->b", law, block_moments, law)
            if not np.all(np.isfinite(noise) & (noise > 0)):
                break
            update = 1 / np.sqrt(noise)
            update /= np.exp(np.mean(np.log(update)))
            if np.allclose(update, weights, rtol=1e-3):
                converged = True
                break
            weights = update
        # a reference that leaves a coordinate out has no fixed point: the weight of the
        # coordinate it leaves grows without bound
        if not converged:
            continue
        weighted = theta[:, support] * np.repeat(weights, rows)[:, None]
        if not explained_coordinates(weighted, law, n_blocks).all() or (
                mass_matrices is not None and not definite_mass(
                    np.asarray(mass_matrices)[:, support], law / scale[support])):
            continue
        if best is None or ratio < best[0]:
            best = (ratio, weights)
    return None if best is None else best[1]


def balanced_select_law(theta, noise_moments, n_blocks: int = 1, mass_matrices=None,
                        noise_draws=None, **options):
    """``homogeneous.select_law``, then again on noise-balanced blocks where a reference law that
    explains every coordinate is found (module documentation)."""
    first = ORIGINAL(theta, noise_moments, n_blocks=n_blocks, mass_matrices=mass_matrices,
                     noise_draws=noise_draws, **options)
    if n_blocks < 2:
        return first
    theta = np.asarray(theta, dtype=float)
    moments = np.asarray(noise_moments, dtype=float)
    law, _, selection = first
    references = [np.flatnonzero(law)] if selection.admissible else []
    if mass_matrices is not None:
        # the admissible lasso's starts, as select_law computes them (same scaling)
        scale = np.sqrt(np.mean(theta**2, axis=0))
        scale[scale == 0] = 1.0
        references += admissible_supports(triangular_factor(theta / scale),
                                          np.asarray(mass_matrices) / scale[None, :, None, None])
    if not references:
        return first
    weights = noise_balance(theta, moments, references, n_blocks, mass_matrices)
    if weights is None:
        return first
    WEIGHTS.append(weights)
    rows = np.repeat(weights, theta.shape[0] // n_blocks)
    draws = None if noise_draws is None else np.asarray(noise_draws, dtype=float) * rows[:, None]
    return ORIGINAL(theta * rows[:, None], moments * weights[:, None, None] ** 2,
                    n_blocks=n_blocks, mass_matrices=mass_matrices, noise_draws=draws, **options)


def install(report: bool = False):
    """Swap the balanced search into ``homogeneous`` (``select_laws`` calls it by name); with
    ``report``, print the spread of the weights set (largest over smallest) at exit."""
    homogeneous.select_law = functools.wraps(ORIGINAL)(balanced_select_law)
    if report:
        import atexit
        atexit.register(summary)


def summary():
    """Print how many searches were balanced and the spread of their weights."""
    spreads = np.array([w.max() / w.min() for w in WEIGHTS])
    if spreads.size:
        print(f"law_balance: {spreads.size} searches balanced; weight spread (largest over "
              f"smallest) quartiles {np.round(np.percentile(spreads, [0, 25, 50, 75, 100]), 2)}")
