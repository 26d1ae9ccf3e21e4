"""Payload on a real arm: identified payload mass and held-out torques of the loaded arm.

Data (``benchmarks/data/real/``, sources and columns in its README): four runs of one
Universal Robots arm, motor currents at about 100 Hz with jittered stamps, from
``wissem01chiha/dynamic-identification`` (there under ``datasets/ur5/``, the files' prefix
kept here). The runs and the code that recorded them come from
``shamilmamedov/dynamic_calibration``, where they are runs of a **UR10e** (its
``parseURData.m``, ``load_regressor_UR10E.m`` and ``ur10e.urdf``), so the robot description is
``ur10e.urdf`` (ros-industrial's ``ur_e_description``, meshes removed). That repository's
drive-gain script (``estimate_drive_gains.m``) uses the two ``14harm`` runs with ``m_load =
2.805`` kg: the documented payload mass of the ``Load`` runs.

* ``ur5_14harm50sec``: unloaded; identifies the arm and the torque constants;
* ``ur5_14harm50secLoad``, ``ur5_15harm50secLoad``: the same payload, two trajectories. Each
  identifies the payload in turn while the other is predicted.

Torque is ``K_j * current_j``, one constant per joint (UR does not publish them), read off
the controller on the unloaded run: the log holds the controller's target torque and the
target current it commands, and least squares of the one on the other plus friction columns
gives the controller's own ``K_j`` (:func:`controller_constants`). No loaded data and no
payload mass enter the constants, so the payload's mass is an independent check. For
comparison the record also holds the constants ``_torque_constants`` fits (the
URDF's nominal inverse dynamics on the current): close on the shoulder and elbow,
meaningless on the wrists, whose nominal torques are too small to fix a scale.

Methods, scored on the held-out loaded run with the same derivatives
(:func:`pysindy_xl.held_out.scoring_derivatives`) against the measured torques:

* ``arm``: ``XLSINDy(kinematic_catalog(system).library()).fit(q, t, u=tau)`` on the unloaded
  run, the payload ignored;
* ``arm+payload``: the same plus the payload that
  ``identify_payload(catalog, q, t, tau, arm=model)`` finds on the other loaded run;
* ``idim-ls loaded``: IDIM-LS (``benchmarks/idim.py``) refitted on the other loaded run
  (reference: it sees the loaded arm directly, with its own friction and offsets).

The arm's own held-out error on the unloaded validation run ``ur5_15harm50sec`` is reported
for context.

Usage: ``python benchmarks/real_payload.py``; writes ``benchmarks/results/real_payload.md``
and ``.json``.
"""

from __future__ import annotations

import json
import pathlib
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).parent))
import idim  # noqa: E402
from real_robots import (  # noqa: E402
    controller_constants,
    fit_package,
    load_log,
    mjcf_system,
    scores,
)

DATA = pathlib.Path(__file__).parent / "data" / "real"
RESULTS = pathlib.Path(__file__).parent / "results"
URDF = DATA / "ur10e.urdf"
DOCUMENTED_MASS = 2.805  # kg, m_load of shamilmamedov/dynamic_calibration's drive-gain script
LOADED = ("ur5_14harm50secLoad", "ur5_15harm50secLoad")


def _torque_constants(urdf, t, q, current, cutoff=4.0):
    """Per joint, the factor from current to torque: least squares of the URDF's nominal
    torque plus friction columns on the measured current."""
    nominal = idim.pinocchio_inverse_dynamics(urdf)
    _, qf, qd, qdd, cf = idim.filtered_states(t, q, cutoff, current)
    tau = nominal(qf, qd, qdd)
    constants = []
    for j in range(q.shape[1]):
        columns = np.column_stack([tau[:, j], qd[:, j], np.sign(qd[:, j]), np.ones(len(qd))])
        slope = np.linalg.lstsq(columns, cf[:, j], rcond=None)[0][0]
        constants.append(1.0 / slope)
    return np.array(constants)


def runs():
    """``(t, q, tau)`` of every run, torques from the unloaded run's constants."""
    unloaded = load_log("ur5_14harm50sec")
    constants = controller_constants(unloaded)
    nominal = _torque_constants(URDF, unloaded["t"], unloaded["q"], unloaded["current"])
    out = {}
    for name in ("ur5_14harm50sec", "ur5_15harm50sec", *LOADED):
        run = unloaded if name == "ur5_14harm50sec" else load_log(name)
        out[name] = (run["t"], run["q"], run["current"] * constants)
    return out, constants, nominal


def consistent(payload) -> bool:
    """Whether the payload's pseudo-inertia is positive semidefinite (to solver tolerance)."""
    from pysindy_xl.physical import pseudo_inertia_matrix

    lowest = np.linalg.eigvalsh(pseudo_inertia_matrix(payload.parameters))[0]
    return bool(lowest >= -1e-6 * max(1.0, abs(payload.mass)))


