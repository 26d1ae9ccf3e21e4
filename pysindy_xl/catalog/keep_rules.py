"""The keep rules of a catalog growth: when a candidate catalog replaces the kept one.

One fold (:func:`single_keeps`): a criterion lower by the tolerance, or within it with fewer
fitted terms. Two folds (``region="consensus"`` of :func:`~.growth.grow_catalog`,
:func:`consensus_keeps`): the time and region blocks (the first fold) and the extreme states
(the second: fitted inside a threshold of the states, judged beyond it) judge each change
together. A larger catalog must be kept by the first fold and not be worse on the second;
any other change is judged by the geometric mean of the two folds' criteria
(:func:`consensus_criteria`), where a relative change counts the same on either fold.
"""

from __future__ import annotations

import numpy as np

from .path import GrowthStep  # noqa: F401 - (the examples' steps)

__all__ = ["single_keeps", "consensus_criteria", "consensus_keeps", "CONSENSUS_REACH"]


def single_keeps(step, best, tolerance) -> bool:
    """The keep rule of one fold: whether ``step`` improves on ``best``.

    A criterion lower by the fraction ``tolerance``, or within that fraction with fewer terms
    in the fitted model (a sine series imitating ``theta^2`` needs more terms than
    ``theta^2``).

    Parameters
    ----------
    step, best : GrowthStep
        The candidate and the kept catalog (``criterion``, ``active``).
    tolerance : float
        The fraction.

    Returns
    -------
    bool

    Examples
    --------
    >>> single_keeps(GrowthStep("degree", "", 5, 3, 0.1, 0.1, 0.1, False),
    ...              GrowthStep("start", "", 4, 4, 0.1, 0.1, 0.1, True), 0.05)
    True
    """
    return (step.criterion < best.criterion * (1 - tolerance)
            or (step.criterion <= best.criterion * (1 + tolerance)
                and step.active < best.active))


#: With ``region="consensus"``, a candidate no larger than the kept catalog but more than this
#: factor worse on the first fold is refused without fitting it on the second (it would need
#: to be better there by more than the factor): the second fold costs a fit only for the
#: candidates that could be kept.
CONSENSUS_REACH = 2.0


def consensus_criteria(step, best, second_step, second_best):
    """The criteria of two folds that the keep rule of ``region="consensus"`` compares.

    With :math:`c_1, b_1` the first fold's criteria of the candidate and of the kept catalog
    and :math:`c_2, b_2` the second fold's, the candidate's and the kept catalog's combined
    criteria are the geometric means :math:`\\sqrt{c_1 c_2}` and :math:`\\sqrt{b_1 b_2}`:
    a relative change counts the same on either fold, so a change is kept where what it
    gains on one fold outweighs what it loses on the other (a stand-in fitted along the
    trajectories gains a little on the time blocks and loses much beyond the recorded
    states). Where both catalogs fail the second fold (:math:`\\min(c_2, b_2) \\ge 1`: a
    residual as large as what the equations should explain, as for a hardening spring fitted
    only inside the threshold), the fold cannot tell them apart and the first fold's
    criteria are compared alone.

    Parameters
    ----------
    step, best : GrowthStep
        The candidate and the kept catalog, judged by the first fold.
    second_step, second_best : GrowthStep
        The same catalogs judged by the second fold.

    Returns
    -------
    (float, float)
        The candidate's and the kept catalog's criteria.

    Examples
    --------
    >>> stand_in = GrowthStep("trig_degree", "", 6, 5, 0.03, 0.03, 0.03, False)
    >>> law = GrowthStep("angle_degree", "", 6, 5, 0.04, 0.04, 0.04, False)
    >>> beyond = GrowthStep("trig_degree", "", 6, 5, 0.1, 0.1, 0.10, False)
    >>> law_beyond = GrowthStep("angle_degree", "", 6, 5, 0.05, 0.05, 0.05, False)
    >>> [round(c, 4) for c in consensus_criteria(law, stand_in, law_beyond, beyond)]
    [0.0447, 0.0548]
    """
    c_2, b_2 = second_step.criterion, second_best.criterion
    if not min(c_2, b_2) < 1:
        return step.criterion, best.criterion
    return float(np.sqrt(step.criterion * c_2)), float(np.sqrt(best.criterion * b_2))


def consensus_keeps(step, best, second_step, second_best, tolerance) -> bool:
    """The keep rule of two folds (``region="consensus"`` of :func:`grow_catalog`).

    With :math:`c_1, b_1` the first fold's criteria of the candidate and of the kept
    catalog, :math:`c_2, b_2` the second fold's and :math:`\\tau` the tolerance:

    - a candidate with more terms than the kept catalog is kept when the first fold's rule
      keeps it (:math:`c_1 < (1 - \\tau) b_1`, or within :math:`(1 + \\tau) b_1` with fewer
      fitted terms) and the second fold does not find it worse,
      :math:`c_2 \\le (1 + \\tau) b_2`;
    - any other candidate (a family dropped, exchanged for another, the smaller of two
      catalogs) is kept when the same rule keeps it on the combined criteria of
      :func:`consensus_criteria`, the geometric means :math:`\\sqrt{c_1 c_2}` and
      :math:`\\sqrt{b_1 b_2}`.

    Where both catalogs fail the second fold (:math:`\\min(c_2, b_2) \\ge 1`), the first
    fold's rule decides alone. The asymmetry is the folds': the second is fitted inside a
    threshold of the states and judged beyond it, on fewer states. It shows that a family
    extrapolates wrongly (a stand-in fitted along the trajectories), a reason to refuse it
    or to drop it for a smaller catalog; its own preference for more terms is not evidence of
    a law (a fit inside the threshold compensates its bias with them).

    Parameters
    ----------
    step, best : GrowthStep
        The candidate and the kept catalog, judged by the first fold (``criterion``,
        ``active``, ``terms``).
    second_step, second_best : GrowthStep or None
        The same catalogs judged by the second fold; None: the first fold alone.
    tolerance : float
        The fraction :math:`\\tau`.

    Returns
    -------
    bool

    Examples
    --------
    >>> stand_in = GrowthStep("trig_degree", "", 6, 5, 0.03, 0.03, 0.03, False)
    >>> law = GrowthStep("-trig+angle_degree", "", 6, 5, 0.04, 0.04, 0.04, False)
    >>> beyond = GrowthStep("trig_degree", "", 6, 5, 0.1, 0.1, 0.10, False)
    >>> law_beyond = GrowthStep("-trig+angle_degree", "", 6, 5, 0.05, 0.05, 0.05, False)
    >>> consensus_keeps(law, stand_in, law_beyond, beyond, 0.05)
    True
    >>> consensus_keeps(law, stand_in, None, None, 0.05)     # the first fold alone
    False
    >>> start = GrowthStep("start", "", 4, 4, 0.04, 0.04, 0.04, True)
    >>> start_beyond = GrowthStep("start", "", 4, 4, 0.06, 0.06, 0.06, True)
    >>> consensus_keeps(stand_in, start, beyond, start_beyond, 0.05)   # worse beyond
    False
    """
    if second_step is None or second_best is None:
        return single_keeps(step, best, tolerance)
    if not min(second_step.criterion, second_best.criterion) < 1:
        return single_keeps(step, best, tolerance)  # (the second fold fails both: no verdict)
    if step.terms > best.terms:
        return (single_keeps(step, best, tolerance)
                and second_step.criterion <= second_best.criterion * (1 + tolerance))
    c, b = consensus_criteria(step, best, second_step, second_best)
    return c < b * (1 - tolerance) or (c <= b * (1 + tolerance) and step.active < best.active)
