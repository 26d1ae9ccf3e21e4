"""How well an identified model explains its own data, and how it simulates it.

:func:`fit_quality` rebuilds the problem the model solved (:meth:`XLSINDy.regression
<pysindy_xl.XLSINDy.regression>`) and reports its ``R^2``; :func:`plot_identification`
simulates the model from a recorded trajectory. ``pysindy-xl identify`` prints and plots both.
"""

from __future__ import annotations

import numpy as np

__all__ = ["fit_quality", "quality_lines", "plot_identification", "force_prediction"]


def fit_quality(model, arguments) -> dict:
    r"""R^2 of the identified equations' residual on the training data.

    With ``Theta`` the fit's regression matrix, ``xi`` the coefficients and ``r = Theta xi``
    the residual, on forced data (some force column in the law)

    .. math:: R^2 = 1 - \frac{\|r\|^2}{\|\Theta_F \xi_F\|^2},

    ``Theta_F xi_F`` the force part; per coordinate the same on its block of rows. Unforced
    (an implicit law, each equation fixed only up to its own factor), each equation ``i`` is
    judged over its kinetic part, the part that states the accelerations:

    .. math:: R^2_i = 1 - e_i^2, \qquad
              e_i = \frac{\|\Theta_i \xi\|}{\|\sum_{j \in K} \Theta_{ij} \xi_j\|},
              \qquad R^2 = 1 - \tfrac1n \textstyle\sum_i e_i^2,

    ``K`` the columns that carry inertia (the Lagrangian's terms quadratic in the velocities;
    :func:`~pysindy_xl.fit.kinetic_scale.kinetic_relative_residuals`, the scale of the
    catalog growth's held-out criterion). ``e_i`` is about the relative error of the
    accelerations the law predicts; ``R^2`` is ``-inf`` for a law with no inertia in an
    equation. A single term's size is no scale of a law: a large term that the others
    nearly cancel would make a law that explains little look exact.

    Parameters
    ----------
    model : XLSINDy
        A fitted model.
    arguments : dict
        The keyword arguments its ``fit`` received (``Dataset.fit_arguments``).

    Returns
    -------
    dict
        ``r2``, ``r2_per_coordinate`` (name -> float), ``formulation``, ``target``
        (``"forces"``, or ``"kinetic"`` for unforced data), ``rows``, ``cv_error`` and
        ``cv_noise_ratio`` (held-out scores of the sparsity selection, or ``None``),
        ``stability`` (after an ensemble fit: the kept term selected least often and the
        dropped term selected most often, each ``[name, fraction]``, else ``None``),
        ``held_still``, ``physical_consistency``.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
    >>> t = np.linspace(0, 10, 1001)
    >>> x = np.cos(2 * t)[:, None]
    >>> arguments = {"x": x, "t": t, "x_dot": -2 * np.sin(2 * t)[:, None],
    ...              "x_ddot": -4 * x, "u": -1.0 * x}
    >>> model = px.XLSINDy(lib).fit(**arguments)
    >>> quality = fit_quality(model, arguments)
    >>> round(quality["r2"], 6), quality["formulation"], quality["target"]
    (1.0, 'strong', 'forces')
    """
    if not isinstance(arguments, dict) or "x" not in arguments:
        raise TypeError("arguments: expected the dict of fit arguments (with 'x'), got "
                        f"{type(arguments).__name__}")
    fit_keys = ("x", "t", "x_dot", "x_ddot", "u", "sample_mask")
    problem = model.regression(**{key: arguments.get(key) for key in fit_keys})
    theta, origin = problem.theta, problem.catalog_map
    coef = model.coef_[origin.columns]
    names = [name for name, moving in zip(model.feature_library_.coords.names,
                                          origin.coordinates, strict=True) if moving]
    n = len(names)
    forces = problem.force_columns
    forced = bool(len(forces)) and np.any(coef[forces] != 0) and np.any(theta[:, forces] != 0)
    if forced:
        residual, target = theta @ coef, theta[:, forces] @ coef[forces]

        def r2(r, b):
            denominator = float(b @ b)
            return float(1 - (r @ r) / denominator) if denominator > 0 else float("nan")

        overall, target_name = r2(residual, target), "forces"
        per = {name: r2(r, b) for name, r, b in zip(names, residual.reshape(n, -1),
                                                    target.reshape(n, -1), strict=True)}
    else:
        from ..fit.kinetic_scale import kinetic_relative_residuals  # not at the CLI's --help
        squared = np.square(kinetic_relative_residuals(model, problem))
        overall, target_name = float(1 - np.mean(squared)), "kinetic"
        per = dict(zip(names, (1 - squared).tolist(), strict=True))
    selection = getattr(model, "selection_", None)
    held_out = {"cv_error": None, "cv_noise_ratio": None}
    for key, attribute in (("cv_error", "cv_error"), ("cv_noise_ratio", "cv_ratio")):
        if hasattr(selection, attribute):
            held_out[key] = float(getattr(selection, attribute)[selection.size - 1])
    return {"r2": overall, "r2_per_coordinate": per,
            "formulation": model.formulation_, "target": target_name,
            "rows": int(theta.shape[0]), **held_out, "stability": _stability(model),
            "held_still": list(getattr(model, "still_coordinates_", ())),
            "physical_consistency": getattr(model, "physical_consistency_", None)}


