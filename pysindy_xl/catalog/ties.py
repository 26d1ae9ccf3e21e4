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
all the blocks' errors (:func:`~.criterion.combine_errors`). All the data then judge, each
block by a fit that did not see it, with the growth's keep rule stated on those fits
(:func:`tie_keeps`): another tie replaces the growth's choice where its cross-validated
criterion is within the tolerance with fewer terms in the fitted models (the median over the
cross-validated fits, the fits that give the criterion: a count on the search's single split
chose a Furuta pendulum's 37-term catalog, one term fewer there, the same terms on every
cross-validated fit, 16 % off in simulation), or lower by the tolerance. A difference of a
few percent is noise on either criterion; the stand-ins that the two blocks let through are
worse by more on all of them, or need more terms. At noise, one block (the largest swings)
may decide a difference of several percent; ``spread`` asks a lower criterion to be lower by
that many standard errors of the block-paired difference of the squared errors too (1: the
one-standard-error rule of cross-validation), 0 by default (:data:`TIE_SPREAD`: measured, it
gained as many rows as it lost).
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["near_ties", "break_ties", "judge_near_ties", "tie_keeps", "TieJudgment",
           "TIE_REACH", "TIE_CANDIDATES", "SAME_LAW", "TIE_SPREAD"]

#: Near ties: catalogs whose criterion is at most ``1 + TIE_REACH`` times the best one's.
TIE_REACH = 0.3
#: Most catalogs judged again (the growth's choice and the next best by the criterion).
TIE_CANDIDATES = 4
#: Two catalogs whose criteria differ by less than this fraction hold the same law on the
#: search's split (a tenth of the keep rule's default tolerance: no choice rests on it).
SAME_LAW = 5e-3
#: Standard errors of the block-paired difference by which a lower cross-validated criterion
#: must be lower to replace the choice without fewer fitted terms (:func:`tie_keeps`; 1: the
#: one-standard-error rule). 0 by default: the one-standard-error rule changed 9 choices on
#: the 149 rows of the sets with near ties, one verdict gained and one lost
#: (``benchmarks/results/tie_rule.md``): no evidence for it yet.
TIE_SPREAD = 0.0


@dataclasses.dataclass(frozen=True)
class TieJudgment:
    """One near tie as the cross-validated fits judge it.

    Parameters
    ----------
    criterion : float
        The RMS of the held-out blocks' errors (inf where a fit failed).
    active : int
        Terms kept by the fitted models (their median over the cross-validated fits).
    blocks : tuple of float, default ()
        The held-out error of each block, in the order of the splits (the same for every
        tie); empty where unknown.
    """

    criterion: float
    active: int
    blocks: tuple = ()


def tie_keeps(step, chosen, tolerance: float = 0.05, spread: float = TIE_SPREAD) -> bool:
    r"""The keep rule of the near ties: whether ``step`` replaces ``chosen``.

    With :math:`c, b` the two cross-validated criteria, :math:`\tau` the tolerance and
    :math:`d_k = e_k^2 - f_k^2` the block-paired differences of the squared block errors
    (``step``'s :math:`e_k`, ``chosen``'s :math:`f_k`, :math:`k = 1 \dots K`; their mean is
    :math:`c^2 - b^2`), ``step`` is kept where

    - :math:`c \le (1 + \tau) b` and its fitted models keep fewer terms, or
    - :math:`c < (1 - \tau) b` and :math:`\bar d + z\, s_d / \sqrt{K} < 0` (:math:`s_d` the
      standard deviation of the :math:`d_k`, :math:`z` = ``spread``): lower by more than the
      blocks' spread, not by one block alone.

    The blocks hold the same noise draws for both catalogs, so the paired difference is free
    of what they share; its standard error counts the folds (:math:`\sqrt{K}`). Where the
    block errors are unknown, not finite or fewer than two, the tolerance alone decides.

    Parameters
    ----------
    step, chosen : TieJudgment
        The candidate and the tie chosen so far.
    tolerance : float, default 0.05
        The fraction :math:`\tau` (the growth's keep rule, :func:`~.keep_rules.single_keeps`).
    spread : float, default TIE_SPREAD
        :math:`z`, in standard errors of the paired difference.

    Returns
    -------
    bool

    Examples
    --------
    >>> chosen = TieJudgment(0.0148, 8, (0.0212, 0.0085, 0.0110, 0.0173, 0.0122))
    >>> step = TieJudgment(0.0135, 8, (0.0151, 0.0091, 0.0112, 0.0162, 0.0145))
    >>> tie_keeps(step, chosen)        # 9 % lower: by the tolerance
    True
    >>> tie_keeps(step, chosen, spread=1.0)   # from the first block alone: not by the spread
    False
    >>> tie_keeps(TieJudgment(0.0135, 8, ()), chosen)   # no blocks: the tolerance alone
    True
    >>> tie_keeps(TieJudgment(0.0150, 7, step.blocks), chosen)   # within, fewer terms
    True
    """
    c, b = step.criterion, chosen.criterion
    if c <= b * (1 + tolerance) and step.active < chosen.active:
        return True
    if not c < b * (1 - tolerance):
        return False
    e, f = (np.asarray(x, dtype=float) for x in (step.blocks, chosen.blocks))
    if e.shape != f.shape or e.size < 2 or not (np.all(np.isfinite(e))
                                                 and np.all(np.isfinite(f))):
        return True
    d = e ** 2 - f ** 2
    return bool(d.mean() + spread * d.std(ddof=1) / np.sqrt(d.size) < 0)


