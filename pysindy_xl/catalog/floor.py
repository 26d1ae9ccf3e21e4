r"""The noise floor of the growth's held-out criterion: what the noise of the positions alone
leaves in the residual of a law that is right.

On held-out rows ``Theta`` built from noisy positions, a law ``xi`` that is exactly right
still has the residual ``Theta xi = E xi``, with ``E`` the rows' error due to the noise of
the positions. The weak regression estimates ``E`` by draws ``Delta_d`` (fresh noise of the
smoother's estimated level, smoothed again: :func:`~pysindy_xl.weak.propagated_draws`), so
the residual's expected size is

.. math:: \|E \xi\| \approx \sqrt{\tfrac1D \textstyle\sum_{d=1}^{D} \|\Delta_d \xi\|^2},

and the held-out criterion's floor is this size over the criterion's scale: the forces' part
``||Theta_F xi_F||`` with forces; each coordinate's kinetic part ``||Theta_{iK} xi_K||``
without (:func:`~pysindy_xl.fit.kinetic_scale.kinetic_relative_residuals`), combined as an
RMS over the coordinates as the criterion is. It is a discrepancy principle (Morozov's): a
model whose held-out residual is as large as the noise explains is as right as the data can
tell; a larger catalog may lower the residual on its training pieces, not on held-out ones.

The floor is a property of the data and the fitted law, not of constants tuned to some
systems: the noise level is the smoother's estimate on the data, and the law's own columns
carry it. On positions free of noise the estimated level is round-off, and so is the floor.
The floor leaves out what the law's coefficients owe to their fit on noisy training rows,
and the smoother's bias, so a right law's criterion is at or above it.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..fit.kinetic_scale import inertial_columns

__all__ = ["held_out_scores", "combined_floor", "models_floor", "floor_reached",
           "noise_explains", "EXACT", "EXPLAINED"]

#: The criterion below which a law is exact to about the precision of noise-free data
#: (differences below it are round-off, not structure).
EXACT = 1e-6
#: A criterion within this factor of its noise floor is one the positions' noise could account
#: for (right laws sit at 0.9 to 1.7 times their floor on noisy data; a stand-in on data free of
#: noise, whose floor is round-off, at a million times or more).
EXPLAINED = 10.0


def held_out_scores(model, held, forced, floor=True) -> tuple:
    r"""The held-out criterion of a fitted model on held-out runs, and its noise floor.

    The criterion is that of :func:`~.criterion.held_out_error`; the floor is its value for
    the residual that the positions' noise alone leaves (see the module docstring): with
    forces

    .. math:: f = \frac{\sqrt{\tfrac1D \sum_d \|\Delta_d \xi\|^2}}{\|\Theta_F \xi_F\|},

    unforced, for each coordinate's block of rows ``i``

    .. math:: f_i = \frac{\sqrt{\tfrac1D \sum_d \|\Delta_{d,i} \xi\|^2}}
              {\|\sum_{j \in K} \Theta_{ij} \xi_j\|}, \qquad
              f = \sqrt{\tfrac1n \textstyle\sum_i f_i^2}.

    Parameters
    ----------
    model : XLSINDy
        Fitted model.
    held : dict
        ``x``, ``t`` and ``u`` (None when unforced) of the held-out runs.
    forced : bool
        Whether the data have forces.
    floor : bool, default True
        Compute the floor (the rows' noise propagated: draws of the held-out rows); False:
        the floor is 0 and the rows are built without it.

    Returns
    -------
    error : float
        The relative error (inf where its scale is zero).
    floor : float
        Its noise floor (0 where the noise is not propagated: the strong form, measured
        velocities, a smoother without a noise estimate; inf where the scale is zero).

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> lib = px.CatalogRepartition([px.ExternalForces(c),
    ...                              px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])])
    >>> t = np.linspace(0, 20, 2001)
    >>> x = (np.sin(t) + 0.5 * np.sin(2.7 * t))[:, None]
    >>> u = -2 * (np.sin(t) + 3.645 * np.sin(2.7 * t))[:, None] + 3 * x   # m = 2, k = 3
    >>> noisy = x + 0.01 * np.random.default_rng(0).normal(size=x.shape)
    >>> model = px.XLSINDy(lib, formulation="weak").fit(noisy[:1500], t[:1500], u=u[:1500])
    >>> error, floor = held_out_scores(model, {"x": noisy[1500:], "t": t[1500:],
    ...                                        "u": u[1500:]}, True)
    >>> bool(floor / 2 < error < 2 * floor)   # a right law: at its floor
    True
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # blocks shorter than a test function: strong form
        problem = model.regression(held["x"], held["t"], u=held["u"], formulation="weak",
                                   propagate_noise=bool(floor))
        if not len(problem.theta):
            problem = model.regression(held["x"], held["t"], u=held["u"], formulation="strong")
    theta, coef = problem.theta, model.coef_[problem.catalog_map.columns]
    residual = theta @ coef
    noise = getattr(problem, "row_noise", None) if floor else None
    # the residual's draws under the rows' noise: one (D, R) product
    drawn = None if noise is None else np.asarray(noise.draws) @ coef
    forces = problem.force_columns
    if forced and len(forces):
        norm = float(np.linalg.norm(theta[:, forces] @ coef[forces]))
        if not norm > 0:
            return float("inf"), float("inf")
        size = 0.0 if drawn is None else float(np.sqrt(np.mean(np.sum(drawn ** 2, axis=1))))
        return float(np.linalg.norm(residual) / norm), size / norm
    kinetic = inertial_columns(model, problem)
    errors, floors = [], []
    for rows in np.array_split(np.arange(len(theta)), problem.n_coordinates):
        norm = float(np.linalg.norm(theta[np.ix_(rows, kinetic)] @ coef[kinetic]))
        if not norm > 0:
            errors.append(np.inf)
            floors.append(np.inf)
            continue
        errors.append(np.linalg.norm(residual[rows]) / norm)
        floors.append(0.0 if drawn is None else
                      float(np.sqrt(np.mean(np.sum(drawn[:, rows] ** 2, axis=1)))) / norm)
    return (float(np.sqrt(np.mean(np.square(errors)))),
            float(np.sqrt(np.mean(np.square(floors)))))


