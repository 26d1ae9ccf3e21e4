"""The removals of :func:`~pysindy_xl.grow_catalog`'s backward phase.

The climb adds families while the held-out criterion improves; it never takes one out. Where
families are nearly dependent on the data's range (``cos(phi) = 1 - phi^2/2 + phi^4/24``), the
one that went in first (the starting catalog's sines and cosines) stays as a stand-in beside
the right one. A removal takes a family, or its last degree step, out of a catalog's
parameters; an exchange follows a removal with a move of the family it may stand in for.
:func:`backward_phase` drops and exchanges families until nothing goes.
"""

from __future__ import annotations

from .candidates import parameters_key
from .moves import START

__all__ = ["REMOVALS", "EXCHANGES", "removed", "backward_phase"]

#: The removals, by the family they drop: a move of :data:`~pysindy_xl.catalog.MOVES` (its
#: family, or its last degree step), or ``"trig"`` (an angle's sines and cosines, beside its
#: powers).
REMOVALS = ("splines", "exponentials", "anchored_springs", "trig", "trig_degree",
            "angle_degree", "degree", "interaction", "kinetic", "gyroscopic", "coulomb",
            "kinetic_trig_degree", "differences")

#: The moves a removal is exchanged for when it is not kept alone: the potential's families
#: that stand in for each other (sines and cosines, or a degree of them, for powers of the
#: angle, powers for a sine degree, splines for powers).
EXCHANGES = {"splines": ("degree", "angle_degree"), "trig": ("angle_degree",),
             "trig_degree": ("angle_degree",), "angle_degree": ("trig_degree",)}


def removed(state: dict, move: str, kinds, start: dict) -> dict | None:
    """The catalog parameters ``state`` with the family of ``move``, or its last degree step,
    taken out.

    An angle keeps a function of its own: its sines and cosines go entirely only beside its
    powers (``"trig"``; ``"trig_degree"`` steps down to degree 1), and its powers only beside
    sines and cosines. The degree, the interaction order, the kinetic and gyroscopic choices
    step back no further than ``start``.

    Parameters
    ----------
    state : dict
        Parameters of an :class:`~pysindy_xl.AutomaticCatalog` (``degree``, ``trig_degree``,
        ``angle_degree``, ``interaction``, ``kinetic``, ``gyroscopic``, ``dissipation``,
        ``splines``, optionally ``exponentials``, ``anchors``).
    move : str
        One of :data:`REMOVALS`.
    kinds : sequence of str
        The coordinates' kinds.
    start : dict
        The smallest catalog's parameters (the floor of the steps back).

    Returns
    -------
    dict or None
        The new parameters, or None when there is nothing of the family to drop.

    Examples
    --------
    >>> start = {"degree": 2, "trig_degree": 1, "angle_degree": 0, "interaction": 1,
    ...          "kinetic": "constant", "gyroscopic": False, "dissipation": ("viscous",),
    ...          "splines": None, "spline_ends": "linear"}
    >>> state = dict(start, angle_degree=4)
    >>> removed(state, "trig", ["angle"], start)["trig_degree"]
    0
    >>> removed(state, "angle_degree", ["angle"], start)["angle_degree"]
    3
    >>> removed(start, "trig", ["angle"], start) is None    # no powers beside the cosine
    True
    """
    if move not in REMOVALS:
        raise ValueError(f"move: expected one of {REMOVALS}, got {move!r}")
    new = dict(state)
    angles = "angle" in kinds
    if move == "exponentials":
        if not state.get("exponentials"):
            return None
        new.pop("exponentials")
    elif move == "anchored_springs":
        if not state.get("anchors"):
            return None
        new.pop("anchors")
    elif move == "splines":
        if state["splines"] is None:
            return None
        new["splines"] = None
        new["spline_ends"] = start.get("spline_ends", "linear")
        new.pop("spline_basis", None)  # (the writing of splines that are gone)
    elif move == "trig_degree":
        if not angles or state["trig_degree"] <= 1:
            return None
        new["trig_degree"] = state["trig_degree"] - 1
    elif move == "trig":
        if not angles or not state["trig_degree"] or not state["angle_degree"]:
            return None
        new["trig_degree"] = 0
    elif move == "angle_degree":
        if not angles or not state["angle_degree"] or not state["trig_degree"]:
            return None
        new["angle_degree"] = 0 if state["angle_degree"] <= 2 else state["angle_degree"] - 1
    elif move in ("degree", "interaction"):
        if state[move] <= start[move]:
            return None
        new[move] = state[move] - 1
        if new.get("kinetic_interaction") == new["interaction"]:  # (the default order)
            new.pop("kinetic_interaction")
    elif move in ("kinetic", "gyroscopic"):
        if state[move] == start[move]:
            return None
        new[move] = start[move]
        if move == "kinetic":  # (the order and degree of the kinetic coefficients go too)
            new.pop("kinetic_interaction", None)
            new.pop("kinetic_trig_degree", None)
    elif move == "kinetic_trig_degree":  # (back to the default degree)
        if state.get("kinetic_trig_degree") is None:
            return None
        new.pop("kinetic_trig_degree")
    elif move == "differences":  # (their squares last)
        if not state.get("differences"):
            return None
        new["differences"] = 0 if state["differences"] <= 2 else state["differences"] - 1
    else:  # coulomb
        if "coulomb" not in state["dissipation"]:
            return None
        new["dissipation"] = tuple(d for d in state["dissipation"] if d != "coulomb")
    return new


