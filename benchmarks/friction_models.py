"""Held-out torque error with and without the friction and sensor models of real joints.

Simulated arms (the planar and spatial arms of the tests, a 7-joint robot-like arm) follow a
finite Fourier excitation; their torques are MuJoCo's inverse dynamics (``mj_inverse``, the
MJCF damping removed) plus a friction written out per joint: viscous, Coulomb
(``tanh(v / 0.01)``) and, joint by joint, an asymmetric Coulomb (``tanh^2``), a Stribeck term
(``tanh exp(-(v / 0.1)^2)``) and a torque-sensor offset, sized against each joint's rigid-body
torque. The positions are quantized like an encoder's (1e-5 rad) and the torques carry white
noise of 1 or 2 % of each joint's spread. Both models are the package's default fit from
positions and torques (``XLSINDy(catalog.library()).fit(q, t, u=tau)``, weak form) on the first
2/3 of the run: ``plain``, ``kinematic_catalog(system)`` (viscous + Coulomb);
``friction``, ``kinematic_catalog(system, friction="all")`` (the fit selects per joint). The
held-out torque RMS of the last 1/3 uses the exact derivatives for both, next to the RMS of
the noise itself (the floor).

Usage: ``python benchmarks/friction_models.py [--noise 0.01 0.02] [--seeds 0]``; writes
``benchmarks/results/friction_models.{json,md}``.
"""

import argparse
import json
import os
import platform
import sys
import time

import mujoco
import numpy as np

import pysindy_xl as px
from pysindy_xl.mujoco import MJCFSystem, kinematic_catalog

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
import kinematic_models  # noqa: E402

RESULTS = os.path.join(os.path.dirname(__file__), "results")
EPS, VS = 0.01, 0.1
MODELS = ("viscous", "coulomb", "asymmetric", "stribeck", "offset")


def arms():
    return {"planar-arm": kinematic_models.PLANAR_ARM,
            "spatial-arm": kinematic_models.SPATIAL_ARM,
            "robot-arm-7": kinematic_models.robot_arm(7)}


def run_data(system, rng, duration=30.0, dt=0.002):
    """Fourier excitation, inverse-dynamics torques and the friction truth."""
    n = system.n
    t = np.arange(0.0, duration, dt)
    harmonics = np.arange(1, 6)
    w = 2 * np.pi * 0.1 * harmonics
    a, b = rng.normal(size=(2, 5, n)) * 0.3 / harmonics[:, None]
    s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
    q, qd = s @ a + c @ b, (c * w) @ a - (s * w) @ b
    qdd = -(s * w**2) @ a - (c * w**2) @ b
    model = system.mj_model()
    model.dof_damping[:] = 0.0
    model.dof_frictionloss[:] = 0.0
    data = mujoco.MjData(model)
    rigid = np.empty_like(q)
    for k in range(len(t)):
        data.qpos[:], data.qvel[:], data.qacc[:] = q[k], qd[k], qdd[k]
        mujoco.mj_inverse(model, data)
        rigid[k] = data.qfrc_inverse
    size = np.sqrt(np.mean(rigid**2, axis=0))
    truth = np.zeros((n, 5))
    truth[:, 0] = 0.05 * size / np.sqrt(np.mean(qd**2, axis=0))
    truth[:, 1] = 0.08 * size
    truth[::2, 2] = 0.03 * size[::2]
    truth[1::2, 3] = 0.05 * size[1::2]
    truth[:, 4] = 0.04 * size * rng.choice([-1.0, 0.0, 1.0], n)
    sign = np.tanh(qd / EPS)
    friction = (truth[:, 0] * qd + truth[:, 1] * sign + truth[:, 2] * sign**2
                + truth[:, 3] * sign * np.exp(-((qd / VS) ** 2)) + truth[:, 4])
    return t, q, qd, qdd, rigid + friction, truth


#: The fits compared: catalog options and optimizer (None: the default).
VARIANTS = {"plain": ({}, None), "friction": ({"friction": "all"}, None),
            "unbagged": ({"friction": "all"}, "unbagged")}


def evaluate(name, xml, noise_level, seed, variants=("plain", "friction")):
    system = MJCFSystem(xml)
    rng = np.random.default_rng(seed)
    t, q, qd, qdd, tau, truth = run_data(system, rng)
    noise = noise_level * tau.std(axis=0) * rng.normal(size=tau.shape)
    measured_q, measured_tau = np.round(q / 1e-5) * 1e-5, tau + noise
    split = 2 * len(t) // 3
    row = {"arm": name, "noise": noise_level, "seed": seed, "joints": list(system.joint_names),
           "floor": np.sqrt(np.mean(noise[split:] ** 2, axis=0)).tolist(),
           "torque_rms": np.sqrt(np.mean(tau[split:] ** 2, axis=0)).tolist(),
           "truth": truth.tolist()}
    for label in variants:
        options, optimizer = VARIANTS[label]
        if optimizer == "unbagged":  # the default's selection without bagging
            optimizer = px.PhysicalOptimizer(px.ExplicitOptimizer(select="friction"))
        start = time.perf_counter()
        catalog = kinematic_catalog(system, **options)
        model = px.XLSINDy(catalog.library(), optimizer).fit(measured_q[:split], t[:split],
                                                             u=measured_tau[:split])
        seconds = time.perf_counter() - start
        error = model.predict_forces(q[split:], qd[split:], qdd[split:]) - measured_tau[split:]
        row[label] = {"rms": np.sqrt(np.mean(error**2, axis=0)).tolist(),
                      "seconds": seconds, "formulation": model.formulation_}
        joints = model.physical_parameters().get("joint_friction")
        if joints:
            row[label]["identified"] = [[joints[j][m] for m in MODELS]
                                        for j in system.joint_names]
    return row


