"""The markdown reports of the generic-systems grids: the summary against the issue's targets,
every case, and the baselines on the same data."""

from __future__ import annotations

import json

import numpy as np
from grid_baselines import THRESHOLDS, WEAK_HALF_WIDTH, WEAK_WINDOWS


def _finite(value):
    if isinstance(value, float) and not np.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    return value


def _pct(value):
    return "-" if value is None else f"{100 * value:.2f}"


def _rate(records, key="auto"):
    if not records:
        return "-"
    right = sum(bool(r[key].get("right")) for r in records)
    return f"{right}/{len(records)} ({100 * right / len(records):.0f} %)"


def _off_box_unscored(record, key):
    """Whether the baseline ``key`` of ``record`` has no off-box figure by design: SINDy rows
    of forced runs written before the baselines scored off the box under no force (no
    ``"off_box_under"``)."""
    scores = record.get(key, {})
    return (key in ("sindy", "weak_sindy") and record["forcing"] == "forced"
            and "error" not in scores and "off_box_under" not in scores)


def _baseline_right(scores, held_out, simulation, off_box):
    """True/False by the issue's definition of "right" on a baseline's ``scores`` (no
    simulation figure when ``simulation`` is None); a missing figure is a failed prediction."""
    if "error" in scores:
        return False
    keys = (held_out, off_box) if simulation is None else (held_out, simulation, off_box)
    limits = (0.02, 0.05) if simulation is None else (0.02, 0.05, 0.05)
    figures = [scores.get(k) for k in keys]
    return all(f is not None and f <= limit for f, limit in zip(figures, limits, strict=True))


def _baseline_rate(verdicts):
    judged = [v for v in verdicts if v is not None]
    if not judged:
        return "-"
    text = f"{sum(judged)}/{len(judged)} ({100 * sum(judged) / len(judged):.0f} %)"
    missing = len(verdicts) - len(judged)
    return text + (f" ({missing} more without an off-box figure)" if missing else "")


def _median_pct(values):
    """The median of ``values`` in percent, a missing figure (a failed prediction) counted as
    infinite; "-" for none."""
    values = [v if v is not None else float("inf") for v in values]
    return _pct(float(np.median(values))) if values else "-"


#: The methods of the baselines section: label, record key, held-out, simulation, off-box keys.
BASELINE_METHODS = (
    ("XLSINDy, automatic catalog", "auto", "held_out", "simulation", "off_box"),
    ("XLSINDy, hand-built catalog", "hand", "held_out", "simulation", "off_box"),
    ("PySINDy SINDy", "sindy", "held_out_accelerations", "simulation",
     "off_box_accelerations"),
    ("PySINDy weak SINDy", "weak_sindy", "held_out_accelerations", "simulation",
     "off_box_accelerations"),
    ("MLP inverse dynamics (forced)", "mlp", "held_out", None, "off_box"),
)


