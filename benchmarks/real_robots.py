"""Real robot logs: held-out joint torques of pysindy-xl against IDIM-LS and the maker's model.

Arms and logs (``benchmarks/data/real/``; sources, licences and columns in its README):

* ``kinova-gen3``: a Kinova Gen3 (7 joints, link-side joint torque sensors) at 1 kHz, one
  4.9 s run: the first two thirds identify, the last third is predicted. Robot
  description: Kinova's ``gen3.urdf`` (meshes removed). The run is a single sweep along one
  curve, every joint moving one way (velocity positive throughout): the training part covers
  about the first 0.48 rad of joints 2-4's 1.63 rad, so the held-out part lies wholly
  outside the positions and velocities the fits saw. It is an **extrapolation test** (how
  far a model identified on one stretch of a path carries along it), not a measure of
  identification; the record's ``coverage`` gives the ranges per joint.
* ``ur10e``: a UR10e (6 joints, motor currents, no torque sensors; the logs' directory says
  UR5, see the data README) at about 100 Hz with jittered stamps (2-13 ms): one 56 s run
  identifies, a second 56 s run with other harmonics is predicted. Torque is
  ``K_j * current_j`` with the controller's own constants, read off the identification run's
  target torque and target current (:func:`controller_constants`); every method sees
  the same torques. Robot description: ``ur10e.urdf`` (ros-industrial, meshes removed).

Methods, each on the same training samples:

* ``default``: ``XLSINDy(kinematic_catalog(system).library()).fit(q, t, u=tau)`` on the log
  as recorded (its own smoother, weak form, physically consistent fit, the noise model chosen
  by time-blocked held-out force error on the training run, :mod:`pysindy_xl.weak.selection`;
  the choice is reported above each table);
* ``default-friction``: the same with ``kinematic_catalog(system, friction="all")``: every
  joint offered viscous, Coulomb, asymmetric, Stribeck and offset terms, the fit selecting
  among them;
* ``strong`` and ``strong-friction``: the same catalogs and optimizer in the strong form, on
  the IDIM filter's derivatives and filtered torques;
* ``idim-ls``: :mod:`idim` (Pinocchio's regressor of the URDF, rotor inertia, viscous,
  smooth Coulomb ``tanh(qd / 0.01)`` (the package's law) and offset per joint, uniform
  grid, zero-phase Butterworth, decimation, OLS then WLS by truncated SVD; the cutoff and the
  SVD's rank tolerance chosen by its own time-blocked cross-validation on the training run
  only);
* ``published``: the URDF's own inertial parameters (Pinocchio's RNEA), no friction.

Metric: on the held-out samples, each method's torques from the same held-out derivatives
against the raw measured torques: RMS per joint in N m and relative to the joint's RMS torque,
and the total relative error ``|tau_pred - tau|_F / |tau|_F``. Three derivative estimates
are reported: ``butterworth`` (IDIM's filter at its chosen cutoff, the main table),
``smoother`` (the package's default smoother on the held-out positions) and ``spline``
(:func:`pysindy_xl.held_out.scoring_derivatives`, what ``score_forces`` uses). Under each
arm's main table, the default's RMS per joint against IDIM-LS's: a win where one is more
than :data:`TIE` (relative) below the other, a tie otherwise.

Usage: ``python benchmarks/real_robots.py [--arms kinova-gen3,ur10e]``; writes
``benchmarks/results/real_robots.md`` and ``.json``.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).parent))
import idim  # noqa: E402

DATA = pathlib.Path(__file__).parent / "data" / "real"
RESULTS = pathlib.Path(__file__).parent / "results"
#: Relative RMS difference below which two methods tie on a joint.
TIE = 0.1
#: What each arm's log can and cannot show, printed above its tables.
NOTES = {
    "kinova-gen3": (
        "**An extrapolation test, not a measure of identification.** The log is one 4.9 s "
        "sweep along a single curve, every joint moving one way (share of samples with "
        "positive filtered velocity below). The training part covers the first stretch of "
        "the sweep (about 0.48 of joints 2-4's 1.63 rad); the held-out part lies wholly "
        "outside the positions and velocities any fit saw (`outside` below), and the "
        "training data cannot separate Coulomb friction from the sensor offset. The tables "
        "say how far a model identified on one stretch carries along the path. IDIM-LS's "
        "cross-validation within the training sweep is itself extrapolation, and picks a "
        "truncated rank (plain least squares, tolerance 1e-10, does far worse in that "
        "cross-validation: `idim_cv` in the JSON). A "
        "physically consistent fit that carries further is a sign of robustness, not a "
        "measure of how accurate its parameters are. Joint 7's torque is below 4e-4 N m "
        "(its sensor barely sees link 7): its relative errors mean nothing."),
    "ur10e": (
        "A separate 56 s validation run with other harmonics, both directions of motion "
        "on every joint: the identification test of the two logs. The held-out run mostly "
        "stays within the training run's ranges (`outside` below: a third of wrist 1's "
        "samples lie beyond them, at most 12 % on the other joints)."),
}


def load_log(name):
    """The arrays of the log ``name`` (an NPZ of ``benchmarks/data/real``)."""
    with np.load(DATA / f"{name}.npz") as f:
        return {k: f[k] for k in f.files}


def kinova():
    """Training and held-out ``(t, q, tau)`` of the Kinova Gen3 log, and its URDF."""
    run = load_log("kinova_gen3_quadratic")
    cut = int(len(run["t"]) * 2 / 3)
    train = tuple(run[k][:cut] for k in ("t", "q", "tau"))
    test = tuple(run[k][cut:] for k in ("t", "q", "tau"))
    return train, test, DATA / "gen3.urdf"


def controller_constants(run):
    """Per joint, the factor from current to torque that the robot's controller uses.

    The log holds the controller's target torque and the target current it commands for it;
    least squares of the target current on the target torque plus viscous, Coulomb and offset
    columns (the controller's friction compensation) gives ``1 / K_j``.
    """
    qd, torque, current = run["qd"], run["target_torque"], run["target_current"]
    constants = []
    for j in range(qd.shape[1]):
        columns = np.column_stack([torque[:, j], qd[:, j], np.sign(qd[:, j]),
                                   np.ones(len(qd))])
        constants.append(1.0 / np.linalg.lstsq(columns, current[:, j], rcond=None)[0][0])
    return np.array(constants)


def ur10e():
    """Training and held-out ``(t, q, tau)`` of the UR10e logs, and its URDF."""
    train, test = load_log("ur5_14harm50sec"), load_log("ur5_15harm50sec")
    constants = controller_constants(train)
    return ((train["t"], train["q"], train["current"] * constants),
            (test["t"], test["q"], test["current"] * constants), DATA / "ur10e.urdf")


def mjcf_system(urdf):
    """The package's system of a URDF (MuJoCo compiles it; meshes are not needed)."""
    from pysindy_xl.mujoco import MJCFSystem

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the Kinova URDF's impossible inertias, balanced
        return MJCFSystem(str(urdf))


def fit_package(catalog, t, q, tau, formulation="auto", derivatives=None):
    """``XLSINDy(catalog.library())`` fitted on one run, and its fit time."""
    import pysindy_xl as px

    start = time.perf_counter()
    kwargs = {} if derivatives is None else dict(x_dot=derivatives[0], x_ddot=derivatives[1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = px.XLSINDy(catalog.library(), formulation=formulation).fit(q, t, u=tau,
                                                                            **kwargs)
    return model, time.perf_counter() - start


def catalogs(system):
    """The default kinematic catalog and the one offering every joint friction model, and
    the seconds each took to derive."""
    from pysindy_xl.mujoco import kinematic_catalog

    built, seconds = {}, {}
    for name, friction in (("default", None), ("friction", "all")):
        start = time.perf_counter()
        built[name] = kinematic_catalog(system, friction=friction)
        seconds[name] = time.perf_counter() - start
    return built, seconds


def scores(predicted, measured):
    rms = np.sqrt(np.mean((predicted - measured) ** 2, axis=0))
    scale = np.sqrt(np.mean(measured**2, axis=0))
    return {"rms_Nm": rms.tolist(), "relative": (rms / scale).tolist(),
            "total": idim.relative_error(predicted, measured)}


def coverage(train, test, cutoff):
    """How far the held-out run lies outside the training run, per joint.

    Returns ``train_range`` and ``test_range`` (rad, ``[min, max]``), ``outside`` (share of
    held-out samples whose position lies outside the training range) and
    ``positive_velocity`` (share of training and held-out samples whose velocity, filtered
    at ``cutoff``, is positive).
    """
    (t, q, _), (t_test, q_test, _) = train, test
    low, high = q.min(axis=0), q.max(axis=0)
    positive = [np.mean(idim.filtered_states(a, b, cutoff)[2] > 0, axis=0)
                for a, b in ((t, q), (t_test, q_test))]
    return {"train_range": np.column_stack([low, high]).tolist(),
            "test_range": np.column_stack([q_test.min(axis=0), q_test.max(axis=0)]).tolist(),
            "outside": np.mean((q_test < low) | (q_test > high), axis=0).tolist(),
            "positive_velocity": {"train": positive[0].tolist(), "test": positive[1].tolist()}}


def verdict(default, baseline, joints):
    """The default's RMS per joint against IDIM-LS's: a markdown table row per joint."""
    rows = []
    for name, a, b in zip(joints, default["rms_Nm"], baseline["rms_Nm"], strict=True):
        word = ("tie" if abs(a - b) <= TIE * min(a, b) else
                "default wins" if a < b else "IDIM-LS wins")
        rows.append(f"| {name} | {a:.3g} | {b:.3g} | {a / b:.2f} | {word} |")
    return rows


def run(arm):
    train, test, urdf = {"kinova-gen3": kinova, "ur10e": ur10e}[arm]()
    t, q, tau = train
    record = {"arm": arm, "train_samples": len(t), "test_samples": len(test[0]),
              "train_step_ms": [1e3 * float(np.min(np.diff(t))), 1e3 * float(np.median(
                  np.diff(t))), 1e3 * float(np.max(np.diff(t)))]}
    start = time.perf_counter()
    baseline = idim.choose_cutoff(idim.pinocchio_regressor(urdf), [(t, q, tau)])
    record["idim_s"] = time.perf_counter() - start
    record["idim_cutoff_hz"] = baseline.cutoff
    record["idim_cv"] = baseline.scores
    record["idim_tolerance"] = baseline.tolerance
    cutoff = baseline.cutoff

    system = mjcf_system(urdf)
    built, record["catalog_s"] = catalogs(system)
    models, record["fit_s"] = {}, {}
    models["default"], record["fit_s"]["default"] = fit_package(built["default"], t, q, tau)
    models["default-friction"], record["fit_s"]["default-friction"] = fit_package(
        built["friction"], t, q, tau)
    record["noise_model"] = {name: (models[name].weak_info_ or {}).get("noise_model")
                             for name in ("default", "default-friction")}
    _, qf, qd, qdd, _ = idim.filtered_states(t, q, cutoff)
    grid, _, _, _, tauf = idim.filtered_states(t, q, cutoff, tau)
    for name, catalog in (("strong", built["default"]), ("strong-friction", built["friction"])):
        models[name], record["fit_s"][name] = fit_package(
            catalog, grid, qf, tauf, formulation="strong", derivatives=(qd, qdd))
    published = idim.pinocchio_inverse_dynamics(urdf)

    predictors = {name: model.predict_forces for name, model in models.items()}
    predictors.update({"idim-ls": baseline.predict_forces, "published": published})
    held = {}
    t_test, q_test, tau_test = test
    grid, qf, qd, qdd, _ = idim.filtered_states(t_test, q_test, cutoff)
    measured = np.column_stack([np.interp(grid, t_test, tau_test[:, j])
                                for j in range(tau_test.shape[1])])
    held["butterworth"] = (qf, qd, qdd, measured)
    from pysindy_xl.weak import WhittakerSmoother

    smoothed = (models["default"].smoother or WhittakerSmoother()).smooth(t_test, q_test)
    held["smoother"] = (*smoothed, tau_test)
    from pysindy_xl.held_out import scoring_derivatives

    held["spline"] = (*scoring_derivatives(t_test, q_test), tau_test)
    record["scores"] = {
        derivatives: {name: scores(predict(*states[:3]), states[3])
                      for name, predict in predictors.items()}
        for derivatives, states in held.items()}
    record["joints"] = list(system.coordinate_names)
    record["coverage"] = coverage(train, test, cutoff)
    return record


def table(records) -> str:
    lines = ["# Real robot logs: held-out joint torques", "",
             "Generated by `python benchmarks/real_robots.py`; see its docstring for data, "
             "splits and methods. RMS in N m, relative to each joint's RMS torque in "
             "parentheses; `total` is `|tau_pred - tau|_F / |tau|_F`.", ""]
    for r in records:
        lines += [f"## {r['arm']}", "",
                  f"{r['train_samples']} training samples (steps min/median/max "
                  f"{r['train_step_ms'][0]:.2f}/{r['train_step_ms'][1]:.2f}/"
                  f"{r['train_step_ms'][2]:.2f} ms), {r['test_samples']} held out. "
                  "Catalogs " + ", ".join(f"{k} {v:.1f} s" for k, v in r["catalog_s"].items())
                  + "; fits " + ", ".join(f"{k} {v:.1f} s" for k, v in r["fit_s"].items())
                  + f"; IDIM-LS with its cutoff and rank search "
                  f"{r['idim_s']:.1f} s (cutoff {r['idim_cutoff_hz']:g} Hz, rank tolerance "
                  f"{r.get('idim_tolerance', 1e-10):g}).", ""]
        if r["arm"] in NOTES:
            lines += [NOTES[r["arm"]], ""]
        if "coverage" in r:
            c = r["coverage"]
            lines += ["| coverage | " + " | ".join(r["joints"]) + " |",
                      "|---" * (len(r["joints"]) + 1) + "|",
                      "| training range (rad) | " + " | ".join(
                          f"{a:.2f} to {b:.2f}" for a, b in c["train_range"]) + " |",
                      "| held-out range (rad) | " + " | ".join(
                          f"{a:.2f} to {b:.2f}" for a, b in c["test_range"]) + " |",
                      "| held-out samples outside the training range | " + " | ".join(
                          f"{100 * a:.0f} %" for a in c["outside"]) + " |",
                      "| positive velocity, training / held-out | " + " | ".join(
                          f"{100 * a:.0f} / {100 * b:.0f} %" for a, b in zip(
                              c["positive_velocity"]["train"],
                              c["positive_velocity"]["test"], strict=True)) + " |", ""]
        for name, choice in r.get("noise_model", {}).items():
            if choice:
                lines += [f"Noise model of `{name}`: **{choice['chosen']}** (half-width "
                          f"{choice['half_width']:.3g} s); held-out errors of the candidates "
                          "on the training run: " + ", ".join(
                              f"{c['noise']} {c['half_width']:.3g} s: "
                              f"{100 * c['held_out_error']:.2f} %"
                              for c in choice["candidates"]) + ".", ""]
        for derivatives, by_method in r["scores"].items():
            lines += [f"Held-out derivatives: **{derivatives}**", "",
                      "| method | total | " + " | ".join(r["joints"]) + " |",
                      "|---" * (len(r["joints"]) + 2) + "|"]
            for name, s in by_method.items():
                cells = [f"{a:.3g} ({100 * b:.1f} %)" for a, b in
                         zip(s["rms_Nm"], s["relative"], strict=True)]
                lines.append(f"| {name} | {100 * s['total']:.2f} % | " + " | ".join(cells)
                             + " |")
            lines.append("")
            if derivatives == "butterworth" and {"default", "idim-ls"} <= set(by_method):
                lines += [f"Default against IDIM-LS per joint (RMS in N m; a tie within "
                          f"{100 * TIE:.0f} %):", "",
                          "| joint | default | IDIM-LS | ratio | |", "|---|---|---|---|---|",
                          *verdict(by_method["default"], by_method["idim-ls"], r["joints"]),
                          ""]
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arms", default="kinova-gen3,ur10e")
    args = parser.parse_args()
    records = []
    for arm in args.arms.split(","):
        print(f"{arm} ...", flush=True)
        records.append(run(arm))
        print(table(records[-1:]), flush=True)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "real_robots.json").write_text(json.dumps(records, indent=1))
    (RESULTS / "real_robots.md").write_text(table(records))


if __name__ == "__main__":
    main()
