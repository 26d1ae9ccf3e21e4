"""The paper's ranking of configurations (Table 1).

Per trajectory, valid models are ranked by validation position RMSE, best first, equal
errors sharing a place (1, 1, 3); errors within :data:`RANK_TOLERANCE` of a group's best are
equal (the same law through two paths differs only at the integrator's tolerance). Per
configuration: ``invalid``, ``timeout``, ``uncompleted`` (status ``error``), ``1st``, ``2nd``,
``2nd>``, ``Wins WC`` (the only valid model of its trajectory, also a 1st) and ``success
rate`` = valid / (valid + invalid + uncompleted), timeouts left out as in the paper. Rows
are sorted by 1st places, then success rate."""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from .records import check_record, latest_records

__all__ = ["TABLE_COLUMNS", "rank_trajectory", "ranking_table", "format_table",
           "table_to_markdown", "table_to_csv", "RANK_TOLERANCE"]

TABLE_COLUMNS = ("combo type", "invalid", "timeout", "uncompleted", "1st", "2nd", "2nd>",
                 "Wins WC", "success rate")
#: Extra columns of the saved tables (not in the paper).
EXTRA_COLUMNS = ("runs", "valid", "median RMSE", "median time (s)")
#: Relative difference below which two validation errors are a tie (see the module docstring).
RANK_TOLERANCE = 1e-3


def _same(a: float, b: float) -> bool:
    return math.isclose(a, b, rel_tol=RANK_TOLERANCE, abs_tol=0.0)


def rank_trajectory(records) -> dict[str, int]:
    """``{config: rank}`` of the records with status ``ok`` among the records of one trajectory
    (competition ranks, 1 the best).

    Parameters
    ----------
    records : iterable of dict
        The records of one trajectory.

    Returns
    -------
    dict of str to int
        Competition rank of each configuration whose run succeeded (equal errors share a rank).

    Examples
    --------
    >>> recs = [{"config": c, "status": "ok", "metrics": {"position_rmse": e}}
    ...         for c, e in [("a", 0.3), ("b", 0.1), ("c", 0.1)]]
    >>> rank_trajectory(recs)
    {'b': 1, 'c': 1, 'a': 3}
    """
    valid = sorted((float(r["metrics"]["position_rmse"]), r["config"]) for r in records
                   if r["status"] == "ok")
    configs = [c for _, c in valid]
    if len(set(configs)) != len(configs):
        raise ValueError(f"records: a configuration appears twice in one trajectory: {configs}")
    ranks: dict[str, int] = {}
    group_error, group_rank = None, 0
    for position, (error, config) in enumerate(valid):
        # compare with the group's best, so that ties cannot chain across a wide range
        if group_error is None or not _same(error, group_error):
            group_error, group_rank = error, position + 1
        ranks[config] = group_rank
    return ranks


def ranking_table(records, configs=None) -> list[dict]:
    """Table 1 from run records (the last record of a run id counts): one row per configuration
    (also those of ``configs`` without records) with the keys of :data:`TABLE_COLUMNS` and
    :data:`EXTRA_COLUMNS`, sorted as in the module docstring; ``success rate`` is ``nan``
    without a counted run.

    Parameters
    ----------
    records : iterable of dict
        Run records.
    configs : sequence of str, default=None
        Configurations listed even without records.

    Returns
    -------
    list of dict
        One row per configuration.

    Examples
    --------
    >>> records = [{"run_id": f"{c}/{t}", "trajectory_id": t, "config": c, "status": s,
    ...             "metrics": {"position_rmse": e}}
    ...            for t, c, s, e in [("t0", "A", "ok", 0.01), ("t0", "B", "ok", 0.02),
    ...                               ("t1", "A", "ok", 0.03), ("t1", "B", "invalid", None)]]
    >>> [(row["combo type"], row["1st"], row["Wins WC"], row["success rate"])
    ...  for row in ranking_table(records)]
    [('A', 2, 1, 1.0), ('B', 0, 0, 0.5)]
    """
    records = [check_record(r) for r in latest_records(list(records))]
    by_trajectory = defaultdict(list)
    for r in records:
        by_trajectory[r["trajectory_id"]].append(r)
    counts = defaultdict(lambda: dict.fromkeys(TABLE_COLUMNS[1:-1], 0))
    errors, times, n_runs = defaultdict(list), defaultdict(list), defaultdict(int)
    for config in configs or ():
        counts[config]  # noqa: B018 - creates the zero row
    status_column = {"invalid": "invalid", "timeout": "timeout", "error": "uncompleted"}
    for group in by_trajectory.values():
        ranks = rank_trajectory(group)
        for r in group:
            config = r["config"]
            row = counts[config]
            n_runs[config] += 1
            run_time = (r.get("time_s") or {}).get("run")
            if isinstance(run_time, (int, float)):
                times[config].append(float(run_time))
            if r["status"] != "ok":
                row[status_column[r["status"]]] += 1
                continue
            errors[config].append(float(r["metrics"]["position_rmse"]))
            rank = ranks[config]
            row["1st" if rank == 1 else "2nd" if rank == 2 else "2nd>"] += 1
            if len(ranks) == 1:
                row["Wins WC"] += 1
    table = []
    for config, row in counts.items():
        valid = row["1st"] + row["2nd"] + row["2nd>"]
        counted = valid + row["invalid"] + row["uncompleted"]
        table.append({
            "combo type": config, **row,
            "success rate": valid / counted if counted else float("nan"),
            "runs": n_runs[config], "valid": valid,
            "median RMSE": float(np.median(errors[config])) if errors[config] else float("nan"),
            "median time (s)": float(np.median(times[config])) if times[config] else float("nan"),
        })
    table.sort(key=lambda row: (-row["1st"], -_nan_low(row["success rate"]), row["combo type"]))
    return table


