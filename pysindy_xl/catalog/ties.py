"""The growth's last judge: the near ties of its criterion, judged again on every block.

The growth's criterion holds out two blocks of each run (the time and the region block): one
fit per catalog, cheap, but judged on two fifths of the data. Where a stand-in differs from the
law by little on the recorded states (``sin(theta)^2`` for ``theta^2`` on swings of a radian, a
configuration-dependent mass for a rotating frame's centrifugal term), the noise of that
judgment is larger than the difference, and the criterion may prefer the stand-in by a few
percent. So the catalogs whose criterion is within :data:`TIE_REACH` of the best one's (at
most :data:`TIE_CANDIDATES` of them, the growth's choice first, one per fitted law) are judged
again by cross-validation: every block of every run held out in turn, each by a fit on the
others (:func:`~.folds.held_out_splits` with ``cross_validate``), and the criterion the RMS of
all the blocks' errors (:func:`~.candidates.combine_errors`). All the data then judge, each
block by a fit that did not see it; the lowest is chosen (the growth's choice unless another
is lower by the fraction :data:`TIE_MARGIN`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["near_ties", "break_ties", "TIE_REACH", "TIE_CANDIDATES", "TIE_MARGIN"]

#: Near ties: catalogs whose criterion is at most ``1 + TIE_REACH`` times the best one's.
TIE_REACH = 0.3
#: Most catalogs judged again (the growth's choice and the next best by the criterion).
TIE_CANDIDATES = 4
#: Another catalog replaces the growth's choice when its cross-validated criterion is lower
#: by this fraction.
TIE_MARGIN = 1e-3


def near_ties(steps, best, physical: bool = False) -> list:
    """The catalogs whose criterion is within :data:`TIE_REACH` of the best one's.

    One per fitted law: a catalog whose fit kept as many terms as another's at the same
    criterion (to nine digits) holds the same law with a family the fit left out, and is
    skipped.

    Parameters
    ----------
    steps : list of GrowthStep
        Every catalog the growth tried.
    best : GrowthStep
        The growth's choice (one of ``steps``).
    physical : bool, default False
        Leave out the catalogs whose fits are less physical than ``best``'s
        (:attr:`~.path.GrowthStep.definite`).

    Returns
    -------
    list of GrowthStep
        ``best`` first, then at most ``TIE_CANDIDATES - 1`` others by increasing criterion.

    Examples
    --------
    >>> from pysindy_xl.catalog.path import GrowthStep
    >>> steps = [GrowthStep("start", "", 4, 3, 0.1, 0.1, 0.1, True),
    ...          GrowthStep("degree", "", 5, 3, 0.011, 0.01, 0.0105, True),
    ...          GrowthStep("trig", "", 5, 3, 0.012, 0.012, 0.012, False)]
    >>> [step.move for step in near_ties(steps, steps[1])]
    ['degree', 'trig']
    """
    reach = best.criterion * (1 + TIE_REACH)
    ties = [best]
    for step in sorted(steps, key=lambda s: s.criterion):
        if len(ties) >= TIE_CANDIDATES or not step.criterion <= reach:
            break
        if (step is best or step.note.startswith(("fit failed", "ceiling"))
                or (physical and step.definite < best.definite)):
            continue
        if not any(step.active == other.active
                   and np.isclose(step.criterion, other.criterion, rtol=1e-9, atol=0.0)
                   for other in ties):
            ties.append(step)
    return ties


def break_ties(ties, parameters_of, judge, progress=None):
    """The near tie with the lowest cross-validated criterion.

    Parameters
    ----------
    ties : list of GrowthStep
        The growth's choice first, then the other near ties (:func:`near_ties`).
    parameters_of : callable
        ``parameters_of(step) -> dict``: a step's catalog parameters.
    judge : CandidateFits
        Fits of the cross-validated splits (:class:`~.candidates.CandidateFits`).
    progress : callable, optional
        Called with a line of text per catalog judged.

    Returns
    -------
    GrowthStep
        The chosen step: the growth's choice unless another's cross-validated criterion is
        lower by :data:`TIE_MARGIN`. Each tie's :attr:`~.path.GrowthStep.tie_error` is set.
    """
    candidates = [parameters_of(step) for step in ties]
    for k, step in enumerate(ties):
        step.tie_error = float(judge.get(candidates[k], candidates[k + 1:])["criterion"])
        if progress is not None:
            progress(f"{step.move:<13} {step.terms:>5} terms  cross-validated near tie "
                     + (f"{100 * step.tie_error:.2f} %" if np.isfinite(step.tie_error)
                        else "-"))
    best = ties[0]
    chosen = min(ties, key=lambda s: s.tie_error)
    if chosen is not best and chosen.tie_error < best.tie_error * (1 - TIE_MARGIN):
        return chosen
    return best