def baselines_section(records):
    """The markdown lines of the report's section "Baselines on the same data" on the JSONL
    ``records`` that hold baselines (``"sindy"``): the methods' rates of "right" and median
    figures per noise level, side by side with both XLSINDy catalogs on the same cases, then
    every case. Empty when no record holds baselines."""
    records = [r for r in records if "sindy" in r]
    if not records:
        return []
    lines = ["", "## Baselines on the same data", "",
             "PySINDy `SINDy` (polynomial degree 3, + Fourier of the angles, input u; strong "
             "form on smoothed derivatives, and weak form with `WeakPDELibrary`, "
             f"{WEAK_WINDOWS} windows of half width {WEAK_HALF_WIDTH} s; STLSQ threshold "
             f"chosen among {list(THRESHOLDS)} on the training runs' last fifth) predicts "
             "accelerations: its figure is the held-out relative error of the "
             "accelerations (forced runs: under the recorded forces). The MLP predicts forces "
             "from smoothed (q, qd, qdd).", "",
             f"Cases with baselines: {len(records)}. \"right\" as above (held-out <= 2 %, "
             "simulation <= 5 %, off-box <= 5 %); for SINDy the held-out and off-box figures "
             "are acceleration errors (off the box: under no force), for XLSINDy on forced "
             "runs force errors. The MLP, an inverse-dynamics map, has no simulation: its "
             "\"right\" counts held-out and off-box alone. A failed fit or simulation counts "
             "as an infinite error in the medians.", "",
             "| noise | method | right | median held-out % | median sim % | "
             "median off-box % |",
             "| --- | --- | --- | --- | --- | --- |"]
    for level in sorted({r["noise"] for r in records}):
        group = [r for r in records if r["noise"] == level]
        for label, key, held, sim, off in BASELINE_METHODS:
            scored = [r[key] for r in group if key in r]
            if not scored:
                continue
            judged = [r[key] for r in group if key in r and not _off_box_unscored(r, key)]
            verdicts = ([bool(s.get("right")) for s in scored] if key in ("auto", "hand")
                        else [_baseline_right(s, held, sim, off) for s in judged])
            verdicts += [None] * (len(scored) - len(judged))
            lines.append(
                f"| {100 * level:g} % | {label} | {_baseline_rate(verdicts)} | "
                f"{_median_pct([s.get(held) for s in scored])} | "
                f"{'-' if sim is None else _median_pct([s.get(sim) for s in scored])} | "
                f"{_median_pct([s.get(off) for s in judged])} |")
    header = ["| system | forcing | noise | seed | XLSINDy auto held-out % | SINDy acc. % | "
              "SINDy sim % | weak SINDy acc. % | weak SINDy sim % | MLP held-out % | "
              "MLP off-box % |",
              "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    lines += ["", "Medians over the cases (held-out relative error; SINDy: of the accelerations, "
              "XLSINDy unforced: of the accelerations, forced: of the forces):", "",
              "| noise | XLSINDy auto | SINDy | weak SINDy | MLP (forced) |",
              "| --- | --- | --- | --- | --- |"]
    for level in sorted({r["noise"] for r in records}):
        group = [r for r in records if r["noise"] == level]
        lines.append(
            f"| {100 * level:g} % | {_median_pct([r['auto'].get('held_out') for r in group])} | "
            f"{_median_pct([r['sindy'].get('held_out_accelerations') for r in group])} | "
            f"{_median_pct([r.get('weak_sindy', {}).get('held_out_accelerations') for r in group])}"
            f" | {_median_pct([r['mlp'].get('held_out') for r in group if 'mlp' in r])} |")
    lines += ["", "Per case:", "", *header]
    for r in records:
        sindy, weak, mlp = r.get("sindy", {}), r.get("weak_sindy", {}), r.get("mlp", {})
        lines.append(
            f"| {r['system']} | {r['forcing']} | {r['noise']:g} | {r['seed']} | "
            f"{_pct(r['auto'].get('held_out'))} | "
            f"{_pct(sindy.get('held_out_accelerations'))} | {_pct(sindy.get('simulation'))} | "
            f"{_pct(weak.get('held_out_accelerations'))} | {_pct(weak.get('simulation'))} | "
            f"{_pct(mlp.get('held_out'))} | {_pct(mlp.get('off_box'))} |")
    return lines

def write_report(path, out):
    """The markdown summary of the JSONL results ``path``, written to ``out``."""
    with open(path, encoding="utf-8") as handle:
        records = [json.loads(line) for line in handle if line.strip()]
    low = [r for r in records if r["noise"] <= 0.01]
    high = [r for r in records if r["noise"] > 0.01]
    ratios = [r["ratio"] for r in records if r.get("ratio") is not None]
    lines = ["# Systems nobody described: the automatic catalog", "",
             "`python benchmarks/generic_systems.py` (see its docstring for the systems, data and "
             "scores; `--report` writes this file). \"right\" = held-out error <= 2 %, 2 s "
             "simulation within 5 %, error off the training box (widened 20 %) <= 5 %.", "",
             f"Cases run: {len(records)} ({', '.join(sorted({str(r['noise']) for r in records}))} "
             f"noise; seeds {sorted({r['seed'] for r in records})}; "
             f"{sum(r['forcing'] == 'forced' for r in records)} forced, "
             f"{sum(r['forcing'] == 'unforced' for r in records)} unforced).", "",
             "| target | automatic catalog | hand-built catalog | issue target |",
             "| --- | --- | --- | --- |",
             f"| right at 0-1 % noise | {_rate(low)} | {_rate(low, 'hand')} | >= 95 % |",
             f"| right at 5 % noise | {_rate(high)} | {_rate(high, 'hand')} | >= 85 % |"]
    for level in sorted({r["noise"] for r in records}):
        group = [r for r in records if r["noise"] == level]
        lines.append(f"| (right at {100 * level:g} % noise) | {_rate(group)} | "
                     f"{_rate(group, 'hand')} | |")
    if ratios:
        within = sum(ratio <= 1.5 for ratio in ratios)
        lines.append(f"| held-out error / hand-built's (median, max; cases <= 1.5) | "
                     f"{np.median(ratios):.2f}, {np.max(ratios):.2f}; {within}/{len(ratios)} "
                     f"({100 * within / len(ratios):.0f} %) | 1 | <= 1.5 |")
    same = [r["ratio_same"] for r in records if r.get("ratio_same") is not None]
    if same:
        within = sum(ratio <= 1.5 for ratio in same)
        lines.append(f"| (the same, the hand-built catalog fitted with the final fit's test "
                     f"functions) | {np.median(same):.2f}, {np.max(same):.2f}; "
                     f"{within}/{len(same)} ({100 * within / len(same):.0f} %) | 1 | |")
    for n in sorted({r["n"] for r in records}):
        group = [r for r in records if r["n"] == n]
        lines.append(f"| catalog + fit, {n} coordinate(s), 20,000 samples: wall s (CPU s), "
                     f"median | {np.median([r['seconds'] for r in group]):.1f} "
                     f"({np.median([r['cpu_seconds'] for r in group]):.1f}) | - | <= 10 s |")
    failed = [r for r in records if not r["auto"].get("right") and "test_outside" in r]
    if failed:
        outside = [r for r in failed if r["test_outside"] > 0]
        lines.append(f"| wrong cases whose fresh test run leaves the training range (share of "
                     f"its samples outside) | {len(outside)}/{len(failed)}: "
                     + ", ".join(f"{r['system']} {r['forcing']} {r['noise']:g} seed "
                                 f"{r['seed']} ({_pct(r['test_outside'])} %)"
                                 for r in outside) + " | - | |")
    lines += ["", "Wall times are on a shared 2-core machine with other jobs running (CPU "
              "seconds are this process's own).", "",
              "## Every case", "",
              "| system | n | forcing | noise | seed | right | held-out % | sim % | off-box % | "
              "hand held-out % | ratio | ratio, same fit | wall s | CPU s | kept / terms | "
              "catalog |",
              "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | "
              "--- | --- | --- |"]
    for r in records:
        a, h = r["auto"], r["hand"]
        mark = " (*)" if r.get("early") else ""
        lines.append(
            f"| {r['system']}{mark} | {r['n']} | {r['forcing']} | {r['noise']:g} | {r['seed']} | "
            f"{'yes' if a.get('right') else 'no'} | {_pct(a.get('held_out'))} | "
            f"{_pct(a.get('simulation'))} | {_pct(a.get('off_box'))} | {_pct(h.get('held_out'))} | "
            f"{'-' if r.get('ratio') is None else format(r['ratio'], '.2f')} | "
            f"{'-' if r.get('ratio_same') is None else format(r['ratio_same'], '.2f')} | "
            f"{r['seconds']:.1f} | {r['cpu_seconds']:.1f} | {r.get('kept', '-')} / "
            f"{r.get('terms', '-')} | {r.get('catalog', a.get('error', ''))} |")
    lines += baselines_section(records)
    with open(out, "w", encoding="utf-8") as handle:
        handle.write("\n".join(lines) + "\n")
