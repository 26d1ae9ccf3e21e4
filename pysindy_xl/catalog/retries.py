"""The retries of a climb's move that the ceiling or the work budget refuses.

A catalog over the data-sized ceiling (``max_terms``) or over the search's work budget
(:mod:`.budget`) is not fitted. Its move may still hold the family the law needs: the
configuration-dependent kinetic coefficients multiply a catalog by the velocity monomials, so
the move is tried again with fewer of them (:func:`retry_catalogs`): the kinetic order its
catalog had, kinetic coefficients over fewer coordinates' functions
(:func:`~.moves.narrow`), or constant ones.

The retries come in the order of what they keep of the catalog the move is made from
(:func:`retry_order`). A climb only adds; dropping a family is the backward phase's job
(:mod:`.backward`), judged there as a drop. So where that catalog holds
configuration-dependent kinetic coefficients, the retries that keep them (over fewer
coordinates' functions) come before the one that drops them (constant coefficients): on a
Furuta pendulum's 85-term catalog (kinetic coefficients over two angles' functions with
``sin(b)^2``, potential products of two angles), the move ``"angle_degree"`` (98 terms, over a
ceiling of 96) is retried as ``"angle_degree@k1"`` (50 terms, the law's inertia
``sin(b)^2 a_dot^2`` and its return spring ``a^2``), not as ``"angle_degree-kinetic"`` (26
terms), which dropped the inertia the climb had kept.
"""

from __future__ import annotations

from .budget import OVER
from .candidates import parameters_key
from .moves import START, holds, kinetic_order, moved, narrow

__all__ = ["attempt_within_limits", "retry_catalogs", "retry_order", "retry_walk", "RETRIES"]

#: The kinds of retries of a refused move (:func:`retry_catalogs`): ``"state_order"`` (the
#: kinetic order of the catalog the move is made from, where the move widened it),
#: ``"narrower"`` (kinetic coefficients over fewer coordinates' functions, widest first) and
#: ``"constant"`` (constant kinetic coefficients).
RETRIES = ("state_order", "narrower", "constant")


def retry_catalogs(parameters, move, state, kinds, n) -> dict:
    """The retries of the move ``move`` to ``parameters`` (from the catalog ``state``), by kind
    (:data:`RETRIES`), each a list of ``(name, parameters)``.

    - ``"state_order"``: where the move widened the configuration-dependent kinetic
      coefficients of ``state`` (an ``"interaction"`` move widens them with the potential's
      products), with the kinetic order ``state`` had (``f"{move}@k<m>"``,
      :func:`~.moves.narrow`): the potential's products grow alone, the inertia the climb
      kept is kept (a three-link arm in relative angles: gravity in ``cos(a + b + c)``,
      inertia in ``cos(b + c)``);
    - ``"narrower"``: with configuration-dependent kinetic coefficients over fewer
      coordinates' functions, each order below the move's, widest first (``f"{move}@k<m>"``),
      the potential's products kept: a cart's pendulum ``cos(a) a_dot x1_dot`` beside the
      spring ``x1 x2`` that couples two carts;
    - ``"constant"``: with constant kinetic coefficients (``f"{move}-kinetic"``):
      configuration-dependent ones multiply the catalog by the velocity monomials.

    Parameters
    ----------
    parameters : dict
        The refused catalog.
    move : str
        The move's name.
    state : dict or None
        The catalog the move is made from (None: unknown).
    kinds : sequence of str
        The coordinates' kinds.
    n : int
        The number of coordinates.

    Returns
    -------
    dict
        ``{kind: [(name, parameters), ...]}`` for each kind of :data:`RETRIES` (an empty list
        where none applies).

    Examples
    --------
    >>> from pysindy_xl.catalog.moves import START, moved
    >>> state = moved(START, "interaction+kinetic_trig_degree", ["angle"] * 2, 2)
    >>> refused = moved(state, "angle_degree", ["angle"] * 2, 2)
    >>> retries = retry_catalogs(refused, "angle_degree", state, ["angle"] * 2, 2)
    >>> [name for kind in RETRIES for name, _ in retries[kind]]
    ['angle_degree@k1', 'angle_degree-kinetic']
    """
    out = {kind: [] for kind in RETRIES}
    configuration = parameters["kinetic"] == "configuration"
    if (state is not None and configuration and state["kinetic"] == "configuration"
            and kinetic_order(parameters) > kinetic_order(state)):
        kept = moved(parameters, narrow("", kinetic_order(state)), kinds, n)
        if kept is not None:
            out["state_order"].append((narrow(move, kinetic_order(state)), kept))
    for order in range(kinetic_order(parameters) - 1, 0, -1) if configuration else ():
        narrower = moved(parameters, narrow("", order), kinds, n)
        if narrower is not None:
            out["narrower"].append((narrow(move, order), narrower))
    smaller = dict(parameters, kinetic=START["kinetic"])
    smaller.pop("kinetic_interaction", None)
    smaller.pop("kinetic_trig_degree", None)
    out["constant"].append((f"{move}-kinetic", smaller))
    return out


