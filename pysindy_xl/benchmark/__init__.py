"""Benchmark suite reproducing the paper's Table 1: the grid (:mod:`.grid`), a parallel,
resumable runner with a time limit per run (:mod:`.runner`), the JSONL records
(:mod:`.records`), the paper's ranking (:mod:`.ranking`), the report (:mod:`.report`) and
the command line (:mod:`.cli`, ``pysindy-xl benchmark``).

>>> from pysindy_xl.benchmark import PRESETS
>>> len(PRESETS["quick"].tasks())  # 36 trajectories x 9 configurations
324
"""

from .cli import add_parser as add_parser  # the `pysindy-xl benchmark` subcommand
from .cli import main
from .grid import PRESETS, GridSettings, Task, TrajectorySpec, all_configurations, config_label
from .ranking import format_table, rank_trajectory, ranking_table
from .records import RecordStore, read_records
from .report import write_report
from .runner import run_grid

__all__ = ["PRESETS", "GridSettings", "Task", "TrajectorySpec", "all_configurations",
           "config_label", "ranking_table", "rank_trajectory", "format_table", "RecordStore",
           "read_records", "run_grid", "write_report", "main"]
