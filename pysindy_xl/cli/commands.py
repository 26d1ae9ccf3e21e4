"""The ``run_*`` functions behind the subcommands, and :func:`main`, which dispatches to them
and prints their :class:`~pysindy_xl.cli.steps.CLIError`."""

from __future__ import annotations

import json
import os
import sys
import time

import numpy as np

from ..evaluation.quality import fit_quality, plot_identification, quality_lines
from ..registry import json_finite
from .automatic import honest_exit, run_automatic
from .parser import AUTOMATIC, build_parser
from .steps import (
    CLIError,
    check_solver,
    data_lines,
    dataset_for,
    dataset_system,
    display_name,
    fit_model,
    generate_data,
    joint_parameters,
    log,
    model_lines,
    output_directory,
    output_file,
    resolve_catalog,
    summarize_coefficients,
    system_by_name,
)
from .verdict import held_out_verdict, wants_verdict

__all__ = ["main", "build_parser", "run_demo", "run_identify"]


def run_demo(args) -> dict:
    """Run ``pysindy-xl demo`` with parsed arguments: generate MuJoCo data, identify, validate
    against a fresh trajectory, print; return the report written to ``args.out/report.json``
    (beside ``validation.png`` unless ``--no-plots``).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of ``pysindy-xl demo`` (:func:`build_parser`).

    Returns
    -------
    dict
        The report written to ``args.out/report.json``: the system and options, the data,
        the features and coefficients (``true_coefficients`` where known), the physical
        parameters, the equations, the ``validation`` metrics, the ``physics`` check and
        the timings.

    Raises
    ------
    CLIError
        On a bad input or a failed step, and when the validation is INVALID (after the
        report is written): the ``demo`` command then exits with status 1.

    Examples
    --------
    Half a second of cart-pole data and a short validation (the kinematic catalog):

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as out:
    ...     args = build_parser().parse_args([
    ...         "demo", "cart-pole", "--duration", "0.5", "--trajectories", "1",
    ...         "--validation-duration", "0.2", "--no-plots", "--quiet", "--out", out])
    ...     report = run_demo(args)
    <BLANKLINE>
    base parameters (value  |  true value  |  stands for):
               1.5  |           1.5  |  1*cart.m + 1*pole.m + 1*slider.armature
              -0.4  |          -0.4  |  1*pole.mcz
              0.32  |          0.32  |  1*pole.Iyy + 1*hinge.armature
    friction per coordinate (viscous, dry):
      x: 0.5, 0 (true 0.5, 0)
      theta: 0.1, 0 (true 0.1, 0)
    L = 0.16*theta_dot**2 + 0.4*theta_dot*x_dot*cos(theta) + 0.75*x_dot**2 + 3.924*cos(theta)
    (x) 0.4*theta_ddot*cos(theta) - 0.4*theta_dot**2*sin(theta) + 1.5*x_ddot + 0.5*x_dot = tau_x
    (theta) 0.32*theta_ddot + 0.1*theta_dot + 0.4*x_ddot*cos(theta) + 3.924*sin(theta) = tau_theta
    <BLANKLINE>
    validation: position RMSE ... over 0.2 s, divergence none, VALID
    data:
      sampling every 2 step(s) of 1 ms = 2 ms
    physics against MuJoCo (mj_fullM, qfrc_bias) at 5 states: mass matrix error ...
    coefficients: 6 terms identified, 6 true, max error ... (relative to the largest)
    report: .../report.json (... s)
    >>> report["validation"]["valid"], report["coefficient_summary"]["support_recovered"]
    (True, True)
    """
    system = system_by_name(args.system, args.joints)
    resolve_catalog(args, system)
    solver = args.forcing if args.solver == "auto" else args.solver
    forced = args.forcing != "implicit"
    check_solver(solver, forced, args.threshold, auto=args.solver == "auto")
    output_directory(args.out)
    timings = {}
    quiet = args.quiet
    log(quiet, f"pysindy-xl demo: {display_name(system)} {system.parameters}")
    log(quiet, f"  forcing {args.forcing}, noise {args.noise:g} ({args.noise_model}), catalog "
                f"{args.catalog}, solver {solver}, seed {args.seed}")

    start = time.perf_counter()
    log(quiet, f"[1/3] MuJoCo: {args.trajectories} trajectories of {args.duration:g} s")
    dataset = generate_data(system, args, progress=None if not quiet else False)
    timings["generate"] = time.perf_counter() - start
    if args.save_data:
        dataset.save(os.path.join(args.out, "training_data.npz"))

    start = time.perf_counter()
    n_samples = sum(tr.n_samples for tr in dataset.trajectories)
    log(quiet, f"[2/3] identification on {n_samples} samples")
    model = fit_model(system, dataset, args, solver, forced)
    timings["identify"] = time.perf_counter() - start
    truth, coefficient_summary = summarize_coefficients(system, model)

    start = time.perf_counter()
    log(quiet, f"[3/3] validation against a fresh {args.validation_duration:g} s MuJoCo "
                "trajectory")
    result, failure = _validate(model, system, args)
    timings["validate"] = time.perf_counter() - start

    files = {}
    start = time.perf_counter()
    if not args.no_plots and result is not None:
        from pysindy_xl.evaluation.plots import plot_validation
        path = os.path.join(args.out, "validation.png")
        plot_validation(result, path, model.get_feature_names(), model.coefficients(), truth,
                        title=f"{display_name(system)} ({args.catalog} catalog, {solver} solver)")
        files["validation_plot"] = path
        timings["plot"] = time.perf_counter() - start

    print()
    for line in model_lines(model, truth):
        print(line)
    print()
    metrics = result.to_dict() if result is not None else {"valid": False, "failure": failure}
    print(_validation_line(result, failure, args))
    print("data:")
    print(*data_lines(system, dataset), sep="\n")
    joints = joint_parameters(system, model)
    for joint, entry in joints.items():
        print(f"  {joint}: " + ", ".join(f"{key} {found:.4g} (MJCF {given:.4g})"
                                         for key, (found, given) in entry.items()))
    physics = _physics(model, system, args) if result is not None else None
    for line in _physics_lines(physics, system):
        print(line)
    if coefficient_summary:
        print(f"coefficients: {coefficient_summary['identified_terms']} terms identified, "
              f"{coefficient_summary['true_terms']} true, max error "
              f"{coefficient_summary['max_relative_error']:.2g} (relative to the largest)")
    timings["total"] = sum(timings.values())
    from ..fitted.equations import prints_equations  # sympy: not imported by --help
    short = prints_equations(model)
    report = {
        "system": system.name,
        "parameters": system.parameters,
        "options": {k: v for k, v in vars(args).items() if k != "func"},
        "solver": solver,
        "n_samples": n_samples,
        "data": {key: dataset.metadata.get(key) for key in (
            "noise", "noise_model", "derivatives", "timestep", "sample_every", "constraints",
            "integrator", "substeps", "integration", "peak_velocity")},
        "excluded_joints": list(getattr(system, "excluded_joints", ())),
        "joint_parameters": joints,
        "physics": physics,
        "features": model.get_feature_names(),
        "coefficients": model.coefficients().tolist(),
        "true_coefficients": None if truth is None else truth.tolist(),
        "dropped_features": model.dropped_features_,
        "still_coordinates": list(model.still_coordinates_),
        "physical_parameters": model.physical_parameters(),
        # a robot's equations run for pages (and take minutes to print): its parameters stand
        # for it; XLSINDy.equations() still gives them
        "lagrangian": str(model.lagrangian()) if short else None,
        "equations": model.equations() if short else None,
        "coefficient_summary": coefficient_summary,
        "validation": metrics,
        "timings_s": timings,
        "files": files,
    }
    path = os.path.join(args.out, "report.json")
    with open(path, "w", encoding="utf-8") as handle:
        json.dump(json_finite(report), handle, indent=2, allow_nan=False)
    print(f"report: {path}" + (f", plot: {files['validation_plot']}" if files else "")
          + f" ({timings['total']:.1f} s)")
    if not metrics["valid"]:  # the report stays, for a look at what went wrong
        raise CLIError("validation: the identified model does not reproduce a fresh "
                       f"trajectory ({metrics.get('failure') or 'INVALID'}); try longer or "
                       "more trajectories (--duration, --trajectories), a larger catalog "
                       "(--trig-degree) or another --solver")
    return report