def combined_floor(errors, floors, combine="rms") -> float:
    """The floor of a criterion combined from held-out block errors, combined as they are.

    The RMS of the blocks' floors, or (``"trimmed"``) of those of the blocks whose errors the
    criterion keeps: all but the block of the largest error
    (:func:`~.criterion.combine_errors`).

    Parameters
    ----------
    errors : sequence of float
        The blocks' held-out errors.
    floors : sequence of float
        Their floors (:func:`held_out_scores`), in the same order.
    combine : {"rms", "trimmed"}, default "rms"
        How the errors make the criterion.

    Returns
    -------
    float
        The criterion's floor (inf when a retained floor is not finite).

    Examples
    --------
    >>> round(combined_floor([0.02, 0.9, 0.03], [0.01, 0.02, 0.03]), 4)
    0.0216
    >>> round(combined_floor([0.02, 0.9, 0.03], [0.01, 0.02, 0.03], "trimmed"), 4)
    0.0224
    """
    floors = np.asarray(floors, dtype=float).ravel()
    if combine == "trimmed":
        floors = floors[np.argsort(np.asarray(errors, dtype=float).ravel(), kind="stable")[:-1]]
    value = float(np.sqrt(np.mean(np.square(floors))))
    return value if np.isfinite(value) else float("inf")


def models_floor(search, models, errors) -> float:
    """The noise floor of a candidate's criterion from its fitted models (asked after its fit).

    Parameters
    ----------
    search : SearchData
        The growth's data (:class:`~.search_data.SearchData`): the splits' held-out blocks,
        the kind of criterion and how the blocks combine.
    models : sequence of XLSINDy or None
        The fitted model of each split, None where its fit failed.
    errors : sequence of float
        The blocks' held-out errors, in order over the splits (the step's ``block_errors``).

    Returns
    -------
    float
        :func:`combined_floor` of the blocks' floors (:func:`held_out_scores`; inf for the
        blocks of a failed fit).
    """
    floors = []
    for split, model in zip(search.splits, models, strict=True):
        floors += [np.inf if model is None else held_out_scores(model, held, search.forced)[1]
                   for held in split.blocks]
    return combined_floor(errors, floors, search.combine)


def floor_reached(criterion, floor, tolerance) -> bool:
    """Whether a criterion is at its noise floor: ``criterion <= floor * (1 + tolerance)``.

    Parameters
    ----------
    criterion : float
        A step's held-out criterion.
    floor : float
        Its noise floor (:func:`held_out_scores`, combined over the blocks as the
        criterion is).
    tolerance : float
        The growth's keep tolerance: a move that would lower the criterion by less is not
        kept, and one below the floor cannot be told from the noise.

    Returns
    -------
    bool
        False where either is not finite or the floor is 0.

    Examples
    --------
    >>> floor_reached(0.031, 0.030, 0.05), floor_reached(0.04, 0.03, 0.05)
    (True, False)
    >>> floor_reached(1e-9, 0.0, 0.05)
    False
    """
    return bool(np.isfinite(criterion) and np.isfinite(floor) and floor > 0
                and criterion <= floor * (1 + tolerance))


def noise_explains(criterion, floor) -> bool:
    """Whether the positions' noise could account for a criterion: ``criterion <= EXPLAINED *
    floor``, or the floor unknown (not finite: nothing to tell).

    On noisy data a small criterion (below the growth's ``good_enough``) is what the noise
    leaves; free of noise the floor is round-off, and a criterion of 0.1 % is a stand-in's
    error, not the data's precision.

    Parameters
    ----------
    criterion : float
        A step's held-out criterion.
    floor : float
        Its noise floor (:func:`models_floor`), NaN where not computed.

    Returns
    -------
    bool

    Examples
    --------
    >>> noise_explains(0.001, 0.0008), noise_explains(0.001, 1e-12)
    (True, False)
    >>> noise_explains(0.001, float("nan"))
    True
    """
    if not np.isfinite(floor):
        return True
    return bool(criterion <= EXPLAINED * floor)
