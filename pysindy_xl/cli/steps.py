"""The steps the ``pysindy-xl`` commands share: systems, catalogs, solvers, the fit and the
report pieces, and the error they report to the user."""

from __future__ import annotations

import os
import sys

import numpy as np


class CLIError(Exception):
    """A bad input or failed step, printed as ``pysindy-xl: error: ...`` with exit status 1.

    Examples
    --------
    >>> from pysindy_xl.cli import build_parser, run_demo
    >>> args = build_parser().parse_args(["demo", "cart-pole", "--forcing", "implicit",
    ...                                   "--solver", "explicit"])
    >>> run_demo(args)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    pysindy_xl.cli.steps.CLIError: --solver explicit needs forces; use --forcing explicit ...
    """


def _optimizer(solver: str, threshold=None):
    import pysindy_xl as px
    cls = {"explicit": px.ExplicitOptimizer, "implicit": px.ImplicitOptimizer,
           "mixed": px.MixedOptimizer}[solver]
    if threshold is not None:
        if "threshold" not in cls().get_params():
            raise CLIError(f"--threshold: {cls.__name__} has no threshold parameter")
        return cls(threshold=threshold)
    return cls()


def display_name(system) -> str:
    """The name to show for ``system``: a model file's name (``ur10e.urdf``), else its own.

    Parameters
    ----------
    system : MuJoCoSystem
        The system.

    Returns
    -------
    str
        The model file's base name, or the system's registry name.
    """
    return os.path.basename(getattr(system, "path", None) or "") or system.name


def system_by_name(name, joints=None):
    """The system of a command line's SYSTEM argument, restricted to ``--joints``.

    Parameters
    ----------
    name : str or MuJoCoSystem
        A registry name, an MJCF or URDF path, or a system.
    joints : list of str, default=None
        Joints identified (MJCF and URDF models only); None: every joint.

    Returns
    -------
    MuJoCoSystem
        The system.

    Raises
    ------
    CLIError
        When the name is unknown or ``--joints`` does not apply.
    """
    from pysindy_xl.mujoco import MuJoCoSystem, get_system
    try:
        if joints is None:
            return get_system(name)
        if not isinstance(name, MuJoCoSystem) and not (
                isinstance(name, str) and name.lower().endswith((".xml", ".urdf"))):
            raise CLIError(f"--joints: only for MJCF .xml and URDF models; {name!r} is a shipped "
                           "system whose joints are all identified")
        return get_system(name, joints=joints)
    except (ValueError, TypeError) as error:
        raise CLIError(str(error).replace("joints: ", "--joints: ", 1)) from None


def output_file(path, option):
    """Check an output file's directory before any long computation.

    Parameters
    ----------
    path : str or os.PathLike
        The file to be written.
    option : str
        The option named in the error.

    Raises
    ------
    CLIError
        When the directory does not exist or ``path`` is a directory.
    """
    directory = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(directory):
        raise CLIError(f"{option}: directory {directory!r} does not exist")
    if os.path.isdir(path):
        raise CLIError(f"{option}: {path!r} is a directory, expected a file name")


def output_directory(path):
    """Create the ``--out`` directory (a CLIError when that cannot be done).

    Parameters
    ----------
    path : str or os.PathLike
        The directory.

    Raises
    ------
    CLIError
        When ``path`` is a file or cannot be created.
    """
    if os.path.exists(path) and not os.path.isdir(path):
        raise CLIError(f"--out: {path!r} exists and is not a directory; give a directory")
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as error:
        raise CLIError(f"--out: cannot create directory {path!r} ({error.strerror})") from None


def generate_data(system, args, progress=None):
    """generate_dataset with the shared options; warnings of the generation are printed.

    Parameters
    ----------
    system : MuJoCoSystem
        The system.
    args : argparse.Namespace
        The parsed arguments.
    progress : bool or None, default=None
        As in :func:`~pysindy_xl.mujoco.generate_dataset`.

    Returns
    -------
    pysindy_xl.data.Dataset
        The generated data.

    Raises
    ------
    CLIError
        When an option is invalid.
    """
    import warnings

    from pysindy_xl.mujoco import generate_dataset
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            dataset = generate_dataset(
                system, n_trajectories=args.trajectories, duration=args.duration,
                forcing=args.forcing, actuators=args.actuators, noise=args.noise,
                noise_model=args.noise_model, seed=args.seed, sample_every=args.sample_every,
                amplitude=args.amplitude, initial_scale=args.initial_scale, progress=progress,
            )
        except (ValueError, RuntimeError, TypeError) as error:
            raise CLIError(str(error)) from None
    for warning in caught:
        print(f"warning: {warning.message}", file=sys.stderr)
    return dataset


