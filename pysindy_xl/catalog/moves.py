"""The moves of the automatic catalog's growth: from which catalog to which.

A catalog of :class:`~.automatic.AutomaticCatalog` is a set of parameters (degrees, the
interaction order, the kinetic coefficients, the dissipation, the exponentials, the splines); a
move changes one
of them by one step (:func:`moved`), and a joint move two at once (:func:`joint_moves`). The
kinetic coefficients share the potential's interaction order unless a state sets
``kinetic_interaction`` (:func:`kinetic_order`): the climb does so where the ceiling refuses
configuration-dependent kinetic coefficients over products of several coordinates'
functions (the suffix ``"@k<m>"`` of a move, :func:`narrow`); the moves keep it as it is (an
``"interaction"`` move grows the potential's products alone), and the move ``"kinetic"``
widens it by one coordinate while it is below the potential's order. A serial chain in
relative joint angles needs the kinetic order one below the potential's: the inertia of a
three-link arm holds ``cos(b + c)`` (two coordinates), its gravity ``cos(a + b + c)`` (three).
:func:`~.growth.grow_catalog` climbs by these moves from :data:`START`; the backward phase
(:mod:`.backward`) undoes them.
"""

from __future__ import annotations

import itertools
import re

__all__ = ["anchor_base", "exponential_base", "MOVES", "MORE_MOVES", "START", "LIMITS",
           "SPLINE_COUNTS", "SPLINE_MOVES", "RATE_MOVES", "LATE_MOVES", "REPEATED", "moved",
           "joint_moves", "holds", "kinetic_order", "NARROW", "narrow", "narrow_order",
           "narrowed", "is_repeated", "kinetic_trig_degree", "KINETIC_TRIG_DEGREE",
           "DIFFERENCE_LIMIT"]

#: The moves of the growth, in the order they are tried. ``"kinetic_trig_degree"`` gives the
#: configuration-dependent kinetic coefficients an angle's trigonometric monomials of degree
#: 2 (``sin(b)^2 a_dot^2``: a spherical pendulum, a Furuta pendulum's arm, a gimbal), and
#: makes them configuration-dependent where they are constant (a move of its own from
#: :data:`START`, not only after ``"kinetic"``); with two coordinates or more, as
#: ``"gyroscopic"`` (a link pitched to another coordinate's axis: with one angle alone,
#: ``sin(phi)^2 phi_dot^2`` beside ``cos(phi) phi_dot^2`` stands in for a quartic spring).
#: ``"differences"`` adds the squared difference of each pair of coordinates of one kind to the
#: potential (``differences`` of :class:`AutomaticCatalog`: ``(l - m)^2``, a joint's spring, in
#: one column where the products ``l^2, l m, m^2`` are three nearly collinear ones), then its
#: higher powers, one degree a move up to :data:`DIFFERENCE_LIMIT`; it applies only where two
#: coordinates are of one kind.
MOVES = ("kinetic", "interaction", "degree", "trig_degree", "angle_degree", "gyroscopic",
         "coulomb", "kinetic_trig_degree", "differences", "exponentials", "anchored_springs",
         "splines", "quadratic_ends", "knots")
#: The moves of the flexible basis, tried after the families: ``"splines"`` adds a
#: coordinate's splines (natural: a constant force beyond the data) or refines them;
#: ``"quadratic_ends"`` gives them quadratic ends (a constant stiffness beyond the data), adding
#: them first where there are none; ``"knots"`` writes them one column per interior knot
#: (:func:`~.bases.truncated_power_splines`, the same span), adding them first where there are
#: none, so that the search's sparse selection keeps the knots the data need. Which
#: continuation and which writing the data support, the held-out criterion judges.
SPLINE_MOVES = ("splines", "quadratic_ends", "knots")
#: The moves whose family has a rate fitted on data: ``"exponentials"`` adds ``exp(a x)`` and
#: ``exp(2 a x)`` to each linear coordinate's potential, with the rate ``a`` that the growth
#: fits for the catalog it moves from (:mod:`.rates`; :func:`moved`'s ``rates``);
#: ``"anchored_springs"`` adds to each coordinate's potential the length of a spring anchored
#: off its path, with the geometry fitted likewise (:mod:`.anchors`; :func:`moved`'s
#: ``anchors``). The growth tries them in this order, before the splines.
RATE_MOVES = ("exponentials", "anchored_springs")  # (degrees back to the first catalog's)
#: The moves tried after the families, alone (never first moves, never in pairs of moves):
#: the exponentials, then the flexible basis. A family with a fitted rate or a flexible basis
#: fits what a missing family leaves; tried first, or lending a pair its gain, it would stand
#: in for that family.
LATE_MOVES = RATE_MOVES + SPLINE_MOVES
#: Moves a growth may be given beyond the default :data:`MOVES`: ``"coupled_damping"`` lets
#: every velocity's viscous force enter every equation (``dissipation`` ``"coupled"`` of
#: :class:`AutomaticCatalog`: the damping of a joint whose angle is a difference of
#: coordinates).
MORE_MOVES = ("coupled_damping",)
#: The highest power of the coordinates' differences that the move ``"differences"`` reaches.
DIFFERENCE_LIMIT = 4

