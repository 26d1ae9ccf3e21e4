"""The baselines of the generic-systems grids, on the same data and scores as the automatic
catalog: PySINDy's ``SINDy`` on the first-order state (strong and weak form, threshold chosen on
the training runs' last fifth) and a scikit-learn MLP inverse-dynamics regressor (see
``generic_systems.py``'s docstring)."""

from __future__ import annotations

import time
import warnings

import numpy as np
from grid_scores import _relative, _widened_box, score
from scipy.integrate import solve_ivp


def baseline_scores(system, truth, forced, data):
    """The baselines' figures on one case's ``data`` (``(runs, test, xs, ts, us)``, as
    :func:`case_data` gives): ``{"sindy": ..., "weak_sindy": ..., "mlp": ...}`` (no ``"mlp"``
    unforced: the inverse-dynamics regressor needs the forces)."""
    runs, test, xs, ts, us = data
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = {"sindy": _sindy_baseline(system, truth, xs, ts, us, test, runs, forced),
               "weak_sindy": _sindy_baseline(system, truth, xs, ts, us, test, runs, forced,
                                             weak=True)}
        if forced:
            out["mlp"] = _mlp_baseline(truth, xs, ts, us, test, runs)
    return out


def _derivatives(xs, ts):
    from pysindy_xl.held_out import scoring_derivatives
    return [scoring_derivatives(t, x) for x, t in zip(xs, ts, strict=True)]


def _bounded_simulation(rhs, x0, t, max_evaluations=20000):
    """RK45 of ``rhs`` over ``t``; stops (RuntimeError) on blow-up or after too many steps."""
    count = [0]
    scale = 1e3 * (1 + np.abs(x0).max())

    def guarded(time, x):
        count[0] += 1
        if count[0] > max_evaluations:
            raise RuntimeError("simulation: too many steps (stiff or diverging)")
        return rhs(time, x)

    def blow_up(time, x):
        return scale - np.abs(x).max()

    blow_up.terminal = True
    solution = solve_ivp(guarded, (t[0], t[-1]), x0, t_eval=t, rtol=1e-6, atol=1e-8,
                         events=blow_up)
    if solution.y.shape[1] != len(t):
        raise RuntimeError("simulation: diverged")
    return solution.y.T


#: STLSQ thresholds tried by the PySINDy baselines (chosen on the training runs' last fifth).
THRESHOLDS = (0.005, 0.02, 0.05, 0.2, 0.5)


def _sindy_library(system):
    import pysindy as ps
    library = ps.PolynomialLibrary(degree=3)
    if "angle" in system["kinds"]:
        library = library + ps.FourierLibrary(n_frequencies=2)
    return library


def _sindy_fit(system, states, derivatives, ts, us, threshold, weak):
    """PySINDy on ``[q, qd]``: the strong form (smoothed derivatives) or the weak form (no
    derivative of the state; the state itself is the smoothed ``[q, qd]``). Returns
    ``accelerations(q, qd, u)`` of the model (strong-form evaluation of its coefficients)."""
    import pysindy as ps
    n = states[0].shape[1] // 2
    library = _sindy_library(system)
    optimizer = ps.STLSQ(threshold=threshold)
    if weak:
        grid = ts[0]
        if any(len(t) != len(grid) or not np.allclose(t, grid) for t in ts):
            raise ValueError("the weak baseline needs runs on one time grid")
        weak_library = ps.WeakPDELibrary(function_library=library, spatiotemporal_grid=grid,
                                         K=WEAK_WINDOWS, H_xt=WEAK_HALF_WIDTH)
        model = ps.SINDy(feature_library=weak_library, optimizer=optimizer)
        model.fit(states, t=ts, u=us)
        coef = model.coefficients()
        strong = _sindy_library(system).fit(np.c_[states[0], us[0]] if us else states[0])

        def rates(x, u):
            return strong.transform(np.c_[x, u] if us else x) @ coef.T
    else:
        model = ps.SINDy(feature_library=library, optimizer=optimizer)
        model.fit(states, t=ts, x_dot=derivatives, u=us)

        def rates(x, u):
            return model.predict(x, u=u if us else None)

    def accelerations(q, qd, u):
        return np.asarray(rates(np.c_[q, qd], u))[:, n:]

    return accelerations, rates