def run():
    from pysindy_xl.held_out import scoring_derivatives
    from pysindy_xl.mujoco import identify_payload, kinematic_catalog

    data, constants, nominal = runs()
    record = {"robot": "UR10e", "urdf": URDF.name, "documented_mass_kg": DOCUMENTED_MASS,
              "torque_constants": constants.tolist(),
              "torque_constants_nominal_model": nominal.tolist()}
    system = mjcf_system(URDF)
    record["joints"] = list(system.coordinate_names)
    start = time.perf_counter()
    catalog = kinematic_catalog(system)
    record["catalog_s"] = time.perf_counter() - start
    t, q, tau = data["ur5_14harm50sec"]
    model, record["fit_s"] = fit_package(catalog, t, q, tau)
    t_v, q_v, tau_v = data["ur5_15harm50sec"]
    record["arm_unloaded_validation"] = scores(
        model.predict_forces(*scoring_derivatives(t_v, q_v)), tau_v)

    regressor = idim.pinocchio_regressor(URDF)
    record["splits"] = []
    for identify, held in (LOADED, LOADED[::-1]):
        t_i, q_i, tau_i = data[identify]
        start = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            payload = identify_payload(catalog, q_i, t_i, tau_i, arm=model)
        seconds = time.perf_counter() - start
        baseline = idim.choose_cutoff(regressor, [(t_i, q_i, tau_i)])
        t_h, q_h, tau_h = data[held]
        states = scoring_derivatives(t_h, q_h)
        arm = model.predict_forces(*states)
        predicted = {"arm": arm, "arm+payload": arm + payload.forces(catalog, *states),
                     "idim-ls loaded": baseline.predict_forces(*states)}
        record["splits"].append({
            "identify": identify, "held_out": held, "payload": payload.to_dict(),
            "payload_s": seconds, "consistent": consistent(payload),
            "mass_error": payload.mass / DOCUMENTED_MASS - 1,
            "idim_cutoff_hz": baseline.cutoff,
            "scores": {name: scores(p, tau_h) for name, p in predicted.items()}})
    # the same masses with the constants fitted to the URDF's nominal model instead
    rescale = nominal / constants
    t, q, tau = data["ur5_14harm50sec"]
    model, _ = fit_package(catalog, t, q, tau * rescale)
    record["mass_with_nominal_model_constants"] = {}
    for name in LOADED:
        t_i, q_i, tau_i = data[name]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            payload = identify_payload(catalog, q_i, t_i, tau_i * rescale, arm=model)
        record["mass_with_nominal_model_constants"][name] = payload.mass
    return record


def table(r) -> str:
    joints = r["joints"]
    lines = ["# Payload on a real arm (UR10e, motor currents)", "",
             "Generated by `python benchmarks/real_payload.py`; see its docstring for data, "
             "splits and methods. Documented payload mass "
             f"{r['documented_mass_kg']} kg. Torque constants (N m/A, the controller's, read "
             "on the unloaded run): " + ", ".join(f"{k:.3g}" for k in r["torque_constants"])
             + " (fitted to the URDF's nominal model instead: "
             + ", ".join(f"{k:.3g}" for k in r["torque_constants_nominal_model"]) + "). "
             f"Catalog {r['catalog_s']:.1f} s, arm fit {r['fit_s']:.1f} s (shared 2-core "
             "machine). RMS in N m, relative to each joint's RMS torque in parentheses; "
             "`total` is `|tau_pred - tau|_F / |tau|_F`.", "",
             "## Identified payload", "",
             "| identified on | mass (kg) | error vs 2.805 kg | COM in wrist_3_link (m) "
             "| principal inertias about COM (kg m^2) | consistent | identifiable | "
             "residual | time |", "|---" * 9 + "|"]
    for s in r["splits"]:
        p = s["payload"]
        eig = np.linalg.eigvalsh(np.array(p["inertia"]))
        lines.append(f"| {s['identify']} | {p['mass']:.3f} | {100 * s['mass_error']:+.1f} % | "
                     + "(" + ", ".join(f"{c:.3f}" for c in p["com"]) + ") | "
                     + ", ".join(f"{e:.2g}" for e in eig) + f" | {s['consistent']} | "
                     f"{p['identifiable']} | {100 * p['residual']:.1f} % | "
                     f"{s['payload_s']:.1f} s |")
    lines += ["", "## Held-out torques of the loaded arm", ""]
    for s in r["splits"]:
        lines += [f"Payload from **{s['identify']}**, predicting **{s['held_out']}** "
                  f"(IDIM-LS cutoff {s['idim_cutoff_hz']:g} Hz)", "",
                  "| method | total | " + " | ".join(joints) + " |",
                  "|---" * (len(joints) + 2) + "|"]
        for name, sc in s["scores"].items():
            cells = [f"{a:.3g} ({100 * b:.1f} %)" for a, b in
                     zip(sc["rms_Nm"], sc["relative"], strict=True)]
            lines.append(f"| {name} | {100 * sc['total']:.2f} % | " + " | ".join(cells) + " |")
        lines.append("")
    masses = r["mass_with_nominal_model_constants"]
    lines += ["With the torque constants fitted to the URDF's nominal model instead, the "
              "identified mass is " + ", ".join(f"{m:.3f} kg ({name})" for name, m in
                                                 masses.items()) + ".", ""]
    v = r["arm_unloaded_validation"]
    lines += ["For context, the arm (no payload) on the unloaded validation run "
              f"`ur5_15harm50sec`: total {100 * v['total']:.2f} %.", ""]
    return "\n".join(lines)


def main():
    record = run()
    text = table(record)
    print(text, flush=True)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "real_payload.json").write_text(json.dumps(record, indent=1))
    (RESULTS / "real_payload.md").write_text(text)


if __name__ == "__main__":
    main()