#: The parameters of the first catalog (:class:`~.automatic.AutomaticCatalog`'s options):
#: constant kinetic coefficients, quadratic potentials of the linear coordinates, sines and
#: cosines of the angles, viscous friction.
START = {"degree": 2, "trig_degree": 1, "angle_degree": 0, "interaction": 1,
         "kinetic": "constant", "gyroscopic": False, "dissipation": ("viscous",),
         "splines": None, "spline_ends": "linear"}
#: The largest degree each degree move reaches. The linear coordinates' powers reach 6: a
#: potential that no family states (a magnet between two repelling magnets,
#: ``-c (1/(d - x) + 1/(d + x))``; an oblique spring) is expanded two terms further than by
#: ``x^4`` where the held-out criterion asks for it (``benchmarks/results/degree_limit.md``).
LIMITS = {"degree": 6, "trig_degree": 3, "angle_degree": 4}
#: Knots of each coordinate's splines when the family is added, then refined.
SPLINE_COUNTS = (8, 12, 16)
#: The suffix of a move after which the configuration-dependent kinetic coefficients are
#: functions of single coordinates (``kinetic_interaction=1``) while the potential's products
#: keep the interaction order: a joint catalog or a climb's move over the ceiling. The suffix
#: ``"@k<m>"`` (:func:`narrow`) holds them to products over at most ``m`` coordinates.
NARROW = "@k1"
_NARROW_SUFFIX = re.compile(r"@k([1-9][0-9]*)$")
#: The moves that go on while they improve (one step of a degree or of the splines each).
REPEATED = ("degree", "trig_degree", "angle_degree", "splines", "differences")
#: The degree of the angles' trigonometric monomials in the kinetic coefficients that the
#: move ``"kinetic_trig_degree"`` sets (one step above the default 1).
KINETIC_TRIG_DEGREE = 2


