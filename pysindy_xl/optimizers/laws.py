"""A homogeneous law ``Theta xi = 0`` once found: the coordinates it explains, whether its mass
matrix is definite, its scale, and laws of uncoupled subsystems combined.
"""

from __future__ import annotations

import numpy as np

__all__ = ["UndeterminedLawWarning", "combine_laws", "definite_mass", "explained_coordinates",
           "normalize_law"]


class UndeterminedLawWarning(UserWarning):
    """The data hold several different laws to the noise and do not say which is the system's."""


def explained_coordinates(theta, law, n_blocks: int, min_share: float = 1e-3) -> np.ndarray:
    """Boolean (n_blocks,): coordinates where the law's terms carry at least ``min_share`` of the
    largest coordinate's squared contribution. ``theta`` (n_blocks * N, k), the law's columns,
    must have balanced blocks.

    >>> import numpy as np
    >>> theta = np.array([[1.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.0, 1.0]])
    >>> explained_coordinates(theta, np.array([1.0, 1e-4]), 2).tolist()
    [True, False]
    """
    contributions = (np.asarray(theta, dtype=float) * law).reshape(n_blocks, -1, len(law))
    shares = np.sum(contributions**2, axis=(1, 2))
    return shares >= min_share * max(float(shares.max(initial=0.0)), 1e-300)


def normalize_law(law, norms, force_columns, reference_columns=None) -> np.ndarray:
    """A law in the catalog's convention: its largest force column (``|law_j| norms_j``) at ``-1``,
    else its dominant term (among ``reference_columns`` if any) at ``+1``.

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
    """Sum (F,) of the laws (n_laws, F) with pairwise disjoint supports, best first, and the
    indices summed: uncoupled subsystems' laws hold together.
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
    """Whether ``sum_j law_j M_j`` is definite (either sign) at every state, unit free as
    :func:`~pysindy_xl.fit.diagnostics.mass_matrix_report` judges; ``mass_matrices`` (S, k, n, n).

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