def near_ties(steps, best, physical: bool = False) -> list:
    """The catalogs whose criterion is within :data:`TIE_REACH` of the best one's.

    One per fitted law: a catalog whose criterion equals that of one listed before it to
    the fraction :data:`SAME_LAW` holds the same law on the search's split (a family the fit
    left out, or kept at a negligible coefficient) and is skipped; what such a family does on
    other folds is the selection's noise, not structure. Each listed law is then stated by
    the smallest catalog whose fit kept exactly its terms (:attr:`~.path.GrowthStep.support`;
    ``best`` too): the larger ones only offer the final fit on all the data more columns to
    choose stand-ins from.

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
        ``best`` (or the smallest catalog of its support) first, then at most
        ``TIE_CANDIDATES - 1`` others by increasing criterion.

    Examples
    --------
    >>> from pysindy_xl.catalog.path import GrowthStep
    >>> steps = [GrowthStep("start", "", 4, 3, 0.1, 0.1, 0.1, True),
    ...          GrowthStep("degree", "", 5, 3, 0.011, 0.01, 0.0105, True),
    ...          GrowthStep("trig", "", 5, 3, 0.012, 0.012, 0.012, False)]
    >>> [step.move for step in near_ties(steps, steps[1])]
    ['degree', 'trig']
    >>> law = (("L[x_dot**2]", "L[x**2]"),)
    >>> steps = [GrowthStep("start", "", 4, 2, 0.02, 0.02, 0.02, True, support=law),
    ...          GrowthStep("degree", "", 6, 2, 0.0199, 0.0199, 0.0199, True, support=law)]
    >>> [step.move for step in near_ties(steps, steps[1])]   # the same law, fewer terms
    ['start']
    """
    reach = best.criterion * (1 + TIE_REACH)
    ties = [best]
    for step in sorted(steps, key=lambda s: (s.criterion, s.terms)):
        if len(ties) >= TIE_CANDIDATES or not step.criterion <= reach:
            break
        if (step is best or step.note.startswith(("fit failed", "ceiling", "budget", "final fit"))
                or (physical and step.definite < best.definite)):
            continue
        if not any(abs(step.criterion - other.criterion) <= SAME_LAW * other.criterion
                   for other in ties):
            ties.append(step)
    stated = []
    for step in ties:
        smallest = _smallest_stating(steps, step)
        if not any(smallest is other for other in stated):
            stated.append(smallest)
    return stated


def _smallest_stating(steps, step):
    """The step of fewest terms whose fits kept exactly ``step``'s terms (``step`` itself
    when none is smaller, or when its support is unknown)."""
    if not step.support:
        return step
    same = [other for other in steps if other.support == step.support
            and np.isfinite(other.criterion)
            and not other.note.startswith(("fit failed", "final fit"))]
    return min(same, key=lambda other: other.terms, default=step) if same else step


