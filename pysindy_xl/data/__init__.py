"""Data in, whatever recorded them: trajectories and datasets, files (NPZ, CSV, TSV, ROS bags),
pandas DataFrames, noise models and constraint masks.

Nothing here imports MuJoCo: reading a CSV of a real robot needs no simulator.
"""

from .constraints import contiguous_segments, unconstrained_samples, unconstrained_windows
from .dataset import Dataset, Trajectory, load_dataset
from .files import DatasetError
from .noise import NOISE_KEYS, NOISE_MODELS, add_noise, noise_levels
from .rosbag import read_rosbag
from .tables import CSV_SUFFIXES, from_columns, from_dataframe, load_data, read_csv

__all__ = [
    "Trajectory", "Dataset", "DatasetError", "load_dataset", "read_csv", "read_rosbag",
    "from_columns", "from_dataframe", "load_data", "CSV_SUFFIXES", "add_noise", "noise_levels",
    "NOISE_KEYS", "NOISE_MODELS", "contiguous_segments", "unconstrained_samples",
    "unconstrained_windows",
]
