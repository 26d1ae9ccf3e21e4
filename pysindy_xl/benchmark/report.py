"""Saving the table: Markdown, CSV, a PNG figure, and a description of the machine."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import time

import numpy as np

from .grid import config_label
from .ranking import format_table, ranking_table, table_to_csv, table_to_markdown
from .records import latest_records

__all__ = ["machine_description", "grid_summary", "write_report", "plot_table"]

_PACKAGES = ("numpy", "scipy", "sympy", "scikit-learn", "pysindy", "cvxpy", "mujoco", "joblib",
             "jax", "pysindy-xl")


def _proc_value(path: str, key: str) -> str | None:
    """The value of the first ``key: value`` line of a /proc file, None if absent."""
    try:
        with open(path, encoding="utf-8") as handle:
            for line in handle:
                if line.startswith(key):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return None


def _cpu_model() -> str:
    return _proc_value("/proc/cpuinfo", "model name") or platform.processor() or platform.machine()


def _memory_gib() -> float | None:
    total = _proc_value("/proc/meminfo", "MemTotal")  # "131894260 kB"
    return None if total is None else round(int(total.split()[0]) / 2**20, 1)


def _git(*arguments) -> str | None:
    try:
        out = subprocess.run(["git", *arguments], capture_output=True, text=True, timeout=10,
                             cwd=os.path.dirname(os.path.abspath(__file__)))
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() if out.returncode == 0 else None


def _git_state() -> dict:
    """Commit of the package's checkout and whether its own files had local changes."""
    commit = _git("rev-parse", "--short", "HEAD")
    if commit is None:
        return {"git_commit": None}
    changed = _git("status", "--porcelain", "--untracked-files=no", "--", "../")
    return {"git_commit": commit, "package_modified": bool(changed)}


def machine_description(n_jobs=None, backend=None) -> dict:
    """The machine and software a grid ran on (JSON-serializable).

    Parameters
    ----------
    n_jobs : int, default=None
        Parallel processes of the grid, recorded.
    backend : str, default=None
        Joblib backend of the grid, recorded.

    Returns
    -------
    dict
        CPU, memory, Python and package versions, the git commit and the options.
    """
    from importlib import metadata
    versions = {}
    for name in _PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return {
        "date": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "platform": platform.platform(),
        "cpu": _cpu_model(),
        "logical_cores": os.cpu_count(),
        "memory_gib": _memory_gib(),
        "python": sys.version.split()[0],
        "packages": versions,
        **_git_state(),
        "n_jobs": n_jobs,
        "backend": backend or "loky",
        # other work on the machine slows the runs down: say how busy it was
        "load_average_1_5_15min": load_average(),
    }


def load_average():
    """The 1, 5 and 15 minute load averages, or None where the system has none.

    Returns
    -------
    list of float or None
        The load averages.
    """
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except (OSError, AttributeError):
        return None


def grid_summary(records, configs=None, reference: str = "mixed x mixed") -> dict:
    """Counts, run times and the acceptance targets of records: ``runs``, ``trajectories``,
    ``statuses``, ``run_time_s`` (median, p90, max, total) and ``reference`` (valid fraction of
    the ``reference`` configuration).

    Parameters
    ----------
    records : iterable of dict
        Run records.
    configs : sequence of str, default=None
        Configurations counted even without records.
    reference : str, default="mixed x mixed"
        The configuration whose valid fraction is reported.

    Returns
    -------
    dict
        ``runs``, ``trajectories``, ``statuses``, ``run_time_s`` and ``reference``.
    """
    records = latest_records(list(records))
    statuses = dict.fromkeys(("ok", "invalid", "timeout", "error"), 0)
    for r in records:
        statuses[r["status"]] += 1
    times = np.array([r["time_s"]["run"] for r in records
                      if isinstance((r.get("time_s") or {}).get("run"), (int, float))])
    mine = [r for r in records if r["config"] == reference]
    valid = sum(r["status"] == "ok" for r in mine)
    return {
        "runs": len(records),
        "trajectories": len({r["trajectory_id"] for r in records}),
        "statuses": statuses,
        "run_time_s": {
            "median": float(np.median(times)) if len(times) else None,
            "p90": float(np.percentile(times, 90)) if len(times) else None,
            "max": float(times.max()) if len(times) else None,
            "total": float(times.sum()) if len(times) else 0.0,
        },
        "reference": {"config": reference, "trajectories": len(mine), "valid": valid,
                      "valid_fraction": valid / len(mine) if mine else None},
    }


