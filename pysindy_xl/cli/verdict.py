"""The verdict of ``pysindy-xl identify`` on a robot log: held-out torque prediction.

An arm under feedback control diverges in an open-loop replay whatever the model, so the
verdict is the torques predicted on data the fit never saw (:mod:`pysindy_xl.held_out`):
``--validate TEST`` files, else time-blocked cross-validation of the training log.
"""

from __future__ import annotations

import os

from .steps import CLIError, dataset_for


def wants_verdict(args, forced: bool) -> bool:
    """Whether ``identify`` scores held-out torques: with ``--validate``, or on a log with
    forces identified against a ``--system`` (unless ``--cv-blocks 0``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of ``identify``.
    forced : bool
        Whether the training data have forces.

    Returns
    -------
    bool
        Whether held-out torques are scored.

    Raises
    ------
    CLIError
        When ``--cv-blocks`` is 1 or ``--validate`` is given for data without forces.
    """
    blocks = getattr(args, "cv_blocks", 0)
    if blocks == 1 or blocks < 0:
        raise CLIError(f"--cv-blocks: expected 0 (no cross-validation) or at least 2, got {blocks}")
    if getattr(args, "validate", None):
        if not forced:
            raise CLIError("--validate: the training data have no forces; held-out torque "
                           "prediction needs them (tau_NAME columns)")
        return True
    return forced and bool(args.system) and blocks >= 2


def _units(system, names) -> list:
    angles = set(getattr(system, "angle_coordinates", ()))
    return ["N m" if k in angles else "N" for k in range(len(names))]


def validation_dataset(args, system, load):
    """The ``--validate`` files read like DATA, in the system's coordinates, as one dataset.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of ``identify``.
    system : MuJoCoSystem
        The system.
    load : callable
        ``load(args, path, system) -> Dataset``, the reader of DATA.

    Returns
    -------
    pysindy_xl.data.Dataset
        The held-out runs.

    Raises
    ------
    CLIError
        When a file's coordinates do not match or it has no forces.
    """
    from pysindy_xl.data import Dataset
    trajectories, names = [], None
    for path in args.validate:
        dataset = load(path)
        if getattr(system, "coordinate_names", None) and dataset.n == system.n:
            dataset = dataset_for(system, dataset)
        if names is not None and dataset.coordinate_names != names:
            raise CLIError(f"--validate: {path!r} has coordinates {list(dataset.coordinate_names)}"
                           f", the other files {list(names)}")
        if not dataset.has("tau"):
            raise CLIError(f"--validate: {path!r} has no forces (tau_NAME columns); held-out "
                           "torque prediction needs them")
        names = dataset.coordinate_names
        trajectories += dataset.trajectories
    return Dataset(trajectories, names)


def held_out_verdict(args, model, system, arguments, load, progress):
    """Score the model on ``--validate`` data or by blocked cross-validation, print the lines
    and return the :class:`~pysindy_xl.held_out.ForceScore`.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of ``identify``.
    model : pysindy_xl.XLSINDy
        The fitted model.
    system : MuJoCoSystem
        The system.
    arguments : dict
        The arguments the model was fitted with (for cross-validation).
    load : callable
        The reader of DATA (:func:`validation_dataset`).
    progress : callable
        Called with a line saying what runs.

    Returns
    -------
    pysindy_xl.held_out.ForceScore
        The held-out score.

    Raises
    ------
    CLIError
        When the held-out data do not match or the cross-validation fails.
    """
    from pysindy_xl.evaluation.held_out import blocked_cross_validation
    if args.validate:
        data = validation_dataset(args, system, load)
        if tuple(data.coordinate_names) != tuple(model.feature_library_.coords.names):
            raise CLIError(f"--validate: coordinates {list(data.coordinate_names)} do not match "
                           f"the model's {list(model.feature_library_.coords.names)}")
        held = data.fit_arguments(forces="tau", constraints="include")
        progress(f"predicting the torques of {', '.join(args.validate)}")
        score = model.score_forces(held["x"], held["t"], held["u"], held["x_dot"],
                                   held["x_ddot"], max_frequency=args.bandwidth)
        n_runs = len(held["x"])
        where = (f"on {', '.join(os.path.basename(p) for p in args.validate)} ({n_runs} "
                 f"run{'s' if n_runs > 1 else ''}, {score.n_samples} samples)")
    else:
        runs = len(arguments["x"])
        folds = min(runs, args.cv_blocks) if runs > 1 else args.cv_blocks
        progress(f"time-blocked cross-validation: {folds} fits of the model, each on the data "
                 "without one " + ("group of runs" if runs > 1 else "block"))
        try:
            score = blocked_cross_validation(
                model, arguments["x"], arguments["t"], arguments["u"], arguments["x_dot"],
                arguments["x_ddot"], n_blocks=args.cv_blocks, max_frequency=args.bandwidth)
        except (ValueError, RuntimeError) as error:
            raise CLIError(f"--cv-blocks: cross-validation failed ({error})") from None
        where = (f"by cross-validation over the {runs} training runs ({folds} folds of whole "
                 "runs)" if runs > 1 else
                 f"by time-blocked cross-validation ({args.cv_blocks} contiguous blocks of the "
                 "run, each predicted by the model refitted on the others)")
    print(f"held-out torque prediction {where}; derivatives: {score.derivatives}:")
    print(*score.lines(_units(system, score.names)), sep="\n")
    return score