def data_lines(system, dataset):
    """What the data hold: sampling, what the fit receives, constraints.

    Parameters
    ----------
    system : MuJoCoSystem
        The system.
    dataset : pysindy_xl.data.Dataset
        The data.

    Returns
    -------
    list of str
        The lines printed.
    """
    meta = dataset.metadata
    period = meta["timestep"] * meta["sample_every"]
    lines = [f"  sampling every {meta['sample_every']} step(s) of {meta['timestep'] * 1e3:g} ms "
             f"= {period * 1e3:g} ms"]
    integration = meta.get("integration")
    if integration and getattr(system, "mj_model", None) is not None:
        from pysindy_xl.simulation.generate import INTEGRATORS
        authored = int(system.mj_model().opt.integrator)
        if INTEGRATORS.get(integration["integrator"]) != authored or integration["substeps"] > 1:
            lines.append(f"  integrated with {integration['reason']}")
            joint, peak = max(meta["peak_velocity"].items(), key=lambda item: item[1])
            lines.append(f"  peak joint velocity {peak:.3g} ({joint})")
    if meta.get("derivatives") == "none":
        lines.append(f"  noise model {meta['noise_model']}: noisy positions only, no velocity "
                     "or acceleration given (weak formulation on smoothed states)")
    if excluded := getattr(system, "excluded_joints", ()):
        lines.append(f"  joints locked at their reference pose (not identified): "
                     f"{', '.join(excluded)}")
    if trimmed := getattr(system, "trimmed_keyframes", ()):
        lines.append(f"  keyframes cut to the identified joints: {', '.join(trimmed)}")
    summary = meta.get("constraints", {})
    if summary.get("active_fraction"):
        hits = ", ".join(f"{j} {c}" for j, c in summary["limit_hits"].items()) or "none"
        lines.append(f"  constraints act on {summary['active_fraction']:.1%} of the samples (joint "
                     f"limit samples: {hits}; contact samples: {summary['contact_samples']})")
    return lines


def dataset_system(metadata):
    """The system a dataset was generated with (a user's MJCF from its path or embedded XML).

    Parameters
    ----------
    metadata : dict
        A dataset's metadata.

    Returns
    -------
    MuJoCoSystem
        The system (:func:`~pysindy_xl.mujoco.system_from_metadata`).

    Raises
    ------
    CLIError
        When the metadata name no system.
    """
    from pysindy_xl.mujoco import system_from_metadata
    try:
        return system_from_metadata(metadata)
    except (ValueError, TypeError) as error:
        raise CLIError(str(error)) from None


def dataset_for(system, dataset):
    """Check the dataset's coordinates against the system's (adopting them when unnamed, and
    putting the columns in the system's order when they name its coordinates in another).

    Parameters
    ----------
    system : MuJoCoSystem
        The system.
    dataset : pysindy_xl.data.Dataset
        The data.

    Returns
    -------
    pysindy_xl.data.Dataset
        The data in the system's coordinates and order.

    Raises
    ------
    CLIError
        When the coordinates do not match.
    """
    from pysindy_xl.mujoco import Dataset
    names = dataset.coordinate_names
    if names == system.coordinate_names:
        return dataset
    if dataset.n != system.n:
        raise CLIError(f"DATA: the dataset has {dataset.n} coordinates {list(names)}, the system "
                       f"{display_name(system)} has {system.n} {list(system.coordinate_names)}")
    if names == tuple(f"q{k}" for k in range(dataset.n)):  # unnamed: adopt the system's
        return Dataset(dataset.trajectories, system.coordinate_names, dataset.metadata)
    joint_forces = any(getattr(tr, key) is not None for tr in dataset.trajectories
                       for key in ("u", "u_constraint"))  # per joint: not reordered by name
    if set(names) == set(system.coordinate_names) and not joint_forces:  # another order
        import dataclasses

        from pysindy_xl.data.files import SERIES
        order = [list(names).index(name) for name in system.coordinate_names]
        trajectories = [dataclasses.replace(tr, **{key: getattr(tr, key)[:, order] for key in
                                                   SERIES if getattr(tr, key) is not None})
                        for tr in dataset.trajectories]
        return Dataset(trajectories, system.coordinate_names, dataset.metadata)
    raise CLIError(f"DATA: coordinate names {list(names)} do not match the system "
                   f"{display_name(system)} {list(system.coordinate_names)}")


