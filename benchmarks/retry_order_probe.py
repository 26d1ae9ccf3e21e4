"""Which growths the order of a refused move's retries changes, and what the budget charges.

A climb's move over the ceiling (or the work budget) is retried smaller
(:func:`pysindy_xl.catalog.retries.attempt_within_limits`). The retries' kinds are now tried
in the order of :func:`~pysindy_xl.catalog.retries.retry_order`: from a catalog with
configuration-dependent kinetic coefficients, those over fewer coordinates' functions
(``"narrower"``) before constant ones (``"constant"``); before, constant ones always came
before the narrower ones. A growth is the same as before, bit for bit, up to its first
refusal at which the two orders make a different retry (a different catalog tried, or a
different set of catalogs recorded as tried); with none, the whole growth is the same.

This script runs each case's growth on the package imported and, at each refusal, walks both
orders over the same retry catalogs (:func:`~pysindy_xl.catalog.retries.retry_catalogs`) with
the climb's ``tried`` set at that point, a catalog over the ceiling being refused (a refusal by
the budget is reported; the walk then cannot be replayed). It checks that the walk of the
order used returns the catalog the growth took. It also reports the growth's work as now
charged (each fit once, :attr:`~pysindy_xl.GrowthResult.work`) and as charged before (each
step fitted, identical content included). One JSON line per case on stdout::

    PYTHONPATH=$PWD python benchmarks/retry_order_probe.py double_pendulum:forced:0.0:0 ...
    PYTHONPATH=$PWD python benchmarks/retry_order_probe.py --grid 0 2   # half 0 of 2 (n >= 2)
    PYTHONPATH=$PWD python benchmarks/retry_order_probe.py --grid 0 2 --done probe.jsonl
"""

import json
import os
import sys
import time

from pysindy_xl.catalog import climbs, retries
from pysindy_xl.catalog.budget import OVER, REFUSED, work_cost
from pysindy_xl.catalog.candidates import parameters_key
from pysindy_xl.catalog.retries import retry_walk

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import generic_systems as gs  # noqa: E402
import growth_cases as gc  # noqa: E402

BEFORE = ("state_order", "constant", "narrower")  # the order before this change


def walk(order, catalogs, tried, state, over):
    """The key of the catalog a refused move ends on and the keys tried, for one order of the
    retry kinds (the rules of ``attempt_within_limits``)."""
    tried, last = set(tried), None
    for _, retry in retry_walk(catalogs, order, tried, state):
        last = parameters_key(retry)
        if not over(retry):
            return last, tried
    return last, tried


def probe(case, table=None) -> dict:
    """The refusals of the growth of ``case`` (``system:forcing:noise:seed``) and whether the
    order before this change would have retried differently at any of them."""
    events = []
    original = climbs.attempt_within_limits

    def hooked(climber, parameters, move, tried, ahead=(), state=None):
        before = set(tried)
        taken, step = original(climber, parameters, move, tried, ahead, state)
        first = climber._cache.get(parameters_key(parameters))
        if first is None or not first.note.startswith(OVER) or not climber.retry_kinetic:
            return taken, step
        ceiling = climber.fits.search.max_terms
        catalogs = retries.retry_catalogs(parameters, move, state, climber.kinds, climber.n)

        def over(p):
            note = climber._cache[parameters_key(p)].note \
                if parameters_key(p) in climber._cache else ""
            return climber.size(p) > ceiling or note.startswith("budget")

        start = set(before) | {parameters_key(parameters)}
        now = walk(retries.retry_order(state), catalogs, start, state, over)
        old = walk(BEFORE, catalogs, start, state, over)
        events.append({
            "move": move, "terms": first.terms, "note": first.note.split(":")[0],
            "state_kinetic": None if state is None else state["kinetic"],
            "retries": [name for kind in retries.retry_order(state)
                        for name, _ in catalogs[kind]],
            "taken": step.move, "taken_terms": step.terms,
            "replayed": now[0] == parameters_key(taken) and now[1] == tried,
            "differs": now[0] != old[0] or now[1] != old[1],
            "before": next((name for kind in BEFORE for name, p in catalogs[kind]
                            if parameters_key(p) == old[0]), None)})
        return taken, step

    start = time.process_time()
    system, _, _, (_, _, xs, ts, us) = gs.case_of(case, table)
    climbs.attempt_within_limits = hooked
    try:
        found = gc.grow(system, xs, ts, us)
    finally:
        climbs.attempt_within_limits = original
    implicit = found.criterion != "forces"
    charged_before = sum(work_cost(s.terms, implicit) for s in found.steps
                         if s.terms > 0 and not s.note.startswith(REFUSED))
    return {"case": case, "ceiling": found.max_terms, "refusals": len(events),
            "differs": any(e["differs"] for e in events),
            "replayed": all(e["replayed"] for e in events),
            "budget_refusals": sum(s.note.startswith("budget") for s in found.steps),
            "work": found.work, "work_charged_before": charged_before,
            "catalog": found.catalog.describe(), "events": events,
            "cpu": time.process_time() - start}


def grid_cases(part, parts):
    """The development grid's cases with two coordinates or more, every ``parts``-th from
    ``part``."""
    table = gs.systems()
    cases = [gs.case_key(case) for case in gs.grid_cases(table)
             if table[case[0]]["coords"].n >= 2]
    return cases[part::parts]


if __name__ == "__main__":
    args = sys.argv[1:]
    done = None
    if "--done" in args:  # (a JSONL file of this script's: its cases are skipped)
        at = args.index("--done")
        done = args[at + 1]
        args = args[:at] + args[at + 2:]
    keys = grid_cases(int(args[1]), int(args[2])) if args[:1] == ["--grid"] else args
    for _, record in gc.iter_cases(keys, probe, done=done):
        print(json.dumps(record), flush=True)