def _validate(model, system, args):
    """``(ValidationResult, None)`` against a fresh MuJoCo run, or ``(None, reason)``."""
    from pysindy_xl.dynamics import DynamicsError
    from pysindy_xl.evaluation.validation import validate_model
    try:
        return validate_model(model, system, duration=args.validation_duration,
                              forcing=args.forcing, actuators=args.actuators,
                              seed=args.seed + 10_000, initial_scale=args.initial_scale,
                              amplitude=args.amplitude, timeout=120.0), None
    except (DynamicsError, ValueError) as error:
        return None, str(error)


def _validation_line(result, failure, args) -> str:
    """The verdict line of the demo."""
    if result is None:
        return f"validation: INVALID ({failure})"
    divergence = ("none" if result.divergence_time is None
                  else f"at {result.divergence_time:.3g} s")
    rmse = (f"{result.position_rmse:.3g}" if np.isfinite(result.position_rmse) else
            f"inf (simulated {result.simulated_fraction:.0%} of the horizon)")
    horizon = f"{args.validation_duration:g} s"
    if result.constrained_at is not None:
        horizon = (f"{result.constrained_at:.3g} s (a joint limit or contact acts in the "
                   "MuJoCo reference from then on)")
    drive = ""
    if result.drive == "closed-loop":  # servos: the MJCF's actuator law acts on the model
        drive = (" (closed loop: the MJCF's servos track the reference controls; actuator "
                 f"force error {result.force_error:.2g})")
    return (f"validation{drive}: position RMSE {rmse} over {horizon}, divergence "
            f"{divergence}, {'VALID' if result.valid else 'INVALID'}"
            + (f" ({result.failure})" if result.failure else ""))