def _stepped_down(smaller: dict, move: str, kinds) -> list:
    """The catalogs an exchange starts from: ``smaller`` (``move``'s family one degree step
    down) and, for the sines and cosines grown by several degree steps, the family back at
    the first catalog's degree 1, with the number of steps taken down.

    A trigonometric stand-in grown degree by degree (``sin^3 a sin^3 b`` products for a
    spring ``(a - b)^2``) is not left one step at a time: the catalog one step down still
    holds most of the stand-in, and its exchange may score worse than the end (0.12 % against
    0.03 % on the noise-free elastic double pendulum), while the sines and cosines of the
    first catalog with the angles' powers beside them are the law (1e-10). Only this
    direction: the angles' powers (from degree 3 or 4) are exchanged one step at a time, as
    before. Their deep exchange (all powers out, sines and cosines one degree up) offers the
    stand-in that the held-out blocks cannot tell from a spring at noise (the elastic double
    pendulum at 1 %, seed 2: ``sin/cos degree 2`` kept over ``a..a^4``, 1.65 % against
    2.00 %, and 68 % off the box).

    Parameters
    ----------
    smaller : dict
        The catalog parameters after the removal ``move`` (one step down).
    move : str
        The removal (:data:`REMOVALS`).
    kinds : sequence of str
        The coordinates' kinds.

    Returns
    -------
    list of tuple
        ``(steps, parameters)``: ``(1, smaller)``, then the lowest where it is further down.

    Examples
    --------
    >>> start = {"degree": 2, "trig_degree": 1, "angle_degree": 0, "interaction": 1,
    ...          "kinetic": "constant", "gyroscopic": False, "dissipation": ("viscous",),
    ...          "splines": None, "spline_ends": "linear"}
    >>> [(k, p["trig_degree"]) for k, p in _stepped_down(dict(start, trig_degree=2),
    ...                                                  "trig_degree", ["angle"])]
    [(1, 2), (2, 1)]
    """
    out = [(1, smaller)]
    if move == "trig_degree":
        steps, lower = 1, smaller
        while (further := removed(lower, move, kinds, START)) is not None:
            steps, lower = steps + 1, further
        if steps > 1:
            out.append((steps, lower))
    return out


def backward_phase(climber, state, best, path, moves) -> tuple:
    """Drop the family whose removal the keep rule accepts best (a smaller catalog within
    the tolerance at an equal fitted size is kept too: the stand-in that a family offers
    next to the right one goes with it), until nothing goes; a family refused alone is
    exchanged for another (:data:`~.backward.EXCHANGES`) while the criterion is not good
    enough.

    Parameters
    ----------
    climber : Climber
        The growth's search (:class:`~.climbs.Climber`): its fits, keep rules and moves.
    state : dict
        The climb's end.
    best : GrowthStep
        Its step.
    path : list of GrowthStep
        The kept steps so far.
    moves : sequence of str
        The growth's moves (only their families are dropped).

    Returns
    -------
    tuple
        The end's parameters, its step, and the kept steps (``path`` extended).
    """
    visited = {parameters_key(state)}
    tolerance = climber.tolerance
    while True:  # below good_enough too: a stand-in can be good enough
        dropped, refused = [], []
        candidates = [(move, parameters) for move in REMOVALS
                      if (parameters := removed(state, move, climber.kinds, START)) is not None
                      and {"trig": "trig_degree"}.get(move, move) in moves
                      and parameters_key(parameters) not in visited
                      and climber.size(parameters) != best.terms]
        for k, (move, parameters) in enumerate(candidates):
            step = climber.attempt(parameters, f"-{move}", [p for _, p in candidates[k + 1:]])
            if climber.keeps(step, best) or (
                    not climber.refused(step) and step.active == best.active
                    and step.terms < best.terms
                    and (not climber.physical or step.definite >= 1 or best.definite < 1)
                    and (lambda c, b: c <= b * (1 + tolerance))(*climber.compared(step, best))):
                dropped.append((step.criterion, step.active, parameters, step))
            else:
                refused.append((move, parameters))
        # a family that stands in for another is not given up alone: exchange it for the
        # other (while the criterion is not good enough: at its noise floor too, where a
        # stand-in and the law it stands in for may both be)
        exchanges = []
        for move, smaller in (refused if not dropped and not climber.settled(best, False)
                              else ()):
            for steps, base in _stepped_down(smaller, move, climber.kinds):
                for other in EXCHANGES.get(move, ()):
                    for skip in (0, 1) if other in moves else ():
                        parameters = climber.moved(base, other, skip)
                        if (parameters is not None and parameters_key(parameters) not in visited
                                and climber.size(parameters) != climber.size(base)):
                            exchanges.append((f"-{move}{'' if steps == 1 else f'*{steps}'}"
                                              f"+{other}", parameters))
        for k, (name, parameters) in enumerate(exchanges):
            step = climber.attempt(parameters, name, [p for _, p in exchanges[k + 1:]])
            if climber.keeps(step, best):
                dropped.append((step.criterion, step.active, parameters, step))
        if not dropped:
            break
        _, _, state, best = min(dropped, key=lambda d: d[:2])
        visited.add(parameters_key(state))
        path.append(best)
    return state, best, path