def break_ties(ties, parameters_of, judge, tolerance: float = 0.05, progress=None,
               spread: float = TIE_SPREAD):
    """The near tie that the keep rule prefers on the cross-validated criterion.

    Parameters
    ----------
    ties : list of GrowthStep
        The growth's choice first, then the other near ties (:func:`near_ties`).
    parameters_of : callable
        ``parameters_of(step) -> dict``: a step's catalog parameters.
    judge : CandidateFits
        Fits of the cross-validated splits (:class:`~.candidates.CandidateFits`): ``get``
        gives a catalog's ``criterion``, and its ``active`` and ``block_errors`` where known.
    tolerance : float, default 0.05
        The keep rule's fraction (:func:`tie_keeps`).
    progress : callable, optional
        Called with a line of text per catalog judged.
    spread : float, default :data:`TIE_SPREAD`
        Standard errors of the block-paired difference a lower criterion must clear
        (:func:`tie_keeps`).

    Returns
    -------
    GrowthStep
        The chosen step: starting from the growth's choice, each other tie in the order of
        its cross-validated criterion replaces the one chosen so far where the keep rule
        of the near ties keeps it on the cross-validated fits (:func:`tie_keeps`: within the
        fraction ``tolerance`` with fewer terms in the fitted models, or lower by it and by
        more than the blocks' spread). Each tie's :attr:`~.path.GrowthStep.tie_error` is set.
    """
    candidates = [parameters_of(step) for step in ties]
    judged = {}
    for k, step in enumerate(ties):
        fields = judge.get(candidates[k], candidates[k + 1:])
        step.tie_error = float(fields["criterion"])
        judged[id(step)] = TieJudgment(step.tie_error, int(fields.get("active", step.active)),
                                       tuple(fields.get("block_errors", ())))
        if progress is not None:
            progress(f"{step.move:<13} {step.terms:>5} terms  cross-validated near tie "
                     + (f"{100 * step.tie_error:.2f} %" if np.isfinite(step.tie_error)
                        else "-"))
    chosen = ties[0]
    for step in sorted(ties[1:], key=lambda s: s.tie_error):
        if tie_keeps(judged[id(step)], judged[id(chosen)], tolerance, spread):
            chosen = step
    return chosen


def judge_near_ties(steps, best, parameters_of, judge, *, physical: bool = False,
                    tolerance: float = 0.05, progress=None):
    """The growth's choice among the near ties of its criterion, judged again on every block.

    The near ties of ``best`` (:func:`near_ties`); where there are two or more, each is
    cross-validated by the fits of ``judge()`` and the keep rule chooses among them
    (:func:`break_ties`); the judge is closed after.

    Parameters
    ----------
    steps : list of GrowthStep
        Every catalog the growth tried.
    best : GrowthStep
        The growth's choice (one of ``steps``).
    parameters_of : callable
        ``parameters_of(step) -> dict``: a step's catalog parameters.
    judge : callable
        ``judge() -> CandidateFits``: the fits on the cross-validated splits (every block held
        out in turn, each by a fit on the others: :func:`~.folds.held_out_splits`); called
        only where there are two near ties or more.
    physical : bool, default False
        Leave out the ties less physical than ``best`` (:func:`near_ties`).
    tolerance : float, default 0.05
        The keep rule's fraction (:func:`break_ties`).
    progress : callable, optional
        Called with a line of text per catalog judged.

    Returns
    -------
    GrowthStep
        The chosen step: ``best``, the smallest catalog that states its law, or another tie.

    Examples
    --------
    >>> from pysindy_xl.catalog.path import GrowthStep
    >>> best = GrowthStep("start", "", 4, 3, 0.1, 0.1, 0.1, True)
    >>> judge_near_ties([best], best, parameters_of=None, judge=None) is best   # no other tie
    True
    """
    ties = near_ties(steps, best, physical)
    chosen = ties[0]  # (the smallest catalog of the chosen law)
    if len(ties) > 1:
        fits = judge()
        try:
            chosen = break_ties(ties, parameters_of, fits, tolerance, progress)
        finally:  # (its workers end even where a judgment fails)
            fits.close()
    return chosen