def moved(state, move, kinds, n, skip=0, rates=None, anchors=None):
    """The catalog parameters after ``move`` from ``state``, or None when it does not apply.

    Parameters
    ----------
    state : dict
        Catalog parameters (the keys of :data:`START`).
    move : str
        One of :data:`MOVES` or :data:`MORE_MOVES`, or ``"a+b"``: the move ``a``, then ``b``;
        with the suffix :data:`NARROW` (``"kinetic+interaction@k1"``), the kinetic
        coefficients are then held to single coordinates' functions (``kinetic_interaction``
        1; None where they are constant or already so); with ``"@k<m>"`` (:func:`narrow`),
        to products over at most ``m`` coordinates (None where they are constant or over at
        most ``m`` already). A named move narrows only the kinetic coefficients it adds: it
        does not apply (None) from a ``state`` whose configuration-dependent kinetic
        coefficients are over more than ``m`` coordinates already (the climb only adds; a
        joint first move ``"interaction+kinetic_trig_degree@k1"`` made from a three-link
        arm's ``cos(b + c)`` inertia would drop it for ``sin(b)^2`` stand-ins). The
        suffix alone (``"@k<m>"``, a refused move's retry) narrows ``state`` itself.
        ``"kinetic"`` makes constant kinetic coefficients configuration-dependent, or
        widens a kinetic order below the potential's by one coordinate.
    kinds : sequence of str
        The coordinates' kinds (``"linear"``, ``"angle"``).
    n : int
        The number of coordinates.
    skip : int, default 0
        Further steps of a repeated move (:data:`REPEATED`): ``skip=1`` looks one degree,
        or one spline count, further.
    rates : callable, mapping or None, default None
        For ``"exponentials"``: the rates ``{name: a}`` of the linear coordinates, or
        ``rates(state) -> {name: a}`` (fitted for the catalog ``state``); None, or an empty
        mapping: the move does not apply.
    anchors : callable, mapping or None, default None
        For ``"anchored_springs"``: the anchors ``{name: (a, b)}`` of the coordinates
        (:func:`~.bases.anchored_spring`), or ``anchors(state) -> {name: (a, b)}``; None, or
        an empty mapping: the move does not apply.

    Returns
    -------
    dict or None
        The new parameters; None where the move does not apply (a family already in, a
        degree at its :data:`LIMITS`, a move without the coordinates it needs).

    Examples
    --------
    >>> moved(START, "trig_degree", ["angle"], 1)["trig_degree"]
    2
    >>> moved(START, "interaction", ["angle"], 1) is None
    True
    >>> moved(START, "kinetic+interaction@k1", ["linear", "angle"], 2)["kinetic_interaction"]
    1
    >>> arm = moved(START, "kinetic+interaction+interaction@k2", ["angle"] * 3, 3)
    >>> arm["interaction"], arm["kinetic_interaction"]
    (3, 2)
    >>> kinetic_order(moved(dict(arm, kinetic_interaction=1), "kinetic", ["angle"] * 3, 3))
    2
    >>> two = moved(START, "kinetic+interaction", ["angle"] * 3, 3)    # cos(b + c) inertia
    >>> moved(two, "interaction+kinetic_trig_degree@k1", ["angle"] * 3, 3) is None
    True
    >>> moved(START, "kinetic_trig_degree", ["angle", "angle"], 2)["kinetic_trig_degree"]
    2
    >>> moved(START, "differences", ["angle", "angle"], 2)["differences"]
    2
    >>> moved(START, "differences", ["linear", "angle"], 2) is None    # no pair of one kind
    True
    >>> moved(START, "exponentials", ["linear"], 1, rates=lambda state: {"x": -1.5})[
    ...     "exponentials"]
    {'x': -1.5}
    >>> moved(START, "anchored_springs", ["angle"], 1, anchors={"theta": (0.85, 0.46)})[
    ...     "anchors"]
    {'theta': (0.85, 0.46)}
    """
    suffix = _NARROW_SUFFIX.search(move)
    if suffix:  # then kinetic coefficients over at most `order` coordinates' functions
        order = int(suffix.group(1))
        if (suffix.start() and state["kinetic"] == "configuration"
                and kinetic_order(state) > order):
            return None  # (a move narrows what it adds, never the kinetic terms `state` has)
        state = moved(state, move[:suffix.start()], kinds, n, skip, rates, anchors) \
            if suffix.start() \
            else dict(state)
        if state is None or state["kinetic"] != "configuration" or kinetic_order(state) <= order:
            return None
        return dict(state, kinetic_interaction=order)
    if "+" in move:
        for part in move.split("+"):
            state = None if state is None else moved(state, part, kinds, n, skip, rates,
                                                     anchors)
        return state
    new = dict(state)
    angles = "angle" in kinds
    if move == "kinetic":
        if state["kinetic"] == "configuration":  # a narrowed kinetic order widens by one
            if kinetic_order(state) >= state["interaction"]:
                return None
            new["kinetic_interaction"] = kinetic_order(state) + 1
            if new["kinetic_interaction"] == state["interaction"]:  # (the default order)
                new.pop("kinetic_interaction")
            return new
        new["kinetic"] = "configuration"
    elif move == "kinetic_trig_degree":
        if not angles or n < 2 or kinetic_trig_degree(state) >= KINETIC_TRIG_DEGREE:
            return None
        new["kinetic"] = "configuration"
        new["kinetic_trig_degree"] = KINETIC_TRIG_DEGREE
    elif move == "interaction":
        if state["interaction"] >= n:
            return None
        new["interaction"] += 1
    elif move in LIMITS:
        relevant = {"degree": "linear" in kinds or (state["angle_degree"] > 0
                                                    and state["interaction"] > 1),
                    "trig_degree": angles, "angle_degree": angles}[move]
        step = (2 if move == "angle_degree" and not state[move] else 1) + skip
        if not relevant or state[move] + step > LIMITS[move]:
            return None
        new[move] = state[move] + step
    elif move == "differences":
        current = state.get("differences", 0)
        step = (2 if not current else 1) + skip
        if len(set(kinds)) == len(kinds) or current + step > DIFFERENCE_LIMIT:
            return None  # (no two coordinates of one kind, or at the limit)
        new["differences"] = current + step
    elif move == "gyroscopic":
        if state["gyroscopic"] or n < 2:
            return None
        new["gyroscopic"] = True
    elif move == "coulomb":
        if "coulomb" in state["dissipation"]:
            return None
        new["dissipation"] = (*state["dissipation"], "coulomb")
    elif move == "coupled_damping":
        if "coupled" in state["dissipation"] or n < 2:
            return None
        new["dissipation"] = (*state["dissipation"], "coupled")
    elif move == "exponentials":
        if state.get("exponentials") or "linear" not in kinds or rates is None:
            return None
        fitted = rates(state) if callable(rates) else rates
        if not fitted:
            return None
        new = dict(exponential_base(state), exponentials=dict(fitted))
    elif move == "anchored_springs":
        if state.get("anchors") or anchors is None:
            return None
        fitted = anchors(state) if callable(anchors) else anchors
        if not fitted:
            return None
        new = dict(anchor_base(state), anchors=dict(fitted))
    elif move == "quadratic_ends":
        if state.get("spline_ends") == "quadratic":
            return None
        new["spline_ends"] = "quadratic"
        new["splines"] = state["splines"] or SPLINE_COUNTS[0]
    elif move == "knots":
        if state.get("spline_basis", "bspline") == "truncated":
            return None
        new["spline_basis"] = "truncated"
        new["splines"] = state["splines"] or SPLINE_COUNTS[0]
    elif move == "splines":
        larger = [k for k in SPLINE_COUNTS if k > (state["splines"] or 0)]
        if skip >= len(larger):
            return None
        new["splines"] = larger[skip]
    return new


