"""The build step of the fit stage: a catalog and trajectories in, one catalog problem out.

:func:`build_problem` leaves out the still coordinates (:mod:`~pysindy_xl.fit.still`) and
their columns, builds the rows of the strong or weak form (the weak with the propagated noise
of the positions), drops exactly dependent columns (found on :func:`probe_points`) and
returns the :class:`~pysindy_xl.optimizers.CatalogProblem` with its row noise and its
:class:`CatalogMap`. Rows are coordinate-major over all trajectories. Without forces the test
functions come in several widths (:data:`UNFORCED_WIDTH_MULTIPLES`): an unforced law is told
from the others by the noise ratio alone, which one width determines poorly.
"""

from __future__ import annotations

import copy
import dataclasses

import numpy as np

from ..optimizers import CatalogProblem, independent_columns
from ..symbols import stack_variables
from ..weak import BumpTestFunctions, WhittakerSmoother, weak_regression
from .diagnostics import column_mass_matrices
from .still import block_rows, driven_coordinates, still_columns, still_coordinates

__all__ = ["CatalogMap", "build_problem", "probe_points", "with_mass_matrices",
           "UNFORCED_WIDTH_MULTIPLES"]

#: Test-function widths of the unforced weak form, in multiples of the spectrum's width
#: (:class:`~pysindy_xl.weak.BumpTestFunctions`, ``width_multiples``).
UNFORCED_WIDTH_MULTIPLES = (1.0, 1.5, 2.0)


@dataclasses.dataclass(frozen=True, eq=False)
class CatalogMap:
    """The map from a catalog problem's columns and blocks back to the catalog, and its states.

    Parameters
    ----------
    columns : ndarray of int, shape (k,)
        The catalog column of each problem column.
    n_features : int
        Number of catalog columns ``F``.
    coordinates, forced : ndarray of bool, shape (n,)
        The coordinates whose equations are the problem's blocks (the others hold still); those
        a recorded force acts on.
    dropped : dict of int to str
        Catalog columns left out, with the reason.
    states : ndarray, shape (S, 4n + 1)
        The rows' library inputs (smoothed for the weak form).
    formulation : {"strong", "weak"}
        How the rows were built.
    weak_info : dict or None
        :func:`~pysindy_xl.weak.weak_regression`'s information.

    Examples
    --------
    >>> import numpy as np
    >>> m = CatalogMap(np.array([0, 2]), 3, np.ones(1, bool), np.ones(1, bool), {},
    ...                np.zeros((1, 5)), "strong")
    >>> m.to_catalog([4.0, 5.0]).tolist()
    [4.0, 0.0, 5.0]
    """

    columns: np.ndarray
    n_features: int
    coordinates: np.ndarray
    forced: np.ndarray
    dropped: dict
    states: np.ndarray
    formulation: str
    weak_info: dict | None = None

    def to_catalog(self, values) -> np.ndarray:
        """Values of the problem's columns placed on the catalog's, zero elsewhere.

        Parameters
        ----------
        values : array, shape (..., k)
            Values per problem column on the last axis (coefficients, for instance).

        Returns
        -------
        ndarray, shape (..., F)
            The same values at the catalog columns ``columns``, zero at the dropped ones.

        Examples
        --------
        >>> import numpy as np
        >>> m = CatalogMap(np.array([0, 2]), 3, np.ones(1, bool), np.ones(1, bool), {},
        ...                np.zeros((1, 5)), "strong")
        >>> m.to_catalog([4.0, 5.0]).tolist()
        [4.0, 0.0, 5.0]
        """
        values = np.asarray(values, dtype=float)
        out = np.zeros(values.shape[:-1] + (self.n_features,))
        out[..., self.columns] = values
        return out


