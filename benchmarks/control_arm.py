"""Arm tracking with identified feedforward (issue 52's "arm tracking" target).

Published 7-joint arms of MuJoCo Menagerie (``benchmarks/models/menagerie/``: Franka FR3,
UFactory xArm7, Rethink Sawyer) with their position servos replaced by torque motors. Each is
identified with its kinematic catalog from 2 x 5 s of randomly excited motion (positions only,
1 % noise, samples every 2 ms; ``generate_dataset`` drives the motors through a tracking servo
and integrates the forced runs finely enough to follow the continuous equations,
``RK4_HELD_BOUND``), then tracks a fast multi-sine for 4 s (every joint: 0.4 rad or 40 % of its half
range, 0.5-1.1 Hz, about the middle of its range) with PD (kp 100, kd 10, 2 ms period) plus a
feedforward along the reference:

- ``pd``: none (PD alone);
- ``true``: MuJoCo's exact inverse dynamics (``mj_inverse``: rigid bodies, armature, damping
  and the solver's regularized dry friction);
- ``smooth``: the identified ``predict_forces``, the catalog's dry friction a smooth Coulomb
  law ``tanh(qd / 0.01)``;
- ``regularized``: the identified ``predict_forces``, the catalog's dry friction MuJoCo's
  regularized law with its acceleration lead (``coulomb_law="mujoco"``), the feedforward
  evaluated on the sliding side (``ComputedTorque(min_speed=2 s)``, ``s`` the law's sticking
  scale) at the joints whose sticking zone the sampled reference cannot resolve
  (``s < max |qdd_r| dt``: the reference crosses it within one period, where the first-order
  lead is an inertia spike ``F tau / s``).

Target: RMS tracking error with identified feedforward <= 1.2x that with the true model's,
and >= 5x better than PD alone. Records: ``benchmarks/results/control_arm.jsonl`` (one line per
arm and seed; a rerun skips them).

``--parts`` prints where an identified feedforward's excess error comes from: the true
feedforward with one part replaced by the identified model's (gravity ``tau(q, 0, 0)``,
velocity ``tau(q, qd, 0) - tau(q, 0, 0)``, acceleration ``tau(q, qd, qdd) - tau(q, qd, 0)``),
as a ratio to the true feedforward's error, and the mean error of the identified mass
matrix's diagonal against ``mj_fullM`` along the reference.

Usage::

    python benchmarks/control_arm.py --arms fr3 xarm7 sawyer --seeds 3
    python benchmarks/control_arm.py --arms fr3 --seeds 1 --parts
    python benchmarks/control_arm.py --summary
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
import warnings
from pathlib import Path

import numpy as np

MODELS = Path(__file__).resolve().parent / "models" / "menagerie"
RESULTS = Path(__file__).resolve().parent / "results"
ARM_JSONL = RESULTS / "control_arm.jsonl"
#: arm name -> stripped Menagerie model
ARMS = {"fr3": "fr3.xml", "xarm7": "xarm7.xml", "sawyer": "sawyer.xml"}
FEEDFORWARDS = ("pd", "true", "smooth", "regularized")
KP, KD, CONTROL_DT, DURATION, FORCE_LIMIT = 100.0, 10.0, 0.002, 4.0, 200.0


def torque_driven(xml: str) -> str:
    """The MJCF text with every actuator replaced by a torque motor on its joint."""
    block = re.search(r"<actuator>.*?</actuator>", xml, flags=re.S).group(0)
    joints = re.findall(r'<\w+ [^>]*joint="([^"]+)"', block)
    motors = "".join(f'    <motor name="{j}_motor" joint="{j}"/>\n' for j in joints)
    return xml.replace(block, "<actuator>\n" + motors + "  </actuator>")


def multisine(model, seed: int):
    """The reference ``t -> (q, qd, qdd)``: one sine per joint about the middle of its range."""
    limited = model.jnt_limited.astype(bool)
    low, high = model.jnt_range[:, 0], model.jnt_range[:, 1]
    centre = np.where(limited, (low + high) / 2, 0.0)
    amplitude = np.where(limited, np.minimum(0.4, 0.4 * (high - low) / 2), 0.4)
    omega = 2 * np.pi * np.random.default_rng(seed).uniform(0.5, 1.1, model.njnt)

    def reference(t):
        return (centre + amplitude * np.sin(omega * t), amplitude * omega * np.cos(omega * t),
                -amplitude * omega ** 2 * np.sin(omega * t))

    return reference


class MuJoCoInverse:
    """The true model's inverse dynamics (``mj_inverse``), as ``predict_forces``."""

    def __init__(self, mujoco, model):
        self.mujoco, self.model = mujoco, model
        self.data = mujoco.MjData(model)

    def predict_forces(self, q, qd, qdd):
        out = np.empty_like(q)
        for k, (position, velocity, acceleration) in enumerate(zip(q, qd, qdd, strict=True)):
            self.data.qpos[:], self.data.qvel[:] = position, velocity
            self.data.qacc[:] = acceleration
            self.mujoco.mj_inverse(self.model, self.data)
            out[k] = self.data.qfrc_inverse
        return out


