"""``pysindy-xl identify`` with the automatic catalog, and the honest verdict of any fit.

For data given coordinates (no model file), ``--catalog auto`` grows an
:class:`~pysindy_xl.AutomaticCatalog` on the data (:func:`~pysindy_xl.grow_catalog`), prints the
growth path, the discovered Lagrangian and forces, and the held-out error. A fit that explains
nothing, or whose mass matrix is not positive definite on its own training states, ends with a
non-zero exit and a message naming what to try (:func:`honest_exit`).
"""

from __future__ import annotations

import sys

import numpy as np

from .steps import CLIError

__all__ = ["WHAT_IS_TRIED", "run_automatic", "honest_exit", "POOR_R2", "POOR_HELD_OUT"]

#: What ``--catalog automatic`` tries (the ``--help`` text).
WHAT_IS_TRIED = (
    "automatic (the default for data given --coordinates/--angles): candidate Lagrangian terms "
    "in a Lagrangian's shape (kinetic terms quadratic in the velocities with configuration-"
    "dependent coefficients, terms linear in the velocities, potentials), grown from the "
    "smallest catalog (quadratic potentials of linear coordinates, sin/cos of --angles, viscous "
    "friction) by trying in turn: configuration-dependent kinetic coefficients, products across "
    "coordinates, higher powers, higher sin/cos degrees, powers of angles (torsion springs), "
    "gyroscopic terms, smooth Coulomb friction, exponentials exp(a x) and exp(2 a x) of "
    "linear coordinates (Morse wells, exponential walls; the rate a fitted on the data), "
    "the length of a spring anchored off a coordinate's path (its anchor fitted on the data) "
    "and cubic splines of single coordinates "
    "(B-splines inside the data, continued beyond it linearly, a constant force, or "
    "quadratically, a constant stiffness), each first alone, "
    "then in the order of what it achieved alone; a step is kept when the error on two "
    "held-out blocks of each run (the last one, and the one reaching farthest from the median "
    "state) drops by 5 %% or more; then families are dropped again (sin/cos of an angle beside "
    "its powers, powers beside sin/cos, exponentials, anchored springs, splines, degrees, "
    "products, kinetic, "
    "gyroscopic and "
    "Coulomb terms), or exchanged for the family they stand in for, while the error stays "
    "within 5 %% with fewer terms; last, the catalogs within 30 %% of the chosen one's error "
    "are judged again with every block held out in turn")

#: Below this R^2 (on the training data) a fit explains nothing.
POOR_R2 = 0.5
#: Above this held-out relative error a fit explains nothing.
POOR_HELD_OUT = 0.5

_ADVICE = ("try: --angles for coordinates that are angles; check that the tau_NAME columns are "
           "the generalized forces on the named coordinates (units, signs); record longer or "
           "better excited runs; --max-terms above {max_terms} for a richer catalog; "
           "--forces none if the forces are not those acting on the coordinates")
_NOT_PHYSICAL = ("the kinetic energy is not positive there (a mechanical system's always is) "
                 "and the model cannot be simulated along its own data; the fit's "
                 "IdentificationWarning names the coordinates without positive inertia")
_PHYSICAL_ADVICE = ("kinetic coefficients that cannot change sign (constants: in Python "
                    "AutomaticCatalog(kinetic='constant'); lower --velocity-degree / "
                    "--trig-degree of the reference catalogs; --catalog automatic, whose search "
                    "prefers catalogs with a positive definite mass matrix); runs in which every "
                    "coordinate moves, longer or better excited; --angles for coordinates that "
                    "are angles; for a MuJoCo or URDF model, a fit with physical parameters (in "
                    "Python px.PhysicalOptimizer)")