def _physics(model, system, args):
    """The identified mass matrix and unforced dynamics against MuJoCo's, or None."""
    from pysindy_xl.dynamics import DynamicsError
    from pysindy_xl.evaluation.physics import compare_physics
    try:
        return compare_physics(model, system, seed=args.seed)
    except (DynamicsError, ValueError, TypeError, np.linalg.LinAlgError):
        return None


def _physics_lines(physics, system) -> list:
    """What :func:`_physics` found, with advice for coordinates without inertia."""
    if physics is None:
        return []
    definite = "" if physics["positive_definite"] else ", mass matrix NOT positive definite"
    lines = [f"physics against MuJoCo (mj_fullM, qfrc_bias) at 5 states: mass matrix error "
             f"{physics['mass_error']:.2g}, unforced dynamics error "
             f"{physics['force_error']:.2g} (relative){definite}"]
    if physics["unidentified"]:
        names = set(physics["unidentified"])
        keep = [j for j, c in zip(system.joint_names, system.coordinate_names, strict=True)
                if c not in names]
        hint = f" (--joints {' '.join(keep)})" if keep and hasattr(system, "frictionloss") \
            else ""
        lines.append(f"no inertia identified for {', '.join(physics['unidentified'])}: no "
                     "force excites these coordinates (a passive, decoupled body?); leave "
                     f"their joints out{hint}")
    return lines


