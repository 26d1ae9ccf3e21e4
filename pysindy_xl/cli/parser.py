"""The argument parser of the ``pysindy-xl`` command: sub-commands, options, value types."""

from __future__ import annotations

import argparse

from .._validation import argument_type

SOLVERS = ("auto", "explicit", "implicit", "mixed")
CATALOGS = ("lagrange", "classical", "mixed", "kinematic")
#: ``identify`` only: the catalog grown on the data (:mod:`pysindy_xl.cli.automatic`)
AUTOMATIC = "automatic"
FORCINGS = ("explicit", "implicit", "mixed")
NOISE_MODELS = ("positions", "all")
CONSTRAINTS = ("exclude", "known", "include")
FORMULATIONS = ("auto", "strong", "weak")


_non_negative_float = argument_type("real", low=0)
_positive_float = argument_type("real", low=0, low_open=True)
_fraction = argument_type("real", low=0, low_open=True, high=1)
_positive_int = argument_type("int", low=1)


def _bandwidth(text):
    """A positive frequency, or ``inf``."""
    return float("inf") if text.strip().lower() == "inf" else _positive_float(text)


def _max_terms(text):
    """A positive integer, or ``auto`` (the ceiling follows the data)."""
    return "auto" if text.strip().lower() == "auto" else _positive_int(text)


def _joint_models(text):
    """``all`` or comma-separated joint model names (checked by the kinematic catalog)."""
    names = tuple(name.strip() for name in text.split(",") if name.strip())
    if not names:
        raise argparse.ArgumentTypeError("expected 'all' or comma-separated model names")
    return "all" if names == ("all",) else names


def _add_generation_options(parser, duration=10.0, trajectories=2):
    parser.add_argument("--forcing", choices=FORCINGS, default="explicit",
                        help="implicit: no force, random initial state; explicit: every "
                             "actuator driven; mixed: a subset (--actuators) (default: explicit)")
    parser.add_argument("--actuators", nargs="+", metavar="NAME",
                        help="joints driven with --forcing mixed (default: the system's choice)")
    parser.add_argument("--noise", type=_non_negative_float, default=0.0,
                        help="relative Gaussian noise: std = NOISE x each coordinate's std "
                             "(default: 0)")
    parser.add_argument("--noise-model", choices=NOISE_MODELS, default="positions",
                        help="positions: noisy positions only, not velocities or accelerations; "
                             "all: the paper's model, noise on every series (default: positions)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    parser.add_argument("--duration", type=_positive_float, default=duration,
                        help=f"seconds per training trajectory (default: {duration:g})")
    parser.add_argument("--trajectories", type=_positive_int, default=trajectories,
                        help=f"number of training trajectories (default: {trajectories})")
    parser.add_argument("--sample-every", type=_positive_int, default=2,
                        help="keep every k-th step of the model's timestep (default: 2)")
    parser.add_argument("--amplitude", type=_fraction, default=None,
                        help="forcing peak as a fraction of each actuator's ctrlrange "
                             "half-width, in (0, 1] (default: 0.5, or the system's amplitudes)")
    parser.add_argument("--initial-scale", type=_non_negative_float, default=1.0,
                        help="spread of the random initial states, as a fraction of the joint "
                             "ranges (default: 1)")
    parser.add_argument("--joints", nargs="+", metavar="NAME", default=None,
                        help="MJCF models: identify these joints only; the others are locked "
                             "at their reference pose (removed with their actuators)")


