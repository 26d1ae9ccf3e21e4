"""Held-out validation of an identified model: the torques it predicts on data it never saw.

An arm under feedback control diverges when simulated open loop even for a good model, so
robotics validates by **inverse dynamics**: on data the fit never saw, the torques
``tau_hat = M(q) qdd + c(q, qd) + friction`` the model needs to move as recorded
(:meth:`XLSINDy.predict_forces <pysindy_xl.XLSINDy.predict_forces>`) against the measured ones,
scored per coordinate and in total (:class:`ForceScore`).

Velocities and accelerations must be the same for every method compared: measured ones when
given, else :func:`scoring_derivatives` over each whole run (whatever the model's smoother).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._inputs import aligned, as_list, check_array
from .._validation import check_option

__all__ = ["ForceScore", "score_forces", "blocked_cross_validation", "scoring_derivatives",
           "SCORING_DERIVATIVES"]

#: Highest frequency (Hz) that :func:`scoring_derivatives` keeps by default.
MAX_FREQUENCY = 10.0
#: How :func:`scoring_derivatives` estimates what the data lack (printed with the scores).
SCORING_DERIVATIVES = ("quintic smoothing spline of the positions (WhittakerSmoother, "
                       f"smoothness by GCV, bandwidth at most {MAX_FREQUENCY:g} Hz), per run")
_ESTIMATED = {(False, False): "measured", (True, True): SCORING_DERIVATIVES,
              (False, True): f"measured velocities, accelerations from a {SCORING_DERIVATIVES}",
              (True, False): f"measured accelerations, velocities from a {SCORING_DERIVATIVES}"}


@dataclasses.dataclass
class ForceScore:
    """Held-out force prediction of a model, per coordinate and in total.

    Built by :func:`score_forces`, :func:`blocked_cross_validation` or
    :meth:`from_predictions`; the parameters are the attributes.

    Attributes
    ----------
    names : tuple of str
        Coordinate names.
    rms, relative, measured_rms : ndarray, shape (n,)
        Per coordinate: RMS of the prediction error (force units), ``rms`` over the measured
        RMS (a fraction), RMS of the measured force.
    total : float
        Relative RMS over all coordinates: ``||predicted - measured|| / ||measured||``.
    n_samples : int
    derivatives : str
        Where the velocities and accelerations came from.
    t, measured, predicted : list of ndarray
        Per run: times, measured and predicted forces (for :meth:`plot`).
    folds : list of float or None
        Cross-validation: ``total`` of each fold, else None.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0.0, 1.0, 4)
    >>> score = ForceScore.from_predictions(["a", "b"], [t], [np.ones((4, 2))],
    ...                                     [np.ones((4, 2)) * [1.02, 0.9]], "measured")
    >>> score.rms.round(3), round(score.total, 4)
    (array([0.02, 0.1 ]), 0.0721)
    """

    names: tuple
    rms: np.ndarray
    relative: np.ndarray
    total: float
    measured_rms: np.ndarray
    n_samples: int
    derivatives: str
    t: list = dataclasses.field(repr=False)
    measured: list = dataclasses.field(repr=False)
    predicted: list = dataclasses.field(repr=False)
    folds: list | None = None

    @classmethod
    def from_predictions(cls, names, t, measured, predicted, derivatives, folds=None):
        """The scores of ``predicted`` against ``measured`` forces (per run, (N, n)); the
        other arguments are the attributes of the same names."""
        error = np.vstack([p - m for p, m in zip(predicted, measured, strict=True)])
        stacked = np.vstack(measured)
        rms = np.sqrt(np.mean(error**2, axis=0))
        scale = np.sqrt(np.mean(stacked**2, axis=0))
        relative = np.where(scale > 0, rms / np.where(scale > 0, scale, 1.0), np.inf)
        norm = np.linalg.norm(stacked)
        total = float(np.linalg.norm(error) / norm) if norm > 0 else float("inf")
        return cls(tuple(names), rms, relative, total, scale, len(stacked), derivatives,
                   list(t), list(measured), list(predicted), folds)

    def to_dict(self) -> dict:
        """JSON-ready figures (no series): ``rms``, ``relative``, ``measured_rms`` (per
        coordinate name), ``total``, ``n_samples``, ``derivatives``, ``folds``."""
        return {"rms": dict(zip(self.names, self.rms.tolist(), strict=True)),
                "relative": dict(zip(self.names, self.relative.tolist(), strict=True)),
                "measured_rms": dict(zip(self.names, self.measured_rms.tolist(), strict=True)),
                "total": self.total, "n_samples": self.n_samples,
                "derivatives": self.derivatives, "folds": self.folds}

    def lines(self, units="N m") -> list:
        """Per-coordinate lines (RMS in ``units``, one or one per coordinate, and %), the total.

        >>> import numpy as np
        >>> score = ForceScore.from_predictions(["joint_1"], [np.arange(4.0)],
        ...     [np.full((4, 1), 2.0)], [np.full((4, 1), 2.1)], "measured")
        >>> score.lines()
        ['  joint_1: RMS 0.1 N m (5.00 % of 2 N m)', '  all coordinates: 5.00 % (relative RMS)']
        """
        units = [units] * len(self.names) if isinstance(units, str) else list(units)
        width = max(len(name) for name in self.names)
        out = [f"  {name + ':':<{width + 1}} RMS {rms:.3g} {unit} ({100 * rel:.2f} % of "
               f"{scale:.3g} {unit})" for name, rms, rel, scale, unit in
               zip(self.names, self.rms, self.relative, self.measured_rms, units, strict=True)]
        out.append(f"  all coordinates: {100 * self.total:.2f} % (relative RMS)")
        if self.folds:
            out.append("  per fold: " + ", ".join(f"{100 * f:.2f} %" for f in self.folds))
        return out

    def plot(self, path, title=None):
        """Write measured against predicted forces to the PNG ``path``, a panel per coordinate."""
        from .plots import new_figure
        n = len(self.names)
        figure = new_figure(8, 1.6 * n + 0.8)
        axes = figure.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
        offset = 0.0
        for run, (t, measured, predicted) in enumerate(
                zip(self.t, self.measured, self.predicted, strict=True)):
            time = t - t[0] + offset
            for i, ax in enumerate(axes):
                ax.plot(time, measured[:, i], color="black", linewidth=0.8,
                        label="measured" if run == 0 else None)
                ax.plot(time, predicted[:, i], color="tab:orange", linewidth=0.8,
                        label="predicted" if run == 0 else None)
            offset = time[-1] + (time[-1] - time[0]) * 0.02
        for ax, name, rel in zip(axes, self.names, self.relative, strict=True):
            ax.set_ylabel(name)
            ax.set_title(f"{name}: {100 * rel:.1f} %", fontsize="small", loc="right")
        axes[0].legend(loc="upper left", fontsize="small")
        axes[-1].set_xlabel("t (s)" + (", runs one after the other" if len(self.t) > 1 else ""))
        figure.suptitle(title or f"held-out forces: {100 * self.total:.2f} % relative RMS")
        figure.savefig(path, dpi=110)


def scoring_derivatives(t, x, smoother=None, max_frequency: float = MAX_FREQUENCY):
    """Positions, velocities and accelerations for scoring, the same for every method.

    A quintic smoothing spline of the positions (:class:`~pysindy_xl.weak.WhittakerSmoother`)
    on the actual stamps, smoothness chosen per coordinate by GCV and at least that of a
    half-power bandwidth ``f = max_frequency``: ``lambda >= (2 sin(pi f dt))^-6`` (``dt`` the
    mean step). GCV assumes white noise and would differentiate a real arm's correlated ripple
    (quantization, jitter, vibration) into large accelerations; joint motion stays below 10 Hz.

    Parameters
    ----------
    t : array, shape (N,)
        Strictly increasing times.
    x : array, shape (N, n)
        Positions.
    smoother : object with ``smooth(t, x)``, optional
        Replaces the smoothing spline (``max_frequency`` is then not used).
    max_frequency : float, default 10.0
        Highest bandwidth kept, in Hz (``inf``: the data-driven smoothness alone).

    Returns
    -------
    q, qd, qdd : ndarray, shape (N, n)

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 4, 4001)
    >>> ripple = 1e-4 * np.sin(2 * np.pi * 60 * t)  # 60 Hz, accelerations of 14 rad/s^2
    >>> q, qd, qdd = scoring_derivatives(t, (np.sin(t) + ripple)[:, None])
    >>> bool(np.abs(qdd[200:-200, 0] + np.sin(t[200:-200])).max() < 0.05)
    True
    """
    from ..weak import WhittakerSmoother, whittaker_smooth
    t = np.asarray(t, dtype=float)
    if smoother is not None:
        return smoother.smooth(t, x)
    if max_frequency != np.inf:
        check_option("max_frequency", max_frequency, "real", low=0, low_open=True)
    smoother = WhittakerSmoother()
    q, qd, qdd = smoother.smooth(t, x)
    dt = (t[-1] - t[0]) / (len(t) - 1)
    if not np.isfinite(max_frequency) or max_frequency * dt >= 0.5:
        return q, qd, qdd
    floor = (2 * np.sin(np.pi * max_frequency * dt)) ** (-2 * smoother.order)
    if np.all(smoother.lam_ >= floor):
        return q, qd, qdd
    return whittaker_smooth(t, np.asarray(x, dtype=float), np.maximum(smoother.lam_, floor),
                            smoother.order)


def _runs(n, x, t, u, x_dot, x_ddot):
    """Checked per-run dicts of x, t, u, x_dot, x_ddot; ``n`` coordinates (None: from x)."""
    xs, is_list = as_list(x, "x")
    for name, value in (("t", t), ("u", u)):
        if value is None:
            raise ValueError(f"{name}: required to score forces")
    layout = {name: aligned(value, name, xs, is_list, "runs") for name, value in
              (("t", t), ("u", u), ("x_dot", x_dot), ("x_ddot", x_ddot))}
    runs = []
    for k, xk in enumerate(xs):
        label = f"[{k}]" if is_list else ""
        xk = check_array(xk, f"x{label}", n_columns=n or (1 if np.ndim(xk) == 1 else None))
        tk = np.asarray(layout["t"][k], dtype=float)
        if tk.shape != (len(xk),) or np.any(np.diff(tk) <= 0):
            raise ValueError(f"t{label}: expected {len(xk)} strictly increasing times")
        runs.append({"x": xk, "t": tk, "u": check_array(layout["u"][k], f"u{label}", xk.shape),
                     **{key: None if layout[key][k] is None else
                        check_array(layout[key][k], f"{key}{label}", xk.shape)
                        for key in ("x_dot", "x_ddot")}})
    return runs


def _with_derivatives(run, smoother, max_frequency=MAX_FREQUENCY):
    """The run's (q, qd, qdd) for scoring and how they were obtained."""
    estimated = (run["x_dot"] is None, run["x_ddot"] is None)
    if not any(estimated):
        return run["x"], run["x_dot"], run["x_ddot"], "measured"
    q, qd, qdd = scoring_derivatives(run["t"], run["x"], smoother, max_frequency)
    qd = qd if run["x_dot"] is None else run["x_dot"]
    qdd = qdd if run["x_ddot"] is None else run["x_ddot"]
    source = _ESTIMATED[estimated]
    if smoother is not None:
        source = source.replace(SCORING_DERIVATIVES, repr(smoother))
    elif max_frequency != MAX_FREQUENCY:
        source = source.replace(f"at most {MAX_FREQUENCY:g} Hz", f"at most {max_frequency:g} Hz")
    return q, qd, qdd, source