def _nan_low(value: float) -> float:
    return -1.0 if value != value else value


def _cell(value, column) -> str:
    if isinstance(value, float):
        if value != value:
            return "-"
        if column == "success rate":
            return f"{value:.6f}"
        if column == "median time (s)":
            return f"{value:.1f}"
        return f"{value:.3g}"
    return str(value)


def format_table(table, extra: bool = False) -> str:
    """The table as aligned text in the paper's columns (``extra``: also the others).

    Parameters
    ----------
    table : list of dict
        Rows of :func:`ranking_table`.
    extra : bool, default=False
        Also the extra columns.

    Returns
    -------
    str
        The aligned text.

    Examples
    --------
    >>> records = [{"run_id": f"{c}/{t}", "trajectory_id": t, "config": c, "status": s,
    ...             "metrics": {"position_rmse": e}}
    ...            for t, c, s, e in [("t0", "A", "ok", 0.01), ("t0", "B", "ok", 0.02),
    ...                               ("t1", "A", "ok", 0.03), ("t1", "B", "invalid", None)]]
    >>> print(format_table(ranking_table(records)))
    combo type  invalid  timeout  uncompleted  1st  2nd  2nd>  Wins WC  success rate
    A                 0        0            0    2    0     0        1      1.000000
    B                 1        0            0    0    1     0        0      0.500000
    """
    columns = TABLE_COLUMNS + (EXTRA_COLUMNS if extra else ())
    rows = [[_cell(row[c], c) for c in columns] for row in table]
    widths = [max(len(c), *(len(r[k]) for r in rows)) if rows else len(c)
              for k, c in enumerate(columns)]
    lines = ["  ".join(c.ljust(w) if k == 0 else c.rjust(w)
                       for k, (c, w) in enumerate(zip(columns, widths, strict=True)))]
    for r in rows:
        lines.append("  ".join(v.ljust(w) if k == 0 else v.rjust(w)
                               for k, (v, w) in enumerate(zip(r, widths, strict=True))))
    return "\n".join(lines)


def table_to_markdown(table) -> str:
    """The table (paper columns, then the extra ones) as a Markdown table.

    Parameters
    ----------
    table : list of dict
        Rows of :func:`ranking_table`.

    Returns
    -------
    str
        The Markdown table.
    """
    columns = TABLE_COLUMNS + EXTRA_COLUMNS
    lines = ["| " + " | ".join(columns) + " |",
             "|" + "|".join([":---"] + ["---:"] * (len(columns) - 1)) + "|"]
    for row in table:
        lines.append("| " + " | ".join(_cell(row[c], c) for c in columns) + " |")
    return "\n".join(lines) + "\n"


def table_to_csv(table) -> str:
    """The table as CSV text (full precision, empty cells for undefined values).

    Parameters
    ----------
    table : list of dict
        Rows of :func:`ranking_table`.

    Returns
    -------
    str
        The CSV text.
    """
    import csv
    import io
    columns = TABLE_COLUMNS + EXTRA_COLUMNS
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    for row in table:
        writer.writerow(["" if isinstance(row[c], float) and row[c] != row[c] else row[c]
                         for c in columns])
    return buffer.getvalue()
