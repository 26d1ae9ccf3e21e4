"""Where a catalog growth's search ends: the climbs, the backward phase, the near ties, and
the resumption past a settling catalog whose final fit is no model of the data.

:func:`search_end` climbs from the first catalog (from its best and its second-best first
move, keeping the better end), drops the families the backward phase gives up and judges the
near ties again on every block. Its end may be *settled*: its criterion is below
``good_enough`` or at its noise floor (:meth:`~.climbs.Climber.settled`), so the climbs tried
no further move and no second climb was made. That is a claim that no larger catalog has more
to find. The chosen catalog's final fit (all the data) can refute it: its mass matrix is not
positive definite on the training states, or (unforced data) it leaves its free runs
(:func:`~.final_fit.failure`). A late family reaching the floor on the search's pieces is where
this happens (on a rotating frame at 5 % noise, anchored springs beside the gyroscopic law at
1.01 times their floor, whose fit on all the data was no mechanical system). Answering then with
the best physical catalog found before the settlement (:func:`~.final_fit.physical_alternative`)
ends on a path that the settlement cut short, so :func:`resumed_end` refuses the settling catalog
(:meth:`~.climbs.Climber.refuse`: never kept again) and searches again: the catalogs already
fitted are not fitted again, and the climbs go on past the refused one. A search whose end is
not settled ended because no move improved on it; its final fit's failure is left to the
physical alternatives, as before.
"""

from __future__ import annotations

import numpy as np

from .ascents import climb, steepest_climb
from .backward import backward_phase
from .final_fit import failure
from .moves import LATE_MOVES
from .ties import judge_near_ties

__all__ = ["search_end", "resumed_end", "RESUMES"]

#: Most settling catalogs a growth refuses (:func:`resumed_end`) before it answers with a
#: physical alternative.
RESUMES = 3


def search_end(climber, order, alone, moves, *, steepest, physical, judge_ties=None,
               progress=None):
    """The end of a growth's search: two climbs, the backward phase, the near ties.

    Parameters
    ----------
    climber : Climber
        The growth's search (:class:`~.climbs.Climber`), started.
    order : list of str
        The moves in the order the climbs try them.
    alone : dict
        ``{move: criterion}`` of each move alone from the first catalog.
    moves : sequence of str
        The growth's moves (the backward phase drops only their families).
    steepest : bool
        Climb by the best move at each step (:func:`~.ascents.steepest_climb`).
    physical : bool
        Never give up a catalog whose fits are physical for one whose fits are not.
    judge_ties : callable or None, default None
        ``judge_ties() -> CandidateFits``: the near ties' judge (every block held out in turn);
        None: the near ties are not judged again.
    progress : callable or None, default None
        Called with a line of text per near tie judged.

    Returns
    -------
    tuple
        The end's catalog parameters (dict), its step and the kept steps (list).
    """
    # climb from the best and from the second-best first move: which family goes in first is
    # where a stand-in wins (a cos(theta) inertia for a torsion spring; a power of an angle for
    # a coupling that needs two moves), so the better of the two ends is kept
    state, best, path = steepest_climb(climber, order) if steepest else climb(climber, order)
    promising = [m for m in order if m not in LATE_MOVES and alone.get(m, np.inf)
                 < climber.first.criterion * (1 - climber.tolerance)]
    if not climber.settled(best) and len(promising) > 1:
        second = [promising[1]] + [m for m in order if m != promising[1]]
        other = (steepest_climb(climber, order, promising[1], state) if steepest
                 else climb(climber, second, state))
        if (climber.keeps(other[1], best) if not physical or (other[1].definite >= 1)
                == (best.definite >= 1) else other[1].definite >= 1):
            state, best, path = other
    state, best, path = backward_phase(climber, state, best, path, moves)
    climber.fits.close()  # (a worker's last guess may still run: it ends during the final fit)
    if judge_ties is not None and np.isfinite(best.criterion):
        # the near ties of the criterion judged again on every block, each by a fit without it
        chosen = judge_near_ties(climber.steps, best, climber.parameters_of, judge_ties,
                                 physical=physical, tolerance=climber.tolerance,
                                 progress=progress)
        if chosen is not best:
            state, best = dict(climber.parameters_of(chosen)), chosen
            path.append(chosen)
    return state, best, path


def resumed_end(climber, search, final_fit, check=None, progress=None):
    """The search's end, searched again past each settling catalog whose final fit fails.

    Parameters
    ----------
    climber : Climber
        The growth's search.
    search : callable
        ``search() -> (state, step, path)``: :func:`search_end` with the growth's options.
    final_fit : callable
        ``final_fit(state, step) -> XLSINDy``: the catalog ``state`` fitted on all the data.
    check : callable or None, default None
        A further judgment of a final fit (:func:`~.final_fit.failure`'s ``check``).
    progress : callable or None, default None
        Called with a line of text per refused catalog.

    Returns
    -------
    tuple
        The end's catalog parameters, its step, the kept steps and its final fit: the first
        end that is not settled, or whose final fit passes :func:`~.final_fit.failure`, or
        the last after :data:`RESUMES` refusals.

    Examples
    --------
    A settled end whose final fit passes is the answer at once (here stand-ins for the
    climber and the fit):

    >>> from types import SimpleNamespace
    >>> end = ({"degree": 2}, SimpleNamespace(move="degree"), [])
    >>> fitted = SimpleNamespace(dynamics_=object(), mass_matrix_check_={
    ...     "positive_definite_fraction": 1.0, "median_condition": 2.0})
    >>> climber = SimpleNamespace(first=None, settled=lambda step: True,
    ...                           refused=lambda step: False)
    >>> resumed_end(climber, lambda: end, lambda state, step: fitted)[-1] is fitted
    True
    """
    state, best, path = search()
    model = final_fit(state, best)
    for _ in range(RESUMES):
        if best is climber.first or climber.refused(best) or not climber.settled(best):
            break
        why = failure(model, check)
        if why is None:
            break
        climber.refuse(best, f"final fit: {why}")
        if progress is not None:
            progress(f"refused       {best.move} ({best.terms} terms): its final fit fails "
                     f"({why}); the climbs go on")
        state, best, path = search()
        model = final_fit(state, best)
    return state, best, path, model