def score_forces(model, x, t, u, x_dot=None, x_ddot=None, smoother=None,
                 max_frequency: float = MAX_FREQUENCY) -> ForceScore:
    """Held-out force prediction of a fitted model (see the module documentation).

    Parameters
    ----------
    model : XLSINDy
        A fitted model with dynamics.
    x, t, u : array (N, n), (N,), (N, n) or lists of them
        Held-out positions, their times (as recorded) and measured generalized forces.
    x_dot, x_ddot : same layout, optional
        Velocities and accelerations; those not given come from :func:`scoring_derivatives`.
    smoother, max_frequency
        As in :func:`scoring_derivatives`.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
    >>> t = np.linspace(0, 5, 501)[:, None]
    >>> x = np.sin(t) + np.sin(2.3 * t) / 2
    >>> xd, xdd = np.cos(t) + 1.15 * np.cos(2.3 * t), -np.sin(t) - 2.645 * np.sin(2.3 * t)
    >>> t = t[:, 0]
    >>> model = px.XLSINDy(lib).fit(x, t, x_dot=xd, x_ddot=xdd, u=2 * xdd + 3 * x)
    >>> score = score_forces(model, x, t, 2 * xdd + 3 * x + 0.01, xd, xdd)
    >>> round(float(score.rms[0]), 6)
    0.01
    """
    runs = _runs(model.n_coordinates_, x, t, u, x_dot, x_ddot)
    times, measured, predicted, sources = [], [], [], set()
    for run in runs:
        q, qd, qdd, source = _with_derivatives(run, smoother, max_frequency)
        predicted.append(model.predict_forces(q, qd, qdd))
        times.append(run["t"])
        measured.append(run["u"])
        sources.add(source)
    return ForceScore.from_predictions(model.feature_library_.coords.names, times, measured,
                                       predicted, "; ".join(sorted(sources)))


