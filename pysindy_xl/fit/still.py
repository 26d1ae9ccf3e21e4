r"""Coordinates that hold still in the data: found at fit time and left out of the regression.

A body that never moves carries no information about its dynamics (its equation reads
``0 = 0`` up to noise) and, left in, makes the fit fail. Coordinate :math:`i` is *still*
(:func:`still_coordinates`) when no recorded force acts on it and, on every trajectory, the
residual :math:`r_i = q_i - a - b t` of the least-squares line through its positions obeys

.. math::

    \operatorname{std}_t r_i \le \kappa \, \hat\sigma_i
    \quad\text{or}\quad
    \max_t r_i - \min_t r_i \le 10^{-9} \,(1 + \max_t |q_i|),

with :math:`\hat\sigma = 1.4826 \, \operatorname{MAD}(\Delta^3 q) / \sqrt{20}` the noise level
(:func:`noise_level`) and :math:`\kappa` the estimator's ``hold_still`` (a sinusoid of amplitude
:math:`A` gives :math:`\sqrt{1 + A^2 / (2 \sigma^2)}`). :func:`still_columns` lists the catalog
columns left out with them; the model holds still coordinates at zero acceleration
(:class:`~pysindy_xl.dynamics.CatalogDynamics` ``held``). A driven coordinate that does not move is
never still: gravity against the recorded torque is information.
"""

from __future__ import annotations

import numpy as np

__all__ = ["noise_level", "driven_coordinates", "still_coordinates", "still_columns",
           "block_rows", "held_note"]

#: Relative range of the departure from uniform motion below which it is numerical.
_UNIFORM = 1e-9


def noise_level(x) -> np.ndarray:
    """Robust noise level of each column: ``1.4826 * MAD(diff(x, 3)) / sqrt(20)``.

    The standard deviation of white noise on a signal smooth at the sampling rate (its third
    differences are the noise's, of variance ``20 sigma^2``), insensitive to a few outliers.

    Parameters
    ----------
    x : array, shape (N, n)
        Samples.

    Returns
    -------
    ndarray, shape (n,)
        The noise levels; zeros when ``N < 4``.

    Examples
    --------
    >>> import numpy as np
    >>> noise = np.random.default_rng(0).normal(scale=0.01, size=(20000, 1))
    >>> bool(abs(noise_level(np.linspace(0, 1, 20000)[:, None] + noise)[0] - 0.01) < 5e-4)
    True
    """
    x = np.asarray(x, dtype=float)
    if x.shape[0] < 4:
        return np.zeros(x.shape[1])
    third = np.diff(x, n=3, axis=0)
    mad = np.median(np.abs(third - np.median(third, axis=0)), axis=0)
    return 1.4826 * mad / np.sqrt(20.0)


def driven_coordinates(library, forces) -> np.ndarray:
    """The coordinates on which a recorded force acts through the force columns.

    Coordinate ``c`` is driven when a force column's entry in its equation contains ``tau_k``
    and the recorded force ``k`` is not zero everywhere.

    Parameters
    ----------
    library : fitted CatalogRepartition
        The catalog.
    forces : list of ndarray (N_k, n) or None
        The recorded forces of each trajectory.

    Returns
    -------
    ndarray of bool, shape (n,)
        True for driven coordinates.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x", "y"])
    >>> lib = px.CatalogRepartition([px.LagrangeLibrary(c, [c.qd[0] ** 2])]).fit()
    >>> driven_coordinates(lib, [np.array([[1.0, 0.0], [2.0, 0.0]])]).tolist()
    [True, False]
    """
    coords = library.coords
    n = coords.n
    if forces is None or all(u is None for u in forces):
        return np.zeros(n, dtype=bool)
    acting = np.any([np.any(np.asarray(u) != 0, axis=0) for u in forces if u is not None], axis=0)
    driven = np.zeros(n, dtype=bool)
    for k, tau in enumerate(coords.tau):
        if acting[k]:
            driven |= library.involves([tau])[:, library.force_columns_].any(axis=1)
    return driven