def run_identify(args):
    """Run ``pysindy-xl identify`` with parsed arguments: fit the dataset's reference catalog
    (solver from its forces with ``--solver auto``), print the model and its quality, score
    held-out torques, save it with ``--out``; return the fitted model.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of ``pysindy-xl identify`` (:func:`build_parser`).

    Returns
    -------
    pysindy_xl.XLSINDy
        The fitted model.

    Raises
    ------
    CLIError
        On a bad input or a failed step.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from pysindy_xl.mujoco import generate_dataset
    >>> data = generate_dataset("cart-pole", n_trajectories=1, duration=0.5, seed=0,
    ...                         progress=False)
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = data.save(pathlib.Path(tmp) / "cart_pole.npz")
    ...     args = build_parser().parse_args(["identify", str(path), "--trig-degree", "1"])
    ...     model = run_identify(args)
    cart-pole: 1 trajectories, 501 samples, kinematic catalog, explicit solver, strong formulation
    base parameters (value  |  stands for):
               1.5  |  1*cart.m + 1*pole.m + 1*slider.armature
              -0.4  |  1*pole.mcz
              0.32  |  1*pole.Iyy + 1*hinge.armature
    friction per coordinate (viscous, dry):
      x: 0.5, 0
      theta: 0.1, 0
    L = 0.16*theta_dot**2 + 0.4*theta_dot*x_dot*cos(theta) + 0.75*x_dot**2 + 3.924*cos(theta)
    (x) 0.4*theta_ddot*cos(theta) - 0.4*theta_dot**2*sin(theta) + 1.5*x_ddot + 0.5*x_dot = tau_x
    (theta) 0.32*theta_ddot + 0.1*theta_dot + 0.4*x_ddot*cos(theta) + 3.924*sin(theta) = tau_theta
    fit quality: R^2 = 1.0000 (x 1.0000, theta 1.0000)
      R^2 = 1 - |residual|^2 / |forces|^2 over 1002 rows of the strong form: equations at ...
      1 is exact; the residual is what the identified equations leave unexplained of the ...
    against the true model: max coefficient error ... (relative), support recovered: True
    >>> import numpy as np
    >>> len(model.get_feature_names()), int(np.count_nonzero(model.coefficients()))
    (9, 6)
    """
    quiet = getattr(args, "quiet", True)
    started = time.perf_counter()

    def progress(message):
        if not quiet:
            print(f"[{time.perf_counter() - started:6.1f} s] {message}", file=sys.stderr,
                  flush=True)

    dataset, system = _identify_inputs(args)
    resolve_catalog(args, system)
    for path, option in ((args.plot, "--plot"), (getattr(args, "open_loop", None),
                                                  "--open-loop")):
        if path:
            output_file(path, option)
    from ..fit import resolve_formulation
    measured = dataset.has("qd") and dataset.has("qdd")
    formulation = resolve_formulation(args.formulation, measured)
    if not measured:
        print("note: velocities/accelerations missing: "
              + ("weak formulation on smoothed positions" if formulation == "weak" else
                 "strong formulation on differentiated positions (--formulation weak is the "
                 "robust choice for noisy positions)"), file=sys.stderr)
    forced = args.forces == "tau" and dataset.has("tau") and any(
        np.any(tr.tau != 0) for tr in dataset.trajectories)
    verdict = wants_verdict(args, forced)  # held-out torques: the verdict on a robot log
    solver = args.solver
    if solver == "auto" and not forced:
        solver = "implicit"
    elif solver == "auto":
        active = np.any(np.vstack([tr.tau for tr in dataset.trajectories]) != 0, axis=0)
        solver = "explicit" if active.all() else "mixed"
    n_samples = sum(tr.n_samples for tr in dataset.trajectories)
    form = ("weak form: smoothing positions, integrating against test functions"
            if formulation == "weak" else "strong form: catalog at every sample")
    if args.formulation == "auto" and measured:
        form += " (weak if the catalog has impulses)"
    progress(f"building the {args.catalog} catalog of {display_name(system)} and fitting "
             f"({form}, {solver} regression with sparsity selection) on {n_samples} samples")
    growth = None
    if args.catalog == AUTOMATIC:
        model, growth, arguments = run_automatic(args, dataset, system, forced, progress)
    else:
        model, arguments = fit_model(system, dataset, args, solver, forced,
                                     return_arguments=True)
    progress(f"fitted: {int(np.count_nonzero(model.coefficients()))} terms of "
             f"{len(model.get_feature_names())}; computing the fit quality")
    print(f"{display_name(system)}: {dataset.n_trajectories} trajectories, {n_samples} samples, "
          f"{args.catalog} catalog, {solver} solver, {model.formulation_} formulation")
    for line in model_lines(model):
        print(line)
    try:
        quality = fit_quality(model, arguments)
    except (ValueError, np.linalg.LinAlgError) as error:  # pragma: no cover - reported
        quality = None
        print(f"fit quality: not available ({error})")
    if quality is not None:
        print(*quality_lines(quality), sep="\n")
    honest_exit(None if quality is None else quality["r2"],
                None if growth is None else growth.held_out_error,
                getattr(args, "max_terms", 400) if growth is None else growth.max_terms,
                model.mass_matrix_check_, None if growth is None else growth.own_runs)
    if system.has_ground_truth:
        _, summary = summarize_coefficients(system, model)
        print(f"against the true model: max coefficient error {summary['max_relative_error']:.2g} "
              f"(relative), support recovered: {summary['support_recovered']}")
    score = None
    if verdict and model.dynamics_ is None:
        print("held-out torque prediction: not available (the identified equations contain "
              "no acceleration)")
    elif verdict:
        score = held_out_verdict(args, model, system, arguments,
                                 lambda path: _load(args, path, system), progress)
        if args.plot:
            score.plot(args.plot, title=f"{display_name(system)}: held-out torques, measured and "
                                        f"predicted ({100 * score.total:.2f} % relative RMS)")
            print(f"torque plot: {args.plot} (measured against predicted torques)")
    replay = getattr(args, "open_loop", None) or (args.plot if score is None else None)
    if replay:  # open loop: a fair check of a free system, not of an arm under feedback
        progress(f"simulating the model from the first trajectory's initial state for {replay}")
        if model.dynamics_ is None:
            raise CLIError("--plot: the identified equations contain no acceleration; "
                           "nothing to simulate")
        result = plot_identification(
            model, dataset.trajectories[0], replay, forced=forced,
            title=f"{display_name(system)}: identified model against trajectory 0\n({args.catalog} "
                  f"catalog, {solver} solver, {model.formulation_} form)")
        rmse = ", ".join(f"{name} {value:.3g}" for name, value in
                         zip(model.feature_library_.coords.names, result["rmse"], strict=True))
        span = dataset.trajectories[0].t
        status = (f"diverged at {result['simulated_until']:.3g} s" if result["diverged"]
                  else f"over {span[-1] - span[0]:.3g} s")
        print(f"validation plot: {replay} (position RMSE {rmse}, {status})")
    if args.out:
        _save_atomically(model, args.out)
        print(f"model: {args.out}")
    progress("done")
    return model


