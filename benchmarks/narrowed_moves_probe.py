"""Which growths a change to the narrowed joint moves (``"a+b@k<m>"``) can touch.

The growth's narrowed moves come only from :func:`pysindy_xl.catalog.moves.narrowed`: the
joint first moves over the data-sized ceiling, narrowed to a kinetic order within it. A growth
whose joint moves are all within the ceiling has no narrowed move in its climbs' order, so a
change to how such a move applies leaves it bit for bit the same. This script sets up each
case's growth up to that point (the data, the search's rows and ceiling), records the
ceiling and the narrowed moves, and stops before the first fit (1-2 CPU s a case). One JSON
line per case on stdout. Usage::

    PYTHONPATH=$PWD python benchmarks/narrowed_moves_probe.py \\
        double_pendulum:forced:0.0:0 four_chain:forced:0.05:2 > probe.jsonl
"""

import json
import os
import sys
import time

from pysindy_xl.catalog import growth

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import generic_systems as gs  # noqa: E402
import growth_cases as gc  # noqa: E402


class _Stop(Exception):
    """Raised once the narrowed moves are known."""


def probe(case, table=None) -> dict:
    """The ceiling and the narrowed joint moves of the growth of ``case``
    (``system:forcing:noise:seed`` of ``table``, default the development grid)."""
    seen = {}
    original = growth.narrowed

    def narrowed(names, kinds, n, size, ceiling):
        seen.update(ceiling=ceiling, joint=list(names),
                    narrowed=original(names, kinds, n, size, ceiling))
        raise _Stop

    start = time.process_time()
    system, _, _, (_, _, xs, ts, us) = gs.case_of(case, table)
    growth.narrowed = narrowed
    try:
        gc.grow(system, xs, ts, us)
    except _Stop:
        pass
    finally:
        growth.narrowed = original
    return {"case": case, **seen, "cpu": time.process_time() - start}


if __name__ == "__main__":
    for key in sys.argv[1:]:
        print(json.dumps(probe(key)), flush=True)