def probe_points(z: np.ndarray, n_points: int = 4000, seed: int = 0) -> np.ndarray:
    """Random points in the bounding box of the states, each variable drawn independently.

    Dependencies among columns found on these points are identities of the catalog (such as
    ``cos^2 + sin^2 = 1``), never the physical law the trajectories obey.

    Parameters
    ----------
    z : ndarray, shape (S, V)
        The states (library inputs).
    n_points : int, default 4000
        Points drawn.
    seed : int, default 0
        Seed of the generator.

    Returns
    -------
    ndarray, shape (n_points, V)
        Uniform draws within ``[min, max]`` of each column of ``z``.

    Examples
    --------
    >>> import numpy as np
    >>> probe_points(np.array([[0.0, 1.0], [1.0, 3.0]]), n_points=5).shape
    (5, 2)
    """
    rng = np.random.default_rng(seed)
    low, high = z.min(axis=0), z.max(axis=0)
    return rng.uniform(low, high, size=(n_points, z.shape[1]))


def _rows(library, data, formulation, test_functions, smoother, half_width, moving, propagate=True):
    """Rows ``(n * R, F)`` of the whole catalog, the states and, for the weak form, the row
    noise and the weak-form information.
    """
    if formulation == "weak":
        if test_functions is None:
            unforced = all(d["u"] is None for d in data)
            test_functions = BumpTestFunctions(
                width_multiples=UNFORCED_WIDTH_MULTIPLES if unforced else None)
        return weak_regression(library, data, test_functions,
                               copy.deepcopy(smoother) or WhittakerSmoother(),
                               noise="draws" if propagate else "none",
                               half_width=half_width, width_columns=moving)
    if formulation != "strong":
        raise ValueError(f"formulation: expected 'strong' or 'weak', got {formulation!r}")
    states = np.vstack([
        stack_variables(d["x"], d["x_dot"], d["x_ddot"], d["u"], d["t"])[d["mask"]]
        for d in data])
    if len(states) == 0:
        raise ValueError("sample_mask: no sample left to fit")
    return library.transform(states), states, None, None


def _check_moving(data, names, still):
    """Refuse coordinates that never move unless held (``still``), and data where all hold still."""
    if still.all():
        raise ValueError("x: no coordinate moves beyond the noise of the positions; there "
                         "are no dynamics to identify")
    for i, name in enumerate(names):
        if not still[i] and all(np.ptp(d["x"][:, i]) == 0 for d in data):
            raise ValueError(f"x: coordinate {name!r} is constant on every sample; a "
                             "coordinate that never moves carries no dynamics to identify")


def _selected(theta, n, moving, keep) -> np.ndarray:
    """The rows of the moving coordinates and the kept columns of ``theta``, column-major;
    ``theta`` itself where it keeps everything (copying fresh rows costs).
    """
    if not moving.all():
        theta = theta[block_rows(n, theta.shape[0], moving)]
    if len(keep) < theta.shape[1]:
        theta = theta[:, keep]
    return np.asfortranarray(theta)


