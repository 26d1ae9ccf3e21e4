"""A homogeneous law ``Theta xi = 0`` once found: the coordinates it explains, whether its mass
matrix is definite, its scale, and laws of uncoupled subsystems combined.
"""

from __future__ import annotations

import numpy as np

__all__ = ["UndeterminedLawWarning", "combine_laws", "definite_mass", "explained_coordinates",
           "normalize_law"]


class UndeterminedLawWarning(UserWarning):
    """The data hold several different laws to the noise and do not say which is the system's.

    Raised as a warning by the unforced selections (``undetermined_`` or ``rivals``); record
    more varied motion, or add forces.

    Examples
    --------
    >>> import warnings
    >>> from pysindy_xl.optimizers import UndeterminedLawWarning
    >>> issubclass(UndeterminedLawWarning, UserWarning)
    True
    """


def explained_coordinates(theta, law, n_blocks: int, min_share: float = 1e-3) -> np.ndarray:
    """The coordinates whose equations a law explains.

    Those where the law's terms carry at least ``min_share`` of the largest coordinate's
    squared contribution.

    Parameters
    ----------
    theta : array, shape (n_blocks * N, k)
        The law's columns, balanced blocks.
    law : array, shape (k,)
        The law's coefficients.
    n_blocks : int
        Number of coordinate blocks.
    min_share : float, default 1e-3
        Smallest share of the largest block's ``|theta_c @ law|^2``.

    Returns
    -------
    ndarray of bool, shape (n_blocks,)
        True for explained coordinates.

    Examples
    --------
    >>> import numpy as np
    >>> theta = np.array([[1.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.0, 1.0]])
    >>> explained_coordinates(theta, np.array([1.0, 1e-4]), 2).tolist()
    [True, False]
    """
    contributions = (np.asarray(theta, dtype=float) * law).reshape(n_blocks, -1, len(law))
    shares = np.sum(contributions**2, axis=(1, 2))
    return shares >= min_share * max(float(shares.max(initial=0.0)), 1e-300)


def normalize_law(law, norms, force_columns, reference_columns=None) -> np.ndarray:
    """A law scaled to the catalog's convention.

    Its largest force column (by ``|law_j| norms_j``) at ``-1``, else its dominant term (among
    ``reference_columns`` if given) at ``+1``.

    Parameters
    ----------
    law : array, shape (F,)
        The law, any scale.
    norms : array, shape (F,)
        Column norms (the size of each term's contribution).
    force_columns : array of int
        The force columns.
    reference_columns : array of int, optional
        Columns that may set the scale without forces; default None: all.

    Returns
    -------
    ndarray, shape (F,)
        The scaled law.

    Examples
    --------
    >>> import numpy as np
    >>> normalize_law(np.array([0.5, -1.0, 0.0]), np.ones(3), np.array([0])).tolist()
    [-1.0, 2.0, 0.0]
    """
    support = np.flatnonzero(law)
    contribution = np.abs(law) * norms
    forces = np.intersect1d(support, force_columns)
    if forces.size:
        pivot = forces[np.argmax(contribution[forces])]
        return law / -law[pivot] + 0.0
    candidates = support
    if reference_columns is not None and np.intersect1d(support, reference_columns).size:
        candidates = np.intersect1d(support, reference_columns)
    pivot = candidates[np.argmax(contribution[candidates])]
    return law / law[pivot] + 0.0


def combine_laws(laws) -> tuple[np.ndarray, list]:
    """Sum of the laws with pairwise disjoint supports, best first.

    Uncoupled subsystems' laws hold together.

    Parameters
    ----------
    laws : array, shape (n_laws, F)
        The laws, best first.

    Returns
    -------
    law : ndarray, shape (F,)
        The sum of the laws kept.
    kept : list of int
        Indices of the laws summed.

    Examples
    --------
    >>> import numpy as np
    >>> law, kept = combine_laws(np.array([[1.0, 1.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]]))
    >>> law.tolist(), kept
    ([1.0, 1.0, 3.0], [0, 2])
    """
    coef = np.zeros(laws.shape[1])
    used = np.zeros(laws.shape[1], dtype=bool)
    chosen = []
    for k, law in enumerate(laws):
        support = law != 0
        if np.any(support & used):
            continue
        coef += law
        used |= support
        chosen.append(k)
    return coef, chosen


def definite_mass(mass_matrices, law) -> bool:
    """Whether a law's mass matrix ``sum_j law_j M_j`` is definite (either sign) at every state.

    Judged unit free, as :func:`~pysindy_xl.fit.diagnostics.mass_matrix_report` does.

    Parameters
    ----------
    mass_matrices : array, shape (S, k, n, n)
        The columns' mass matrices.
    law : array, shape (k,)
        The law's coefficients.

    Returns
    -------
    bool
        True when definite at every state.

    Examples
    --------
    >>> import numpy as np
    >>> columns = np.array([[[[1.0, 0.0], [0.0, 0.0]], [[0.0, 0.0], [0.0, 1.0]]]])
    >>> definite_mass(columns, np.array([-2.0, -1.0])), definite_mass(columns, [1.0, 0.0])
    (True, False)
    """
    mass = np.einsum("sfij,f->sij", np.asarray(mass_matrices, dtype=float), law)
    mass = (mass + np.swapaxes(mass, 1, 2)) / 2
    diagonal = np.max(np.abs(np.diagonal(mass, axis1=1, axis2=2)), axis=0, initial=0.0)
    unit = 1.0 / np.sqrt(np.where(diagonal > 0, diagonal, 1.0))
    eigenvalues = np.linalg.eigvalsh(mass * unit[None, :, None] * unit[None, None, :])
    if np.median(np.trace(mass, axis1=1, axis2=2)) < 0:
        eigenvalues = -eigenvalues
    scale = max(float(np.abs(eigenvalues).max(initial=0.0)), 1e-300)
    return bool(np.all(eigenvalues.min(axis=1) > 1e-9 * scale))