def _add_fit_options(parser, coulomb_law="smooth", automatic=False):
    if automatic:
        from .automatic import WHAT_IS_TRIED
        parser.add_argument("--catalog", choices=(*CATALOGS, AUTOMATIC, "auto"), default="auto",
                            help="lagrange, classical, mixed (Lagrange + friction), kinematic "
                                 "(from the kinematic tree) or " + WHAT_IS_TRIED + "; auto: "
                                 "kinematic for a MuJoCo model, mixed with --velocity-degree "
                                 "or --trig-degree, else automatic (default: auto)")
        parser.add_argument("--max-terms", type=_max_terms, default="auto",
                            help="automatic catalog: ceiling on its size; larger catalogs are "
                                 "not tried; auto: two thirds of the equations of the search's "
                                 "fits, at most 400 (default: auto)")
        parser.add_argument("--n-jobs", type=_positive_int, default=1, metavar="N",
                            help="automatic catalog: processes of the search (while one "
                                 "candidate catalog is fitted, N - 1 workers fit the next ones; "
                                 "the result does not depend on N) (default: 1)")
    else:
        parser.add_argument("--catalog", choices=(*CATALOGS, "auto"), default="auto",
                            help="lagrange, classical, mixed (Lagrange + friction) or kinematic "
                                 "(from the kinematic tree); auto: kinematic for a MuJoCo model, "
                                 "else mixed (default: auto)")
    parser.add_argument("--solver", choices=SOLVERS, default="auto",
                        help="explicit, implicit or mixed regression; auto follows the forcing "
                             "and bags explicit fits of positions-only data (default: auto)")
    parser.add_argument("--threshold", type=_non_negative_float, default=None,
                        help="relative pruning threshold of the explicit solver")
    parser.add_argument("--friction", choices=("auto", "diagonal", "full"), default="auto",
                        help="friction terms of the catalogs (default: auto)")
    parser.add_argument("--joint-models", type=_joint_models, default=None, metavar="MODELS",
                        help="kinematic catalog: joint models offered to every joint, "
                             "comma-separated among viscous, coulomb, asymmetric, stribeck, "
                             "offset, or all (default: viscous and smooth Coulomb)")
    parser.add_argument("--coulomb-law", choices=("smooth", "mujoco"), default=None,
                        help="kinematic catalog: law of the Coulomb candidates, smooth (tanh) "
                             f"or mujoco (MuJoCo's frictionloss) (default: {coulomb_law}, mujoco "
                             "for a dataset MuJoCo generated, smooth with --joint-models)")
    parser.set_defaults(default_coulomb_law=coulomb_law)
    parser.add_argument("--velocity-degree", type=_positive_int, default=None,
                        help="degree of the velocity monomials of the reference catalogs "
                             "(default: 2)")
    parser.add_argument("--trig-degree", type=_positive_int, default=None,
                        help="degree of the sin/cos monomials of the reference catalogs "
                             "(default: 2)")
    parser.add_argument("--formulation", choices=FORMULATIONS, default="auto",
                        help="strong: equations at each sample; weak: equations integrated "
                             "against test functions on smoothed positions (robust to noise); "
                             "auto: strong when the data have velocities and accelerations and "
                             "the catalog no impulse, else weak (default: auto)")
    parser.add_argument("--no-hold-still", dest="hold_still", action="store_false",
                        help="fit every coordinate, also those that hold still in the data "
                             "(by default the model holds them)")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``pysindy-xl`` command: ``demo``, ``identify``, ``generate``,
    ``benchmark`` and ``control`` (:doc:`/cli` describes every option).

    Returns
    -------
    argparse.ArgumentParser
        The parser, one subcommand each.

    Examples
    --------
    >>> args = build_parser().parse_args(["demo", "double-pendulum", "--noise", "0.01"])
    >>> args.command, args.system, args.noise, args.catalog, args.solver, args.forcing
    ('demo', 'double-pendulum', 0.01, 'auto', 'auto', 'explicit')
    """
    parser = argparse.ArgumentParser(prog="pysindy-xl", description="Identify mechanical "
                                     "systems with XLSINDy: MuJoCo demos and your data.")
    from .. import __version__
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    from ..benchmark import add_parser as add_benchmark_parser
    add_benchmark_parser(sub)
    from ..control.command import add_parser as add_control_parser
    add_control_parser(sub)

    demo = sub.add_parser("demo", help="generate MuJoCo data, identify, validate, plot",
                          description="Generate randomly forced MuJoCo trajectories of a system, "
                          "identify its equations of motion, validate the model against a fresh "
                          "trajectory, print the equations and metrics, and write plots and a "
                          "JSON report. Exits with status 1 when the model fails the "
                          "validation (the report is still written).")
    demo.add_argument("system", metavar="SYSTEM",
                      help="cart-pole, double-pendulum, cart-double-pendulum, triple-pendulum, "
                           "an MJCF .xml or a URDF .urdf")
    _add_generation_options(demo)
    _add_fit_options(demo, coulomb_law="mujoco")  # the demo's data come from MuJoCo
    demo.add_argument("--constraints", choices=CONSTRAINTS, default="exclude",
                      help="samples where a constraint acts: exclude them, pass the recorded "
                           "constraint forces as known, or include them (default: exclude)")
    demo.add_argument("--validation-duration", type=_positive_float, default=4.0,
                      help="seconds of the validation trajectory (default: 4)")
    demo.add_argument("--out", default="pysindy-xl-demo", metavar="DIR",
                      help="output directory for report.json and plots (default: "
                           "./pysindy-xl-demo)")
    demo.add_argument("--save-data", action="store_true", help="also write the training data")
    demo.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    demo.add_argument("--quiet", action="store_true", help="print only the final summary")

    identify = sub.add_parser("identify", help="fit your data (CSV or NPZ) and print the model",
                              description="Fit a dataset and print the model: with a MuJoCo "
                              "model, its kinematic catalog; given only coordinates, a catalog "
                              "grown on the data (--catalog automatic). A fit that explains "
                              "nothing (R^2 below 0.5, held-out error above 50 %), or whose "
                              "mass matrix is not positive definite on its own training states "
                              "(the fit's warning), exits with status 1 and says what to try. "
                              "CSV (.csv, .txt, .tsv): columns t, NAME, optionally "
                              "NAME_dot, NAME_ddot, tau_NAME, trajectory; --column maps other "
                              "headers. NPZ: arrays t, q, optionally qd, qdd, tau, trajectory. "
                              "Coordinates come from --system, --coordinates/--angles, or the "
                              "CSV header.")
    identify.add_argument("data", metavar="DATA",
                          help="a .csv, .tsv, .txt or .npz file, or a ROS bag of "
                               "sensor_msgs/JointState (.bag, or a ROS 2 bag directory)")
    identify.add_argument("--topic", default=None, metavar="NAME",
                          help="ROS bags: the JointState topic (default: the only one)")
    identify.add_argument("--coordinates", default=None, metavar="NAMES",
                          help="comma-separated coordinate names, e.g. x,theta (CSV: the "
                               "position columns; NPZ: names of q's columns)")
    identify.add_argument("--angles", default=None, metavar="NAMES",
                          help="comma-separated coordinates that are angles (enter the catalog "
                               "through sin and cos), e.g. theta")
    identify.add_argument("--column", action="append", default=[], metavar="KEY=HEADER",
                          help="CSV header of a role KEY (t, trajectory, NAME, NAME_dot, "
                               "NAME_ddot, tau_NAME), repeatable: --column t=time_s")
    identify.add_argument("--delimiter", default=None,
                          help="CSV field separator (default: tab for .tsv, comma otherwise)")
    identify.add_argument("--system", default=None,
                          help="system name, MJCF .xml or URDF .urdf giving coordinates and "
                               "catalog (default: the dataset's metadata)")
    _add_fit_options(identify, automatic=True)
    identify.add_argument("--forces", choices=("tau", "none"), default="tau",
                          help="use the dataset's generalized forces or fit unforced "
                               "(default: tau when present)")
    identify.add_argument("--out", default=None, metavar="FILE.json",
                          help="write the fitted model (JSON) there")
    identify.add_argument("--validate", action="append", default=None, metavar="TEST",
                          help="held-out data (as DATA, with forces; repeatable): score the "
                               "torques the model predicts there, per coordinate")
    identify.add_argument("--cv-blocks", type=int, default=5, metavar="K",
                          help="without --validate, score a log with forces and --system by "
                               "time-blocked cross-validation in K blocks; 0 skips it (default: 5)")
    identify.add_argument("--bandwidth", type=_bandwidth, default=10.0, metavar="HZ",
                          help="held-out scoring without accelerations: highest frequency the "
                               "differentiating spline keeps (inf: from the data) (default: 10)")
    identify.add_argument("--plot", default=None, metavar="FILE.png",
                          help="plot the verdict: measured against predicted held-out torques, "
                               "else the open-loop replay")
    identify.add_argument("--open-loop", default=None, metavar="FILE.png",
                          help="plot an open-loop replay of the first trajectory under its "
                               "recorded forces (an arm under feedback diverges anyway)")
    identify.add_argument("--quiet", action="store_true",
                          help="no progress lines (on stderr) during the identification")

    generate = sub.add_parser("generate", help="write a MuJoCo dataset (NPZ + JSON)")
    generate.add_argument("system", metavar="SYSTEM")
    generate.add_argument("out", metavar="DATA.npz")
    _add_generation_options(generate, trajectories=4)
    return parser
