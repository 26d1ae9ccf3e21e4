"""Time of the demo's data generation on published arms, and the data it makes.

Runs ``generate_dataset`` with the settings of ``pysindy-xl demo ARM.xml --noise 0.01`` (two
trajectories of 10 s, forcing ``explicit``, a sample every 2 steps, 1 % position noise, seed 0)
on the Menagerie arms of ``benchmarks/models/menagerie/`` and prints, per arm, the integration,
the internal steps taken, the process CPU time and the wall time, with the load average.
``--save PATH`` writes every array of the datasets to an NPZ; ``--compare PATH`` checks them
against such a file, bit for bit (the data of the code before a change: run ``--save`` with
``PYTHONPATH`` at that code). ``--loop`` takes every internal step with ``mj_step`` from Python
(:data:`~pysindy_xl.simulation.stepping.ROLLOUT_MIN_STEPS` set out of reach) instead of in C.

Usage::

    python benchmarks/generation_time.py [ARM ...] [--save PATH | --compare PATH] [--loop]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
MODELS = os.path.join(HERE, "models", "menagerie")
FIELDS = ("t", "q", "qd", "qdd", "tau", "u", "u_constraint", "tau_constraint")


def generate(arm: str):
    """The demo's dataset of one arm, its CPU and wall seconds."""
    from pysindy_xl.mujoco import MJCFSystem, generate_dataset
    system = MJCFSystem(os.path.join(MODELS, f"{arm}.xml"))
    cpu, wall = time.process_time(), time.perf_counter()
    dataset = generate_dataset(system, n_trajectories=2, duration=10.0, forcing="explicit",
                               noise=0.01, noise_model="positions", seed=0, sample_every=2,
                               progress=False)
    return dataset, time.process_time() - cpu, time.perf_counter() - wall


def arrays(arm: str, dataset) -> dict:
    """Every array of the dataset, keyed ``arm/trajectory/field``."""
    out = {}
    for i, trajectory in enumerate(dataset.trajectories):
        for field in FIELDS:
            value = getattr(trajectory, field, None)
            if value is not None:
                out[f"{arm}/{i}/{field}"] = np.asarray(value)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("arms", nargs="*", default=["z1"])
    parser.add_argument("--save")
    parser.add_argument("--compare")
    parser.add_argument("--loop", action="store_true")
    args = parser.parse_args(argv)
    if args.loop:
        from pysindy_xl.simulation import stepping
        stepping.ROLLOUT_MIN_STEPS = sys.maxsize
    reference = dict(np.load(args.compare)) if args.compare else None
    saved, same = {}, True
    print("| arm | integrator | substeps | internal steps | CPU (s) | wall (s) | load | data |")
    print("|---|---|---|---|---|---|---|---|")
    for arm in args.arms:
        dataset, cpu, wall = generate(arm)
        meta = dataset.metadata
        steps = sum(len(tr.t) for tr in dataset.trajectories) * meta["sample_every"] * \
            meta["substeps"]
        found = arrays(arm, dataset)
        saved.update(found)
        verdict = "-"
        if reference is not None and any(key in reference for key in found):
            equal = all(key in reference and np.array_equal(value, reference[key])
                        for key, value in found.items())
            verdict = "bit-identical" if equal else "DIFFERENT"
            same &= equal
        elif reference is not None:
            verdict = "not in the reference"
        print(f"| {arm} | {meta['integrator']} | {meta['substeps']} | {steps:.3g} | {cpu:.1f} | "
              f"{wall:.1f} | {os.getloadavg()[0]:.1f} | {verdict} |", flush=True)
    if args.save:
        np.savez_compressed(args.save, **saved)
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