def resolve_catalog(args, system):
    """Replace ``--catalog auto`` by ``kinematic`` for a MuJoCo model (compact, it holds the
    true model); for coordinates named without one, ``mixed`` (the paper's) when a degree of it
    is given, else ``automatic`` (``identify``: grown on the data); default degrees 2.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments. ``args.catalog``, ``args.velocity_degree`` and
        ``args.trig_degree`` are set in place.
    system : MuJoCoSystem
        The system.
    """
    from pysindy_xl.mujoco import MuJoCoSystem
    degrees = (getattr(args, "velocity_degree", None), getattr(args, "trig_degree", None))
    if args.catalog == "auto":
        has_model = type(system).xml is not MuJoCoSystem.xml  # an MJCF to read the tree from
        automatic = hasattr(args, "max_terms") and degrees == (None, None)
        args.catalog = ("kinematic" if has_model else
                        "automatic" if automatic else "mixed")
    if hasattr(args, "velocity_degree") and args.velocity_degree is None:
        args.velocity_degree = 2
    if hasattr(args, "trig_degree") and args.trig_degree is None:
        args.trig_degree = 2


def log(quiet, *args):
    """Print ``args`` unless ``quiet``.

    Parameters
    ----------
    quiet : bool
        Print nothing.
    *args
        What :func:`print` prints.
    """
    if not quiet:
        print(*args, flush=True)


def check_solver(solver, forced, threshold, auto=False):
    """The optimizer of ``solver``, checked before any long computation; for ``auto`` without
    a threshold, the kind's name (XLSINDy's default optimizer of that kind).

    Parameters
    ----------
    solver : {"explicit", "implicit", "mixed", "auto"}
        The ``--solver`` option (resolved).
    forced : bool
        Whether the data have forces.
    threshold : float or None
        The ``--threshold`` option.
    auto : bool, default=False
        Whether ``--solver auto`` chose ``solver``.

    Returns
    -------
    optimizer or str
        The optimizer, or the kind's name for XLSINDy's default optimizer.

    Raises
    ------
    CLIError
        When the explicit solver is asked for without forces.
    """
    if solver == "explicit" and not forced:
        raise CLIError("--solver explicit needs forces; use --forcing explicit or mixed, or "
                       "--solver implicit")
    if auto and threshold is None:
        return solver  # the default optimizer of that kind (XLSINDy's bagging policy)
    return _optimizer(solver, threshold)


def coulomb_law(args, dataset=None) -> str:
    """``--coulomb-law``, or the default of the data's source: ``mujoco`` for data MuJoCo
    simulated, ``smooth`` for any other log and with joint models.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments.
    dataset : pysindy_xl.data.Dataset, default=None
        The data, whose metadata say whether MuJoCo simulated them.

    Returns
    -------
    str
        ``"mujoco"`` or ``"smooth"``.
    """
    if (law := getattr(args, "coulomb_law", None)) is not None:
        return law
    if getattr(args, "joint_models", None) is not None:
        return "smooth"
    if dataset is not None and "integration" in dataset.metadata:
        return "mujoco"
    return getattr(args, "default_coulomb_law", "smooth")


def fit_model(system, dataset, args, solver, forced, return_arguments=False):
    """Fit the reference catalog of the options to a dataset.

    Parameters
    ----------
    system : MuJoCoSystem
        The system.
    dataset : pysindy_xl.data.Dataset
        The training data.
    args : argparse.Namespace
        The parsed arguments.
    solver : str
        The resolved solver.
    forced : bool
        Whether the data have forces.
    return_arguments : bool, default=False
        Also return the arguments given to ``fit``.

    Returns
    -------
    pysindy_xl.XLSINDy or tuple
        The fitted model, or ``(model, arguments)``.

    Raises
    ------
    CLIError
        When an option is invalid or the identification fails.
    """
    import pysindy_xl as px
    from pysindy_xl.mujoco.catalogs.reference import reference_catalog
    optimizer = check_solver(solver, forced, args.threshold,
                             auto=getattr(args, "solver", "auto") == "auto")
    try:
        catalog = reference_catalog(system, args.catalog, velocity_degree=args.velocity_degree,
                                    trig_degree=args.trig_degree, friction=args.friction,
                                    joint_models=getattr(args, "joint_models", None),
                                    **({"coulomb_law": coulomb_law(args, dataset)}
                                       if args.catalog == "kinematic" else {}))
    except ValueError as error:
        if str(error).startswith("coulomb_law:"):
            raise CLIError(f"--coulomb-law: {str(error).split(': ', 1)[1]}") from None
        if not str(error).startswith(("friction:", "joint_models:")):
            raise
        raise CLIError(f"--joint-models: {str(error).split(': ', 1)[1]}") from None
    model = px.XLSINDy(catalog, optimizer, formulation=getattr(args, "formulation", "auto"),
                       **({} if getattr(args, "hold_still", True) else {"hold_still": False}))
    try:
        arguments = dataset.fit_arguments(forces="tau" if forced else None,
                                          constraints=getattr(args, "constraints", "exclude"))
        model.fit(**arguments)
    except (RuntimeError, ValueError, np.linalg.LinAlgError) as error:
        raise CLIError(f"identification failed ({type(error).__name__}): {error}") from None
    return (model, arguments) if return_arguments else model