def force_prediction(model, x, t, u, x_dot=None, x_ddot=None) -> dict:
    """How well the model predicts measured forces on a trajectory (inverse dynamics).

    The forces ``tau_hat`` that :meth:`~pysindy_xl.XLSINDy.predict_forces` needs to move as
    recorded, against the measured ``u``: per coordinate ``rms(tau_hat - u) / rms(u)``.

    Parameters
    ----------
    model : XLSINDy
        A fitted model with dynamics.
    x : array, shape (N, n)
        Positions.
    t : array, shape (N,)
        Their times.
    u : array, shape (N, n)
        Measured generalized forces.
    x_dot, x_ddot : array, shape (N, n), optional
        Velocities and accelerations; default None: from the model's smoother (or a default
        :class:`~pysindy_xl.WhittakerSmoother`).

    Returns
    -------
    dict
        ``relative_rms`` (coordinate name -> float), ``worst`` (the largest) and
        ``predicted`` (ndarray (N, n)).

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
    >>> t = np.linspace(0, 5, 501)
    >>> x = (np.sin(t) + 0.5 * np.sin(3 * t))[:, None]  # two frequencies
    >>> xd = (np.cos(t) + 1.5 * np.cos(3 * t))[:, None]
    >>> xdd = (-np.sin(t) - 4.5 * np.sin(3 * t))[:, None]
    >>> model = px.XLSINDy(lib).fit(x, t, x_dot=xd, x_ddot=xdd, u=2 * xdd + 3 * x)
    >>> force_prediction(model, x, t, 2 * xdd + 3 * x, xd, xdd)["worst"] < 1e-9
    True
    """
    from .._inputs import check_array
    from ..weak import WhittakerSmoother
    n = model.n_coordinates_
    x = check_array(x, "x", n_columns=n)
    u = check_array(u, "u", x.shape)
    if x_dot is None or x_ddot is None:  # noisy positions: smoothed with their derivatives
        q, qd, qdd = (model.smoother or WhittakerSmoother()).smooth(np.asarray(t, dtype=float), x)
        x, x_dot, x_ddot = q, qd if x_dot is None else x_dot, qdd if x_ddot is None else x_ddot
    predicted = model.predict_forces(x, x_dot, x_ddot)
    scale = np.sqrt(np.mean(u**2, axis=0))
    error = np.sqrt(np.mean((predicted - u) ** 2, axis=0)) / np.where(scale > 0, scale, 1.0)
    names = model.feature_library_.coords.names
    return {"relative_rms": dict(zip(names, error.tolist(), strict=True)),
            "worst": float(error.max()), "predicted": predicted}


def _stability(model):
    """The ``stability`` entry of :func:`fit_quality`."""
    probability = getattr(model, "inclusion_probability_", None)
    if probability is None:
        return None
    names, kept = model.get_feature_names(), model.coef_ != 0
    forces = np.isin(np.arange(len(names)), model.feature_library_.force_columns_)

    def extreme(mask, pick):
        if not mask.any():
            return None
        j = np.flatnonzero(mask)[pick(probability[mask])]
        return [names[j], float(probability[j])]

    return {"kept_least": extreme(kept & ~forces, np.argmin),
            "dropped_most": extreme(~kept & ~forces, np.argmax)}


def quality_lines(quality) -> list:
    """The lines ``pysindy-xl identify`` prints for a :func:`fit_quality` result.

    Parameters
    ----------
    quality : dict
        A result of :func:`fit_quality`.

    Returns
    -------
    list of str
        R^2 overall and per coordinate, then the selection's held-out scores and the stability
        over subsample fits when known.

    Examples
    --------
    >>> quality = {"r2": 0.999, "r2_per_coordinate": {"theta": 0.999}, "formulation": "weak",
    ...            "target": "forces", "rows": 120, "cv_error": 1e-3, "cv_noise_ratio": None,
    ...            "stability": {"kept_least": ["L[cos(theta)]", 0.95],
    ...                          "dropped_most": ["L[theta_dot**2*cos(theta)]", 0.1]}}
    >>> lines = quality_lines(quality)
    >>> lines[0]
    'fit quality: R^2 = 0.9990 (theta 0.9990)'
    >>> lines[-1][:68]
    '  stability over the subsample fits: every kept term in 95% of them '
    """
    kind = ("weak form: equations integrated against test functions on smoothed positions"
            if quality["formulation"] == "weak" else "strong form: equations at each sample")
    per = ", ".join(f"{k} {v:.4f}" for k, v in quality["r2_per_coordinate"].items())
    lines = [f"fit quality: R^2 = {quality['r2']:.4f} ({per})"]
    if quality["target"] == "forces":
        lines += [f"  R^2 = 1 - |residual|^2 / |forces|^2 over {quality['rows']} rows of the "
                  f"{kind};",
                  "  1 is exact; the residual is what the identified equations leave "
                  "unexplained of the generalized forces"]
    else:
        lines += [f"  R^2 = 1 - |residual|^2 / |kinetic part|^2, averaged over the equations, on "
                  f"{quality['rows']} rows of the {kind};",
                  "  1 is exact; unforced data: each equation's residual against its terms "
                  "quadratic in the velocities (about the relative error of the accelerations)"]
    if quality["cv_error"] is not None:
        lines.append(f"  held-out relative squared error of the chosen sparsity (5-fold "
                     f"cross-validation): {quality['cv_error']:.3g}")
    stability = quality.get("stability")
    if stability is not None:
        kept, dropped = stability["kept_least"], stability["dropped_most"]
        line = "  stability over the subsample fits:"
        if kept is not None:
            line += f" every kept term in {kept[1]:.0%} of them or more (least: {kept[0]})"
        if dropped is not None:
            line += (";" if kept is not None else "") + (
                f" the most frequent dropped term in {dropped[1]:.0%} ({dropped[0]})")
        lines.append(line)
    if quality.get("held_still"):
        lines.append(f"  not identified, held still: {', '.join(quality['held_still'])} (no "
                     "force and no acceleration beyond the noise in the data)")
    if quality.get("cv_noise_ratio") is not None:
        lines.append("  held-out noise ratio of the chosen law (5-fold cross-validation; about 1 "
                     f"when it leaves only the propagated noise): {quality['cv_noise_ratio']:.3g}")
    from ..fitted.equations import consistency_line  # sympy: not imported by the CLI's --help
    consistency = consistency_line(quality.get("physical_consistency"))
    if consistency:
        lines.append(f"  {consistency}")
    return lines