def exponential_base(state) -> dict:
    """The catalog ``state`` that the move ``"exponentials"`` adds the exponentials to: its
    exponentials left out and its degree back to :data:`START`'s where higher.

    The exponentials take the place of the powers above the first catalog's, as the splines
    take that of the powers: beside a quartic that stands in for a wall, the selection at noise
    mixes the two (the Morse well at 5 % noise, unforced: 2.4 % held out with ``x^4`` beside
    them, 0.06 % without); a degree move may add the powers again.

    Parameters
    ----------
    state : dict
        Catalog parameters (the keys of :data:`START`).

    Returns
    -------
    dict

    Examples
    --------
    >>> exponential_base(dict(START, degree=4, exponentials={"x": -1.5}))["degree"]
    2
    """
    new = {key: value for key, value in state.items() if key != "exponentials"}
    new["degree"] = min(state["degree"], START["degree"])
    return new


def anchor_base(state) -> dict:
    """The catalog ``state`` that the move ``"anchored_springs"`` adds the springs' lengths
    to: its anchors left out, its degree and trigonometric degree back to :data:`START`'s
    where higher.

    The square of a spring's length is a quadratic of a linear coordinate and a first-degree
    sine and cosine of an angle, in the first catalog already; the length takes the place of
    the higher powers and degrees that stand in for it (as the exponentials take that of the
    powers, :func:`exponential_base`); a degree move may add them again.

    Parameters
    ----------
    state : dict
        Catalog parameters (the keys of :data:`START`).

    Returns
    -------
    dict

    Examples
    --------
    >>> anchor_base(dict(START, trig_degree=3, anchors={"theta": (0.85, 0.46)}))["trig_degree"]
    1
    """
    new = {key: value for key, value in state.items() if key != "anchors"}
    new["degree"] = min(state["degree"], START["degree"])
    new["trig_degree"] = min(state["trig_degree"], START["trig_degree"])
    return new


