"""The automatic catalog's growth on the cart double pendulum's exploration, against MuJoCo.

For each seed, the data are those of the learning loop's first exploration
(:func:`~pysindy_xl.control.learn_to_control` at 20 N, 8 s, 1 % position noise, as its
identification receives them). :class:`~pysindy_xl.control.AutomaticGrowth` grows the catalog
from the coordinates and their kinds only. Per seed:

- ``catalog``: the chosen catalog; ``coupling``: whether the fitted model keeps a product of
  both angles' functions times ``theta1_dot * theta2_dot`` (the ``cos(theta1 - theta2)``
  coupling of the kinetic energy);
- ``box``: the largest relative acceleration error over the coordinates against MuJoCo's
  (``mj_forward``) on 600 held-out states: positions within +-0.5 of hanging and of upright,
  velocities within +-2, cart forces within +-20 N;
- ``traj``: the same on the true states and forces of another seed's exploration (never
  fitted);
- ``definite``: the fraction of those states where the model's mass matrix is positive
  definite; ``cpu_s``: CPU seconds of the growth and its final fit.

Usage::

    python benchmarks/cdp_growth.py --seeds 4 5 6 --label before --out results.jsonl
    python benchmarks/cdp_growth.py --seeds 4 5 6 --label before --combine rms
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings

import numpy as np

NAME = "cart-double-pendulum"
CACHE = os.environ.get("CDP_GROWTH_CACHE", "/tmp/cdp_growth_data")


def exploration(seed: int):
    """The loop's first exploration of ``seed``: ``(q_noisy, t, tau)`` and the true ``q, qd``."""
    path = os.path.join(CACHE, f"seed{seed}.npz")
    if os.path.exists(path):
        saved = np.load(path)
        return saved["q"], saved["t"], saved["u"], saved["q_true"], saved["qd_true"]
    from pysindy_xl.control import learn_to_control
    from pysindy_xl.control import plant as plant_module
    seen, episodes = [], []
    run = plant_module.MuJoCoPlant.run

    def recorded(self, *args, **kwargs):
        episode = run(self, *args, **kwargs)
        episodes.append(episode)
        return episode

    def identify(system, data):
        seen.extend(data)
        raise ValueError("recorded")

    plant_module.MuJoCoPlant.run = recorded
    try:
        learn_to_control(NAME, identify=identify, max_episodes=1 + 1, seed=seed, noise=0.01)
    finally:
        plant_module.MuJoCoPlant.run = run
    q, t, u = seen[0]
    os.makedirs(CACHE, exist_ok=True)
    np.savez(path, q=q, t=t, u=u, q_true=episodes[0].q, qd_true=episodes[0].qd)
    return q, t, u, episodes[0].q, episodes[0].qd


def mujoco_accelerations(states, tau):
    """Generalized accelerations of MuJoCo's model (``mj_forward``) at ``states`` (S, 2n) under
    generalized forces ``tau`` (S, n)."""
    import mujoco

    from pysindy_xl.mujoco import get_system
    system = get_system(NAME)
    model = system.mj_model()
    data = mujoco.MjData(model)
    n = system.n
    qpos, qvel = system.from_generalized(states[:, :n], states[:, n:])
    joint = tau @ np.linalg.inv(system.force_matrix()).T  # B u = tau
    out = np.empty((len(states), n))
    for k in range(len(states)):
        data.qpos[:], data.qvel[:] = qpos[k], qvel[k]
        data.qfrc_applied[:] = joint[k]
        data.ctrl[:] = 0.0
        mujoco.mj_forward(model, data)
        out[k] = system.to_generalized(qpos[k], qvel[k], data.qacc.copy())[2]
    return out


def held_out_states(seed: int):
    """``(box states, box forces, trajectory states, trajectory forces)`` (module docstring)."""
    rng = np.random.default_rng(1000 + seed)
    n, count = 3, 300
    boxes, forces = [], []
    for center in (np.zeros(3), np.r_[0.0, np.pi, np.pi]):
        boxes.append(np.c_[center + rng.uniform(-0.5, 0.5, (count, n)),
                           rng.uniform(-2, 2, (count, n))])
        f = np.zeros((count, n))
        f[:, 0] = rng.uniform(-20, 20, count)
        forces.append(f)
    other = seed + 100
    _, _, u, q_true, qd_true = exploration(other)
    pick = np.arange(0, len(q_true), 20)
    return np.vstack(boxes), np.vstack(forces), np.c_[q_true, qd_true][pick], u[pick]