def plot_identification(model, trajectory, path, title=None, forced=True) -> dict:
    """Simulate the model from a recorded trajectory's initial state and plot both.

    Under the recorded forces (when ``forced``), one panel per coordinate, written as PNG.

    Parameters
    ----------
    model : XLSINDy
        A fitted model with dynamics.
    trajectory : Trajectory
        The recorded run (:class:`~pysindy_xl.mujoco.Trajectory`: ``t``, ``q``, ``qd``,
        ``tau``).
    path : str or path-like
        The PNG file to write.
    title : str, optional
        Figure title; default None: "identified model against the data".
    forced : bool, default True
        Simulate under the recorded forces ``tau`` (False: unforced).

    Returns
    -------
    dict
        ``rmse`` (per coordinate over the simulated span), ``simulated_until`` (s) and
        ``diverged`` (bool).

    Examples
    --------
    >>> import numpy as np, pathlib, tempfile, pysindy_xl as px
    >>> from pysindy_xl.mujoco import Trajectory
    >>> c = px.Coordinates(["x"])
    >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
    >>> t = np.linspace(0, 5, 501)
    >>> x = np.cos(2 * t)[:, None]
    >>> model = px.XLSINDy(lib).fit(x, t, x_dot=-2 * np.sin(2 * t)[:, None],
    ...                             x_ddot=-4 * x, u=-1.0 * x)
    >>> data = Trajectory(t=t, q=x, qd=-2 * np.sin(2 * t)[:, None], tau=-1.0 * x)
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     result = plot_identification(model, data, pathlib.Path(tmp) / "fit.png")
    ...     written = (pathlib.Path(tmp) / "fit.png").stat().st_size > 0
    >>> written, result["diverged"], bool(result["rmse"][0] < 1e-3)
    (True, False, True)
    """
    from ..dynamics import DynamicsError
    from .plots import new_figure
    if model.dynamics_ is None:
        raise ValueError("model: the identified equations contain no acceleration; nothing "
                         "to simulate")
    t, q = trajectory.t, trajectory.q
    qd0 = trajectory.qd[0] if trajectory.qd is not None else model.differentiate(q, t)[0]
    tau = trajectory.tau if forced and trajectory.tau is not None else None
    diverged = False
    try:
        states = model.simulate(np.r_[q[0], qd0], t, tau, timeout=60.0)
    except DynamicsError as error:
        partial = getattr(error, "states", None)
        states = np.asarray(partial) if partial is not None else np.empty((0, 2 * q.shape[1]))
        diverged = True
    k = len(states)
    rmse = (np.sqrt(np.mean((states[:, :q.shape[1]] - q[:k]) ** 2, axis=0)) if k
            else np.full(q.shape[1], np.inf))
    names = model.feature_library_.coords.names
    figure = new_figure(7, 1.8 * len(names) + 0.6)
    axes = figure.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
    for i, (ax, name) in enumerate(zip(axes, names, strict=True)):
        ax.plot(t, q[:, i], color="black", linestyle="--", linewidth=1.2, label="recorded")
        if k:
            ax.plot(t[:k], states[:, i], color="tab:blue", linewidth=1.2, label="identified model")
        ax.set_ylabel(name)
    axes[0].legend(loc="upper right", fontsize="small")
    axes[-1].set_xlabel("t (s)")
    figure.suptitle(title or "identified model against the data"
                    + (" (diverged)" if diverged else ""))
    figure.savefig(path, dpi=110)
    return {"rmse": rmse, "simulated_until": float(t[k - 1]) if k else float(t[0]),
            "diverged": diverged}
