"""Catalogs for the learning loop: a library factory ``catalog(system) -> library`` or a
data-driven identifier.

``"automatic"`` (the default of the loop) is :class:`AutomaticGrowth`: the automatic catalog
(:class:`~pysindy_xl.AutomaticCatalog`) grown on the loop's data by
:func:`~pysindy_xl.grow_catalog`, from the coordinates' names and kinds only (hinges are angles,
slides linear; the ranges come from the data), no MJCF structure. It is *data-driven*: it is
called as ``catalog(system, data)`` and returns the growth's
:class:`~pysindy_xl.catalog.GrowthResult`, whose ``model`` the loop controls with.
``"generic"`` is a fixed catalog from the coordinates and their kinds, as for a rig without a
model file: Lagrangian candidates ``qd^a * trig(theta)^b`` (degrees <= 2) plus
the potentials ``p`` and ``p^2`` of the linear coordinates, viscous friction of every velocity
in every equation, and the forces. ``"kinematic"`` is the catalog the MJCF's kinematic tree
gives (:func:`~pysindy_xl.mujoco.kinematic_catalog`), nearly the true structure. Any callable
``f(system) -> library`` can stand in for them, and any object with ``data_driven = True``
called as ``f(system, data) -> model or GrowthResult`` for :class:`AutomaticGrowth`.
:func:`catalog_identifier` turns either kind into ``identify(system, data) -> (model, text)``."""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["AutomaticGrowth", "CATALOGS", "catalog_identifier", "generic_catalog",
           "kinematic_catalog_of", "resolve_catalog", "system_kinds"]


def generic_catalog(system, velocity_degree: int = 2, trig_degree: int = 2):
    """A catalog from the coordinates and their kinds only (module docstring).

    Parameters
    ----------
    system : MuJoCoSystem or str
        Only its ``coords`` and ``angle_coordinates`` are read.
    velocity_degree, trig_degree : int, default 2
        Degrees of the Lagrangian candidates.

    Returns
    -------
    CatalogRepartition

    Examples
    --------
    >>> generic_catalog("cart-pole").fit().n_output_features_
    42
    """

    from ..feature_library import (
        CatalogRepartition,
        ClassicalLibrary,
        ExternalForces,
        LagrangeLibrary,
    )
    from ..mujoco import get_system, lagrange_terms
    system = get_system(system)
    coords = system.coords
    terms = lagrange_terms(system, velocity_degree, trig_degree)
    linear = [coords.q[i] for i in range(coords.n) if i not in system.angle_coordinates]
    terms += linear + [p ** 2 for p in linear]
    friction = np.ones((coords.n, coords.n), dtype=bool)
    return CatalogRepartition([ExternalForces(coords), LagrangeLibrary(coords, terms),
                               ClassicalLibrary(coords, list(coords.qd), mask=friction)])


def kinematic_catalog_of(system):
    """The kinematic catalog of the system's MJCF (its structure given).

    Parameters
    ----------
    system : MuJoCoSystem or str
        The system or its registry name (:func:`pysindy_xl.mujoco.get_system`).

    Returns
    -------
    CatalogRepartition

    Examples
    --------
    >>> kinematic_catalog_of("cart-pole").fit().n_output_features_
    9
    """
    from ..mujoco import get_system, reference_catalog
    return reference_catalog(get_system(system), "kinematic")


def system_kinds(system) -> list[str]:
    """The kind of each coordinate of a system: ``"angle"`` for a hinge, else ``"linear"``.

    Parameters
    ----------
    system : MuJoCoSystem or str
        Only its ``n`` and ``angle_coordinates`` are read.

    Returns
    -------
    list of str
        One kind per coordinate (:data:`~pysindy_xl.catalog.KINDS`).

    Examples
    --------
    >>> system_kinds("cart-double-pendulum")
    ['linear', 'angle', 'angle']
    """
    from ..mujoco import get_system
    system = get_system(system)
    return ["angle" if i in system.angle_coordinates else "linear" for i in range(system.n)]


