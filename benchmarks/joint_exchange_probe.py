"""Which growths the backward phase's exchange from a family's lowest degree touches.

The backward phase exchanges a degree family that it may not drop alone (``"-trig_degree"``,
``"-angle_degree"``) for the family it stands in for; since the joint-springs change it also
does so from the family at its lowest degree (``"-trig_degree*2+angle_degree"``: sines and
cosines back from degree 3 to 1 beside the angles' powers). A growth whose backward phase
never asks for such an exchange from a family grown two steps or more is bit for bit the same
as before: only growths of angles can be touched (the removals of the two families need an
angle), and only where the climb kept ``trig_degree`` 3 or ``angle_degree`` 3-4. This script
runs each case's growth with the change and records every candidate of the new kind that the
backward phase asks for (``asked``: its name, terms, criterion and whether it was kept); a
case with none asked is the same as before. One JSON line per case. Usage::

    PYTHONPATH=$PWD python benchmarks/joint_exchange_probe.py --systems double_pendulum \\
        --out probe.jsonl
"""

import argparse
import os
import sys
import time

from pysindy_xl.catalog import climbs

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import generic_systems as gs  # noqa: E402
import growth_cases as gc  # noqa: E402

ANGLES = ("gravity_torsion", "torsion_quartic", "bead_on_hoop", "spring_pendulum",
          "double_pendulum", "cart_spring_pendulum")


def probe(case, table=None) -> dict:
    """The growth of ``case`` (``system:forcing:noise:seed`` of ``table``, default the
    development grid) and the deep exchanges its backward phase asked for."""
    asked = []
    original = climbs.Climber.attempt

    def attempt(self, parameters, move, ahead=()):
        step = original(self, parameters, move, ahead)
        if "*" in move:
            asked.append([move, step.terms, step.criterion])
        return step

    system, truth, forced, (runs, test, xs, ts, us) = gs.case_of(case, table)
    climbs.Climber.attempt = attempt
    cpu = time.process_time()
    try:
        found = gc.grow(system, xs, ts, us)
    finally:
        climbs.Climber.attempt = original
    kept = [s.move for s in found.steps if s.chosen]
    return {"case": case, "asked": asked, "kept_deep": [m for m in kept if "*" in m],
            "catalog": found.catalog.describe(), "criterion": found.held_out_error,
            "cpu_seconds": time.process_time() - cpu}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--systems", nargs="*", default=list(ANGLES))
    parser.add_argument("--noise", nargs="*", type=float, default=[0.0, 0.01, 0.05])
    parser.add_argument("--seeds", nargs="*", type=int, default=[0, 1, 2])
    parser.add_argument("--out", required=True)
    args = parser.parse_args(argv)
    table = gs.systems()
    cases = [gs.case_key(case) for case in gs.grid_cases(table, args.systems,
                                                         noise=args.noise, seeds=args.seeds)]
    for case, record in gc.iter_cases(cases, lambda case: probe(case, table), args.out):
        print(case, "asked", record["asked"], "kept", record["kept_deep"],
              f"cpu {record['cpu_seconds']:.1f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