def errors(model, states, tau, truth):
    """Largest relative acceleration error over the coordinates, and the fraction of states
    where the model's mass matrix is positive definite."""
    from pysindy_xl.control.discrete import continuous_dynamics
    n = truth.shape[1]
    predicted = np.asarray(continuous_dynamics(model)(states, tau))[:, n:]
    bad = ~np.all(np.isfinite(predicted), axis=1)
    predicted = np.where(np.isfinite(predicted), predicted, 0.0)
    error = np.linalg.norm(predicted - truth, axis=0) / np.linalg.norm(truth, axis=0)
    z = np.c_[states, np.zeros((len(states), n)), tau, np.zeros(len(states))]
    mass = np.asarray(model.dynamics_.mass_and_forcing(z)[0]).reshape(len(states), n, n)
    definite = np.linalg.eigvalsh(0.5 * (mass + np.swapaxes(mass, 1, 2))).min(axis=1) > 0
    return float(np.max(error)) if not bad.any() else float("inf"), float(np.mean(definite))


def coupling(model) -> bool:
    """Whether the model keeps a term ``f(theta1) g(theta2) theta1_dot theta2_dot``."""
    library, coef = model.feature_library_, model.coef_
    for term, category, c in zip(library.feature_terms_, library.categories_, coef,
                                 strict=True):
        if category != "lagrange" or c == 0:
            continue
        names = {str(s) for s in term.free_symbols}
        if {"theta1", "theta2", "theta1_dot", "theta2_dot"} <= names:
            return True
    return False


def cached_candidates(label: str, seed: int) -> None:
    """Keep every candidate's fit and score (:func:`~pysindy_xl.catalog.candidates.
    evaluate_candidate`) in a JSON-lines file of ``label`` and ``seed``: a run that stops
    replays them. A replayed candidate's criterion is recombined from its block errors with
    the search's ``combine`` (a cache serves both criteria; entries without block errors
    are replayed as they are)."""
    from pysindy_xl.catalog import candidates
    path = os.path.join(CACHE, f"candidates_{label}_{seed}.jsonl")
    known = {}
    if os.path.exists(path):
        for line in open(path):
            key, value = json.loads(line)
            known[key] = value
    original = getattr(candidates, "_original_evaluate", candidates.evaluate_candidate)
    candidates._original_evaluate = original

    def evaluate(search, parameters):
        key = candidates.parameters_key(parameters)
        if key not in known:
            known[key] = original(search, parameters)
            with open(path, "a") as f:
                f.write(json.dumps([key, known[key]], default=float) + "\n")
        found = dict(known[key])
        if found.get("block_errors"):
            found["block_errors"] = tuple(found["block_errors"])
            found["criterion"] = candidates.combine_errors(found["block_errors"],
                                                           search.combine)
        return found

    candidates.evaluate_candidate = evaluate


def catalog_of(description: str, q, t) -> object:
    """The :class:`~pysindy_xl.AutomaticCatalog` a growth on ``q, t`` would build from its
    ``describe()`` text."""
    import re

    from pysindy_xl.catalog import AutomaticCatalog
    from pysindy_xl.catalog.growth_data import END_PERCENTILE
    found = {"degree": 2, "trig_degree": 1, "angle_degree": 0}
    if m := re.search(r"x\.\.x\^(\d)", description):
        found["degree"] = int(m.group(1))
    if m := re.search(r"sin/cos degree (\d)", description):
        found["trig_degree"] = int(m.group(1))
    if m := re.search(r"theta1\.\.theta1\^(\d)", description):
        found["angle_degree"] = int(m.group(1))
    found["interaction"] = int(re.search(r"interaction (\d)", description).group(1))
    found["kinetic"] = re.search(r"kinetic (\w+)", description).group(1)
    found["gyroscopic"] = "gyroscopic" in description
    found["dissipation"] = tuple(re.search(r"dissipation ([\w+]+)", description)
                                 .group(1).split("+"))
    scale = float(np.std(np.gradient(q, t, axis=0), axis=0).mean())
    low, high = np.percentile(q, [END_PERCENTILE, 100 - END_PERCENTILE], axis=0)
    bounds = [(float(a), float(b)) for a, b in zip(low, high, strict=True)]
    return AutomaticCatalog(["x", "theta1", "theta2"], kinds=["linear", "angle", "angle"],
                            bounds=bounds, coulomb_scale=max(1e-3, 0.02 * scale),
                            max_terms=400, **found)