def _folds(lengths, n_blocks):
    """``(run, start, stop)`` of each fold: groups of whole runs, or blocks of the one run."""
    if len(lengths) > 1:
        groups = np.array_split(np.arange(len(lengths)), min(n_blocks, len(lengths)))
        return [[(int(k), 0, lengths[k]) for k in group] for group in groups]
    edges = np.linspace(0, lengths[0], n_blocks + 1).round().astype(int)
    return [[(0, int(a), int(b))] for a, b in zip(edges[:-1], edges[1:], strict=True)]


def blocked_cross_validation(model, x, t, u, x_dot=None, x_ddot=None, n_blocks: int = 5,
                             smoother=None, max_frequency: float = MAX_FREQUENCY) -> ForceScore:
    """Time-blocked cross-validation of the force prediction of a model class.

    One run is cut into ``n_blocks`` contiguous time blocks, each predicted by a clone of
    ``model`` fitted on the other blocks (as separate runs); several runs stay whole, one run
    or group of runs per fold. The scores pool all folds; ``folds`` gives each fold's total.
    Scoring derivatives are computed once per whole run; the fits get the data as ``fit`` would.

    Parameters
    ----------
    model : XLSINDy
        The model to cross-validate (fitted or not; its parameters are used).
    x, t, u, x_dot, x_ddot, smoother, max_frequency
        As in :func:`score_forces`; the training data.
    n_blocks : int, default 5
        Contiguous blocks of a single run, or most groups of runs (at least 2).

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
    >>> t = np.linspace(0, 10, 1001)[:, None]
    >>> x = np.sin(t) + np.sin(2.3 * t) / 2
    >>> xd, xdd = np.cos(t) + 1.15 * np.cos(2.3 * t), -np.sin(t) - 2.645 * np.sin(2.3 * t)
    >>> t = t[:, 0]
    >>> score = blocked_cross_validation(px.XLSINDy(lib), x, t, 2 * xdd + 3 * x, xd, xdd,
    ...                                  n_blocks=4)
    >>> len(score.folds), score.total < 1e-6
    (4, True)
    """
    from sklearn.base import clone
    check_option("n_blocks", n_blocks, "int", low=2)
    runs = _runs(None, x, t, u, x_dot, x_ddot)
    folds = _folds([len(run["t"]) for run in runs], n_blocks)
    if len(runs) == 1 and len(runs[0]["t"]) < 20 * n_blocks:
        raise ValueError(f"n_blocks: {n_blocks} blocks of {len(runs[0]['t'])} samples are too "
                         "short to fit on; use fewer blocks or more data")
    scoring = [_with_derivatives(run, smoother, max_frequency) for run in runs]
    predicted = [np.empty_like(run["u"]) for run in runs]
    totals, names = [], None
    for fold in folds:
        pieces = []
        for k, run in enumerate(runs):
            keep = np.ones(len(run["t"]), dtype=bool)
            for a, b in [(a, b) for kk, a, b in fold if kk == k]:
                keep[a:b] = False
            edges = np.flatnonzero(np.diff(np.r_[0, keep.astype(int), 0]))
            pieces += [(k, a, b) for a, b in zip(edges[::2], edges[1::2], strict=True)]
        train = {key: [runs[k][key][a:b] if runs[k][key] is not None else None
                       for k, a, b in pieces] for key in ("x", "t", "u", "x_dot", "x_ddot")}
        for key in ("x_dot", "x_ddot"):
            if any(value is None for value in train[key]):
                train[key] = None
        fitted = clone(model).fit(**train)
        names = fitted.feature_library_.coords.names
        error, norm = 0.0, 0.0
        for k, a, b in fold:
            q, qd, qdd, _ = scoring[k]
            run = runs[k]
            predicted[k][a:b] = fitted.predict_forces(q[a:b], qd[a:b], qdd[a:b])
            error += float(np.sum((predicted[k][a:b] - run["u"][a:b]) ** 2))
            norm += float(np.sum(run["u"][a:b] ** 2))
        totals.append(float(np.sqrt(error / norm)) if norm > 0 else float("inf"))
    source = "; ".join(sorted({entry[3] for entry in scoring}))
    return ForceScore.from_predictions(names, [run["t"] for run in runs],
                                       [run["u"] for run in runs], predicted, source, totals)