def is_repeated(move) -> bool:
    """Whether ``move``, or a part of a joint move ``"a+b"``, is one of :data:`REPEATED`: it
    goes on while it improves, and looks one degree further before it stops.

    Parameters
    ----------
    move : str
        A move's name.

    Returns
    -------
    bool

    Examples
    --------
    >>> is_repeated("degree"), is_repeated("interaction+degree"), is_repeated("kinetic")
    (True, True, False)
    """
    return any(part in REPEATED for part in move.split("+"))


def joint_moves(moves, kinds, n, size) -> list:
    """The pairs of moves that are first moves of their own.

    A pair ``"a+b"`` of moves, at most one of them repeated (:data:`REPEATED`; the
    :data:`LATE_MOVES` left out), qualifies when, from :data:`START`, its joint catalog has
    more terms than the two moves add alone: the second move multiplies the first's family
    (``"kinetic+interaction"``: configuration-dependent kinetic coefficients over products
    of two coordinates' functions, as ``cos(a - b)`` in ``cos(a - b) a_dot b_dot``;
    ``"interaction+degree"``: products of two coordinates' powers above the first degree, as
    the ``x^2 y`` of a cubic coupling), so neither alone shows what the pair can. A pair with
    a repeated move is tried one degree further too, as that move alone.

    Parameters
    ----------
    moves : sequence of str
        The growth's moves.
    kinds : sequence of str
        The coordinates' kinds.
    n : int
        The number of coordinates.
    size : callable
        ``size(parameters) -> int``: a catalog's number of terms.

    Returns
    -------
    list of str
        The qualifying pairs, ``"a+b"`` in the order of ``moves``.
    """
    base = size(START)
    out = []
    for a, b in itertools.combinations([m for m in moves if m not in LATE_MOVES], 2):
        if a in REPEATED and b in REPEATED:
            continue  # (one degree with another: a product needs no second coordinate)
        once, other = (moved(dict(START), m, kinds, n) for m in (a, b))
        both = None if once is None or other is None else moved(once, b, kinds, n)
        if both is not None and (size(both) - base
                                 > size(once) - base + size(other) - base):
            out.append(f"{a}+{b}")
    return out


def narrow(move, order) -> str:
    """The name of ``move`` with its kinetic coefficients held to products over at most
    ``order`` coordinates' functions (``kinetic_interaction=order``): ``f"{move}@k{order}"``,
    :data:`NARROW` for ``order=1``.

    Parameters
    ----------
    move : str
        A move's name (without a narrowing suffix), or ``""``: the catalog itself.
    order : int
        The kinetic coefficients' interaction order, 1 or more.

    Returns
    -------
    str

    Examples
    --------
    >>> narrow("kinetic+interaction", 1), narrow("interaction", 2)
    ('kinetic+interaction@k1', 'interaction@k2')
    """
    if not isinstance(order, int) or order < 1:
        raise ValueError(f"order: expected an int >= 1, got {order!r}")
    return f"{move}@k{order}"


def narrow_order(move):
    """The kinetic order of a move's narrowing suffix (:func:`narrow`), None without one.

    Parameters
    ----------
    move : str
        A move's name.

    Returns
    -------
    int or None

    Examples
    --------
    >>> narrow_order("kinetic+interaction@k1"), narrow_order("interaction@k2")
    (1, 2)
    >>> narrow_order("kinetic") is None
    True
    """
    suffix = _NARROW_SUFFIX.search(move)
    return int(suffix.group(1)) if suffix else None