def honest_exit(r2=None, held_out=None, max_terms=400, mass_matrix_check=None,
                own_runs=None) -> None:
    """``CLIError`` when the fit explains nothing, its mass matrix is not physical or,
    simulated, it leaves its own free runs.

    Three judgments, all required of a model ``identify`` reports:

    - **it explains the data:** R^2 (on the training data) at least :data:`POOR_R2`, and the
      held-out relative error (of a grown catalog) at most :data:`POOR_HELD_OUT`;
    - **it is a mechanical system on its own data:** the mass matrix ``M(q)`` positive
      definite on every training state the fit checked, by the rule of the fit-time warning
      (:func:`~pysindy_xl.fit.diagnostics.mass_matrix_failure` on the model's
      ``mass_matrix_check_``). Where it is not, the kinetic energy is not positive, and a run
      crossing from one to the other passes a singular ``M``: the model cannot be simulated
      along its own data, whatever its R^2 (a kinetic coefficient that changes sign can fit the
      weak form to R^2 = 0.9 with a law whose inertia vanishes at rest);
    - **it is a model of its free runs** (a grown catalog on unforced data): simulated from
      each run's first state it stays within ten times the recorded range
      (:func:`~pysindy_xl.fit.own_runs.own_runs_divergence`, ``GrowthResult.own_runs``): a
      law that holds the rows but drives every state away from them is no law of the system.

    Parameters
    ----------
    r2 : float, optional
        Coefficient of determination of the fit on its own data.
    held_out : float, optional
        Relative held-out error (a fraction; ``inf`` when no catalog predicted the blocks).
    max_terms : int, default 400
        The catalog ceiling, named in the advice.
    mass_matrix_check : dict, optional
        The fitted model's ``mass_matrix_check_``
        (:func:`~pysindy_xl.fit.diagnostics.mass_matrix_report`); None: not judged.
    own_runs : str, optional
        Where the model leaves its own free runs (``GrowthResult.own_runs``); None: it stays
        in them, or not judged.

    Returns
    -------
    None
        Returns when the figures say the model explains the data and its mass matrix is
        positive definite; raises ``CLIError`` naming what failed and what to try otherwise.

    Examples
    --------
    >>> honest_exit(r2=0.04)
    Traceback (most recent call last):
    ...
    pysindy_xl.cli.steps.CLIError: the identified model explains nothing (R^2 = 0.04 ...
    >>> honest_exit(r2=0.91, mass_matrix_check={"positive_definite_fraction": 0.5,
    ...                                         "median_condition": float("inf")})
    Traceback (most recent call last):
    ...
    pysindy_xl.cli.steps.CLIError: the identified model is not physical (the identified mass ...
    >>> honest_exit(r2=0.97, own_runs="run 0 leaves its recorded range (z_dot) at t = 0.6 s")
    Traceback (most recent call last):
    ...
    pysindy_xl.cli.steps.CLIError: the identified model is no model of its free runs (run 0 ...
    >>> honest_exit(r2=0.999, mass_matrix_check={"positive_definite_fraction": 1.0,
    ...                                          "median_condition": 2.3})
    """
    reasons = []
    if r2 is not None and not (r2 >= POOR_R2):
        reasons.append(f"R^2 = {r2:.2g} below {POOR_R2:g}")
    if held_out is not None and not np.isfinite(held_out):
        reasons.append("no catalog predicted the held-out blocks")
    elif held_out is not None and not (held_out <= POOR_HELD_OUT):
        reasons.append(f"held-out error {100 * held_out:.3g} % above {100 * POOR_HELD_OUT:g} %")
    from ..fit.diagnostics import mass_matrix_failure  # the fit stage: not loaded by --help
    failure = mass_matrix_failure(mass_matrix_check)
    verdicts, advice = [], []
    if reasons:
        verdicts.append(f"explains nothing ({'; '.join(reasons)})")
        advice.append(_ADVICE.format(max_terms=max_terms))
    if failure is not None:
        verdicts.append(f"is not physical ({failure}: {_NOT_PHYSICAL})")
        advice.append(("for the mass matrix: " if advice else "try: ") + _PHYSICAL_ADVICE)
    if own_runs is not None:
        from ..fit.own_runs import FREE_RUNS_ADVICE
        verdicts.append(f"is no model of its free runs ({own_runs}, simulated from the run's "
                        "first state)")
        advice.append(("for the free runs: " if advice else "") + FREE_RUNS_ADVICE)
    if verdicts:
        raise CLIError(f"the identified model {' and '.join(verdicts)}; " + "; ".join(advice))


def run_automatic(args, dataset, system, forced, progress):
    """Grow, fit and print the automatic catalog for ``identify``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed ``identify`` options (``solver``, ``max_terms``, ``constraints``, ...).
    dataset : Dataset
        The recorded trajectories.
    system : object
        Names the coordinates (``coordinate_names``) and which are angles
        (``angle_coordinates``).
    forced : bool
        Whether the data carry forces (``tau``).
    progress : callable
        ``progress(message)`` prints a progress line.

    Returns
    -------
    model : XLSINDy
    result : GrowthResult
    arguments : dict
        The fit arguments (``x``, ``t``, ``u``, ...).
    """
    from ..catalog import grow_catalog
    arguments = dataset.fit_arguments(forces="tau" if forced else None,
                                      constraints=getattr(args, "constraints", "exclude"))
    names = list(system.coordinate_names)
    kinds = ["angle" if k in system.angle_coordinates else "linear" for k in range(len(names))]
    solver = None if args.solver == "auto" else args.solver
    xs = arguments["x"] if isinstance(arguments["x"], list) else [arguments["x"]]
    listed = ", ".join(f"{n} ({k})" for n, k in zip(names, kinds, strict=True))
    progress(f"growing the automatic catalog of {listed} "
             f"on {sum(len(x) for x in xs)} samples (at most "
             + ("as many terms as the data carry" if args.max_terms == "auto"
                else f"{args.max_terms} terms") + ")")
    try:
        result = grow_catalog(arguments["x"], arguments["t"], arguments.get("u") if forced
                              else None, arguments.get("x_dot"), arguments.get("x_ddot"),
                              coordinates=names, kinds=kinds, max_terms=args.max_terms,
                              optimizer=solver, formulation=args.formulation,
                              progress=progress, n_jobs=getattr(args, "n_jobs", 1))
    except (RuntimeError, ValueError, np.linalg.LinAlgError) as error:
        raise CLIError(f"identification failed ({type(error).__name__}): {error}") from None
    model = result.model
    print(f"automatic catalog: {result.catalog.describe()}")
    print("growth (held-out relative error of the "
          + ("generalized forces" if result.criterion == "forces" else "accelerations")
          + " on the last block of each run and on the block reaching farthest):")
    print(result.table())
    for name, (grid, values) in result.spline_potentials().items():
        print(f"spline potential of {name} (no family states it), V({name}) at "
              + ", ".join(f"{g:.3g}: {v:.4g}" for g, v in zip(grid, values, strict=True)))
    if model.dynamics_ is None:
        raise CLIError("the identified model explains nothing (its equations contain no "
                       "acceleration); " + _ADVICE.format(max_terms=result.max_terms))
    sys.stdout.flush()
    return model, result, arguments
