"""The scores of a model on one case of the generic-systems grids (``generic_systems.py``,
``unseen_systems.py``): held-out error on a fresh run, a 2 s simulation, and the error on states
off the training trajectories (their box widened by 20 %); "right" is the issue's definition."""

from __future__ import annotations

import numpy as np


def _relative(a, b):
    norm = np.linalg.norm(b)
    return float(np.linalg.norm(a - b) / norm) if norm > 0 else float("inf")


def _widened_box(runs, n, samples=2000, widen=1.2):
    """States drawn uniformly from the runs' box of (q, qd, qdd), widened by ``widen``."""
    rng = np.random.default_rng(99)
    box = {}
    for key in ("q", "qd", "qdd"):
        values = np.vstack([r[key] for r in runs])
        low, high = values.min(axis=0), values.max(axis=0)
        middle, half = (low + high) / 2, (high - low) / 2 * widen
        box[key] = rng.uniform(middle - half, middle + half, (samples, n))
    return box


def score(predict_forces, predict_accelerations, simulate, system, truth, test, train_runs,
          forced):
    """held_out, simulation, off_box of a model given as functions."""
    out = {}
    try:
        if forced:
            out["held_out"] = _relative(predict_forces(test["q"], test["qd"], test["qdd"]),
                                        test["u"])
        else:
            out["held_out"] = _relative(predict_accelerations(test["q"], test["qd"], test["u"]),
                                        test["qdd"])
    except Exception as error:  # noqa: BLE001 - a failed prediction is a failed case
        out["held_out"], out["error"] = float("inf"), repr(error)[:200]
    try:
        horizon = test["t"] <= 2.0
        y = simulate(np.r_[test["q"][0], test["qd"][0]], test["t"][horizon], test["force"])
        err = np.sqrt(np.mean((y[:, :truth.n] - test["q"][horizon]) ** 2, axis=0))
        out["simulation"] = float(np.max(err / test["q"].std(axis=0)))
    except Exception as error:  # noqa: BLE001
        out["simulation"], out["simulation_error"] = float("inf"), repr(error)[:200]
    box = _widened_box(train_runs, truth.n)
    try:
        if forced:
            out["off_box"] = _relative(predict_forces(box["q"], box["qd"], box["qdd"]),
                                       truth.forces(box["q"], box["qd"], box["qdd"]))
        else:
            zero = np.zeros_like(box["q"])
            out["off_box"] = _relative(predict_accelerations(box["q"], box["qd"], zero),
                                       truth.accelerations(box["q"], box["qd"], zero))
    except Exception as error:  # noqa: BLE001
        out["off_box"], out["off_box_error"] = float("inf"), repr(error)[:200]
    out["right"] = bool(out["held_out"] <= 0.02 and out["simulation"] <= 0.05
                        and out["off_box"] <= 0.05)
    return out


def _xlsindy_functions(model):
    def simulate(x0, t, force):
        return model.simulate(x0, t, u=force)
    return (model.predict_forces, lambda q, qd, u: model.predict(q, qd, u), simulate)


def outside_share(test, train_runs):
    """The share of the fresh test run's samples with a coordinate outside the range the
    training runs recorded (there the held-out error measures extrapolation)."""
    q = np.vstack([r["q"] for r in train_runs])
    low, high = q.min(axis=0), q.max(axis=0)
    return float(np.mean(np.any((test["q"] < low) | (test["q"] > high), axis=1)))