def _moving_error(truth, found) -> float:
    """Largest relative error of the viscous, Coulomb and Stribeck terms and of the sum of
    asymmetry and offset (the even torque of a moving joint, which the samples away from
    rest determine; the split between the two rests on the few samples at rest)."""
    def merged(values):
        return np.column_stack([values[:, :2], values[:, 3], values[:, 2] + values[:, 4]])
    truth, found = merged(truth), merged(found)
    present = truth != 0
    return float(np.max(np.abs(found - truth)[present] / np.abs(truth[present]),
                        initial=0.0))


def markdown(rows) -> str:
    lines = [f"Held-out torque RMS (N m) with and without the joint friction models "
             f"({platform.machine()}, Python {platform.python_version()}; default fit from "
             "quantized positions, 2/3 to fit, 1/3 held out; floor: the RMS of the torque "
             "noise; wall times on a shared 2-core machine)", "",
             "| arm | noise | joint | floor | viscous + Coulomb | friction models | "
             "ratio to floor (plain / models) | models unbagged (ratio) |",
             "|---|---|---|---|---|---|---|---|"]
    for row in rows:
        for k, joint in enumerate(row["joints"]):
            floor, plain, models = (row["floor"][k], row["plain"]["rms"][k],
                                    row["friction"]["rms"][k])
            unbagged = (f"{row['unbagged']['rms'][k] / floor:.2f}" if "unbagged" in row
                        else "-")
            lines.append(f"| {row['arm']} | {row['noise']:.0%} | {joint} | {floor:.3g} | "
                         f"{plain:.3g} | {models:.3g} | {plain / floor:.2f} / "
                         f"{models / floor:.2f} | {unbagged} |")
    lines += ["", "Identified joint models against the truth (terms the joints have, terms they "
              "do not):", "", "| arm | noise | fit | missed | spurious | largest error of a "
              "present term (relative) | of which model | largest, asymmetry and offset as "
              "their sum |",
              "|---|---|---|---|---|---|---|---|"]
    for row, key in ((row, key) for row in rows for key in ("friction", "unbagged")
                     if key in row):
        truth, found = np.array(row["truth"]), np.array(row[key]["identified"])
        present = truth != 0
        relative = np.where(present, np.abs(found - truth) / np.where(present, np.abs(truth),
                                                                         1.0), 0.0)
        worst = np.unravel_index(np.argmax(relative), relative.shape)
        lines.append(f"| {row['arm']} | {row['noise']:.0%} | {key} | "
                     f"{int(np.sum(present & (found == 0)))} of {int(present.sum())} | "
                     f"{int(np.sum(~present & (found != 0)))} of {int((~present).sum())} | "
                     f"{relative[worst]:.1%} | {row['joints'][worst[0]]} "
                     f"{MODELS[worst[1]]} | {_moving_error(truth, found):.1%} |")
    lines += ["", "| arm | noise | total relative error, plain | with models | unbagged | "
              "floor | fit s plain / models / unbagged |", "|---|---|---|---|---|---|---|"]
    for row in rows:
        scale = np.sqrt(np.sum(np.square(row["torque_rms"])))
        keys = [key for key in VARIANTS if key in row]
        total = {key: f"{np.sqrt(np.sum(np.square(row[key]['rms']))) / scale:.2%}"
                 for key in keys}
        floor = np.sqrt(np.sum(np.square(row["floor"]))) / scale
        lines.append(f"| {row['arm']} | {row['noise']:.0%} | {total['plain']} | "
                     f"{total['friction']} | {total.get('unbagged', '-')} | {floor:.2%} | "
                     + " / ".join(f"{row[key]['seconds']:.1f}" for key in keys) + " |")
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--noise", type=float, nargs="+", default=[0.01, 0.02])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--arms", nargs="+", default=list(arms()))
    parser.add_argument("--variants", nargs="+", default=["plain", "friction"],
                        choices=list(VARIANTS))
    parser.add_argument("--markdown-only", action="store_true",
                        help="rewrite the table from the stored results")
    args = parser.parse_args()
    rows = []
    if args.markdown_only:
        args.arms = []
    for name in args.arms:
        for noise in args.noise:
            for seed in args.seeds:
                rows.append(evaluate(name, arms()[name], noise, seed, args.variants))
                print(json.dumps({k: rows[-1][k] for k in ("arm", "noise", "floor")}),
                      [[round(v, 4) for v in rows[-1][k]["rms"]] for k in args.variants],
                      flush=True)
    os.makedirs(RESULTS, exist_ok=True)
    path = os.path.join(RESULTS, "friction_models.json")
    if os.path.exists(path):  # keep the rows of other runs (arms, noise levels, seeds)
        with open(path, encoding="utf-8") as f:
            done = {(r["arm"], r["noise"], r["seed"]): r for r in json.load(f)}
        for r in rows:  # new variants join the stored row of the same run
            done[(r["arm"], r["noise"], r["seed"])] = {**done.get(
                (r["arm"], r["noise"], r["seed"]), {}), **r}
        rows = sorted(done.values(), key=lambda r: (list(arms()).index(r["arm"]), r["noise"],
                                                   r["seed"]))
    with open(path, "w", encoding="utf-8") as f:
        json.dump(rows, f, indent=1)
    with open(os.path.join(RESULTS, "friction_models.md"), "w", encoding="utf-8") as f:
        f.write(markdown(rows))


if __name__ == "__main__":
    main()
