"""The criterion of a candidate catalog: its held-out errors, block by block, combined.

A candidate catalog is fitted on the search's training pieces and scored on each held-out
block by :func:`held_out_error` (the relative residual of its equations there: over the
forces' part with forces, over each equation's kinetic part without); the blocks' errors make
its criterion by :func:`combine_errors` (their RMS, or the RMS of all but the largest).
"""

from __future__ import annotations

import numpy as np

from .floor import held_out_scores

__all__ = ["combine_errors", "held_out_error", "COMBINES", "MIN_TRIMMED_BLOCKS"]

#: How a candidate's held-out block errors make its criterion (:func:`combine_errors`):
#: ``"rms"`` (all of them) or ``"trimmed"`` (all but the largest).
COMBINES = ("rms", "trimmed")
#: Fewest held-out blocks from which ``"trimmed"`` may leave the worst one out.
MIN_TRIMMED_BLOCKS = 4


def combine_errors(errors, combine: str = "rms") -> float:
    r"""The criterion of a candidate catalog from its held-out block errors.

    With ``"rms"``, the root mean square of the ``n`` errors :math:`e_1, \dots, e_n`;
    with ``"trimmed"``, that of all but the largest: for the sorted errors
    :math:`e_{(1)} \le \dots \le e_{(n)}`,

    .. math:: c_\text{rms} = \sqrt{\frac{1}{n} \sum_{i=1}^{n} e_i^2}, \qquad
              c_\text{trimmed} = \sqrt{\frac{1}{n - 1} \sum_{i=1}^{n-1} e_{(i)}^2}.

    Cross-validated on a recording of a few seconds, one block (the largest swings) can
    hold most of what identifies the configuration-dependent terms: the fit without it fails
    for the right catalog too, and that one error (tens of percent where the others are
    below one) decides the RMS, so the growth refuses the right move. The trimmed criterion
    tolerates one failing fit out of ``n``. It needs :data:`MIN_TRIMMED_BLOCKS` (4) blocks
    at least: a catalog is then still judged on ``n - 1 >= 3`` blocks, each by a fit on
    other data, so a stand-in that holds along the trajectories but fails wherever it
    extrapolates must fail on one block only to pass; with two or three blocks, the one
    left out would be half or a third of the evidence (and the time and region blocks of
    the default split would be one judgment).

    Parameters
    ----------
    errors : sequence of float
        The held-out relative errors, one per block (inf for a failed fit).
    combine : {"rms", "trimmed"}, default "rms"
        How they are combined (:data:`COMBINES`).

    Returns
    -------
    float
        The criterion (inf when a retained error is not finite).

    Examples
    --------
    >>> errors = [0.005, 0.004, 0.9, 0.006, 0.005]   # one fit of five fails
    >>> round(combine_errors(errors), 3), round(combine_errors(errors, "trimmed"), 4)
    (0.403, 0.005)
    """
    if combine not in COMBINES:
        raise ValueError(f"combine: expected one of {COMBINES}, got {combine!r}")
    errors = np.asarray(errors, dtype=float).ravel()
    if combine == "trimmed":
        if len(errors) < MIN_TRIMMED_BLOCKS:
            raise ValueError(f"combine='trimmed' needs at least {MIN_TRIMMED_BLOCKS} held-out "
                             f"blocks, got {len(errors)}")
        errors = np.sort(errors)[:-1]
    value = float(np.sqrt(np.mean(np.square(errors))))
    return value if np.isfinite(value) else float("inf")


def held_out_error(model, held, forced) -> float:
    r"""Relative residual of a fitted model's weak-form equations on held-out runs.

    With forces, ``||Theta xi|| / ||Theta_F xi_F||`` (the residual over the forces' part).
    Unforced, each coordinate's block of rows ``i`` over the kinetic part of its equation:

    .. math:: e_i = \frac{\|\Theta_i \xi\|}{\|\sum_{j \in K} \Theta_{ij} \xi_j\|},
              \qquad e = \sqrt{\tfrac1n \textstyle\sum_i e_i^2},

    with ``K`` the columns that carry inertia (a nonzero mass matrix,
    :func:`~pysindy_xl.fit.kinetic_scale.inertial_columns`: the terms quadratic in the
    velocities; ``e_i`` is :func:`~pysindy_xl.fit.kinetic_scale.kinetic_relative_residuals`,
    which also makes the ``R^2`` of unforced fits, :func:`~pysindy_xl.quality.fit_quality`).
    An implicit law fixes each equation only up to its own factor, so each
    block needs its own scale; its kinetic part, ``d/dt dT/dqd - dT/dq``, is the one that
    states the accelerations, and the ratio is about the relative error of the accelerations
    the law predicts. A scale taken from single terms (the largest ``||Theta_j xi_j||``)
    is not one of the law: a law can keep a large potential term that its other terms
    nearly cancel (``r cos(theta) - 0.25 r^2 cos(theta) - 0.58 cos(theta)`` for
    ``0.25 r cos(theta)``, a flexible family of ``r`` absorbing the rest) and shrink the
    kinetic part, whose columns carry most of the noise of positions, to a quarter: its
    residual shrinks with it against an unchanged largest term. Judged over the kinetic
    part, a law whose inertia cancels, or that has none in an equation, scores inf. The
    strong form where the blocks are shorter than a test function.

    Parameters
    ----------
    model : XLSINDy
        Fitted model.
    held : dict
        ``x``, ``t`` and ``u`` (None when unforced) of the held-out runs.
    forced : bool
        Whether the data have forces.

    Returns
    -------
    float
        The relative error (inf where the norm is zero).
    """
    return held_out_scores(model, held, forced, floor=False)[0]