def _setup(arm: str, seed: int, noise: float, trajectories: int):
    """The system, its identified models (both laws), the reference and the sliding floors."""
    import pysindy_xl as px
    from pysindy_xl.mujoco import MJCFSystem, generate_dataset, reference_catalog
    from pysindy_xl.mujoco.systems.friction import dry_friction_scales
    system = MJCFSystem(torque_driven((MODELS / ARMS[arm]).read_text()))
    mj_model = system.mj_model()
    data = generate_dataset(system, n_trajectories=trajectories, duration=5.0, seed=seed,
                            noise=noise, progress=False)
    models, identify_s = {}, {}
    for law in ("smooth", "regularized"):
        start = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            catalog = reference_catalog(system, "kinematic",
                                        coulomb_law="mujoco" if law == "regularized" else law)
            models[law] = px.XLSINDy(catalog).fit(**data.fit_arguments(forces="tau"))
        identify_s[law] = time.perf_counter() - start
    reference = multisine(mj_model, seed)
    times = np.arange(0.0, DURATION + 0.01, CONTROL_DT)
    # joints are the coordinates of an MJCF system: the dof scales apply one to one
    sticking = dry_friction_scales(mj_model)[0][mj_model.jnt_dofadr]
    peak_acceleration = np.abs(np.stack([reference(t)[2] for t in times])).max(axis=0)
    unresolved = sticking < peak_acceleration * CONTROL_DT
    floors = {"smooth": None, "regularized": np.where(unresolved, 2 * sticking, 0.0)}
    return system, models, identify_s, reference, times, floors


def _track(system, feedforward, reference, times, min_speed=None):
    """RMS tracking error (rad) and largest force of PD + ``feedforward`` on the plant."""
    from pysindy_xl.control import ComputedTorque, MuJoCoPlant
    plant = MuJoCoPlant(system, list(system.coordinate_names), force_limit=FORCE_LIMIT,
                        control_dt=CONTROL_DT)
    q0, qd0, _ = reference(0.0)
    plant.reset(q0, qd0)
    controller = ComputedTorque(feedforward, reference, kp=KP, kd=KD, n=system.n,
                                feedforward_times=times, min_speed=min_speed)
    episode = plant.run(controller, DURATION)
    q_ref = np.stack([reference(t)[0] for t in episode.t])
    return float(np.sqrt(np.mean((episode.q - q_ref) ** 2))), float(np.abs(episode.tau).max())


def arm_tracking(arm: str, seed: int, noise: float = 0.01, trajectories: int = 2) -> dict:
    """RMS tracking errors (rad) of one arm and seed for every feedforward of the module."""
    from pysindy_xl.mujoco import import_mujoco
    system, models, identify_s, reference, times, floors = _setup(arm, seed, noise,
                                                                  trajectories)
    feedforwards = {"pd": (None, None),
                    "true": (MuJoCoInverse(import_mujoco(), system.mj_model()), None),
                    **{law: (models[law], floors[law]) for law in models}}
    errors, peak = {}, {}
    for name, (feedforward, min_speed) in feedforwards.items():
        errors[name], peak[name] = _track(system, feedforward, reference, times, min_speed)
    return {"arm": arm, "seed": seed, "noise": noise, "training_s": 5.0 * trajectories,
            **{f"rms_{k}": v for k, v in errors.items()},
            **{f"{law}_over_true": errors[law] / errors["true"]
               for law in ("smooth", "regularized")},
            **{f"pd_over_{law}": errors["pd"] / errors[law] for law in ("smooth", "regularized")},
            "max_abs_tau": peak, "identify_s": identify_s}


class _Swapped:
    """The true inverse dynamics with one part (0 gravity, 1 velocity, 2 acceleration)
    replaced by the identified model's (evaluated at speeds raised to ``floor``)."""

    def __init__(self, true, model, part, floor):
        self.true, self.model, self.part, self.floor = true, model, part, floor

    @staticmethod
    def _parts(forces, q, qd, qdd):
        zero = np.zeros_like(q)
        gravity, moving = forces(q, zero, zero), forces(q, qd, zero)
        return gravity, moving - gravity, forces(q, qd, qdd) - moving

    def predict_forces(self, q, qd, qdd):
        sliding = qd if self.floor is None else np.where(
            np.abs(qd) < self.floor, np.where(qd < 0, -self.floor, self.floor), qd)
        true = self._parts(self.true.predict_forces, q, qd, qdd)[self.part]
        mine = self._parts(self.model.predict_forces, q, sliding, qdd)[self.part]
        return self.true.predict_forces(q, qd, qdd) + mine - true