def _column_map(items):
    """``--column KEY=HEADER`` options as a dict."""
    columns = {}
    for item in items or []:
        key, sep, header = item.partition("=")
        if not sep or not key.strip() or not header.strip():
            raise CLIError(f"--column: expected KEY=HEADER (e.g. t=time_s), got {item!r}")
        columns[key.strip()] = header.strip()
    return columns


def _names(text, option="--coordinates"):
    """The comma-separated names of ``option`` (None when not given); a name twice refused."""
    names = [c.strip() for c in text.split(",") if c.strip()] if text else None
    twice = sorted({name for name in names or () if names.count(name) > 1})
    if twice:
        raise CLIError(f"{option}: the names {twice} are given more than once")
    return names


def _load(args, path, system=None):
    """A data file of ``identify`` (DATA or --validate) read with the column options; a ROS
    bag's joints are the system's unless named."""
    from pysindy_xl.data import DatasetError, load_data
    from pysindy_xl.data.rosbag import is_rosbag
    columns = _column_map(getattr(args, "column", None))
    coordinates = _names(args.coordinates)
    if path.lower().endswith(".npz") and (columns or args.delimiter):
        raise CLIError(f"--column/--delimiter: apply to CSV files, not to the NPZ {path!r}")
    bag = is_rosbag(path)
    if getattr(args, "topic", None) and not bag:
        raise CLIError(f"--topic: applies to ROS bags, not to {path!r}")
    if bag and coordinates is None and hasattr(system, "joint_names"):
        coordinates = list(system.coordinate_names)
        columns = {**dict(zip(system.coordinate_names, system.joint_names, strict=True)),
                   **columns}
    try:
        return load_data(path, coordinates=coordinates, columns=columns or None,
                         delimiter=args.delimiter, **({"topic": args.topic} if bag else {}))
    except (DatasetError, ValueError) as error:
        raise CLIError(str(error)) from None