class AutomaticGrowth:
    """The automatic catalog grown on the loop's data: coordinates and their kinds only.

    Called as ``growth(system, data)``, it runs :func:`~pysindy_xl.grow_catalog` on the noisy
    positions and forces of every episode so far, with the system's coordinate names and kinds
    (:func:`system_kinds`; ranges from the data), and returns its
    :class:`~pysindy_xl.catalog.GrowthResult`. No structure of the MJCF is read, and nothing
    is kept between calls.

    The catalog is sized for the data. A recording of ``N`` samples of ``n`` coordinates gives
    ``N n`` equations; catalogs over

    .. math:: \\text{max\\_terms} = \\min\\big(\\text{ceiling},\\
              \\lfloor N n / \\text{rows\\_per\\_term} \\rfloor\\big)

    terms are not tried: at 1 % position noise a fit of a few seconds of data finds the law
    with about 20 candidates and loses it with 40 (the surplus columns, products with the
    cart's position over its short range, are nearly collinear). The growth holds out each
    of the ``n_blocks`` time blocks of every recording in turn (``cross_validate``): on a
    few seconds the block with the largest swings holds most of what identifies
    configuration-dependent terms, and with it held out of the only fit the right catalog
    loses to the constant start. The criterion leaves the worst of the blocks' errors out of
    their RMS (``combine="trimmed"``): the fit without that block can fail for the right
    catalog as well (the cart double pendulum's coupled damping). B-splines are not among
    the default moves: they are local to the explored range, which a swing-up leaves. The
    chosen catalog is fitted on all the data with the weak-form test functions of the search,
    at most a third of the default width (on a few seconds of a fast, chaotic motion the
    default, wider test functions lose terms or blur them: the cart double pendulum's gravity,
    for one, and its catalog of the law's shape is 7-25 % off with test functions of 0.53 s,
    within 1 % with 0.1-0.27 s).

    Parameters
    ----------
    rows_per_term : int, default 150
        Equations (samples x coordinates) per candidate term.
    ceiling : int, default 400
        Largest catalog, whatever the data.
    n_blocks : int, default 5
        Time blocks per recording (:func:`~pysindy_xl.grow_catalog`).
    cross_validate : bool, default True
        Hold out every block in turn (``n_blocks`` fits per candidate catalog) rather than
        the last and the farthest-reaching block at once.
    moves : sequence of str, optional
        Moves of the growth; default all of :data:`~pysindy_xl.catalog.MOVES` but "splines" and
        "anchored_springs", and :data:`~pysindy_xl.catalog.MORE_MOVES` (coupled damping).
    physical : bool, default False
        Never give up a catalog whose fits have a positive definite mass matrix on all
        their training states for one whose fits have not (``physical`` of
        :func:`~pysindy_xl.grow_catalog`). Off by default: on 2 s of the cart-pole a
        cross-validation fit of the right catalog can be indefinite on some training
        states, and the rule then keeps the constant start.
    steepest : bool, default True
        Climb by the best move from each kept catalog (``steepest`` of
        :func:`~pysindy_xl.grow_catalog`).
    progress : callable, optional
        ``progress(line)`` after each step of the growth.
    n_jobs : int or None, default None
        Processes of the growth's search (:func:`~pysindy_xl.grow_catalog`): while one
        candidate is fitted, ``n_jobs - 1`` workers fit the ones it will probably try next.
        The path, the chosen catalog and the model do not depend on it. None: 1 (joblib's
        convention; -1: all cores).
    combine : {"auto", "rms", "trimmed"}, default "auto"
        How the held-out blocks' errors make the growth's criterion (``combine`` of
        :func:`~pysindy_xl.grow_catalog`). ``"trimmed"`` leaves the largest out of their
        RMS, so one failing fit out of ``n_blocks`` does not refuse a catalog: on 8 s of the
        cart double pendulum the fit without the block of the largest swings fails for the
        catalog with the coupled damping (the second joint's friction on
        ``theta2_dot - theta1_dot``), which the RMS over all five blocks then refuses. It
        needs ``cross_validate`` and ``n_blocks >= 4``. ``"rms"``: every block counts.
        ``"auto"``: ``"trimmed"`` where it applies, else ``"rms"``.

    Examples
    --------
    >>> growth = AutomaticGrowth()
    >>> growth.data_driven, growth.name, growth.max_terms(2500, 2)
    (True, 'automatic', 33)
    """

    data_driven = True
    name = "automatic"

    def __init__(self, rows_per_term: int = 150, ceiling: int = 400, n_blocks: int = 5,
                 cross_validate: bool = True, moves=None, physical: bool = False,
                 steepest: bool = True, progress=None, n_jobs=None, combine: str = "auto"):
        self.rows_per_term = rows_per_term
        self.ceiling = ceiling
        self.n_blocks = n_blocks
        self.cross_validate = cross_validate
        self.moves = moves
        self.physical = physical
        self.steepest = steepest
        self.progress = progress
        self.n_jobs = n_jobs
        self.combine = combine

    def max_terms(self, n_samples: int, n_coordinates: int) -> int:
        """The ceiling of the catalog for ``n_samples`` samples of ``n_coordinates``.

        Parameters
        ----------
        n_samples : int
            Samples in all recordings.
        n_coordinates : int
            Coordinates of the system.

        Returns
        -------
        int
            ``min(ceiling, n_samples * n_coordinates // rows_per_term)``.
        """
        from .._validation import check_option
        rows = check_option("rows_per_term", self.rows_per_term, "int", low=1)
        ceiling = check_option("ceiling", self.ceiling, "int", low=1)
        return int(min(ceiling, n_samples * n_coordinates // rows))

    def __call__(self, system, data):
        """Grow the automatic catalog on ``data`` (class docstring).

        Parameters
        ----------
        system : MuJoCoSystem or str
            Only its coordinate names and kinds are read.
        data : list of tuple
            ``(q (N, n), t (N,), tau (N, n))`` per recording.

        Returns
        -------
        GrowthResult
            Its ``model`` is the chosen catalog fitted on all the data.
        """
        from ..catalog import MORE_MOVES, MOVES, grow_catalog
        from ..catalog.criterion import MIN_TRIMMED_BLOCKS
        from ..model import XLSINDy
        from ..mujoco import get_system
        from ..weak import BumpTestFunctions
        system = get_system(system)
        if not data:
            raise ValueError("data: expected at least one recording (q, t, tau)")
        q, t, u = (list(part) for part in zip(*data, strict=True))
        moves = tuple(m for m in MOVES + MORE_MOVES if m not in ("splines", "anchored_springs")) \
            if self.moves is None \
            else tuple(self.moves)
        combine = self.combine
        if combine == "auto":
            combine = ("trimmed" if self.cross_validate is True and isinstance(self.n_blocks, int)
                       and self.n_blocks >= MIN_TRIMMED_BLOCKS else "rms")
        found = grow_catalog(q, t, u, coordinates=list(system.coords.names),
                             kinds=system_kinds(system),
                             max_terms=self.max_terms(sum(len(tk) for tk in t), system.n),
                             n_blocks=self.n_blocks, cross_validate=self.cross_validate,
                             moves=moves, physical=self.physical, steepest=self.steepest,
                             progress=self.progress, n_jobs=self.n_jobs,
                             combine=combine)
        # the chosen catalog fitted on all the data with the search's test functions, at most
        # a third of the default width: grow_catalog's own final fit takes the search's width,
        # and a third of a fifth of 8 s (0.53 s) blurs the cart double pendulum's fast motion
        # (its law's catalog 7-25 % off, within 1 % at 0.1-0.27 s)
        model = XLSINDy(found.catalog, test_functions=BumpTestFunctions(
            width=final_fit_width(t, q, self.n_blocks)))
        model.fit(q, t=t, u=u)
        return dataclasses.replace(found, model=model)

    def __repr__(self) -> str:
        return (f"AutomaticGrowth(rows_per_term={self.rows_per_term}, ceiling={self.ceiling}, "
                f"n_blocks={self.n_blocks}, cross_validate={self.cross_validate}, "
                f"moves={self.moves}, physical={self.physical}, steepest={self.steepest}, "
                f"combine={self.combine!r}"
                + ("" if self.n_jobs is None else f", n_jobs={self.n_jobs}") + ")")


def _search_width(t, q, n_blocks: int) -> float:
    """Width of the weak-form test functions of :func:`~pysindy_xl.grow_catalog`'s scored
    fits: the default width of the longest recording, at most a third of the shortest
    recording's time block."""
    from ..weak import BumpTestFunctions
    block = min(len(tk) for tk in t) // n_blocks
    longest = int(np.argmax([len(tk) for tk in t]))
    return float(min(BumpTestFunctions().half_width(t[longest], q[longest]),
                     min(tk[block - 1] - tk[0] for tk in t) / 3))


def final_fit_width(t, q, n_blocks: int) -> float:
    """Width of the final fit's test functions of :class:`AutomaticGrowth`.

    The search's width (the default width of the longest recording, at most a third of the
    shortest recording's time block), at most a third of the default width of the longest
    recording, which resolves the motion's corner frequency: 0.17 s on 2.5 s of the
    cart-pole, 0.2 s on 8 s of the cart double pendulum.

    Parameters
    ----------
    t : list of ndarray, each of shape (n_samples_k,)
        Sample times of each recording.
    q : list of ndarray, each of shape (n_samples_k, n)
        Positions of each recording.
    n_blocks : int
        Time blocks of each recording in the growth's search.

    Returns
    -------
    float
        The test functions' half-width in seconds
        (:class:`~pysindy_xl.weak.BumpTestFunctions`'s ``width``).
    """
    from ..weak import BumpTestFunctions
    longest = int(np.argmax([len(tk) for tk in t]))
    return float(min(_search_width(t, q, n_blocks),
                     BumpTestFunctions().half_width(t[longest], q[longest]) / 3))


#: Catalogs by name: ``"automatic"`` is data-driven (:class:`AutomaticGrowth`), the others
#: library factories.
CATALOGS = {"automatic": AutomaticGrowth(), "generic": generic_catalog,
            "kinematic": kinematic_catalog_of}


def resolve_catalog(catalog):
    """A catalog given by name (:data:`CATALOGS`) or as a callable.

    Parameters
    ----------
    catalog : str or callable
        ``"automatic"``, ``"generic"``, ``"kinematic"``, a library factory
        ``f(system) -> library``, or a data-driven identifier (``data_driven = True``,
        ``f(system, data) -> model or GrowthResult``, such as :class:`AutomaticGrowth`).

    Returns
    -------
    tuple
        ``(name, catalog)``: the name, and the factory or identifier. ``"automatic"`` gives a
        new :class:`AutomaticGrowth`.

    Examples
    --------
    >>> resolve_catalog("generic")[0]
    'generic'
    >>> resolve_catalog("automatic")  # doctest: +NORMALIZE_WHITESPACE
    ('automatic', AutomaticGrowth(rows_per_term=150, ceiling=400, n_blocks=5,
                                  cross_validate=True, moves=None, physical=False,
                                  steepest=True, combine='auto'))
    >>> resolve_catalog("mjcf")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: catalog: expected one of ['automatic', 'generic', ...] or a callable ..., got 'mjcf'
    """
    if isinstance(catalog, str):
        if catalog not in CATALOGS:
            raise ValueError(f"catalog: expected one of {sorted(CATALOGS)} or a callable system "
                             f"-> library, got {catalog!r}")
        if catalog == "automatic":
            return catalog, AutomaticGrowth()
        return catalog, CATALOGS[catalog]
    if callable(catalog):
        name = getattr(catalog, "name", None) if getattr(catalog, "data_driven", False) \
            else None
        return name or getattr(catalog, "__name__", type(catalog).__name__), catalog
    raise TypeError(f"catalog: expected a name or a callable system -> library, got "
                    f"{type(catalog).__name__}")


def catalog_identifier(catalog):
    """``identify(system, data) -> (model, description)`` for a catalog of any kind.

    A library factory is fitted by :class:`~pysindy_xl.XLSINDy` on the data; a data-driven
    identifier is called with the data. The description names the catalog the model came
    from (the grown catalog's :meth:`~pysindy_xl.AutomaticCatalog.describe`, or the number of
    candidate columns).

    Parameters
    ----------
    catalog : str or callable
        As for :func:`resolve_catalog`.

    Returns
    -------
    tuple
        ``(name, identify)``; ``data`` is a list of ``(q (N, n), t (N,), tau (N, n))``.

    Examples
    --------
    >>> name, identify = catalog_identifier("automatic")
    >>> name, callable(identify)
    ('automatic', True)
    """
    import warnings
    name, spec = resolve_catalog(catalog)

    def identify(system, data):
        from ..model import XLSINDy
        from ..mujoco import get_system
        system = get_system(system)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if getattr(spec, "data_driven", False):
                found = spec(system, data)
                model = getattr(found, "model", found)
                catalog_ = getattr(found, "catalog", None)
                return model, (catalog_.describe() if hasattr(catalog_, "describe")
                               else name)
            q, t, u = (list(part) for part in zip(*data, strict=True))
            library = spec(system)
            model = XLSINDy(library).fit(q, t=t, u=u)
            return model, f"{model.feature_library_.n_output_features_} columns"

    return name, identify
