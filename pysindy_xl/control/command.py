"""The ``pysindy-xl control`` sub-command: the learning loop on a MuJoCo plant, a JSON report.

Registered by :func:`add_parser` on the ``pysindy-xl`` parser; :func:`run_control` runs it.
Progress goes to stderr; the report (:meth:`~.loop.LearningResult.to_dict`) to ``--out``."""

from __future__ import annotations

import json
import sys

from .._validation import argument_type

__all__ = ["add_parser", "run_control"]

_positive_float = argument_type("real", low=0, low_open=True)
_non_negative_float = argument_type("real", low=0)
_positive_int = argument_type("int", low=1)
_SYSTEMS = ("cart-pole", "cart-double-pendulum")


def add_parser(subparsers):
    """Register the ``control`` sub-command on argparse subparsers.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        What ``ArgumentParser.add_subparsers`` returns.

    Returns
    -------
    argparse.ArgumentParser
        The ``control`` parser; the parsed namespace's ``func(args)`` (:func:`run_control`)
        runs it and returns the exit status.

    Examples
    --------
    >>> import argparse
    >>> parser = argparse.ArgumentParser()
    >>> _ = add_parser(parser.add_subparsers(dest="command"))
    >>> args = parser.parse_args(["control", "cart-pole", "--force-limit", "8"])
    >>> args.task, args.force_limit, args.noise, args.catalog
    ('swing-up', 8.0, 0.01, 'automatic')
    """
    parser = subparsers.add_parser(
        "control", help="learn to control a MuJoCo system: explore, identify, swing up",
        description="Run the learning loop on a MuJoCo plant: excite it within the limits, "
                    "identify its equations from noisy positions, control it with sampling "
                    "MPC (and LQR near the goal) on the identified model, and repeat with the "
                    "new data until the task succeeds. Progress on stderr; a JSON report.")
    parser.add_argument("system", metavar="SYSTEM", choices=_SYSTEMS,
                        help="cart-pole or cart-double-pendulum")
    parser.add_argument("--task", default="swing-up", choices=("swing-up",),
                        help="the task (default: swing-up: from hanging to upright, held 2 s)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    parser.add_argument("--force-limit", type=_positive_float, default=None, metavar="N",
                        help="largest force on the cart (default: 10 for the cart-pole, 20 for "
                             "the cart double pendulum)")
    parser.add_argument("--track-limit", type=_positive_float, default=1.5, metavar="M",
                        help="half length of the track (default: 1.5)")
    parser.add_argument("--noise", type=_non_negative_float, default=0.01, metavar="LEVEL",
                        help="relative noise on the recorded positions (default: 0.01)")
    parser.add_argument("--catalog", default="automatic",
                        choices=("automatic", "generic", "kinematic"),
                        help="automatic: the automatic catalog grown on the data from the "
                             "coordinates and their kinds only (hinges angles, slides linear), "
                             "sized for the data; generic: a fixed catalog from the coordinates "
                             "and their kinds; kinematic: from the MJCF's kinematic tree "
                             "(default: automatic)")
    parser.add_argument("--explore", type=_positive_float, default=None, metavar="SECONDS",
                        help="seconds of the first exploration (default: 2.5 for the "
                             "cart-pole, 8 for the cart double pendulum)")
    parser.add_argument("--max-episodes", type=_positive_int, default=6,
                        help="most episodes on the plant (default: 6)")
    parser.add_argument("--n-jobs", type=int, default=None, metavar="N",
                        help="processes of the automatic catalog's growth (-1: all cores; "
                             "the result does not depend on it; default: 1)")
    parser.add_argument("--out", default=None, metavar="FILE.json",
                        help="write the JSON report there (default: stdout)")
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")
    parser.set_defaults(func=run_control)
    return parser


def run_control(args) -> int:
    """Run ``pysindy-xl control`` with parsed arguments.

    The JSON report (:meth:`~pysindy_xl.control.loop.LearningResult.to_dict`) goes to
    ``args.out`` (stdout without it), progress to stderr unless ``args.quiet``.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed by the parser of :func:`add_parser`: ``system``, ``task``, ``seed``,
        ``force_limit``, ``track_limit``, ``noise``, ``catalog``, ``explore``,
        ``max_episodes``, ``n_jobs`` (optional), ``out`` and ``quiet``.

    Returns
    -------
    int
        Exit status: 0 when the task succeeded, 3 when it did not, 1 on an error in the
        arguments (printed on stderr).

    Examples
    --------
    >>> import argparse
    >>> parser = argparse.ArgumentParser()
    >>> _ = add_parser(parser.add_subparsers(dest="command"))
    >>> args = parser.parse_args(["control", "cart-pole", "--force-limit", "8", "--quiet"])
    >>> args.func is run_control
    True
    >>> args.task = "balance"  # an unknown task: status 1
    >>> run_control(args)  # the message goes to stderr
    1
    """
    from .catalogs import AutomaticGrowth
    from .loop import learn_to_control

    def log(message):
        if not args.quiet:
            print(f"[control] {message}", file=sys.stderr, flush=True)

    try:
        n_jobs = getattr(args, "n_jobs", None)
        catalog = AutomaticGrowth(n_jobs=n_jobs) \
            if args.catalog == "automatic" and n_jobs is not None else args.catalog
        result = learn_to_control(args.system, args.task, catalog=catalog,
                                  noise=args.noise, seed=args.seed,
                                  force_limit=args.force_limit, track_limit=args.track_limit,
                                  explore_s=args.explore, max_episodes=args.max_episodes,
                                  log=log)
    except (ValueError, TypeError) as error:
        print(f"pysindy-xl: error: {error}", file=sys.stderr)
        return 1
    report = json.dumps(result.to_dict(), indent=2, allow_nan=False, default=float)
    if args.out:
        with open(args.out, "w", encoding="utf-8") as handle:
            handle.write(report + "\n")
    else:
        print(report)
    log(f"{'success' if result.success else 'failure'} after {result.interaction_s:.2f} s of "
        f"interaction in {result.episodes} episodes ({result.catalog} catalog)")
    return 0 if result.success else 3