def narrowed(names, kinds, n, size, ceiling) -> list:
    """The moves of ``names`` whose catalog from :data:`START` is over ``ceiling``, each
    narrowed (:func:`narrow`) to the widest kinetic order below its own whose catalog is
    within it.

    Configuration-dependent kinetic coefficients over products of several coordinates'
    functions multiply the velocity products by the potential's products; held to fewer
    coordinates' functions (``cos(a) a_dot x1_dot``) beside the potential's products
    (``x1 x2``), the joint catalog may fit under the ceiling that the full one is over. The
    climbs make the narrowed moves from later catalogs too, where they narrow only what they
    add (:func:`moved`: none from a catalog whose kinetic coefficients are wider already).

    Parameters
    ----------
    names : sequence of str
        Moves from :data:`START` (the growth's joint first moves).
    kinds : sequence of str
        The coordinates' kinds.
    n : int
        The number of coordinates.
    size : callable
        ``size(parameters) -> int``: a catalog's number of terms (negative where it cannot be
        built).
    ceiling : int
        The most terms a catalog may have.

    Returns
    -------
    list of str
        The narrowed names (``f"{name}@k<m>"``), in the order of ``names``.

    Examples
    --------
    >>> from pysindy_xl.catalog import AutomaticCatalog
    >>> def size(parameters):
    ...     return AutomaticCatalog("x1,x2,a,b", kinds=["linear"] * 2 + ["angle"] * 2,
    ...                             max_terms=10 ** 4, **parameters).n_terms
    >>> narrowed(["kinetic+interaction"], ["linear"] * 2 + ["angle"] * 2, 4, size, 144)
    ['kinetic+interaction@k1']
    """
    out = []
    for name in names:
        full = moved(dict(START), name, kinds, n)
        if full is None or full["kinetic"] != "configuration" or not size(full) > ceiling:
            continue
        for order in range(kinetic_order(full) - 1, 0, -1):
            narrower = moved(dict(START), narrow(name, order), kinds, n)
            if narrower is not None and 0 < size(narrower) <= ceiling:
                out.append(narrow(name, order))
                break
    return out


def holds(state, other) -> bool:
    """Whether the catalog ``state`` holds every family of ``other``, each at least as far
    grown (degrees, interaction order, spline count with the same ends and writing;
    configuration-dependent kinetic coefficients over as many coordinates and of as high a
    trigonometric degree, gyroscopic terms,
    each dissipation model, exponentials, whatever their rates).

    Parameters
    ----------
    state, other : dict
        Catalog parameters (the keys of :data:`START`).

    Returns
    -------
    bool

    Examples
    --------
    >>> holds(moved(START, "degree", ["linear"], 1), START)
    True
    >>> holds(START, moved(START, "kinetic", ["linear"], 1))
    False
    """
    return (all(state[key] >= other[key] for key in (*LIMITS, "interaction"))
            and (other["kinetic"] == "constant" or (state["kinetic"] == "configuration"
                                                    and kinetic_order(state)
                                                    >= kinetic_order(other)
                                                    and kinetic_trig_degree(state)
                                                    >= kinetic_trig_degree(other)))
            and (state["gyroscopic"] or not other["gyroscopic"])
            and set(other["dissipation"]) <= set(state["dissipation"])
            and (state["splines"] or 0) >= (other["splines"] or 0)
            and (other["splines"] is None
                 or (state.get("spline_ends") == other.get("spline_ends")
                     and state.get("spline_basis", "bspline")
                     == other.get("spline_basis", "bspline")))
            and (bool(state.get("exponentials")) or not other.get("exponentials"))
            and (bool(state.get("anchors")) or not other.get("anchors"))
            and state.get("differences", 0) >= other.get("differences", 0))


def kinetic_order(state) -> int:
    """The most coordinates in one configuration-dependent kinetic coefficient of the catalog
    ``state``: its ``kinetic_interaction`` where given (a climb's move that the ceiling
    refuses may hold the kinetic coefficients to single coordinates' functions while the
    potential's products grow), else its ``interaction``.

    Parameters
    ----------
    state : dict
        Catalog parameters (the keys of :data:`START`, optionally ``kinetic_interaction``).

    Returns
    -------
    int

    Examples
    --------
    >>> kinetic_order(dict(START, interaction=2)), kinetic_order(
    ...     dict(START, interaction=2, kinetic_interaction=1))
    (2, 1)
    """
    order = state.get("kinetic_interaction")
    return state["interaction"] if order is None else order


def kinetic_trig_degree(state) -> int:
    """The degree of the angles' trigonometric monomials in the configuration-dependent
    kinetic coefficients of the catalog ``state``: its ``kinetic_trig_degree`` where given,
    else ``min(trig_degree, 1)`` (:class:`~.automatic.AutomaticCatalog`'s default).

    Parameters
    ----------
    state : dict
        Catalog parameters (the keys of :data:`START`, optionally ``kinetic_trig_degree``).

    Returns
    -------
    int

    Examples
    --------
    >>> kinetic_trig_degree(START), kinetic_trig_degree(dict(START, kinetic_trig_degree=2))
    (1, 2)
    """
    degree = state.get("kinetic_trig_degree")
    return min(state["trig_degree"], 1) if degree is None else degree
