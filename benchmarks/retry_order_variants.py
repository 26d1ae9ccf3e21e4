"""One set row's growth table under three orders of a refused move's retries.

``main``: the package's order (:func:`pysindy_xl.catalog.retries.retry_order`: from
configuration-dependent kinetic coefficients, the narrower kinetic orders before constant
coefficients); ``old``: constant coefficients first, always (the order before ``h-retry``);
``both``: the first retry within the limits of each kind (narrower, constant) is fitted and the
one with the lower criterion is the move's step. The growth's own code runs; only the order is
swapped in this process. Results: ``results/retry_order_traces_5836b2b.txt``,
``results/retry_budget.md`` (section 8). Usage::

    PYTHONPATH=$PWD python benchmarks/retry_order_variants.py both blind3_systems \\
        elastic_crane:forced:0.05:2
"""

from __future__ import annotations

import importlib
import os
import sys

import pysindy_xl.catalog.climbs as climbs
import pysindy_xl.catalog.retries as retries
from pysindy_xl.catalog.budget import OVER

sys.path.insert(0, os.path.dirname(__file__))

import unseen_systems  # noqa: E402 - the sets' explain


def attempt_keeping_the_better(climber, parameters, move, tried, ahead=(), state=None):
    """:func:`~pysindy_xl.catalog.retries.attempt_within_limits` with the ``both`` order."""
    tried.add(retries.parameters_key(parameters))
    step = climber.attempt(parameters, move, ahead)
    if not (step.note.startswith(OVER) and climber.retry_kinetic):
        return parameters, step
    kinds = retries.retry_catalogs(parameters, move, state, climber.kinds, climber.n)
    found = []
    for group in (("state_order", "narrower"), ("constant",)):
        for name, retry in retries.retry_walk(kinds, group, tried, state):
            retry_step = climber.attempt(retry, name)
            if not retry_step.note.startswith(OVER):
                found.append((retry, retry_step))
                break
    return min(found, key=lambda pair: pair[1].criterion) if found else (parameters, step)


def main(argv=None) -> int:
    variant, set_name, case = (argv or sys.argv[1:])[:3]
    if variant == "old":
        retries.retry_order = lambda state: ("state_order", "constant", "narrower")
    elif variant == "both":
        climbs.attempt_within_limits = attempt_keeping_the_better
    elif variant != "main":
        raise ValueError(f"variant: expected 'main', 'old' or 'both', got {variant!r}")
    table = importlib.import_module(set_name).systems
    unseen_systems.main(["--explain", case], table=table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