def _identify_inputs(args):
    """The dataset of ``identify`` (CSV or NPZ) and the system naming its coordinates."""
    from pysindy_xl.mujoco import coordinate_system
    coordinates, angles = _names(args.coordinates), _names(args.angles, "--angles") or []
    if args.system and args.angles:
        raise CLIError("--angles: the system gives the angles; use --angles with "
                       "--coordinates (no --system)")
    given = system_by_name(args.system) if args.system else None
    dataset = _load(args, args.data, given)
    name = args.system or (None if coordinates else dataset.metadata.get("system"))
    if name:
        if args.angles:
            raise CLIError("--angles: the system gives the angles; use --angles with "
                           "--coordinates (no --system)")
        system = given or dataset_system(dataset.metadata)
        if given is not None:
            system = _joints_of_the_log(system, dataset, args.system)
        return dataset_for(system, dataset), system
    if not args.data.lower().endswith(".npz") or coordinates:
        if not angles:
            print("note: no --angles: the catalog has no sin/cos terms of the positions",
                  file=sys.stderr)
        try:
            return dataset, coordinate_system(dataset.coordinate_names, angles)
        except ValueError as error:
            raise CLIError(f"--angles: {error}") from None
    raise CLIError("--system: the dataset names no system; pass --system NAME (or an MJCF "
                   ".xml), or --coordinates x,theta [--angles theta]")


def _joints_of_the_log(system, dataset, path):
    """The system restricted to the joints its log records (a URDF with gripper fingers), the
    others locked at their reference pose."""
    names = dataset.coordinate_names
    others = [c for c in system.coordinate_names if c not in names]
    if (not others or not set(names) < set(system.coordinate_names)
            or not str(path).lower().endswith((".xml", ".urdf"))):
        return system
    print(f"note: joints not in the data are locked at their reference pose: "
          f"{', '.join(others)}", file=sys.stderr)
    return system_by_name(path, list(names))


def _save_atomically(model, path):
    """Write the model to ``path`` through a temporary file: never a half-written file."""
    directory = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(directory):
        raise CLIError(f"--out: directory {directory!r} does not exist")
    base, ext = os.path.splitext(os.path.basename(path))
    tmp = os.path.join(directory, f".{base}.{os.getpid()}.tmp{ext}")
    try:
        model.save(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def run_generate(args):
    """Run ``pysindy-xl generate``; returns the NPZ path written (the JSON beside it).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of ``pysindy-xl generate`` (:func:`build_parser`).

    Returns
    -------
    pathlib.Path
        The NPZ file written.

    Raises
    ------
    CLIError
        On a bad input.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     args = build_parser().parse_args(["generate", "cart-pole", f"{tmp}/data.npz",
    ...                                       "--duration", "0.2", "--trajectories", "1"])
    ...     path = run_generate(args)
    wrote .../data.npz and .../data.json: Dataset(coordinates=['x', 'theta'], trajectories=1,
    samples=101)
      sampling every 2 step(s) of 1 ms = 2 ms
    """
    system = system_by_name(args.system, args.joints)
    output_file(args.out, "DATA.npz")
    dataset = generate_data(system, args)
    path = dataset.save(args.out)
    print(f"wrote {path} and {path.with_suffix('.json')}: {dataset}")
    print(*data_lines(system, dataset), sep="\n")
    return path


def main(argv=None) -> int:
    """Entry point of the ``pysindy-xl`` command on ``argv`` (default ``sys.argv[1:]``);
    returns the exit status: 0 on success, 1 on an error (printed on stderr, no traceback),
    2 on a usage error.

    Parameters
    ----------
    argv : list of str, default=None
        The arguments; None: ``sys.argv[1:]``.

    Returns
    -------
    int
        The exit status: 0 on success, 1 on an error, 2 on a usage error.

    Examples
    --------
    >>> import contextlib, sys
    >>> with contextlib.redirect_stderr(sys.stdout):
    ...     status = main(["identify", "missing.npz", "--system", "cart-pole"])
    pysindy-xl: error: path: dataset file 'missing.npz' does not exist
    >>> status
    1
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command in ("benchmark", "control"):
        return args.func(args)
    commands = {"demo": run_demo, "identify": run_identify, "generate": run_generate}
    try:
        if args.command == "identify" and args.out:
            output_file(args.out, "--out")  # before fitting, not after
        commands[args.command](args)
    except CLIError as error:
        print(f"pysindy-xl: error: {error}", file=sys.stderr)
        return 1
    return 0