def build_problem(library, data, formulation: str, *, test_functions=None, smoother=None,
                  half_width=None, hold_still=False, still=None,
                  drop_dependent=False, propagate=True) -> CatalogProblem:
    """The catalog problem of ``library`` on trajectories ``data`` (see the module docstring).

    Parameters
    ----------
    library : fitted CatalogRepartition
        The catalog.
    data : list of dict
        From :func:`~pysindy_xl.fit.trajectory_data`; the strong form needs ``x_dot`` and
        ``x_ddot``.
    formulation : {"strong", "weak"}
        Pointwise Euler-Lagrange rows, or rows integrated against test functions.
    test_functions : BumpTestFunctions, optional
        Weak form; default None: ``BumpTestFunctions()`` (of the widths
        :data:`UNFORCED_WIDTH_MULTIPLES` without forces).
    smoother : WhittakerSmoother, optional
        Weak form; default None: ``WhittakerSmoother()`` (copied).
    half_width : float, optional
        Weak form: the test functions' half-width; default None: chosen from the data.
    hold_still : float or False, default False
        Leave out the coordinates that hold still, with this threshold
        (:func:`~pysindy_xl.fit.still.still_coordinates`).
    still : array of bool, shape (n,), optional
        The coordinates to leave out, when known; overrides ``hold_still``. Default None.
    drop_dependent : bool, default False
        Leave out columns that are zero or exact linear combinations of preferred ones
        (:func:`~pysindy_xl.optimizers.independent_columns`).
    propagate : bool, default True
        Weak form: propagate the noise of the positions into the rows (``row_noise``).

    Returns
    -------
    CatalogProblem
        With ``row_noise`` (weak form) and ``catalog_map`` (a :class:`CatalogMap`).

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> from pysindy_xl.fit import trajectory_data
    >>> c = px.Coordinates(["x"])
    >>> library = px.CatalogRepartition([px.LagrangeLibrary(c, [c.qd[0] ** 2])]).fit()
    >>> t = np.linspace(0, 1, 11)
    >>> data = trajectory_data(np.sin(t), t, np.cos(t), -np.sin(t), None, 1)
    >>> problem = build_problem(library, data, "strong")
    >>> problem.theta.shape, problem.catalog_map.columns.tolist()
    ((11, 2), [0, 1])
    """
    coords = library.coords
    n = coords.n
    forces = None if all(d["u"] is None for d in data) else [d["u"] for d in data]
    if still is None:
        still = np.zeros(n, dtype=bool)
        if hold_still is not False:
            still = still_coordinates([d["x"] for d in data], [d["t"] for d in data],
                                      driven_coordinates(library, forces), float(hold_still))
        _check_moving(data, coords.names, still)
    still = np.asarray(still, dtype=bool)
    moving = ~still
    theta, states, noise, info = _rows(library, data, formulation, test_functions, smoother,
                                       half_width, moving, propagate)
    library.check_domain(states)
    forced = np.zeros(n, dtype=bool)
    if forces is not None:
        block = theta[:, library.force_columns_].reshape(n, -1, len(library.force_columns_))
        forced = np.any(block != 0, axis=(1, 2))
    # the equations of still coordinates and the columns of their motion leave the problem
    left_out = still_columns(library, still)
    candidates = np.setdiff1d(np.arange(theta.shape[1]), list(left_out))
    if drop_dependent:
        probe = library.transform(probe_points(states))
        order = library.column_priority()
        order = order[np.isin(order, candidates)]
        local, dropped = independent_columns(
            probe if moving.all() and len(candidates) == probe.shape[1] else
            probe[np.ix_(block_rows(n, probe.shape[0], moving), candidates)],
            np.searchsorted(candidates, order), n_blocks=int(moving.sum()),
            force_columns=np.flatnonzero(np.isin(candidates, library.force_columns_)))
        keep = candidates[local]
        dropped = {int(candidates[j]): reason for j, reason in dropped.items()}
    else:
        keep, dropped = candidates, {}
    dropped.update(left_out)
    force_columns = [int(np.flatnonzero(keep == j)[0]) for j in library.force_columns_ if j in keep]
    if noise is not None:
        noise = noise.columns(keep)
        noise = noise.coordinates(moving) if still.any() else noise
    structure = library.physical_structure()  # for optimizers that constrain to it
    return CatalogProblem.from_arrays(
        _selected(theta, n, moving, keep), int(moving.sum()),
        force_columns, physical=None if structure is None else structure.select(keep),
        noise_moments=None if noise is None else noise.moments(),
        noise_draws=None if noise is None else noise.draws, row_noise=noise,
        catalog_map=CatalogMap(keep, theta.shape[1], moving, forced, dropped, states,
                               formulation, info))


def with_mass_matrices(problem: CatalogProblem, library) -> CatalogProblem:
    """``problem`` with the mass matrices of its columns at up to 200 of its states.

    For optimizers whose tags ask for them
    (:func:`~pysindy_xl.fit.diagnostics.column_mass_matrices`).

    Parameters
    ----------
    problem : CatalogProblem
        From :func:`build_problem`.
    library : fitted CatalogRepartition
        The catalog the problem was built from.

    Returns
    -------
    CatalogProblem
        A copy with ``mass_matrices`` (S, k, m, m) set: per state and problem column, the
        mass matrix over the ``m`` moving coordinates.
    """
    origin = problem.catalog_map
    moving = origin.coordinates
    mass = column_mass_matrices(library, origin.states)[:, origin.columns]
    return dataclasses.replace(problem, mass_matrices=mass[:, :, moving][:, :, :, moving])
