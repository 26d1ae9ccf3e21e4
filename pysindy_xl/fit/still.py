r"""Coordinates that hold still in the data: found at fit time and left out of the regression.

A body that never moves (a passive target beside an arm, a part resting on its support)
carries no information about its own dynamics: its equation of motion reads ``0 = 0`` on the
data, up to noise, and its inertia cannot be identified. Left in the regression it makes the
fit fail (no law explains the noise of its rows; a mass matrix without inertia for it). Such
a coordinate is *still*, and :class:`~pysindy_xl.XLSINDy` leaves it out of the regression:

* **Criterion** (:func:`still_coordinates`). Coordinate :math:`i` is still when it is
  undriven (no recorded generalized force acts on it: its rows of the force columns are
  zero) and, on every trajectory :math:`k`, its recorded motion departs from a uniform one
  by no more than the noise. With :math:`r_i^{(k)}(t) = q_i^{(k)}(t) - a - b t` the residual
  of the least-squares line through the positions,

  .. math::

      \operatorname{std}_t r_i^{(k)} \le \kappa \, \hat\sigma_i^{(k)}
      \quad\text{or}\quad
      \max_t r_i^{(k)} - \min_t r_i^{(k)} \le \epsilon \,(1 + \max_t |q_i^{(k)}|),

  with :math:`\hat\sigma_i^{(k)}` the noise level of the positions, estimated robustly from
  their third differences (which remove any smooth motion sampled finely enough):
  :math:`\hat\sigma = 1.4826 \, \operatorname{MAD}(\Delta^3 q) / \sqrt{20}` (white noise of
  standard deviation :math:`\sigma` has third differences of variance :math:`20 \sigma^2`),
  :math:`\kappa` the ``hold_still`` threshold of the estimator and :math:`\epsilon = 10^{-9}`
  (numerically uniform). Pure noise gives a ratio
  :math:`\operatorname{std} r / \hat\sigma` close to 1; a sinusoid of amplitude :math:`A`
  under the noise gives :math:`\sqrt{1 + A^2 / (2 \sigma^2)}`, so with the default
  :math:`\kappa = 2` a motion of amplitude above about 2.5 noise levels keeps its
  coordinate in the regression. The margin to 1 leaves room for the estimators' scatter on
  short trajectories; the margin to larger values keeps coupled coordinates that move little
  (a heavy cart under a pendulum) whose motion, though small, is resolved over many samples.
  A body at rest is the common case (:math:`b = 0`); a body drifting at
  constant velocity is the same: its accelerations, all its equation could be identified
  from, are zero. Such a body is decoupled from the coordinates that move: in a Lagrangian
  system a coupling term acts on both sides, so it would accelerate the body as the others
  move.
* **Leaving out** (:func:`still_columns`). The rows of still coordinates (their equations)
  are removed, and so is every catalog column that, in the equations of the other
  coordinates, is zero, involves a velocity, acceleration or force of a still coordinate, or
  depends on the positions of still coordinates only (a constant on the data). The remaining
  coordinates are identified as if the still body were absent; columns coupling a still
  position with moving coordinates stay (the still position is a constant of their law).
* **In the model** the still coordinates are held: their acceleration is zero
  (:class:`~pysindy_xl.dynamics.CatalogDynamics` with ``held``), so they keep their initial
  velocity in a simulation (zero for a body at rest), and the model says so in ``print()``,
  the quality report and the CLI.

A driven coordinate that does not move (a joint held by its motor) is never still: its
equation, gravity against the recorded torque, carries information.
"""

from __future__ import annotations

import numpy as np

__all__ = ["noise_level", "driven_coordinates", "still_coordinates", "still_columns",
           "block_rows", "held_note"]

#: Relative range of the departure from uniform motion below which it is numerical.
_UNIFORM = 1e-9


def noise_level(x) -> np.ndarray:
    r"""Robust noise level of each column of ``x`` from its third differences.

    ``1.4826 * MAD(diff(x, 3)) / sqrt(20)``: the standard deviation of white noise added to a
    signal that is smooth at the sampling rate (its third differences are negligible), and
    insensitive to a few outliers.

    Parameters
    ----------
    x : array, shape (N, n)

    Returns
    -------
    ndarray, shape (n,)
        Zeros when ``N < 4``.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> t = np.linspace(0, 10, 4001)[:, None]
    >>> sigma = noise_level(np.sin(t) + 0.01 * rng.normal(size=t.shape))
    >>> bool(abs(sigma[0] - 0.01) < 0.001)
    True
    """
    x = np.asarray(x, dtype=float)
    if x.shape[0] < 4:
        return np.zeros(x.shape[1])
    third = np.diff(x, n=3, axis=0)
    mad = np.median(np.abs(third - np.median(third, axis=0)), axis=0)
    return 1.4826 * mad / np.sqrt(20.0)


def driven_coordinates(library, forces) -> np.ndarray:
    """The coordinates on which a recorded force acts through the catalog's force columns.

    Coordinate ``c`` is driven when an entry of a force column in its equation contains the
    force ``tau_k`` of a coordinate ``k`` whose recorded force is not zero everywhere.

    Parameters
    ----------
    library : fitted CatalogRepartition
    forces : list of array (N_k, n) or None
        Recorded generalized forces per trajectory (None: unforced).

    Returns
    -------
    ndarray of bool, shape (n,)

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
    acting = np.any([np.any(np.asarray(u) != 0, axis=0) for u in forces if u is not None],
                    axis=0)
    driven = np.zeros(n, dtype=bool)
    for k, tau in enumerate(coords.tau):
        if acting[k]:
            driven |= library.involves([tau])[:, library.force_columns_].any(axis=1)
    return driven


def still_coordinates(positions, times, forced, threshold: float) -> np.ndarray:
    """The coordinates that hold still in the data (see the module docstring).

    Parameters
    ----------
    positions : list of array, shape (N_k, n)
        Recorded positions, one array per trajectory.
    times : list of array, shape (N_k,)
        Their sample times.
    forced : array of bool, shape (n,)
        Coordinates on which a recorded force acts (never still).
    threshold : float
        ``kappa``: motion up to this many noise levels counts as noise.

    Returns
    -------
    ndarray of bool, shape (n,)

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
    """Catalog columns left out with the still coordinates, with the reason.

    Parameters
    ----------
    library : fitted CatalogRepartition
    still : array of bool, shape (n,)

    Returns
    -------
    dict of int to str
        Column index -> reason, for the columns that are zero in the equations of the moving
        coordinates, involve a velocity, acceleration or force of a still coordinate there,
        or depend only on positions of still coordinates there.

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
    """Row indices of ``blocks`` (a boolean mask) in a matrix stacked coordinate-major.

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
    """The note that a model prints about its still coordinates (empty when none).

    Examples
    --------
    >>> held_note(["target_x"]).endswith("model): target_x"), held_note([])
    (True, '')
    """
    if not len(names):
        return ""
    return ("held still (no force and no acceleration beyond the noise in the data; left out "
            f"of the regression, zero acceleration in the model): {', '.join(names)}")
