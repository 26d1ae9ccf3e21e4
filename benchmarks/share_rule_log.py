"""Run a benchmark grid with one of three share rules and log where they disagree with the
package's.

The unforced law search asks :func:`pysindy_xl.optimizers.laws.explained_coordinates` which
coordinates a law explains: each block's share of the law's squared term contributions, at
least ``1e-3`` of the largest, in the units of the catalog's balance (``--rule old``, the
package's). The alternatives, evaluated on every call next to the package's:

- ``own``: the blocks balanced over the law's own columns
  (:func:`~pysindy_xl.optimizers.coordinate_weights` of the support), not the catalog's;
- ``energy``: each block in the Lagrangian's units, its generalized forces times the spread
  (standard deviation) of its coordinate's positions on the fit's states, a virtual work:
  unit free and independent of both the catalog and the law.

``--rule`` says which one answers. Each row's record gets ``share_rule``: the calls and, per
alternative, the calls where it disagrees with the package's rule (``explains`` where only
the alternative explains every coordinate, ``refuses`` the other way). The counts cover
every fit of the row (the growth's and the hand-built catalog's). Everything after ``--``
goes to the grid script's ``main``.

    PYTHONPATH=$PWD python benchmarks/share_rule_log.py --rule energy --script generic -- \\
        --forcing unforced --seeds 0 1 2 --no-baselines --out benchmarks/results/x.jsonl
"""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

import generic_systems as gs  # noqa: E402

from pysindy_xl.optimizers import ImplicitOptimizer, homogeneous  # noqa: E402
from pysindy_xl.optimizers.problem import coordinate_weights, scale_blocks  # noqa: E402

COUNTS = {}
UNITS = {"energy": None}  # the energy units of the blocks of the problem being solved


def old_rule(theta, law, n_blocks: int, min_share: float = 1e-3) -> np.ndarray:
    """The package's rule (shares in the units of the caller's theta)."""
    contributions = (np.asarray(theta, dtype=float) * law).reshape(n_blocks, -1, len(law))
    shares = np.sum(contributions**2, axis=(1, 2))
    return shares >= min_share * max(float(shares.max(initial=0.0)), 1e-300)


def own_rule(theta, law, n_blocks: int, min_share: float = 1e-3) -> np.ndarray:
    """Shares with the blocks balanced over the law's own columns."""
    law = np.asarray(law, dtype=float)
    support = np.flatnonzero(law)
    columns = np.asarray(theta, dtype=float)[:, support]
    if n_blocks > 1 and support.size:
        columns = scale_blocks(columns, coordinate_weights(columns, n_blocks))
    return old_rule(columns, law[support], n_blocks, min_share)


def energy_rule(theta, law, n_blocks: int, min_share: float = 1e-3) -> np.ndarray:
    """Shares in energy units (the package's rule where the units are not known: a law for
    some coordinates only, in :func:`~pysindy_xl.optimizers.homogeneous.select_laws`' second
    round)."""
    units = UNITS["energy"]
    if units is None or len(units) != n_blocks:
        return old_rule(theta, law, n_blocks, min_share)
    return old_rule(scale_blocks(np.asarray(theta, dtype=float), units), law, n_blocks,
                    min_share)


RULES = {"old": old_rule, "own": own_rule, "energy": energy_rule}


def energy_units(problem):
    """Each block's factor from the problem's balanced rows to energy units: the spread of
    its coordinate's positions on the problem's states over the block's balance weight."""
    origin = problem.catalog_map
    if origin is None or not problem.balance:
        return None
    n = len(origin.coordinates)
    spread = np.std(origin.states[:, :n], axis=0)[origin.coordinates]
    if np.any(spread <= 0) or len(spread) != problem.n_coordinates:
        return None
    return spread / problem.block_weights


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rule", choices=list(RULES), required=True)
    parser.add_argument("--script", choices=["generic", "blind2"], default="generic")
    args, rest = parser.parse_known_args()
    rest = [a for a in rest if a != "--"]

    def reset():
        COUNTS.clear()
        COUNTS.update(calls=0, **{f"{name}_{how}": 0 for name in ("own", "energy")
                                  for how in ("explains", "refuses")})

    def both(theta, law, n_blocks, *extra, **options):
        verdicts = {name: rule(theta, law, n_blocks, *extra, **options).all()
                    for name, rule in RULES.items()}
        COUNTS["calls"] += 1
        for name in ("own", "energy"):
            if verdicts[name] != verdicts["old"]:
                COUNTS[f"{name}_{'explains' if verdicts[name] else 'refuses'}"] += 1
        return RULES[args.rule](theta, law, n_blocks, *extra, **options)

    homogeneous.explained_coordinates = both
    fit_problem = ImplicitOptimizer.fit_problem

    def units_known(self, problem, support=None):
        UNITS["energy"] = energy_units(problem)
        try:
            return fit_problem(self, problem, support)
        finally:
            UNITS["energy"] = None

    ImplicitOptimizer.fit_problem = units_known
    run_case = gs.run_case

    def logged(*a, **k):
        reset()
        record = run_case(*a, **k)
        record["share_rule"] = dict(COUNTS, rule=args.rule)
        return record

    gs.run_case = logged
    if args.script == "blind2":
        import blind2_systems as b2
        import unseen_systems as us
        return us.main(rest, table=b2.systems, results=b2.RESULTS, script="blind2_systems.py",
                       title="Systems the automatic catalog was run on blind, second set")
    return gs.main(rest)


if __name__ == "__main__":
    sys.exit(main())
