"""One cell of the unforced noise sweep (``benchmarks/noise_sweep.py``) fitted with the
defaults: three 10 s unforced runs of a paper system, noisy positions only."""

import pathlib
import sys
import warnings

import numpy as np
from ground_truth import random_initial_state

import pysindy_xl as px

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "benchmarks"))
import noise_sweep  # noqa: E402


def fit_unforced_cell(name: str, level: float, seed: int):
    """``(model, true)``: the default fit of the cell and the true law (forces zeroed)."""
    system, library, true = noise_sweep._setup(name)
    true = true.copy()
    true[library.force_columns_] = 0.0
    t = np.arange(0.0, 10.0, 0.01)
    runs = [system.simulate(random_initial_state(system, seed + 1000 * k), t, None)
            for k in range(3)]
    rng = np.random.default_rng(10_000 + seed)
    noisy = [r["q"] + level * r["q"].std(axis=0) * rng.normal(size=r["q"].shape)
             for r in runs]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = px.XLSINDy(library).fit(noisy, [t] * 3)
    return model, true
