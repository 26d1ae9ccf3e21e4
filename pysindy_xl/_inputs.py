"""Validation of the arrays given to :class:`~pysindy_xl.XLSINDy` (trajectories, times, masks).

One trajectory is an array ``(N, n)`` (1-D for one coordinate); several are a list, and every
other argument then follows the same layout.
"""

from __future__ import annotations

import numpy as np

from ._validation import check_numeric_array, check_times

__all__ = ["aligned", "as_list", "check_array", "check_mask", "sample_times",
           "trajectory_arrays"]

MAX_ABS = 1e100  # larger data overflow in the products and squares of the regression


def as_list(value, name: str) -> tuple[list, bool]:
    """``value`` as a list of trajectories and whether it was given as a list."""
    if isinstance(value, (list, tuple)):
        if not value:
            raise ValueError(f"{name}: expected at least one trajectory")
        for k, item in enumerate(value):
            if item is None:
                raise ValueError(f"{name}[{k}]: is None; give an array for every trajectory "
                                 f"(or {name}=None for all of them)")
        return list(value), True
    return [value], False


def aligned(value, name: str, xs: list, is_list: bool, what: str = "trajectories") -> list:
    """``value`` as a list laid out like ``xs`` (``as_list`` of ``x``); Nones when absent."""
    if value is None:
        return [None] * len(xs)
    values, listed = as_list(value, name)
    if listed != is_list or len(values) != len(xs):
        raise ValueError(f"{name}: expected the same layout as x ({len(xs)} "
                         f"{what if is_list else 'array'})")
    return values


def check_array(a, name: str, shape=None, n_columns=None) -> np.ndarray:
    """Float 2-D array (one column per coordinate); a 1-D array is one coordinate, as in
    PySINDy, when one column is expected."""
    a = check_numeric_array(a, name, finite=False, min_samples=0)
    if shape is not None:
        n_columns = shape[1]
    if a.ndim == 1 and n_columns == 1:
        a = a[:, None]
    if a.ndim != 2:
        raise ValueError(f"{name}: expected a 2-D array (n_samples, n), got shape {a.shape}")
    if shape is not None and a.shape != tuple(shape):
        raise ValueError(f"{name}: expected shape {tuple(shape)}, got {a.shape}")
    if a.shape[0] == 0 or a.shape[1] == 0:
        raise ValueError(f"{name}: expected a non-empty array, got shape {a.shape}")
    if n_columns is not None and a.shape[1] != n_columns:
        raise ValueError(f"{name}: expected {n_columns} columns (one per coordinate), got "
                         f"shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or inf")
    return check_numeric_array(a, name, max_abs=MAX_ABS)


def check_mask(mask, name: str, n_samples: int) -> np.ndarray:
    """Boolean sample mask (all True when absent)."""
    if mask is None:
        return np.ones(n_samples, dtype=bool)
    mask = np.asarray(mask)
    if mask.shape != (n_samples,):
        raise ValueError(f"{name}: expected shape ({n_samples},) (one flag per sample), got "
                         f"{mask.shape}")
    if mask.dtype != bool:
        if not np.issubdtype(mask.dtype, np.number) or not np.isin(mask, (0, 1)).all():
            raise TypeError(f"{name}: expected booleans (or 0/1), got dtype {mask.dtype}")
        mask = mask.astype(bool)
    return mask


def sample_times(t, n_samples: int, name: str) -> np.ndarray:
    """Sample times from a time step or an array of strictly increasing times."""
    if np.ndim(t) == 0:
        if isinstance(t, (str, bytes, bool, np.bool_, np.datetime64, np.timedelta64)):
            raise TypeError(f"{name}: expected a time step in seconds (a real number) or an "
                            f"array of times, got the {type(t).__name__} {t!r}")
        try:
            dt = float(t)
        except (TypeError, ValueError):
            raise TypeError(f"{name}: expected a time step or an array of times") from None
        if not np.isfinite(dt) or dt <= 0:
            raise ValueError(f"{name}: the time step must be positive and finite, got {t!r}")
        return np.arange(n_samples) * dt
    t = check_times(check_numeric_array(t, name, finite=False, min_samples=0), name)
    if len(t) != n_samples:
        raise ValueError(f"{name}: expected {n_samples} times (one per sample), got {len(t)}")
    return t


def trajectory_arrays(x, t, x_dot, x_ddot, u, sample_mask, n: int) -> list[dict]:
    """Validated per-trajectory dicts of ``XLSINDy.fit`` / ``score`` inputs: ``x``, ``t``,
    ``x_dot``, ``x_ddot``, ``u`` (None when not given) and ``mask`` (all True by default)."""
    xs, is_list = as_list(x, "x")
    if isinstance(t, (list, tuple)):
        if not is_list or len(t) != len(xs):
            raise ValueError("t: a list of times needs x to be a list of the same length")
        ts = list(t)
    else:
        ts = [t] * len(xs)
    optional = {name: aligned(value, name, xs, is_list) for name, value in
                (("x_dot", x_dot), ("x_ddot", x_ddot), ("u", u), ("sample_mask", sample_mask))}
    out = []
    for k, (xk, tk) in enumerate(zip(xs, ts, strict=True)):
        label = f"[{k}]" if is_list else ""
        xk = check_array(xk, f"x{label}", n_columns=n)
        if xk.shape[0] < 5:
            raise ValueError(f"x{label}: expected at least 5 samples, got {xk.shape[0]}")
        arrays = {"x": xk, "t": sample_times(tk, xk.shape[0], f"t{label}"),
                  "mask": check_mask(optional["sample_mask"][k], f"sample_mask{label}",
                                     xk.shape[0])}
        for name in ("x_dot", "x_ddot", "u"):
            v = optional[name][k]
            arrays[name] = None if v is None else check_array(v, f"{name}{label}", xk.shape)
        out.append(arrays)
    return out
