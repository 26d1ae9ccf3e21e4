"""Benchmark suite reproducing the paper's Table 1: grid, parallel resumable runner, ranking.

Modules
-------
:mod:`.grid`
    Trajectories (system x friction x forcing x noise x seed) x configurations (catalog x
    solver, plus the plain ``pysindy.SINDy`` baseline); the ``quick`` and ``full`` presets.
:mod:`.runner`
    One run = MuJoCo data, identification, validation against a fresh MuJoCo trajectory, one
    record; joblib parallelism (local processes, Dask or Ray), per-run time limit, resume.
:mod:`.records`
    The JSONL record store (atomic appends, torn-line repair, last record wins).
:mod:`.ranking`
    The paper's ranking and table (1st, 2nd, 2nd>, invalid, timeout, uncompleted, Wins WC,
    success rate).
:mod:`.report`
    Markdown, CSV, PNG and machine description.
:mod:`.cli`
    ``pysindy-xl benchmark`` / ``benchmarks/table1.py``.

Examples
--------
>>> from pysindy_xl.benchmark import PRESETS
>>> len(PRESETS["quick"].tasks())  # 36 trajectories x 9 configurations
324
"""

from .cli import add_parser, main
from .grid import PRESETS, GridSettings, Task, TrajectorySpec, all_configurations, config_label
from .ranking import format_table, rank_trajectory, ranking_table
from .records import RecordStore, read_records
from .report import machine_description, write_report
from .runner import execute_task, run_grid, run_task

__all__ = [
    "PRESETS",
    "GridSettings",
    "Task",
    "TrajectorySpec",
    "all_configurations",
    "config_label",
    "ranking_table",
    "rank_trajectory",
    "format_table",
    "RecordStore",
    "read_records",
    "run_grid",
    "run_task",
    "execute_task",
    "write_report",
    "machine_description",
    "add_parser",
    "main",
]