def summarize_coefficients(system, model):
    """True coefficients and errors against them (None for systems without ground truth).

    Parameters
    ----------
    system : MuJoCoSystem
        The system.
    model : pysindy_xl.XLSINDy
        The fitted model.

    Returns
    -------
    truth : numpy.ndarray or None
        The true coefficients (scaled like an implicit law), None without ground truth.
    summary : dict
        ``max_relative_error``, ``true_terms``, ``identified_terms``, ``support_recovered`` and
        ``true_model_missing_from_catalog`` (empty without ground truth).
    """
    from pysindy_xl.mujoco.catalogs.reference import true_coefficients
    try:  # known Lagrangians, and the MJCF's own values in its kinematic catalog
        truth, missing = true_coefficients(system, model.feature_library_)
    except ValueError:
        return None, {}
    coef = model.coefficients()
    forces = model.feature_library_.force_columns_
    if not np.allclose(coef[forces], -1.0):
        # an implicit law is defined up to a factor
        rest = np.setdiff1d(np.arange(len(coef)), forces)
        norm = truth[rest] @ truth[rest]
        factor = (coef[rest] @ truth[rest]) / norm if norm > 0 else 1.0
        truth = truth * (factor if factor != 0 else 1.0)
        truth[forces] = coef[forces]
    scale = np.abs(truth).max()
    active = truth != 0
    summary = {"max_relative_error": float(np.abs(coef - truth).max() / scale),
               "true_terms": int(active.sum()),
               "identified_terms": int(np.count_nonzero(coef)),
               "support_recovered": bool(np.array_equal(coef != 0, active)),
               "true_model_missing_from_catalog": missing}
    return truth, summary


def joint_parameters(system, model):
    """Identified joint damping and dry friction next to the MJCF's (user models only).

    Parameters
    ----------
    system : MuJoCoSystem
        The system.
    model : pysindy_xl.XLSINDy
        The fitted model.

    Returns
    -------
    dict
        Per joint, the identified and the MJCF's damping and dry friction (empty for the
        shipped systems).
    """
    if system.has_ground_truth or not hasattr(system, "frictionloss"):
        return {}
    friction = model.physical_parameters()["friction"]
    out = {}
    for i, (joint, name) in enumerate(zip(system.joint_names, system.coordinate_names,
                                          strict=True)):
        found = friction[name]
        entry = {"damping": [found["viscous"], float(system.joint_damping[i])]}
        if found["dry"] or system.frictionloss[i]:
            entry["frictionloss"] = [found["dry"], float(system.frictionloss[i])]
        out[joint] = entry
    return out


def _rounded(expr, digits=4):
    import sympy as sp
    return expr.xreplace({f: sp.Float(f, digits) for f in expr.atoms(sp.Float)})


def model_lines(model, truth=None):
    """The identified model as printed: physical parameters (next to ``truth``'s), Lagrangian
    and equations unless they run for pages, the coordinates held still.

    Parameters
    ----------
    model : pysindy_xl.XLSINDy
        The fitted model.
    truth : array_like, default=None
        True coefficients, whose physical parameters are shown beside.

    Returns
    -------
    list of str
        The lines printed.
    """
    from pysindy_xl.fit.still import held_note
    from pysindy_xl.fitted.equations import (
        parameter_lines,
        physical_parameters,
        prints_equations,
    )
    from pysindy_xl.physical.structure import has_parameter_map
    lines = []
    if has_parameter_map(model.feature_library_):
        reference = (None if truth is None
                     else physical_parameters(np.asarray(truth), model.feature_library_))
        lines += parameter_lines(model.physical_parameters(), 4, reference)
    if prints_equations(model):
        lagrangian = model.lagrangian()
        if lagrangian != 0:
            lines.append(f"L = {_rounded(lagrangian)}")
        lines += [f"({name}) {eq}" for name, eq in
                  zip(model.feature_library_.coords.names, model.equations(), strict=True)]
    note = held_note(model.still_coordinates_)
    return lines + ([note] if note else [])