def refit(seed: int, description: str) -> dict:
    """The final fit of :class:`~pysindy_xl.control.AutomaticGrowth` of the catalog
    ``description`` (a recorded growth's choice) on the seed's exploration, evaluated."""
    from types import SimpleNamespace

    from pysindy_xl import XLSINDy
    from pysindy_xl.control.catalogs import final_fit_width
    from pysindy_xl.weak import BumpTestFunctions
    q, t, u, _, _ = exploration(seed)
    catalog = catalog_of(description, q, t)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = XLSINDy(catalog, test_functions=BumpTestFunctions(
            width=final_fit_width([t], [q], 5))).fit([q], t=[t], u=[u])
    found = SimpleNamespace(model=model, catalog=catalog, held_out_error=float("nan"),
                            steps=[], table=lambda: "")
    return evaluated(seed, found, float("nan"), float("nan"), t)


def evaluated(seed, found, cpu_s, wall_s, t) -> dict:
    box_states, box_tau, traj_states, traj_tau = held_out_states(seed)
    try:
        box = errors(found.model, box_states, box_tau, mujoco_accelerations(box_states, box_tau))
        traj = errors(found.model, traj_states, traj_tau,
                      mujoco_accelerations(traj_states, traj_tau))
    except Exception as error:  # noqa: BLE001 - the row is kept with the growth's figures
        print(f"evaluation failed: {error!r}", file=sys.stderr)
        box = traj = (float("nan"), float("nan"))
    steps_cpu = sum(s.cpu_seconds for s in found.steps)
    return {"seed": seed, "duration_s": float(t[-1] - t[0]), "catalog": found.catalog.describe(),
            "coupling": coupling(found.model), "criterion": found.held_out_error,
            "box_error": box[0], "box_definite": box[1], "traj_error": traj[0],
            "traj_definite": traj[1], "cpu_s": cpu_s, "steps_cpu_s": steps_cpu,
            "wall_s": wall_s, "steps": len(found.steps), "table": found.table()}


def run_seed(seed: int, growth, label: str = "") -> dict:
    if label:
        cached_candidates(label, seed)
    q, t, u, q_true, _ = exploration(seed)
    started, cpu = time.perf_counter(), time.process_time()
    lines = []

    def progress(line):
        lines.append(line)
        print(f"[seed {seed}] {line}", file=sys.stderr, flush=True)

    growth.progress = progress
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = growth(NAME, [(q, t, u)])
    cpu_s, wall_s = time.process_time() - cpu, time.perf_counter() - started
    return evaluated(seed, found, cpu_s, wall_s, t)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", required=True)
    parser.add_argument("--label", default="")
    parser.add_argument("--out", default=None)
    parser.add_argument("--data-only", action="store_true")
    parser.add_argument("--physical", choices=("default", "on", "off"), default="default",
                        help="AutomaticGrowth's physical keep rule")
    parser.add_argument("--combine", choices=("auto", "rms", "trimmed"), default="auto",
                        help="AutomaticGrowth's criterion over the held-out blocks")
    parser.add_argument("--refit", nargs="+", default=None, metavar="SEED=DESCRIPTION",
                        help="fit a recorded growth's catalog instead of growing one")
    args = parser.parse_args(argv)
    from pysindy_xl.control import AutomaticGrowth
    if args.refit:
        for item in args.refit:
            seed, description = item.split("=", 1)
            row = refit(int(seed), description)
            row["label"] = args.label
            print(json.dumps({k: v for k, v in row.items() if k != "table"}), flush=True)
            if args.out:
                with open(args.out, "a") as f:
                    f.write(json.dumps(row) + "\n")
        return
    for seed in args.seeds:
        if args.data_only:
            q, t, *_ = exploration(seed)
            exploration(seed + 100)
            print(seed, round(float(t[-1]), 2), flush=True)
            continue
        options = {} if args.physical == "default" else {"physical": args.physical == "on"}
        options["combine"] = args.combine
        row = run_seed(seed, AutomaticGrowth(**options), args.label)
        row["label"], row["combine"] = args.label, args.combine
        print(json.dumps({k: v for k, v in row.items() if k != "table"}), flush=True)
        print(row["table"], flush=True)
        if args.out:
            with open(args.out, "a") as f:
                f.write(json.dumps(row) + "\n")


if __name__ == "__main__":
    main()
