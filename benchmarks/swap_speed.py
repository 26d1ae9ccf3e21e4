"""CPU seconds of catalog growths, and what they found, before and after a change meant to keep it.

Runs :func:`pysindy_xl.grow_catalog` on rows of the generic, blind and second blind sets
(``table:system:forcing:noise:seed``, ``table`` one of ``generic``, ``blind``, ``blind2``) and
appends to a JSONL file per row: the CPU seconds of the growth (``time.process_time``), the
catalog's description, the model's Lagrangian, the search's held-out criterion, the supports and
a digest of the coefficients' bytes. ``--profile`` prints the cProfile (process time) of the
rows' growths instead, with the share of the support selection and of the swap search;
``--shares`` times those functions alone (process time, by wrappers: cProfile's overhead on the
search's many small calls triples the growth's CPU and inflates their share).

Usage (the package imported is the first on ``PYTHONPATH``)::

    PYTHONPATH=/path/to/before python benchmarks/swap_speed.py --label before --out rows.jsonl \\
        --rows generic:three_masses:forced:0.01:0
    PYTHONPATH=/path/to/before python benchmarks/swap_speed.py --profile \\
        --rows blind:two_link_arm:forced:0.01:0
"""

from __future__ import annotations

import argparse
import cProfile
import hashlib
import io
import json
import os
import pstats
import sys
import time
import warnings

import numpy as np

import pysindy_xl as px

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blind2_systems  # noqa: E402
import blind_systems  # noqa: E402
import generic_systems as gs  # noqa: E402

TABLES = {"generic": gs.systems, "blind": blind_systems.systems, "blind2": blind2_systems.systems}

# functions whose cumulative time is reported as a share of the growth's
SHARES = ("select_support", "_swap_candidates", "swap_search", "first_swaps", "_best_swap",
          "_exchanged")


def grow(row):
    """The growth of ``row`` (``table:system:forcing:noise:seed``): ``(result, cpu_seconds)``."""
    table, name, forcing, noise, seed = row.split(":")
    system = TABLES[table]()[name]
    truth, forced = gs.Truth(system), forcing == "forced"
    _, _, xs, ts, us = gs.case_data(system, truth, float(noise), int(seed), forced)
    start = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = px.grow_catalog(xs, ts, us, coordinates=list(system["coords"].names),
                                kinds=system["kinds"])
    return found, time.process_time() - start


def summary(row, label, found, cpu) -> dict:
    """What the growth of ``row`` found, with its CPU seconds."""
    coefficients = np.ascontiguousarray(found.model.coefficients())
    return {"row": row, "label": label, "cpu_seconds": cpu, "catalog": found.catalog.describe(),
            "lagrangian": str(found.model.lagrangian()), "criterion": found.held_out_error,
            "steps": len(found.steps), "support": np.flatnonzero(coefficients).tolist(),
            "coefficients_sha1": hashlib.sha1(coefficients.tobytes()).hexdigest()}


def profiled(row) -> str:
    """The cProfile (process time) of the growth of ``row``: the shares of :data:`SHARES` and
    the 25 functions of most own time."""
    profile = cProfile.Profile(time.process_time)
    profile.enable()
    _, cpu = grow(row)
    profile.disable()
    stats = pstats.Stats(profile)
    lines = [f"{row}: CPU {cpu:.1f} s"]
    for (_, _, function), (_, calls, _, cumulative, _) in sorted(stats.stats.items()):
        if function in SHARES:
            lines.append(f"  {function:18s} {calls:8d} calls {cumulative:7.1f} s "
                         f"({100 * cumulative / cpu:4.1f} %)")
    text = io.StringIO()
    pstats.Stats(profile, stream=text).sort_stats("tottime").print_stats(25)
    return "\n".join(lines) + "\n" + text.getvalue()


def timed_shares(row) -> str:
    """CPU seconds of the growth of ``row`` and of the support selection, the swap refinement and
    the swap searches in it (process time, measured by wrappers of those functions only)."""
    from pysindy_xl.optimizers import explicit, selection

    spent = dict.fromkeys(("select_support", "_swap_candidates", "swap_search + first_swaps"), 0.0)
    calls = dict.fromkeys(spent, 0)

    def wrapped(function, name):
        def timed(*args, **kwargs):
            start = time.process_time()
            try:
                return function(*args, **kwargs)
            finally:
                spent[name] += time.process_time() - start
                calls[name] += 1
        return timed

    originals = {(explicit, "select_support"): explicit.select_support,
                 (selection, "_swap_candidates"): selection._swap_candidates,
                 (selection, "swap_search"): selection.swap_search,
                 (selection, "first_swaps"): selection.first_swaps}
    names = ["select_support", "_swap_candidates", "swap_search + first_swaps",
             "swap_search + first_swaps"]
    for (module, attribute), name in zip(originals, names, strict=True):
        setattr(module, attribute, wrapped(originals[module, attribute], name))
    try:
        _, cpu = grow(row)
    finally:
        for (module, attribute), function in originals.items():
            setattr(module, attribute, function)
    lines = [f"{row}: CPU {cpu:.1f} s"]
    lines += [f"  {name:26s} {calls[name]:7d} calls {spent[name]:7.1f} s "
              f"({100 * spent[name] / cpu:4.1f} %)" for name in spent]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", nargs="+", required=True)
    parser.add_argument("--label", default="")
    parser.add_argument("--out", default=None, help="append the rows' records to this JSONL")
    parser.add_argument("--profile", action="store_true")
    parser.add_argument("--shares", action="store_true")
    args = parser.parse_args(argv)
    print(f"package: {px.__file__}", flush=True)
    for row in args.rows:
        if args.profile:
            print(profiled(row), flush=True)
            continue
        if args.shares:
            print(timed_shares(row), flush=True)
            continue
        record = summary(row, args.label, *grow(row))
        print(f"{row:48s} CPU {record['cpu_seconds']:6.1f} s  {record['coefficients_sha1'][:10]}",
              flush=True)
        if args.out:
            with open(args.out, "a", encoding="utf-8") as handle:
                handle.write(json.dumps(record) + "\n")


if __name__ == "__main__":
    main()