#: Test windows and their half width (s) of the weak-form PySINDy baseline.
WEAK_WINDOWS, WEAK_HALF_WIDTH = 400, 0.1


def _sindy_baseline(system, truth, xs, ts, us, test, runs, forced, weak=False):
    """PySINDy ``SINDy`` on [q, qd] with polynomial (+ Fourier of the angles) library, strong or
    weak form; the STLSQ threshold is the one of :data:`THRESHOLDS` whose model predicts the
    accelerations of the training runs' last fifth best when fitted on the first four fifths."""
    n = truth.n
    smooth = _derivatives(xs, ts)
    states = [np.c_[q, qd] for q, qd, _ in smooth]
    derivatives = [np.c_[qd, qdd] for _, qd, qdd in smooth]
    controls = us if forced else None
    started = time.perf_counter()
    try:
        cut = [int(0.8 * len(t)) for t in ts]
        validation = []
        for threshold in THRESHOLDS:
            try:
                accelerations, _ = _sindy_fit(
                    system, [s[:c] for s, c in zip(states, cut, strict=True)],
                    [d[:c] for d, c in zip(derivatives, cut, strict=True)],
                    [t[:c] for t, c in zip(ts, cut, strict=True)],
                    None if controls is None else [u[:c] for u, c in zip(controls, cut,
                                                                         strict=True)],
                    threshold, weak)
                predicted = np.vstack([accelerations(s[c:, :n], s[c:, n:],
                                                     None if controls is None else u[c:])
                                       for s, c, u in zip(states, cut, controls or states,
                                                          strict=True)])
                target = np.vstack([d[c:, n:] for d, c in zip(derivatives, cut, strict=True)])
                error = _relative(predicted, target)
            except Exception:  # noqa: BLE001 - a threshold that fails loses
                error = float("inf")
            validation.append(error if np.isfinite(error) else float("inf"))
        threshold = THRESHOLDS[int(np.argmin(validation))]
        accelerations, rates = _sindy_fit(system, states, derivatives, ts, controls, threshold,
                                          weak)

        def simulate(x0, t, force):
            return _bounded_simulation(
                lambda time, x: rates(x[None], force(time)[None] if forced else None)[0], x0, t)

        scores = {"threshold": threshold,
                  "held_out_accelerations": _relative(accelerations(test["q"], test["qd"],
                                                                    test["u"]), test["qdd"])}
        full = score(None, accelerations, simulate, system, truth, test, runs, False)
        # off the box: the accelerations under no force (forced runs too; a failed
        # prediction is recorded as None)
        scores.update({"simulation": full["simulation"],
                       "off_box_accelerations": full["off_box"], "off_box_under": "no force"})
    except Exception as error:  # noqa: BLE001
        scores = {"error": repr(error)[:200]}
    scores["seconds"] = time.perf_counter() - started
    return scores


def _mlp_baseline(truth, xs, ts, us, test, runs):
    """scikit-learn MLP inverse dynamics (q, qd, qdd) -> u on smoothed derivatives."""
    from sklearn.neural_network import MLPRegressor
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    smooth = _derivatives(xs, ts)
    features = np.vstack([np.c_[q, qd, qdd] for q, qd, qdd in smooth])[::4]
    targets = np.vstack(us)[::4]
    started = time.perf_counter()
    regressor = MLPRegressor(hidden_layer_sizes=(64, 64), max_iter=300, random_state=0,
                             early_stopping=True)
    model = make_pipeline(StandardScaler(), regressor)
    model.fit(features, targets if targets.shape[1] > 1 else targets[:, 0])

    def forces(q, qd, qdd):
        return model.predict(np.c_[q, qd, qdd]).reshape(len(q), -1)

    held = _relative(forces(test["q"], test["qd"], test["qdd"]), test["u"])
    box = _widened_box(runs, truth.n)
    off = _relative(forces(box["q"], box["qd"], box["qdd"]),
                    truth.forces(box["q"], box["qd"], box["qdd"]))
    return {"held_out": held, "off_box": off, "seconds": time.perf_counter() - started}
