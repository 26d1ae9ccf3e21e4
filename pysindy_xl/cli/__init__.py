"""The ``pysindy-xl`` command: MuJoCo demo, identification of a dataset, data generation.

Examples::

    pysindy-xl demo cart-pole                         # generate, identify, validate, plot
    pysindy-xl demo double-pendulum --forcing mixed --noise 0.01 --out results/
    pysindy-xl generate cart-pole data.npz --forcing explicit --trajectories 4
    pysindy-xl identify data.npz --system cart-pole --catalog mixed
"""

from ..evaluation.quality import fit_quality
from .commands import main, run_demo, run_generate, run_identify
from .parser import build_parser
from .steps import CLIError

__all__ = ["main", "build_parser", "run_demo", "run_identify", "run_generate", "CLIError",
           "fit_quality"]
