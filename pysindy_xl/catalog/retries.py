"""The retries of a climb's move that the ceiling or the work budget refuses.

A catalog over the data-sized ceiling (``max_terms``) or over the search's work budget
(:mod:`.budget`) is not fitted. Its move may still hold the family the law needs: the
configuration-dependent kinetic coefficients multiply a catalog by the velocity monomials, so
the move is tried again with fewer of them (the kinetic order its catalog had, constant
coefficients, then narrower orders, :func:`~.moves.narrow`).
"""

from __future__ import annotations

from .budget import OVER
from .candidates import parameters_key
from .moves import START, holds, kinetic_order, moved, narrow

__all__ = ["attempt_within_limits"]


def attempt_within_limits(climber, parameters, move, tried, ahead=(), state=None) -> tuple:
    """The parameters and the step of a climb's move (:meth:`~.climbs.Climber.attempt`),
    recorded in ``tried``. Where the ceiling or the work budget refuses it (and the climber's
    ``retry_kinetic``), the move is tried again, in turn, until a retry is within both:

    1. where the move widened configuration-dependent kinetic coefficients of the catalog
       ``state`` it moved from (an ``"interaction"`` move widens them with the
       potential's products), with the kinetic order ``state`` had (``f"{move}@k<m>"``,
       :func:`~.moves.narrow`): the potential's products grow alone, the inertia the
       climb kept is kept (a three-link arm in relative angles: gravity in
       ``cos(a + b + c)``, inertia in ``cos(b + c)``);
    2. with constant kinetic coefficients (``f"{move}-kinetic"``), where that catalog is
       neither in ``tried`` nor one that ``state`` holds: configuration-dependent ones
       multiply the catalog by the velocity monomials;
    3. with configuration-dependent kinetic coefficients over fewer coordinates'
       functions, the widest order below the move's first (``f"{move}@k<m>"``), the
       potential's products kept: a cart's pendulum ``cos(a) a_dot x1_dot`` beside the
       spring ``x1 x2`` that couples two carts.

    A retry whose catalog is in ``tried`` is not made.

    Parameters
    ----------
    climber : Climber
        The growth's search (:class:`~.climbs.Climber`).
    parameters : dict
        The move's catalog.
    move : str
        The move's name, for the path.
    tried : set
        The keys of the catalogs the climb has tried (:func:`~.candidates.parameters_key`);
        updated.
    ahead : sequence of dict, default ()
        Catalogs the climb may try next (fitted ahead by idle workers).
    state : dict, optional
        The catalog the move is made from.

    Returns
    -------
    tuple
        The parameters and the step (:class:`~.path.GrowthStep`) of the last catalog tried.
    """
    tried.add(parameters_key(parameters))
    step = climber.attempt(parameters, move, ahead)
    if not (step.note.startswith(OVER) and climber.retry_kinetic):
        return parameters, step
    original = parameters
    configuration = original["kinetic"] == "configuration"
    if (state is not None and configuration and state["kinetic"] == "configuration"
            and kinetic_order(original) > kinetic_order(state)):
        kept = moved(original, narrow("", kinetic_order(state)), climber.kinds, climber.n)
        if kept is not None and parameters_key(kept) not in tried:
            tried.add(parameters_key(kept))
            parameters, step = kept, climber.attempt(
                kept, narrow(move, kinetic_order(state)))
            if not step.note.startswith(OVER):
                return parameters, step
    smaller = dict(original, kinetic=START["kinetic"])
    smaller.pop("kinetic_interaction", None)
    smaller.pop("kinetic_trig_degree", None)
    if parameters_key(smaller) not in tried and (state is None or not holds(state, smaller)):
        tried.add(parameters_key(smaller))  # the kinetic coefficients give way
        parameters, step = smaller, climber.attempt(smaller, f"{move}-kinetic")
        if not step.note.startswith(OVER):
            return parameters, step
    for order in range(kinetic_order(original) - 1, 0, -1) if configuration else ():
        narrower = moved(original, narrow("", order), climber.kinds, climber.n)
        if narrower is None or parameters_key(narrower) in tried:
            return parameters, step
        tried.add(parameters_key(narrower))
        parameters, step = narrower, climber.attempt(narrower, narrow(move, order))
        if not step.note.startswith(OVER):
            break
    return parameters, step