def retry_order(state) -> tuple:
    """The order in which the kinds of retries (:data:`RETRIES`) of a move from ``state`` are
    tried: first what keeps every family of ``state``, then what narrows what it holds, last
    what drops one.

    Where ``state`` holds configuration-dependent kinetic coefficients, the constant retry
    drops them: it comes after the narrower ones, which keep them over fewer coordinates'
    functions. Where ``state``'s kinetic coefficients are constant (or ``state`` is unknown),
    the constant retry drops only what the move adds, and comes before the narrower ones.

    Parameters
    ----------
    state : dict or None
        The catalog the move is made from.

    Returns
    -------
    tuple of str

    Examples
    --------
    >>> from pysindy_xl.catalog.moves import START
    >>> retry_order(dict(START, kinetic="configuration"))
    ('state_order', 'narrower', 'constant')
    >>> retry_order(START)
    ('state_order', 'constant', 'narrower')
    """
    if state is not None and state["kinetic"] == "configuration":
        return ("state_order", "narrower", "constant")
    return ("state_order", "constant", "narrower")


def attempt_within_limits(climber, parameters, move, tried, ahead=(), state=None) -> tuple:
    """The parameters and the step of a climb's move (:meth:`~.climbs.Climber.attempt`),
    recorded in ``tried``. Where the ceiling or the work budget refuses it (and the climber's
    ``retry_kinetic``), the move is tried again (:func:`retry_catalogs`, in the order of
    :func:`retry_order`) until a retry is within both:

    - a ``"state_order"`` retry whose catalog is in ``tried`` is not made;
    - the ``"narrower"`` retries stop at the first whose catalog is in ``tried`` (the
      kinetic order ``state`` had, tried already: below it the retries narrow what ``state``
      holds, and the climb has judged that order);
    - the ``"constant"`` retry is not made where its catalog is in ``tried`` or is one that
      ``state`` holds (no move forward).

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
    retries = retry_catalogs(parameters, move, state, climber.kinds, climber.n)
    for name, retry in retry_walk(retries, retry_order(state), tried, state):
        parameters, step = retry, climber.attempt(retry, name)
        if not step.note.startswith(OVER):
            return parameters, step
    return parameters, step


def retry_walk(retries, order, tried, state):
    """The retries to make, in turn, until one is within the limits (the caller stops there).

    A retry whose catalog is in ``tried`` is skipped (and ends the narrower orders: a
    narrower one would be tried already too); a constant-coefficients retry that ``state``
    holds is not made (it would drop nothing the move adds).

    Parameters
    ----------
    retries : dict
        The kinds of retries and their ``(name, parameters)`` (:func:`retry_catalogs`).
    order : sequence of str
        The kinds in turn (:func:`retry_order`).
    tried : set
        Keys of the catalogs tried (:func:`~.candidates.parameters_key`); updated with each
        retry yielded.
    state : dict or None
        The catalog the move is made from.

    Yields
    ------
    tuple
        ``(name, parameters)`` of each retry to make.

    Examples
    --------
    >>> retries = {"constant": [("degree-kinetic", {"degree": 3})], "narrower": []}
    >>> list(retry_walk(retries, ["narrower", "constant"], set(), None))
    [('degree-kinetic', {'degree': 3})]
    """
    for kind in order:
        for name, retry in retries[kind]:
            key = parameters_key(retry)
            if key in tried:
                if kind == "narrower":
                    break
                continue
            if kind == "constant" and state is not None and holds(state, retry):
                continue
            tried.add(key)
            yield name, retry