def arm_parts(arm: str, seed: int, noise: float = 0.01, trajectories: int = 2) -> dict:
    """Ratios to the true feedforward's error with one part swapped, per law (``--parts``)."""
    from pysindy_xl.mujoco import import_mujoco
    mujoco = import_mujoco()
    system, models, _, reference, times, floors = _setup(arm, seed, noise, trajectories)
    mj_model = system.mj_model()
    true = MuJoCoInverse(mujoco, mj_model)
    base, _ = _track(system, true, reference, times)
    q = np.stack([reference(t)[0] for t in times[::25]])
    data, full = mujoco.MjData(mj_model), np.zeros((system.n, system.n))
    diagonal = []
    for position in q:
        data.qpos[:] = position
        mujoco.mj_forward(mj_model, data)
        mujoco.mj_fullM(mj_model, data, full)
        diagonal.append(np.diag(full).copy())
    out = {"arm": arm, "seed": seed}
    for law, model in models.items():
        floor = floors[law]
        speeds = np.full_like(q, 1.0)  # sliding everywhere: the lead's zone stays out
        rest = model.predict_forces(q, speeds, np.zeros_like(q))
        identified = np.stack([model.predict_forces(q, speeds, np.tile(np.eye(system.n)[j],
                                                                       (len(q), 1)))[:, j]
                               - rest[:, j] for j in range(system.n)], axis=1)
        out[law] = {"ratio": _track(system, model, reference, times, floor)[0] / base,
                    **{name: _track(system, _Swapped(true, model, part, floor), reference,
                                    times)[0] / base
                       for part, name in enumerate(("gravity", "velocity", "acceleration"))},
                    "mass_diagonal_error": (identified - np.array(diagonal)).mean(0).tolist()}
    return out


def arm_summary() -> str:
    """The markdown table of the records (empty without records)."""
    if not ARM_JSONL.exists():
        return ""
    records = [json.loads(line) for line in ARM_JSONL.read_text().splitlines() if line.strip()]
    records = [r for r in records if "arm" in r and "rms_regularized" in r]
    if not records:
        return ""
    lines = ["| arm | seed | RMS PD alone (rad) | RMS true FF | RMS identified FF, smooth "
             "law | RMS identified FF, regularized law | smooth / true | regularized / true "
             "(target <= 1.2) | PD / regularized (target >= 5) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in sorted(records, key=lambda r: (list(ARMS).index(r["arm"]), r["seed"])):
        lines.append(f"| {r['arm']} | {r['seed']} | {r['rms_pd']:.4f} | {r['rms_true']:.5f} | "
                     f"{r['rms_smooth']:.5f} | {r['rms_regularized']:.5f} | "
                     f"{r['smooth_over_true']:.2f} | {r['regularized_over_true']:.2f} | "
                     f"{r['pd_over_regularized']:.0f} |")
    lines += ["", "| arm | seeds | identified / true, smooth law: median (worst), within 1.2 | "
              "regularized law: median (worst), within 1.2 | PD / regularized: worst |",
              "|---|---|---|---|---|"]
    for arm in ARMS:
        mine = [r for r in records if r["arm"] == arm]
        if not mine:
            continue
        cells = []
        for law in ("smooth", "regularized"):
            ratios = np.array([r[f"{law}_over_true"] for r in mine])
            cells.append(f"{np.median(ratios):.2f} ({ratios.max():.2f}), "
                         f"{int(np.sum(ratios <= 1.2))} / {len(ratios)}")
        lines.append(f"| {arm} | {len(mine)} | {cells[0]} | {cells[1]} | "
                     f"{min(r['pd_over_regularized'] for r in mine):.0f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arms", nargs="+", choices=list(ARMS), default=list(ARMS))
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..N-1 (default 3)")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--summary", action="store_true", help="only print the summary")
    parser.add_argument("--parts", action="store_true",
                        help="print where the identified feedforwards' error comes from")
    args = parser.parse_args(argv)
    if args.parts:
        for arm in args.arms:
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                print(json.dumps(arm_parts(arm, seed)), flush=True)
        return 0
    if not args.summary:
        RESULTS.mkdir(parents=True, exist_ok=True)
        done = set()
        if ARM_JSONL.exists():
            done = {(r.get("arm"), r["seed"]) for r in map(json.loads, filter(
                str.strip, ARM_JSONL.read_text().splitlines())) if "rms_regularized" in r}
        for arm in args.arms:
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                if (arm, seed) in done:
                    continue
                print(f"arm tracking {arm} seed {seed}", file=sys.stderr, flush=True)
                record = arm_tracking(arm, seed)
                print(json.dumps(record), file=sys.stderr, flush=True)
                with ARM_JSONL.open("a") as handle:
                    handle.write(json.dumps(record) + "\n")
    print(arm_summary())
    return 0


if __name__ == "__main__":
    sys.exit(main())
