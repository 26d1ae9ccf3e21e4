"""Reproduce the paper's Table 1: every configuration on MuJoCo trajectories, ranked.

Usage (from the repository root)::

    python benchmarks/table1.py --quick            # < 15 min on 2 cores; writes benchmarks/results/
    python benchmarks/table1.py --full -j 32 --out benchmarks/results/full
    python benchmarks/table1.py --quick --fresh    # start over (the committed records are kept
                                                   # aside as records.TIME.jsonl)
    python benchmarks/table1.py --help             # all options (backends, retries, subsets)

Equivalent to ``pysindy-xl benchmark``, except that the output goes to
``benchmarks/results/`` (quick preset) or ``benchmarks/results/<preset>`` by default. An
interrupted run resumes where it stopped when started again with the same options.
"""

import os
import sys

from pysindy_xl.benchmark.cli import build_parser, run_benchmark

RESULTS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results")


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    if args.out is None:
        args.out = RESULTS if args.preset == "quick" else os.path.join(RESULTS, args.preset)
    return run_benchmark(args)


if __name__ == "__main__":
    sys.exit(main())
