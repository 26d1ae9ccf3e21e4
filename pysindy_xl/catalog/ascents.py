"""The climbs of a catalog growth: from the first catalog, move by move, to where the keep rules
keep nothing more.

:func:`climb` tries the moves in turn (a degree move repeated while it is kept, looking one
degree further before it stops); :func:`steepest_climb` tries every move from each kept catalog
and keeps the best. Both look two moves ahead (:func:`move_pairs`) where no single move is kept:
a law that needs two structural moves at once (a coupling ``cos(a - b) a_dot b_dot`` needs
products of two angles' functions and configuration-dependent kinetic coefficients) gains from
neither alone. The catalogs, their fits and the keep rules are the :class:`~.climbs.Climber`'s;
:func:`~.climb_ends.search_end` runs the climbs.
"""

from __future__ import annotations

import itertools

from .candidates import parameters_key
from .moves import LATE_MOVES, REPEATED, START, holds, is_repeated, moved
from .retries import attempt_within_limits

__all__ = ["climb", "move_pairs", "steepest_climb"]


def move_pairs(climber, state, order, tried) -> list:
    """The pairs of non-repeated moves (the splines' left out) from ``state`` not tried yet.

    Parameters
    ----------
    climber : Climber
        The growth's search (:class:`~.climbs.Climber`), started.
    state : dict
        The kept catalog's parameters.
    order : list of str
        The moves, in the climb's order.
    tried : set of str
        The keys (:func:`~.candidates.parameters_key`) already tried.

    Returns
    -------
    list of (dict, str)
        The parameters and the name (``"a+b"``) of each pair.
    """
    out = []
    # (the exponentials' and the splines' moves stay single: they are for what the families
    # leave, not a second move that lends a family's pair its gain)
    single = [m for m in order if m not in REPEATED and m not in LATE_MOVES
              and "+" not in m]
    for first_move, second_move in itertools.combinations(single, 2):
        once = climber.moved(state, first_move)
        twice = None if once is None else climber.moved(once, second_move)
        if twice is not None and parameters_key(twice) not in tried:
            out.append((twice, f"{first_move}+{second_move}"))
    return out


def _rejected(climber, state, order, index, skip, tried, improved) -> list:
    """The candidates a climb tries after ``order[index]`` (at ``skip``) if it keeps
    none of them: the guess of what to fit meanwhile."""
    out, seen = [], set(tried)
    for k in range(index, len(order)):
        move = order[k]
        skips = [skip] if k == index else [0]
        if is_repeated(move) and skips[0] == 0:
            skips.append(1)
        for s in skips:  # (no rates fitted for a guess)
            parameters = moved(state, move, climber.kinds, climber.n, s)
            if parameters is None or parameters_key(parameters) in seen:
                break
            seen.add(parameters_key(parameters))
            out.append(parameters)
    if not improved:
        out += [p for p, _ in move_pairs(climber, state, order, seen)]
    return out[1:]  # (the first is the current one)


def _going(climber, state, best, end, floor=True) -> bool:
    """Whether a climb at ``state`` (its step ``best``) goes on: the criterion is not
    settled (:meth:`~.climbs.Climber.settled`, with ``floor``) and the catalog does not hold ``end``
    (:func:`~.moves.holds`; None: no end)."""
    return not climber.settled(best, floor) and (end is None or not holds(state, end))