def plot_table(table, records, path) -> None:
    """PNG at ``path``: outcome counts per configuration of ``table`` (:func:`ranking_table`) and
    the validation errors of the valid runs among ``records``.

    Parameters
    ----------
    table : list of dict
        Rows of :func:`~pysindy_xl.benchmark.ranking.ranking_table`.
    records : iterable of dict
        Run records.
    path : str or os.PathLike
        The PNG file to write.
    """
    import matplotlib
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    configs = [row["combo type"] for row in table]
    parts = [("1st", "#1a9850"), ("2nd", "#91cf60"), ("2nd>", "#d9ef8b"),
             ("invalid", "#fc8d59"), ("timeout", "#d73027"), ("uncompleted", "#999999")]
    fig, (left, right) = plt.subplots(1, 2, figsize=(13, 0.45 * len(configs) + 2.2),
                                      sharey=True, gridspec_kw={"width_ratios": [1.2, 1]})
    y = np.arange(len(configs))[::-1]
    base = np.zeros(len(configs))
    for column, color in parts:
        values = np.array([row[column] for row in table], dtype=float)
        left.barh(y, values, left=base, color=color, label=column, edgecolor="white")
        base += values
    left.set_yticks(y, configs)
    left.set_xlabel("runs (trajectories)")
    left.set_title("Outcome per configuration (number at the right: success rate)")
    left.legend(ncols=6, fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14),
                frameon=False)
    right_edge = max(base.max(), 1.0)
    left.set_xlim(0, right_edge * 1.13)
    for yk, row in zip(y, table, strict=True):
        rate = row["success rate"]
        label = "-" if rate != rate else f"{rate:.2f}"
        left.text(right_edge * 1.01, yk, label, va="center", fontsize=8)
    errors = {c: [] for c in configs}
    for r in latest_records(records):
        if r["status"] == "ok" and r["config"] in errors:
            errors[r["config"]].append(r["metrics"]["position_rmse"])
    for yk, config in zip(y, configs, strict=True):
        values = np.asarray(errors[config], dtype=float)
        if len(values):
            jitter = np.random.default_rng(0).uniform(-0.2, 0.2, len(values))
            right.scatter(values, yk + jitter, s=10, alpha=0.6, color="#2c7bb6")
            right.plot([np.median(values)] * 2, [yk - 0.3, yk + 0.3], color="black")
    right.set_xscale("log")
    right.set_xlabel("validation position RMSE of valid models (rad or m), bar = median")
    right.set_title("Validation error")
    right.grid(axis="x", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _settings_lines(settings) -> list[str]:
    if settings is None:
        return []
    d = settings if isinstance(settings, dict) else settings.to_dict()
    return [
        f"- grid `{d.get('name')}`: systems {', '.join(d['systems'])}; friction levels "
        f"{d['friction_levels']} (x default damping); forcing {', '.join(d['forcings'])}; "
        f"noise {d['noise_levels']} (all channels), {d.get('position_noise_levels', [])} "
        f"(positions only); seeds {d['seeds']}",
        f"- data: {d['n_trajectories']} training trajectories of {d['duration']:g} s per "
        f"dataset, every {d['sample_every']} ms; validation on a fresh {d['validation_duration']:g}"
        f" s MuJoCo trajectory; time limit {d['timeout']:g} s per run",
    ]


def write_report(records, out_dir, settings=None, machine=None, configs=None) -> dict:
    """Write ``table.md``, ``table.csv``, ``table.png``, ``summary.json`` (and ``machine.json``
    when ``machine``, from :func:`machine_description`, is given) to ``out_dir``; returns
    ``{"table", "summary", "files", "text"}``. ``settings`` (a GridSettings or its dict) is
    described in the Markdown, ``configs`` are listed even without records.

    Parameters
    ----------
    records : iterable of dict
        Run records.
    out_dir : str or os.PathLike
        The directory written to.
    settings : GridSettings or dict, default=None
        Described in the Markdown.
    machine : dict, default=None
        From :func:`machine_description`; written to ``machine.json``.
    configs : sequence of str, default=None
        Configurations listed even without records.

    Returns
    -------
    dict
        ``{"table", "summary", "files", "text"}``.

    Examples
    --------
    >>> import os, tempfile
    >>> records = [{"run_id": c, "trajectory_id": "t0", "config": c, "status": "ok",
    ...             "metrics": {"position_rmse": e}, "time_s": {"run": 1.0}}
    ...            for c, e in [("A", 0.01), ("B", 0.02)]]
    >>> out = tempfile.mkdtemp()
    >>> report = write_report(records, out)
    >>> sorted(os.listdir(out)), report["summary"]["runs"]
    (['summary.json', 'table.csv', 'table.md', 'table.png'], 2)
    """
    os.makedirs(out_dir, exist_ok=True)
    records = latest_records(list(records))
    if configs is None and settings is not None and not isinstance(settings, dict):
        configs = [config_label(c, s) for c, s in settings.configurations]
    table = ranking_table(records, configs)
    summary = grid_summary(records)
    files = {name: os.path.join(out_dir, name)
             for name in ("table.md", "table.csv", "table.png", "summary.json")}
    lines = ["# Benchmark: Table 1 of the paper, reproduced", ""]
    lines += _settings_lines(settings)
    times = summary["run_time_s"]
    ref = summary["reference"]
    lines += [
        f"- {summary['runs']} runs on {summary['trajectories']} trajectories: "
        + ", ".join(f"{k} {v}" for k, v in summary["statuses"].items()),
        "- run time (identification + validation) per run: median "
        + ("-" if times["median"] is None else
           f"{times['median']:.1f} s, 90th percentile {times['p90']:.1f} s, max "
           f"{times['max']:.1f} s"),
    ]
    if ref["valid_fraction"] is not None:
        lines.append(f"- {ref['config']}: valid on {ref['valid']} of {ref['trajectories']} "
                     f"trajectories ({100 * ref['valid_fraction']:.0f} %)")
    if machine:
        lines.append(f"- machine: {machine.get('cpu')}, {machine.get('logical_cores')} logical "
                     f"cores, {machine.get('memory_gib')} GiB, Python {machine.get('python')}, "
                     f"{machine.get('n_jobs')} jobs ({machine.get('backend')})"
                     + (f", wall time {machine['wall_time_s']:.0f} s"
                        if machine.get("wall_time_s") is not None else "")
                     + (f", load average at start / end {machine['load_average_at_start'][0]}"
                        f" / {machine['load_average_1_5_15min'][0]}"
                        if machine.get("load_average_at_start") and
                        machine.get("load_average_1_5_15min") else ""))
    lines += ["", "Ranked by number of 1st places (paper's columns, then extra ones). "
              "success rate = valid / (valid + invalid + uncompleted), timeouts excluded as in "
              "the paper; Wins WC = only valid model of its trajectory.", "",
              table_to_markdown(table), "![ranking](table.png)", ""]
    with open(files["table.md"], "w", encoding="utf-8") as handle:
        handle.write("\n".join(lines))
    with open(files["table.csv"], "w", encoding="utf-8") as handle:
        handle.write(table_to_csv(table))
    plot_table(table, records, files["table.png"])
    payload = {"summary": summary, "table": [_json_row(r) for r in table]}
    if settings is not None:
        payload["settings"] = settings if isinstance(settings, dict) else settings.to_dict()
    with open(files["summary.json"], "w", encoding="utf-8") as handle:
        json.dump(payload, handle, indent=2, allow_nan=False)
        handle.write("\n")
    if machine:
        files["machine.json"] = os.path.join(out_dir, "machine.json")
        with open(files["machine.json"], "w", encoding="utf-8") as handle:
            json.dump(machine, handle, indent=2)
            handle.write("\n")
    return {"table": table, "summary": summary, "files": files, "text": format_table(table)}


def _json_row(row: dict) -> dict:
    return {k: (None if isinstance(v, float) and v != v else v) for k, v in row.items()}
