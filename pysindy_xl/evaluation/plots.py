"""Figures of a validation (the paper's Figure 1), on matplotlib Agg canvases (no pyplot
global state, no display)."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_validation", "plot_coefficients"]

_REFERENCE = {"color": "black", "linestyle": "--", "linewidth": 1.2, "label": "MuJoCo"}
_MODEL = {"color": "tab:blue", "linewidth": 1.2, "label": "identified model"}


def new_figure(width, height):
    """A constrained-layout figure on an Agg canvas, not registered with pyplot.

    Parameters
    ----------
    width, height : float
        Size (inches).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    figure = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def plot_coefficients(ax, feature_names, coefficients, true_coefficients=None, max_features=40):
    """Bar chart of identified (and true) coefficients (F,) on a symmetric log scale, on ``ax``.

    Only features non-zero in either vector are drawn (the ``max_features`` largest); a
    ValueError says when the lengths differ.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes to draw on.
    feature_names : sequence of str
        One name per coefficient.
    coefficients : array_like of shape (F,)
        Identified coefficients.
    true_coefficients : array_like of shape (F,), default=None
        True coefficients, drawn beside them.
    max_features : int, default=40
        Most features drawn (the largest).

    Returns
    -------
    None

    Examples
    --------
    >>> from matplotlib.figure import Figure
    >>> ax = Figure().add_subplot()
    >>> plot_coefficients(ax, ["a", "b", "c"], [1.0, 0.0, -0.5], [1.0, 0.0, -0.4])
    >>> [label.get_text() for label in ax.get_xticklabels()]  # zero in both: not drawn
    ['a', 'c']
    """
    coefficients = np.asarray(coefficients, dtype=float)
    if len(feature_names) != len(coefficients):
        raise ValueError(f"feature_names: {len(feature_names)} names for {len(coefficients)} "
                         "coefficients")
    truth = None if true_coefficients is None else np.asarray(true_coefficients, dtype=float)
    if truth is not None and truth.shape != coefficients.shape:
        raise ValueError(f"true_coefficients: expected shape {coefficients.shape}")
    size = np.abs(coefficients) if truth is None else np.maximum(np.abs(coefficients),
                                                                np.abs(truth))
    shown = np.flatnonzero(size > 0)
    if len(shown) > max_features:
        shown = np.sort(shown[np.argsort(-size[shown])[:max_features]])
    x = np.arange(len(shown))
    width = 0.4 if truth is not None else 0.8
    ax.bar(x - (width / 2 if truth is not None else 0), coefficients[shown], width,
           color="tab:blue", label="identified")
    if truth is not None:
        ax.bar(x + width / 2, truth[shown], width, color="black", alpha=0.6, label="true")
    ax.set_yscale("symlog", linthresh=1e-2)
    ax.set_xticks(x, [feature_names[j] for j in shown], rotation=60, ha="right", fontsize=7)
    ax.axhline(0, color="grey", linewidth=0.5)
    ax.set_ylabel("coefficient")
    ax.legend(fontsize=8)


def plot_validation(result, path=None, feature_names=None, coefficients=None,
                    true_coefficients=None, title=None):
    """Trajectories, residuals and coefficients of a validation, as in the paper's Figure 1.

    ``result`` is a :class:`ValidationResult`; the PNG is saved at ``path`` when given;
    ``feature_names``, ``coefficients`` (and ``true_coefficients``) draw panel (C) by
    :func:`plot_coefficients`; ``title`` prefixes the figure title. Returns the
    :class:`~matplotlib.figure.Figure` on an Agg canvas, not registered with pyplot.

    Parameters
    ----------
    result : ValidationResult
        The validation to draw.
    path : str or os.PathLike, default=None
        Where to save the PNG; None: not saved.
    feature_names : sequence of str, default=None
        With ``coefficients``, draw the coefficient panel.
    coefficients : array_like of shape (F,), default=None
        Identified coefficients.
    true_coefficients : array_like of shape (F,), default=None
        True coefficients.
    title : str, default=None
        Prefix of the figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, on an Agg canvas, not registered with pyplot.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from pysindy_xl.mujoco import compare_trajectories
    >>> t = np.linspace(0.0, 1.0, 51)
    >>> reference = np.column_stack([np.sin(t), np.cos(t)])
    >>> result = compare_trajectories(t, reference, reference + 0.01, coordinate_names=["x"])
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     figure = plot_validation(result, pathlib.Path(tmp) / "validation.png", title="demo")
    >>> figure.get_suptitle()
    'demo: position RMSE 0.01, valid'
    """
    n = result.n
    with_coefficients = coefficients is not None
    figure = new_figure(11, 2.0 * n + (4.0 if with_coefficients else 0.0))
    grid = figure.add_gridspec(n + (2 if with_coefficients else 0), 2)
    k = len(result.prediction)
    names = result.coordinate_names or tuple(f"q{i}" for i in range(n))
    for i in range(n):
        ax = figure.add_subplot(grid[i, 0])
        ax.plot(result.t, result.reference[:, i], **_REFERENCE)
        ax.plot(result.t[:k], result.prediction[:, i], **_MODEL)
        ax.set_ylabel(names[i])
        if i == 0:
            ax.set_title("(A) trajectories")
            ax.legend(fontsize=8, loc="upper right")
        if result.divergence_time is not None:
            ax.axvline(result.divergence_time, color="tab:red", linewidth=0.8)
        ax = figure.add_subplot(grid[i, 1])
        ax.plot(result.t[:k], result.prediction[:, i] - result.reference[:k, i],
                color="tab:red", linewidth=1.0)
        ax.axhline(0, color="grey", linewidth=0.5)
        ax.set_ylabel(f"error {names[i]}")
        if i == 0:
            ax.set_title("(B) residuals (model - MuJoCo)")
        if i == n - 1:
            figure.axes[-2].set_xlabel("t [s]")
            ax.set_xlabel("t [s]")
    if with_coefficients:
        ax = figure.add_subplot(grid[n:, :])
        plot_coefficients(ax, feature_names, coefficients, true_coefficients)
        ax.set_title("(C) coefficients")
    status = "valid" if result.valid else f"invalid ({result.failure or 'diverged'})"
    figure.suptitle((f"{title}: " if title else "")
                    + f"position RMSE {result.position_rmse:.3g}, {status}", fontsize=11)
    if path is not None:
        figure.savefig(path, dpi=110)
    return figure