def still_coordinates(positions, times, forced, threshold: float) -> np.ndarray:
    """The coordinates that hold still in the data (module docstring).

    A coordinate holds still when, in every trajectory, its departure from uniform motion stays
    within ``threshold`` times its estimated noise (:func:`noise_level`).

    Parameters
    ----------
    positions : list of ndarray, shape (N_k, n)
        Positions of each trajectory.
    times : list of ndarray, shape (N_k,)
        Their times.
    forced : ndarray of bool, shape (n,)
        Coordinates that are never still (driven by a recorded force).
    threshold : float
        ``kappa``, in multiples of the noise level.

    Returns
    -------
    ndarray of bool, shape (n,)
        True for still coordinates.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 10, 1001)
    >>> x = np.column_stack([np.sin(t), np.full_like(t, 0.3), np.full_like(t, 0.3)])
    >>> still_coordinates([x], [t], np.array([False, False, True]), 3.0).tolist()
    [False, True, False]
    >>> drift = np.column_stack([np.sin(t), 0.3 + 0.1 * t])  # uniform motion: still too
    >>> still_coordinates([drift], [t], np.zeros(2, dtype=bool), 3.0).tolist()
    [False, True]
    """
    forced = np.asarray(forced, dtype=bool)
    still = ~forced
    for x, t in zip(positions, times, strict=True):
        if not still.any():  # one moving trajectory per coordinate decides it
            break
        x = np.asarray(x, dtype=float)
        t = np.asarray(t, dtype=float)
        line = np.column_stack([np.ones_like(t), t - t.mean()])
        residual = x - line @ np.linalg.lstsq(line, x, rcond=None)[0]
        uniform = np.ptp(residual, axis=0) <= _UNIFORM * (1.0 + np.abs(x).max(axis=0))
        still &= uniform | (residual.std(axis=0) <= threshold * noise_level(x))
    return still


def still_columns(library, still) -> dict:
    """Catalog columns left out with the ``still`` coordinates: ``{column index: reason}``.

    A column goes when, in the equations of the moving coordinates, it is zero, involves a
    velocity, acceleration or force of a still coordinate, or depends only on still positions.

    Parameters
    ----------
    library : fitted CatalogRepartition
        The catalog.
    still : ndarray of bool, shape (n,)
        The still coordinates.

    Returns
    -------
    dict of int to str
        ``{column index: reason}``.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x", "y"])
    >>> lib = px.CatalogRepartition([px.LagrangeLibrary(
    ...     c, [c.qd[0] ** 2, c.qd[1] ** 2, c.q[0] * c.q[1], c.q[1] ** 2])]).fit()
    >>> lib.get_feature_names()
    ['F[tau]', 'L[x_dot**2]', 'L[y_dot**2]', 'L[x*y]', 'L[y**2]']
    >>> for j, reason in still_columns(lib, np.array([False, True])).items():
    ...     print(j, reason)
    2 only in the equations of still coordinates
    3 a function of still coordinates' positions only
    4 only in the equations of still coordinates
    """
    still = np.asarray(still, dtype=bool)
    if not still.any():
        return {}
    coords = library.coords
    moving = np.flatnonzero(~still)
    held = np.flatnonzero(still)
    motion = {symbol: coords.names[i] for i in held
              for symbol in (coords.qd[i], coords.qdd[i], coords.tau[i])}
    positions = {coords.q[i] for i in held}
    variables = list(coords.variables)
    # (F, V): the variables of each column's entries in the moving equations
    uses = np.stack([library.involves([v])[moving].any(axis=0) for v in variables], axis=1)
    nonzero = (library.entry_sizes()[moving] > 0).any(axis=0)
    reasons = {}
    for j in range(library.n_output_features_):
        if not nonzero[j]:
            reasons[j] = "only in the equations of still coordinates"
            continue
        symbols = {variables[v] for v in np.flatnonzero(uses[j])}
        involved = sorted({motion[s] for s in symbols if s in motion})
        if involved:
            reasons[j] = f"involves the motion of still coordinate(s) {', '.join(involved)}"
        elif symbols & positions and not symbols - positions - {coords.t}:
            reasons[j] = "a function of still coordinates' positions only"
    return reasons


def block_rows(n_blocks: int, n_rows: int, blocks) -> np.ndarray:
    """Row indices of chosen blocks of a matrix stacked coordinate-major.

    Parameters
    ----------
    n_blocks : int
        Number of blocks (coordinates).
    n_rows : int
        Rows of the matrix (``n_blocks`` equal blocks).
    blocks : ndarray of bool, shape (n_blocks,)
        The blocks to keep.

    Returns
    -------
    ndarray of int
        The rows of the kept blocks, in order.

    Examples
    --------
    >>> import numpy as np
    >>> block_rows(3, 6, np.array([True, False, True])).tolist()
    [0, 1, 4, 5]
    """
    per = n_rows // n_blocks
    chosen = np.flatnonzero(np.asarray(blocks, dtype=bool))
    return (chosen[:, None] * per + np.arange(per)).ravel()


def held_note(names) -> str:
    """The note that a model prints about its still coordinates.

    Parameters
    ----------
    names : sequence of str
        Names of the still coordinates.

    Returns
    -------
    str
        The note; empty when there are none.

    Examples
    --------
    >>> held_note(["target_x"]).endswith("model): target_x"), held_note([])
    (True, '')
    """
    if not len(names):
        return ""
    return ("held still (no force and no acceleration beyond the noise in the data; left out "
            f"of the regression, zero acceleration in the model): {', '.join(names)}")
