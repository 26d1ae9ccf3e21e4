"""The demo, first try, on published arm models: ``pysindy-xl demo ARM.xml --noise 0.01``.

Runs the command line demo (default settings, 1 % position noise) on each stripped MuJoCo
Menagerie arm of ``benchmarks/models/menagerie/`` in a subprocess and prints one row per arm:
exit code, verdict, mass-matrix and gravity errors against MuJoCo (``mj_fullM``,
``qfrc_bias``; largest error relative to the largest entry, at random states), the peak joint
velocity of the training data, the integration chosen (integrator and substeps) and the wall
time. Targets (issue 42): exit 0, VALID, mass matrix <= 2 %, under 60 s.

Usage::

    python benchmarks/published_arms.py [ARM ...] [--timeout S] [--out DIR] [-- DEMO OPTIONS]

Writes ``benchmarks/results/published_arms.jsonl`` (one record per arm, appended) and
``benchmarks/results/published_arms.md`` (the table of this run).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
MODELS = os.path.join(HERE, "models", "menagerie")
RESULTS = os.path.join(HERE, "results")
ARMS = ("fr3", "xarm7", "ur10e", "sawyer", "z1", "lite6", "m1013", "piper", "arx_l5")


def run_arm(arm: str, timeout: float, extra: list[str]) -> dict:
    """One demo run; the record of its report (or of its failure)."""
    out = tempfile.mkdtemp(prefix=f"demo_{arm}_")
    command = [sys.executable, "-m", "pysindy_xl.cli", "demo", os.path.join(MODELS, f"{arm}.xml"),
               "--noise", "0.01", "--no-plots", "--quiet", "--out", out, *extra]
    env = dict(os.environ, PYTHONPATH=os.path.dirname(HERE))
    load_before = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
    start = time.perf_counter()
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout, env=env)
        code, tail = done.returncode, (done.stdout + done.stderr)[-2000:]
    except subprocess.TimeoutExpired:
        code, tail = "timeout", ""
    record = {"arm": arm, "exit": code, "time_s": time.perf_counter() - start,
              "options": ["--noise", "0.01", *extra],
              "load_average": [load_before,
                               os.getloadavg()[0] if hasattr(os, "getloadavg") else None]}
    path = os.path.join(out, "report.json")
    if os.path.exists(path):
        with open(path, encoding="utf-8") as handle:
            report = json.load(handle)
        validation, physics, data = report["validation"], report["physics"] or {}, report["data"]
        peak = data.get("peak_velocity") or {}
        record.update(
            valid=validation.get("valid"), failure=validation.get("failure"),
            drive=validation.get("drive"), force_error=validation.get("force_error"),
            simulator=validation.get("simulator"),
            position_rmse=validation.get("position_rmse"),
            mass_error=physics.get("mass_error"), gravity_error=physics.get("gravity_error"),
            peak_velocity=max(peak.values()) if peak else None,
            peak_joint=max(peak, key=peak.get) if peak else None,
            integrator=data.get("integrator"), substeps=data.get("substeps"),
            reason=(data.get("integration") or {}).get("reason"),
            timings=report.get("timings_s"))
    elif code != 0:
        record["error"] = tail.strip().splitlines()[-1] if tail.strip() else "no report"
    return record


def _cell(value, fmt="{:.2%}"):
    return "-" if value is None else fmt.format(value)


def table(records) -> str:
    lines = ["| arm | exit | verdict | mass matrix | gravity | peak velocity (rad/s) | "
             "integrator | substeps | time (s) |", "|---|---|---|---|---|---|---|---|---|"]
    for r in records:
        verdict = "-" if r.get("valid") is None else ("VALID" if r["valid"] else "INVALID")
        lines.append(
            f"| {r['arm']} | {r['exit']} | {verdict} | {_cell(r.get('mass_error'))} | "
            f"{_cell(r.get('gravity_error'))} | {_cell(r.get('peak_velocity'), '{:.2f}')} | "
            f"{r.get('integrator', '-')} | {r.get('substeps', '-')} | {r['time_s']:.0f} |")
    return "\n".join(lines)


def details(records) -> str:
    """Per arm: the closed-loop force error, who simulated the model, the phases' times and
    the machine's load average (1 min) before and after the run."""
    lines = ["| arm | force error | simulator | generate / identify / validate (s) | load "
             "before, after | failure |", "|---|---|---|---|---|---|"]
    for r in records:
        times = r.get("timings") or {}
        phases = " / ".join(f"{times[k]:.0f}" if k in times else "-"
                            for k in ("generate", "identify", "validate"))
        load = ", ".join("-" if v is None else f"{v:.1f}" for v in r.get("load_average", ()))
        failure = r.get("failure") or r.get("error") or "-"
        lines.append(f"| {r['arm']} | {_cell(r.get('force_error'), '{:.4f}')} | "
                     f"{r.get('simulator') or '-'} | {phases} | {load} | {failure} |")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("arms", nargs="*", default=list(ARMS))
    parser.add_argument("--timeout", type=float, default=600.0)
    parser.add_argument("--label", default="", help="a note stored with each record")
    args, extra = parser.parse_known_args(argv)
    extra = [e for e in extra if e != "--"]
    records = []
    for arm in args.arms:
        record = run_arm(arm, args.timeout, extra)
        record["label"] = args.label
        records.append(record)
        print(table([record]).splitlines()[-1], flush=True)
        os.makedirs(RESULTS, exist_ok=True)
        with open(os.path.join(RESULTS, "published_arms.jsonl"), "a", encoding="utf-8") as f:
            f.write(json.dumps(record) + "\n")
    text = table(records) + "\n\n" + details(records)
    print(text)
    with open(os.path.join(RESULTS, "published_arms.md"), "w", encoding="utf-8") as handle:
        handle.write("# `pysindy-xl demo ARM.xml --noise 0.01` on published arms\n\n"
                     f"Options: {' '.join(['--noise', '0.01', *extra])}. {args.label}\n"
                     f"Machine: {os.cpu_count()} cores, shared with other jobs; the load "
                     "average of each run is in the second table (wall times grow with it).\n\n"
                     + text + "\n")


if __name__ == "__main__":
    main()
