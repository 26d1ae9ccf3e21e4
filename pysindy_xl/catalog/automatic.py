"""The automatic catalog: candidate Lagrangian terms from the coordinates' names and kinds.

A Lagrangian has a shape: a kinetic part quadratic in the velocities with coefficients that
depend on the configuration, terms linear in the velocities (gyroscopic forces, moving frames)
and a potential of the positions. :class:`AutomaticCatalog` writes the candidates in that
shape,

.. math::

    \\{\\,\\phi(q)\\,\\} \\times \\{1\\} \\;\\cup\\; \\{\\,\\kappa(q)\\,\\dot q_i \\dot q_j\\,\\}
    \\;\\cup\\; \\{\\,\\gamma(q_k)\\,\\dot q_i,\\ k \\ne i\\,\\},

with ``phi`` the products of single-coordinate functions (:mod:`.bases`) over at most
``interaction`` coordinates, ``kappa`` a constant or (``kinetic="configuration"``) such a
product of low degree over at most ``kinetic_interaction`` coordinates (by default
``interaction``; an angle's sines and cosines in it of degree ``kinetic_trig_degree``, by
default 1: with 2, ``sin(b)^2`` as in a spherical pendulum's ``sin(theta)^2 phi_dot^2``), and
``gamma`` the first-degree functions of another coordinate. The
potential may hold, per linear coordinate, the exponentials ``exp(a x)`` and ``exp(2 a x)``
of one given rate (``exponentials``; :func:`~.bases.exponential_pair`), beside its powers, and
per coordinate the length of a spring anchored off its path (``anchors``;
:func:`~.bases.anchored_spring`). Per
coordinate it adds dissipation (viscous ``qd_i``, smooth Coulomb ``tanh(qd_i / eps_i)``; with
``"coupled"`` each velocity's viscous force in every equation, a Rayleigh function with
cross terms) as classical terms, and the force columns. Terms that are trigonometric
polynomials go to a :class:`~pysindy_xl.feature_library.PolynomialLagrangeLibrary` (derived
on arrays); the others (powers of angles, splines) to a :class:`~pysindy_xl.LagrangeLibrary`.
The terms are written by :mod:`.terms` from the checked parameters; this module checks them
and builds the libraries.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping

import numpy as np
import sympy as sp

from .._validation import (
    Boolean,
    Collection,
    InstanceOf,
    Interval,
    Options,
    check_option,
    validate_params,
)
from ..feature_library import (
    CatalogRepartition,
    ClassicalLibrary,
    ExternalForces,
    LagrangeLibrary,
    PolynomialLagrangeLibrary,
)
from ..symbols import Coordinates
from .bases import KINDS, SPLINE_BASES, anchored_spring, bspline_centers, exponential_pair
from .kinds import coordinate_kinds, coordinate_names, per_coordinate
from .terms import dissipation_terms, lagrangian_candidates, spline_basis

__all__ = ["AutomaticCatalog", "DISSIPATION"]

#: Dissipation models an automatic catalog offers per coordinate (``"coupled"``: viscous forces
#: of each velocity in the other coordinates' equations too).
DISSIPATION = ("viscous", "coulomb", "coupled")


@functools.cache
def _param_names(cls) -> tuple:
    """``cls._get_param_names()``, read from the signature once per class."""
    return tuple(cls._get_param_names())


def _check_bound(name, bound) -> None:
    """``ValueError`` unless ``bound`` is a pair ``(low, high)`` of finite reals, low < high."""
    try:
        low, high = (float(b) for b in bound)
    except (TypeError, ValueError):
        raise ValueError(f"bounds: expected a pair (low, high) of real numbers for {name!r}, "
                         f"got {bound!r}") from None
    if not (np.isfinite(low) and np.isfinite(high) and high > low):
        raise ValueError(f"bounds: expected finite low < high for {name!r}, got {bound!r}")


#: Terms of recent catalogs by their parameters, most recently used last (sympy expressions
#: are immutable): the clones that every fit makes, and equal catalogs, build them once.
_TERMS: dict = {}
_CACHED_TERMS = 32


class AutomaticCatalog(CatalogRepartition):
    """Candidate terms of a Lagrangian from the coordinates alone (see the module docstring).

    A :class:`~pysindy_xl.CatalogRepartition` whose libraries follow from its parameters: pass
    it to :class:`~pysindy_xl.XLSINDy` like any catalog. :func:`~pysindy_xl.grow_catalog`
    chooses its sizes from data.

    Parameters
    ----------
    coordinates : list of str, str or Coordinates
        The coordinates' names (``"r,theta"`` also works).
    kinds : None, str, sequence or mapping, default None
        ``"linear"`` or ``"angle"`` per coordinate (a mapping ``{name: kind}`` leaves the
        others linear; None: all linear).
    bounds : mapping or sequence of (low, high), optional
        Range of each coordinate (the end knots of its splines); required for its splines.
    degree : int, default 2
        Highest power of a linear coordinate, and highest total power (of linear coordinates
        and angles) in a product of several coordinates' functions.
    trig_degree : int, default 1
        Degree of the trigonometric monomials of the angles.
    angle_degree : int, default 0
        Highest power of an angle itself (``theta^2``: torsion springs).
    interaction : int, default 1
        Most coordinates in one product of functions.
    differences : int, default 0
        Highest power of the difference of each pair of coordinates of one kind: the
        potential gains ``(q_j - q_i)^k``, ``k = 2..differences`` (0: none; 1 is refused), a
        spring between two coordinates (a joint's deflection ``l - m``, a coupling spring) in
        one column, where the products of powers state it in three (``m^2, l m, l^2``) that the
        sparse selection must keep together, and sines and cosines stand in for it in two
        (``cos(l - m) = cos(l) cos(m) + sin(l) sin(m)``). Independent of ``interaction``.
    kinetic : {"constant", "configuration"}, default "configuration"
        Coefficients of the velocity products ``qd_i qd_j``: constants, or also products (over
        ``kinetic_interaction`` coordinates) of linear coordinates up to degree 2 and of the
        angles' trigonometric monomials up to degree ``kinetic_trig_degree`` (by default 1:
        sines and cosines).
    kinetic_trig_degree : int or None, default None
        Degree of the trigonometric monomials of the angles in the configuration-dependent
        kinetic coefficients (None: ``min(trig_degree, 1)``). With 2 they hold ``sin(b)^2``
        and ``sin(b) cos(b)`` (``cos(b)^2 = 1 - sin(b)^2`` is in their span with the
        constant): the inertia of a link about an axis it is pitched to, as the spherical
        pendulum's ``sin(theta)^2 phi_dot^2`` or a Furuta pendulum's arm inertia
        ``(J + m l^2 sin(b)^2) a_dot^2``. Independent of ``trig_degree`` (the potential's);
        ignored with ``kinetic="constant"``. Each step multiplies the kinetic terms: per angle
        ``2 k`` functions at degree ``k`` (4 at 2, against 2).
    kinetic_interaction : int or None, default None
        Most coordinates in one configuration-dependent kinetic coefficient ``kappa(q)``
        (None: ``interaction``). The potential's products keep ``interaction``: with
        ``kinetic_interaction=1, interaction=2`` the catalog holds
        ``kappa(q_k) qd_i qd_j`` (``cos(a) a_dot x_dot``) and ``phi(q_k) phi(q_l)``
        (``x1 x2``) but no ``kappa(q_k, q_l) qd_i qd_j``: of the
        ``(1 + K_1 + K_2 + ...) n (n + 1) / 2`` kinetic terms (``K_m``: the products of
        ``m`` coordinates' low-degree functions) only ``1 + K_1`` per velocity product are
        kept. Ignored with ``kinetic="constant"``; the gyroscopic terms are functions of one
        other coordinate whatever the orders.
    gyroscopic : bool, default False
        Add ``f(q_k) qd_i`` (``k != i``; ``f`` a linear coordinate, a sine or a cosine).
    dissipation : str, sequence of {"viscous", "coulomb", "coupled"} or None, default ("viscous",)
        Dissipation terms in each coordinate's equation (None or ``()``: none). ``"coupled"``:
        the viscous force ``qd_j`` of every velocity in every equation (a Rayleigh function
        ``sum_ij c_ij qd_i qd_j / 2`` with cross terms: damping of a joint whose angle is the
        difference of two coordinates, as for links measured from the vertical).
    coulomb_scale : float or sequence of float, default 0.01
        ``eps_i`` of the smooth Coulomb law ``tanh(qd_i / eps_i)``.
    splines : int or mapping {name: int}, optional
        Number of natural cubic splines (:func:`~pysindy_xl.catalog.bases.natural_splines`, at
        least 4) in the potential of each coordinate: knots evenly spread over its ``bounds``,
        continued linearly beyond them (a constant force outside the range). They take the
        place of the coordinate's own powers in the potential (``x, x^2, ...``; their span
        holds the line), not of its products with other coordinates. The last of the ``K``
        functions is left out: they sum to 1, and a potential matters up to a constant, so
        ``K - 1`` of them give every such potential with no exact dependency among the
        columns. With ``spline_ends="quadratic"`` the count is of knots (``K + 2``
        functions, ``K + 1`` kept).
    spline_ends : {"linear", "quadratic"}, default "linear"
        How the splines continue beyond their end knots. ``"linear"``: the natural splines
        above (a constant force outside the range: a well that flattens, as ``log cosh x``).
        ``"quadratic"``: every cubic spline on the knots, continued by its quadratic Taylor
        polynomial (:func:`~pysindy_xl.catalog.bases.quadratic_end_splines`: a constant
        stiffness outside the range, a wall that keeps rising, as a Morse well's repulsive
        side; ``x^2`` is in the span exactly).
    spline_basis : {"bspline", "truncated"}, default "bspline"
        How the splines are written (the span is the same): local B-splines, or one function
        per interior knot (:func:`~pysindy_xl.catalog.bases.truncated_power_splines`, the
        constant left out), so that a sparse selection that leaves out a column removes a knot
        rather than cutting a dip into the potential.
    exponentials : mapping {name: float}, optional
        A rate ``a`` (finite, nonzero, signed) per linear coordinate: its potential gains
        ``exp(a x)`` and ``exp(2 a x)`` (:func:`~pysindy_xl.catalog.bases.exponential_pair`)
        beside its powers (and splines), for exponential laws that no power series states
        beyond the data: a Morse well ``D (1 - exp(-a x))^2``, a Born-Mayer wall
        ``A exp(-x / rho)``, an exponential spring. They are functions of single coordinates
        and enter no product with other coordinates' functions (a product would multiply
        the catalog for laws that mechanics rarely writes; a pair potential of a difference,
        as the Toda lattice's ``exp(x_1 - x_2)``, is not stated). Coordinates not named get
        none; an angle gets none (``ValueError``). :func:`~pysindy_xl.grow_catalog` fits the
        rates (:mod:`~pysindy_xl.catalog.rates`).
    anchors : mapping {name: (float, float)}, optional
        Per coordinate, the geometry of a spring anchored off its path: its potential gains the
        spring's length (:func:`~pysindy_xl.catalog.bases.anchored_spring`:
        ``sqrt(1 - e cos(theta - phi))`` of an angle, ``(e, phi)``; ``sqrt((x - c)^2 + h^2)``
        of a linear coordinate, ``(c, h)``), one column beside its other functions.
        :func:`~pysindy_xl.grow_catalog` fits the geometry (:mod:`~pysindy_xl.catalog.anchors`,
        the move ``"anchored_springs"``).
    interlink : array (n, n), optional
        Of :class:`~pysindy_xl.ExternalForces`.
    max_terms : int, default 2000
        Ceiling on the number of candidate terms; a larger catalog raises ``ValueError``.

    Attributes
    ----------
    libraries : list of SymbolicLibrary
        Forces, Lagrange terms (trigonometric polynomials, then others), dissipation.

    Examples
    --------
    >>> import pysindy_xl as px
    >>> cat = px.AutomaticCatalog(["r", "theta"], kinds={"theta": "angle"}, interaction=2)
    >>> cat.n_terms
    37
    >>> cat.fit().get_feature_names()[:4]
    ['F[tau]', 'L[r_dot**2]', 'L[r_dot*theta_dot]', 'L[theta_dot**2]']
    """

    _parameter_constraints = {
        "coordinates": [InstanceOf((str, Coordinates), "a Coordinates or comma-separated names"),
                        Collection("a list of names")],
        "kinds": [None, Options(KINDS), Collection("a sequence or mapping of kinds")],
        "bounds": [None, Collection("a mapping or sequence of (low, high)")],
        "degree": [Interval("int", 0)],
        "trig_degree": [Interval("int", 0)],
        "angle_degree": [Interval("int", 0)],
        "interaction": [Interval("int", 1)],
        "differences": [Interval("int", 0)],
        "kinetic_interaction": [None, Interval("int", 1)],
        "kinetic": [Options(("constant", "configuration"))],
        "kinetic_trig_degree": [None, Interval("int", 0)],
        "gyroscopic": [Boolean()],
        "dissipation": [None, Options(DISSIPATION), Collection("a sequence of dissipation models")],
        "coulomb_scale": [Interval("real", 0, low_open=True),
                          Collection("a sequence or mapping of float")],
        "splines": [None, Interval("int", 0), Collection("a mapping {name: int}")],
        "spline_ends": [Options(("linear", "quadratic"))],
        "spline_basis": [Options(SPLINE_BASES)],
        "exponentials": [None, Collection("a mapping {name: rate}")],
        "anchors": [None, Collection("a mapping {name: (a, b)}")],
        "interlink": [None, Collection("an array of shape (n, n)")],
        "max_terms": [Interval("int", 1)],
    }

    def __init__(self, coordinates, kinds=None, bounds=None, degree=2, trig_degree=1,
                 angle_degree=0, interaction=1, kinetic="configuration", gyroscopic=False,
                 dissipation=("viscous",), coulomb_scale=0.01, splines=None, interlink=None,
                 max_terms=2000, kinetic_interaction=None, spline_ends="linear",
                 spline_basis="bspline", exponentials=None, kinetic_trig_degree=None,
                 differences=0, anchors=None):
        self.coordinates = coordinates
        self.kinds = kinds
        self.bounds = bounds
        self.degree = degree
        self.trig_degree = trig_degree
        self.angle_degree = angle_degree
        self.interaction = interaction
        self.kinetic = kinetic
        self.gyroscopic = gyroscopic
        self.dissipation = dissipation
        self.coulomb_scale = coulomb_scale
        self.splines = splines
        self.interlink = interlink
        self.max_terms = max_terms
        self.kinetic_interaction = kinetic_interaction
        self.spline_ends = spline_ends
        self.spline_basis = spline_basis
        self.exponentials = exponentials
        self.kinetic_trig_degree = kinetic_trig_degree
        self.differences = differences
        self.anchors = anchors

    # -- the parameters, checked ---------------------------------------------------------------
    def _coordinates(self) -> Coordinates:
        if isinstance(self.coordinates, Coordinates):
            return self.coordinates
        return Coordinates(coordinate_names(self.coordinates))

    def _options(self) -> dict:
        validate_params(self)
        coords = self._coordinates()
        names = list(coords.names)
        options = {"coords": coords, "kinds": coordinate_kinds(names, self.kinds)}
        for name, low in (("degree", 0), ("trig_degree", 0), ("angle_degree", 0),
                          ("interaction", 1), ("max_terms", 1)):
            options[name] = check_option(name, getattr(self, name), "int", low=low)
        options["differences"] = check_option("differences", self.differences, "int", low=0)
        if options["differences"] == 1:
            raise ValueError("differences: expected 0 (none) or a highest power of 2 or more, "
                             "got 1 (a difference's first power is in the coordinates' own)")
        options["kinetic_interaction"] = (
            options["interaction"] if self.kinetic_interaction is None else
            check_option("kinetic_interaction", self.kinetic_interaction, "int", low=1))
        options["kinetic_trig_degree"] = (
            min(options["trig_degree"], 1) if self.kinetic_trig_degree is None else
            check_option("kinetic_trig_degree", self.kinetic_trig_degree, "int", low=0))
        options["kinetic"] = check_option("kinetic", self.kinetic, "choice",
                                          choices=("constant", "configuration"))
        options["gyroscopic"] = check_option("gyroscopic", self.gyroscopic, "bool")
        dissipation = (self.dissipation,) if isinstance(self.dissipation, str) else \
            tuple(self.dissipation or ())
        for model in dissipation:
            if model not in DISSIPATION:
                raise ValueError(f"dissipation: unknown model {model!r}; expected some of "
                                 f"{DISSIPATION}")
        options["dissipation"] = dissipation
        scales = per_coordinate(self.coulomb_scale, names, "coulomb_scale")
        for scale in scales:
            check_option("coulomb_scale", scale, "real", low=0, low_open=True)
        options["coulomb_scale"] = [float(s) for s in scales]
        splines = per_coordinate(self.splines, names, "splines", default=0)
        bounds = per_coordinate(self.bounds, names, "bounds")
        options["splines"] = []
        options["spline_ends"] = check_option("spline_ends", self.spline_ends, "choice",
                                              choices=("linear", "quadratic"))
        options["spline_basis"] = check_option("spline_basis", self.spline_basis, "choice",
                                               choices=SPLINE_BASES)
        for name, count, bound in zip(names, splines, bounds, strict=True):
            if bound is not None:
                _check_bound(name, bound)
            count = check_option("splines", count or 0, "int", low=0)
            if count and bound is None:
                raise ValueError(f"bounds: B-splines of {name!r} need its range (low, high)")
            if count and count < 4:
                raise ValueError(f"splines: expected at least 4 natural splines of {name!r} "
                                 f"(or 0), got {count}")
            if count:
                bspline_centers(*bound, count)  # checks the count against the range
            options["splines"].append((tuple(map(float, bound)), count) if count else None)
        options["exponentials"] = self._rates(names, options["kinds"])
        if self.anchors is not None and not isinstance(self.anchors, Mapping):
            raise TypeError(f"anchors: expected a mapping {{name: (a, b)}}, got {self.anchors!r}")
        anchors = per_coordinate(self.anchors or {}, names, "anchors")
        options["anchors"] = [None if a is None else anchored_spring(q, kind, a)
                              for q, kind, a in zip(coords.q, options["kinds"], anchors,
                                                    strict=True)]
        return options

    def _rates(self, names, kinds) -> list:
        """The checked ``exponentials``: a rate (float) or None per coordinate."""
        if self.exponentials is None:
            return [None] * len(names)
        if not isinstance(self.exponentials, Mapping):
            raise TypeError(f"exponentials: expected a mapping {{name: rate}}, got "
                            f"{type(self.exponentials).__name__} {self.exponentials!r}")
        rates = per_coordinate(self.exponentials, names, "exponentials")
        for name, kind, rate in zip(names, kinds, rates, strict=True):
            if rate is not None and kind != "linear":
                raise ValueError(f"exponentials: {name!r} is an angle; exponentials of a "
                                 "coordinate are for linear coordinates only")
            if rate is not None:
                try:
                    exponential_pair(sp.Symbol(name), rate)
                except (TypeError, ValueError) as error:
                    raise type(error)(f"{error} (coordinate {name!r})") from None
        return [None if rate is None else float(rate) for rate in rates]

    # -- the terms -----------------------------------------------------------------------------
    def lagrange_terms(self) -> list[sp.Expr]:
        """The candidate Lagrangian terms: kinetic, gyroscopic, then potential ones.

        Returns
        -------
        list of sympy.Expr
            The terms in catalog order (the Euler-Lagrange operator turns each into a column).
        """
        return list(self._built_terms(self._options())[0])

    @property
    def n_terms(self) -> int:
        """Number of candidate terms (Lagrangian and dissipation), forces left out."""
        options = self._options()
        terms, _, _, mask = self._built_terms(options)
        return len(terms) + int(mask.sum())

    def content_key(self) -> tuple:
        """A hashable key of what the catalog holds: its coordinates, its terms (each with the
        library it goes to), its dissipation terms and their equations, and the forces'
        interlink.

        Two catalogs with equal keys build the same libraries, whatever their parameters (an
        interaction order that the degrees leave without a product adds nothing), so a fit
        depends on the catalog only through this key.

        Returns
        -------
        tuple
            Of strings, sympy expressions, booleans and bytes.

        Examples
        --------
        >>> two = AutomaticCatalog("x,y", degree=2, interaction=2, kinetic="constant")
        >>> three = AutomaticCatalog("x,y", degree=2, interaction=3, kinetic="constant")
        >>> two.content_key() == three.content_key(), two.content_key() == AutomaticCatalog(
        ...     "x,y", degree=3, interaction=2, kinetic="constant").content_key()
        (True, False)
        """
        options = self._options()
        terms, fast, dissipation, mask = self._built_terms(options)
        interlink = None if self.interlink is None else np.asarray(self.interlink, float)
        return (tuple(options["coords"].names), tuple(terms), tuple(fast), tuple(dissipation),
                mask.shape, mask.tobytes(),
                None if interlink is None else (interlink.shape, interlink.tobytes()))

    def spline_columns(self) -> list[list[int]]:
        """The columns of each coordinate's splines in the fitted catalog.

        A coordinate's splines are one basis of its unknown potential, meaningful only whole:
        :class:`~pysindy_xl.optimizers.GroupedOptimizer` keeps each of these groups whole or
        leaves it out.

        Returns
        -------
        list of list of int
            One group of catalog column indices (the columns of ``XLSINDy.coef_``) per
            coordinate with splines, in coordinate order; empty without splines.

        Examples
        --------
        >>> catalog = AutomaticCatalog("x", bounds=[(-1.0, 1.0)], splines=5, kinetic="constant")
        >>> catalog.spline_columns()
        [[2, 3, 4, 5]]
        """
        from sklearn.base import clone

        options = self._options()
        owners = {}
        for i, (q, spline) in enumerate(zip(options["coords"].q, options["splines"],
                                            strict=True)):
            if spline is not None:
                (low, high), count = spline
                owners.update({term: i for term in spline_basis(options, q, low, high, count)})
        if not owners:
            return []
        fitted = clone(self).fit()
        groups = {}
        for j, (term, category) in enumerate(zip(fitted.feature_terms_, fitted.categories_,
                                                 strict=True)):
            if category == "lagrange" and term in owners:
                groups.setdefault(owners[term], []).append(j)
        return [groups[i] for i in sorted(groups)]

    def _built_terms(self, options, key=None) -> tuple:
        """``(*_terms, *_dissipation)``, built once per parameters (clones, which every fit
        makes, and equal catalogs share them; sympy expressions are immutable)."""
        if key is None:
            key = repr([(name, getattr(self, name)) for name in _param_names(type(self))])
        found = _TERMS.pop(key, None)
        if found is None:
            found = (*lagrangian_candidates(options), *dissipation_terms(options))
        _TERMS[key] = found
        while len(_TERMS) > _CACHED_TERMS:
            del _TERMS[next(iter(_TERMS))]
        return found

    # -- the catalog ---------------------------------------------------------------------------
    @property
    def libraries(self) -> list:
        """The catalog's libraries (built from the parameters; see the class docstring)."""
        key = repr([(name, getattr(self, name)) for name in _param_names(type(self))])
        cached = self.__dict__.get("_built")
        if cached is not None and cached[0] == key:  # checked when built
            return cached[1]
        options = self._options()
        coords = options["coords"]
        # clones (every fit clones its catalog) and equal catalogs share the terms
        terms, fast, dissipation, mask = self._built_terms(options, key)
        total = len(terms) + int(mask.sum())
        if total > options["max_terms"]:
            raise ValueError(f"max_terms: the catalog would have {total} terms, more than "
                             f"max_terms={options['max_terms']}; lower degree, trig_degree, "
                             "angle_degree, interaction, kinetic_interaction, "
                             "kinetic_trig_degree or splines, or "
                             "raise max_terms")
        libraries = [ExternalForces(coords, interlink=self.interlink)]
        polynomial = [t for t, f in zip(terms, fast, strict=True) if f]
        other = [t for t, f in zip(terms, fast, strict=True) if not f]
        if polynomial:
            libraries.append(PolynomialLagrangeLibrary(coords, polynomial))
        if other:
            libraries.append(LagrangeLibrary(coords, other))
        if dissipation:
            libraries.append(ClassicalLibrary(coords, list(dissipation), mask=mask.copy()))
        self.__dict__["_built"] = (key, libraries)
        return libraries

    @libraries.setter
    def libraries(self, value):  # the parameters define the libraries
        raise AttributeError("libraries: an AutomaticCatalog builds its libraries from its "
                             "parameters; use CatalogRepartition for a list of libraries")

    def describe(self) -> str:
        """A one-line summary of the catalog's families and sizes.

        Returns
        -------
        str
            The families per coordinate, the interaction order, the kinetic and dissipation
            choices and the number of terms, separated by ``"; "``.

        Examples
        --------
        >>> AutomaticCatalog("x,theta", kinds=["linear", "angle"]).describe().split("; ")
        ['x: x..x^2', 'theta: sin/cos degree 1',
         'interaction 1, kinetic configuration, dissipation viscous (21 terms)']
        """
        options = self._options()
        parts = []
        for i, (name, kind) in enumerate(zip(options["coords"].names, options["kinds"],
                                             strict=True)):
            splines = options["splines"][i]
            if kind == "linear":
                text = f"{name}: " + ("" if splines else f"{name}..{name}^{options['degree']}")
            else:
                text = f"{name}: sin/cos degree {options['trig_degree']}"
                if options["angle_degree"] and not splines:
                    text += f", {name}..{name}^{options['angle_degree']}"
            rate = options["exponentials"][i]
            if rate is not None:
                text += ("" if text.endswith(": ") else ", ") + (
                    f"exp({rate:.4g} {name}), exp({2 * rate:.4g} {name})")
            if options["anchors"][i] is not None:
                text += ("" if text.endswith(": ") else ", ") + str(options["anchors"][i])
            if splines is not None:
                text += (", " if not text.endswith(": ") else "") + (
                    f"{splines[1]} natural splines" if options["spline_ends"] == "linear"
                    else f"{splines[1]} cubic splines, quadratic ends")
            parts.append(text)
        extras = [f"interaction {options['interaction']}", f"kinetic {options['kinetic']}"]
        if options["differences"]:
            extras.insert(0, f"differences ..^{options['differences']}")
        notes = []
        if options["kinetic"] == "configuration" and self.kinetic_interaction is not None \
                and options["kinetic_interaction"] != options["interaction"]:
            notes.append(f"interaction {options['kinetic_interaction']}")
        if options["kinetic"] == "configuration" and self.kinetic_trig_degree is not None \
                and "angle" in options["kinds"]:
            notes.append(f"sin/cos degree {options['kinetic_trig_degree']}")
        if notes:
            extras[-1] += f" ({', '.join(notes)})"
        if options["gyroscopic"]:
            extras.append("gyroscopic")
        extras.append("dissipation " + ("+".join(options["dissipation"]) or "none"))
        return "; ".join(parts) + "; " + ", ".join(extras) + f" ({self.n_terms} terms)"

    def to_spec(self) -> dict:
        """The spec of the equivalent :class:`~pysindy_xl.CatalogRepartition` (a saved model
        loads with the concrete libraries).

        Returns
        -------
        dict
            JSON-ready specification of the concrete libraries.
        """
        return CatalogRepartition(self.libraries).to_spec()

    def __repr__(self) -> str:
        changed = {k: v for k, v in self.get_params(deep=False).items()
                   if k == "coordinates" or v != _DEFAULTS.get(k)}
        return "AutomaticCatalog(" + ", ".join(f"{k}={v!r}" for k, v in changed.items()) + ")"


_DEFAULTS = {"kinds": None, "bounds": None, "degree": 2, "trig_degree": 1, "angle_degree": 0,
             "interaction": 1, "kinetic": "configuration", "gyroscopic": False,
             "dissipation": ("viscous",), "coulomb_scale": 0.01, "splines": None,
             "interlink": None, "max_terms": 2000, "kinetic_interaction": None,
             "spline_ends": "linear", "spline_basis": "bspline", "exponentials": None,
             "kinetic_trig_degree": None, "differences": 0, "anchors": None}