def steepest_climb(climber, order, forced=None, end=None) -> tuple:
    """From the first catalog (after the move ``forced``), try every move of ``order``
    from the current catalog and keep the best; two moves at once where none is kept;
    stop once the catalog holds ``end`` (the first climb's end). A move that the ceiling
    refuses is tried with constant kinetic coefficients, as in :func:`climb`.

    Parameters
    ----------
    climber : Climber
        The growth's search (:class:`~.climbs.Climber`), started.
    order : list of str
        The moves, in the order of what each achieved alone.
    forced : str, optional
        A move made first (kept if the keep rule keeps it).
    end : dict, optional
        The first climb's end (:func:`~.moves.holds`).

    Returns
    -------
    tuple
        The end's parameters, its step, and the kept steps.
    """
    state, best, path = dict(START), climber.first, []
    tried = {parameters_key(state)}
    if forced is not None:
        parameters, step = attempt_within_limits(climber, climber.moved(state, forced), forced,
                                                 tried, state=state)
        if climber.keeps(step, best):
            state, best = parameters, step
            path.append(step)
    while _going(climber, state, best, end):
        options = []
        for move in order:
            for skip in (0, 1) if is_repeated(move) else (0,):
                parameters = climber.moved(state, move, skip)
                if parameters is None:
                    break
                options.append((parameters, move))
        kept = []
        for k, (parameters, move) in enumerate(options):
            moved_to, step = attempt_within_limits(
                climber, parameters, move, tried, [p for p, _ in options[k + 1:]], state)
            if climber.keeps(step, best):
                kept.append((step.criterion, step.active, k, moved_to, step))
        if not kept:  # two moves at once, as the climb looks ahead
            candidates = move_pairs(climber, state, order, set())
            for k, (twice, name) in enumerate(candidates):
                step = climber.attempt(twice, name, [p for p, _ in candidates[k + 1:]])
                if climber.keeps(step, best):
                    kept.append((step.criterion, step.active, k, twice, step))
                    break
        if not kept:
            break
        _, _, _, state, best = min(kept, key=lambda item: item[:3])
        path.append(best)
    return state, best, path


def climb(climber, order, end=None) -> tuple:
    """Try the moves of ``order`` in turn from the first catalog (a degree move repeated
    while it is kept, looking one degree further before it stops), two at once where a
    pass keeps none; stop once the catalog holds ``end`` (the first climb's end).

    Parameters
    ----------
    climber : Climber
        The growth's search (:class:`~.climbs.Climber`), started.
    order : list of str
        The moves, in the order of what each achieved alone.
    end : dict, optional
        The first climb's end (:func:`~.moves.holds`).

    Returns
    -------
    tuple
        The end's parameters, its step, and the kept steps.
    """
    state, best, path = dict(START), climber.first, []
    tried = {parameters_key(state)}
    improved = not climber.settled(best)
    while improved and _going(climber, state, best, end):
        improved = False
        for index, move in enumerate(order):
            skip = 0  # a degree move looks one degree further before it stops
            # the floor stops the climb before a move, not within one: a degree that
            # stands in for the next (a cosine beside phi^2 for phi^4) may be at its floor
            # on the recorded states, and the look one degree further puts the law
            # among the near ties
            repeated = False
            while _going(climber, state, best, end, floor=not repeated):
                repeated = True
                parameters = climber.moved(state, move, skip)
                if parameters is None or parameters_key(parameters) in tried:
                    break
                ahead = _rejected(climber, state, order, index, skip, tried, improved)
                parameters, step = attempt_within_limits(climber, parameters, move, tried,
                                                         ahead, state)
                keep = climber.keeps(step, best)
                if keep:
                    state, best, improved = parameters, step, True
                    path.append(step)
                if not is_repeated(move) or (not keep and skip):
                    break
                skip = 0 if keep else 1
        if not improved and _going(climber, state, best, end):
            # a law that needs two structural moves at once (a coupling cos(a - b) a_dot
            # b_dot needs products of two angles' functions and configuration-dependent
            # kinetic coefficients) gains from neither alone: look two moves ahead
            candidates = move_pairs(climber, state, order, tried)
            for k, (twice, name) in enumerate(candidates):
                if parameters_key(twice) in tried:
                    continue
                tried.add(parameters_key(twice))
                step = climber.attempt(twice, name, [p for p, _ in candidates[k + 1:]])
                if climber.keeps(step, best):
                    state, best, improved = twice, step, True
                    path.append(step)
                    break
    return state, best, path
