"""A grid script run with the growth's mass-matrix guards logged.

Runs ``benchmarks/<grid>`` (``generic_systems.py``, ``blind2_systems.py``, ...) with its own
arguments, and appends to ``--log FILE.jsonl`` one line per call of
:func:`pysindy_xl.catalog.final_fit.mass_matrix_fails` in a growth's final fits: the case, the
model's optimizer (``RestrictedOptimizer``: the refit among the judged terms) and its check.
A guard acted where a ``RestrictedOptimizer`` line that fails is followed by a passing line
of the same fit (the final fit's guard), or where the growth's check of its answer fails and
an alternative's passes (the growth's guard). Usage::

    PYTHONPATH=$PWD python benchmarks/mass_matrix_guard.py --log guard.jsonl blind2_systems.py \\
        --systems half_car --forcing unforced --noise 0.01 --seeds 0 --no-baselines --out rows.jsonl
"""

import json
import os
import runpy
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def main(argv):
    if len(argv) < 3 or argv[0] != "--log":
        raise SystemExit(__doc__)
    log, grid, rest = argv[1], argv[2], argv[3:]
    sys.path.insert(0, HERE)
    import generic_systems as gs

    import pysindy_xl.catalog.final_fit as final_fit

    original, run_case, case = final_fit.mass_matrix_fails, gs.run_case, {}

    def fails(model):
        result = original(model)
        with open(log, "a", encoding="utf-8") as handle:
            handle.write(json.dumps(dict(case, optimizer=type(model.optimizer_).__name__,
                                         fails=result, check=model.mass_matrix_check_)) + "\n")
        return result

    def logged_case(system, truth, noise, seed, forced, **options):
        case.update(system=system["name"], noise=noise, seed=seed, forced=forced)
        return run_case(system, truth, noise, seed, forced, **options)

    final_fit.mass_matrix_fails = fails  # (both guards call it there: final_fit.final_answer)
    gs.run_case = logged_case
    if grid == "generic_systems.py":  # (run as __main__ it would not see the patch)
        return gs.main(rest)
    sys.argv = [grid] + rest
    runpy.run_path(os.path.join(HERE, grid), run_name="__main__")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
