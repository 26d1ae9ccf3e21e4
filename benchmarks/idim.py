"""IDIM-LS: the robotics baseline of dynamic identification, written to be hard to beat.

Inverse dynamic identification model with least squares (Gautier and Khalil; the BIRDy
benchmark of Leboutet et al. 2021): the torques are linear in the base parameters,
``tau = Y(q, qd, qdd) beta``, so filter the positions, differentiate them, and solve a least
squares. The choices a careful roboticist makes, and this module makes:

* **a uniform grid first**: logged time stamps jitter; positions and torques are linearly
  interpolated onto a grid at the median step before any filter;
* **parallel zero-phase filtering**: a 4th-order Butterworth forwards and backwards on the
  positions *and* on the torques (the same filter on both sides of the equation), central
  differences for the velocities and accelerations, the filter's edges dropped;
* **decimation** to about ten samples per period of the cutoff (the rows beyond carry no
  new information and correlated errors);
* **the cutoff and the rank chosen by the data**: the cutoff of a grid, and the relative
  singular-value tolerance of the least squares (the numerical base-parameter rank, which
  truncates directions a poorly exciting log barely sees), with the smallest held-out torque
  error over time-blocked folds of the training data itself (:func:`choose_cutoff`; the
  data it is given, never a held-out run);
* **friction and offsets**: viscous ``qd``, smooth Coulomb ``tanh(qd / eps)`` and a constant
  torque offset per joint, beside the rigid-body columns. ``eps`` is
  :data:`COULOMB_SCALE`, the velocity scale of the package's own smooth Coulomb law
  (``JointFrictionLibrary(coulomb_scale=0.01)``), so both methods offer the same friction
  law. A hard ``sign(qd)`` of the filtered velocity would flip at random during the rests of
  a log, where the filtered velocity is noise around zero, and inject a spurious ``+-f_c``;
* **weighted least squares**: ordinary least squares on unit-norm columns (truncated SVD at
  the chosen tolerance), then each joint's rows weighted by the inverse of its residual
  standard deviation and solved again (Gautier's WLS).

The rigid-body regressor is any callable ``regressor(q, qd, qdd) -> (N, n, p)``: the
kinematic catalog's columns, or Pinocchio's ``computeJointTorqueRegressor`` (see
:func:`pinocchio_regressor`), which makes the baseline independent of pysindy-xl.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.signal

#: Cutoff frequencies (Hz) among which :func:`choose_cutoff` picks.
CUTOFFS = (1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0)

#: Relative singular-value thresholds (of the column-scaled regressor) among which
#: :func:`choose_cutoff` picks the numerical rank of the least squares: ``1e-10`` is plain
#: minimum-norm least squares, the larger ones truncate directions the data barely excite.
TOLERANCES = (1e-10, 1e-6, 1e-4, 1e-3, 1e-2)

#: Velocity scale (rad/s) of the smooth Coulomb column ``tanh(qd / COULOMB_SCALE)``: the
#: default ``coulomb_scale`` of the package's ``JointFrictionLibrary`` and
#: ``kinematic_catalog``.
COULOMB_SCALE = 0.01


def uniform_grid(t, *signals):
    """``t`` and ``signals`` on a uniform grid at the median step (linear interpolation)."""
    t = np.asarray(t, dtype=float)
    step = float(np.median(np.diff(t)))
    grid = t[0] + step * np.arange(int(np.floor((t[-1] - t[0]) / step + 1e-9)) + 1)
    return (grid, *(np.column_stack([np.interp(grid, t, s[:, j]) for j in range(s.shape[1])])
                    for s in signals))


def filtered_states(t, q, cutoff, tau=None):
    """Zero-phase Butterworth-filtered positions, central-difference velocities and
    accelerations (and the same filter on the torques) on a uniform grid.

    Returns ``(t, q, qd, qdd, tau)`` on the grid, the filter's edges dropped.
    """
    signals = (q,) if tau is None else (q, tau)
    grid, *signals = uniform_grid(t, *signals)
    step = grid[1] - grid[0]
    b, a = scipy.signal.butter(4, min(cutoff * 2 * step, 0.99))
    signals = [scipy.signal.filtfilt(b, a, s, axis=0) for s in signals]
    q = signals[0]
    qd = np.gradient(q, step, axis=0)
    qdd = np.gradient(qd, step, axis=0)
    edge = min(int(np.ceil(1.0 / (cutoff * step))), len(grid) // 10)
    keep = slice(edge, len(grid) - edge)
    tau = signals[1][keep] if tau is not None else None
    return grid[keep], q[keep], qd[keep], qdd[keep], tau


def friction_columns(qd, coulomb_scale=COULOMB_SCALE):
    """Viscous ``qd``, smooth Coulomb ``tanh(qd / coulomb_scale)`` and offset ``1`` columns
    per joint: (N, n, 3 n)."""
    n_samples, n = qd.shape
    columns = np.zeros((n_samples, n, 3 * n))
    joints = np.arange(n)
    columns[:, joints, 3 * joints] = qd
    columns[:, joints, 3 * joints + 1] = np.tanh(qd / coulomb_scale)
    columns[:, joints, 3 * joints + 2] = 1.0
    return columns


def design(regressor, q, qd, qdd):
    """Rigid-body and friction columns, (N, n, p + 3 n)."""
    return np.concatenate([regressor(q, qd, qdd), friction_columns(qd)], axis=2)


@dataclass
class IDIMModel:
    """An IDIM-LS fit: the parameters over ``design``'s columns and how they were found."""

    regressor: object
    parameters: np.ndarray
    cutoff: float
    joint_sigma: np.ndarray
    tolerance: float = TOLERANCES[0]
    scores: dict = field(default_factory=dict)

    def predict_forces(self, q, qd, qdd):
        """Joint torques (N, n) of the fitted model."""
        return design(self.regressor, q, qd, qdd) @ self.parameters


def _solver(rows, tolerance):
    """``solve(weights, target)``: truncated-SVD least squares of the weighted ``rows``.

    The columns are scaled to unit norm first, and singular values below ``tolerance``
    times the largest are dropped: the numerical base-parameter rank. Unidentifiable
    combinations get the minimum norm.
    """
    scale = np.linalg.norm(rows, axis=0)
    scale[scale == 0] = 1.0
    scaled = rows / scale

    def solve(weights, target):
        return np.linalg.lstsq(scaled * weights[:, None], target * weights,
                               rcond=tolerance)[0] / scale

    return solve


def _least_squares(columns, tau, weighted, tolerance=TOLERANCES[0]):
    """OLS (minimum norm over unidentifiable combinations), then one WLS step."""
    n_samples, n, p = columns.shape
    rows = columns.transpose(1, 0, 2).reshape(n * n_samples, p)
    target = tau.T.reshape(-1)
    solve = _solver(rows, tolerance)
    parameters = solve(np.ones(len(rows)), target)
    residual = (target - rows @ parameters).reshape(n, n_samples)
    sigma = np.sqrt(np.mean(residual**2, axis=1))
    if weighted:
        weights = np.repeat(1.0 / np.maximum(sigma, 1e-12 * sigma.max() + 1e-300), n_samples)
        parameters = solve(weights, target)
        residual = (target - rows @ parameters).reshape(n, n_samples)
        sigma = np.sqrt(np.mean(residual**2, axis=1))
    return parameters, sigma


def _decimation(step, cutoff):
    """Keep about ten samples per period of the cutoff."""
    return max(1, int(1.0 / (10.0 * cutoff * step)))


def _stacked(regressor, runs, cutoff):
    """The filtered, decimated design columns and torques of several runs at one cutoff."""
    blocks = []
    for t, q, tau in runs:
        grid, qf, qd, qdd, tauf = filtered_states(t, q, cutoff, tau)
        every = _decimation(grid[1] - grid[0], cutoff)
        blocks.append((design(regressor, qf[::every], qd[::every], qdd[::every]),
                       tauf[::every]))
    return np.concatenate([b[0] for b in blocks]), np.concatenate([b[1] for b in blocks])


def fit_idim(regressor, runs, cutoff, weighted=True, tolerance=TOLERANCES[0]):
    """IDIM-LS on several runs ``[(t, q, tau), ...]`` at one cutoff (Hz) and one relative
    singular-value ``tolerance`` of the least squares."""
    columns, tau = _stacked(regressor, runs, cutoff)
    parameters, sigma = _least_squares(columns, tau, weighted, tolerance)
    return IDIMModel(regressor, parameters, cutoff, sigma, tolerance)


def relative_error(predicted, measured):
    """Total relative RMS error: ``|predicted - measured|_F / |measured|_F``."""
    return float(np.linalg.norm(predicted - measured) / np.linalg.norm(measured))


def choose_cutoff(regressor, runs, cutoffs=CUTOFFS, folds=4, weighted=True,
                  tolerances=TOLERANCES):
    """The IDIM-LS fit at the cutoff and rank tolerance with the smallest time-blocked
    held-out torque error on the training runs.

    Each training run ``(t, q, tau)`` is cut into ``folds`` contiguous blocks; for each
    cutoff, each tolerance and each ``k``, block ``k`` of every run is predicted by the fit
    on the other blocks, from its own positions filtered at that cutoff, against its raw
    measured torques. Only ``runs`` are used: pass the training data, never a held-out run.
    The returned fit uses every run whole; its ``scores`` map each cutoff to
    ``{tolerance: error}``.
    """
    runs = [tuple(np.asarray(a, dtype=float) for a in run) for run in runs]
    scores = {}
    for cutoff in cutoffs:
        predicted = {tolerance: [] for tolerance in tolerances}
        measured = []
        for k in range(folds):
            train, held = [], []
            for t, q, tau in runs:
                edges = np.linspace(0, len(t), folds + 1).astype(int)
                a, b = edges[k], edges[k + 1]
                train += [(t[i:j], q[i:j], tau[i:j]) for i, j in ((0, a), (b, len(t)))
                          if j - i > 50]
                held.append((t[a:b], q[a:b], tau[a:b]))
            columns, tau_train = _stacked(regressor, train, cutoff)
            held_columns = []
            for t, q, tau in held:
                grid, qf, qd, qdd, _ = filtered_states(t, q, cutoff)
                measured.append(np.column_stack([np.interp(grid, t, tau[:, j])
                                                 for j in range(tau.shape[1])]))
                held_columns.append(design(regressor, qf, qd, qdd))
            for tolerance in tolerances:
                parameters, _ = _least_squares(columns, tau_train, weighted, tolerance)
                predicted[tolerance] += [c @ parameters for c in held_columns]
        measured = np.concatenate(measured)
        scores[cutoff] = {tolerance: relative_error(np.concatenate(predicted[tolerance]),
                                                    measured) for tolerance in tolerances}
    cutoff, tolerance = min(((c, r) for c in scores for r in scores[c]),
                            key=lambda pair: scores[pair[0]][pair[1]])
    model = fit_idim(regressor, runs, cutoff, weighted, tolerance)
    model.scores = scores
    return model


def catalog_regressor(library):
    """``regressor(q, qd, qdd) -> (N, n, p)``: the rigid-body (Lagrange) columns of a fitted
    kinematic catalog's library, and their indices in the library."""
    from pysindy_xl import stack_variables

    columns = [j for j, c in enumerate(library.categories_) if c == "lagrange"]

    def regressor(q, qd, qdd):
        n_samples, n = q.shape
        theta = library.transform(stack_variables(q, qd, qdd, np.zeros_like(q)))
        return theta.reshape(n, n_samples, -1)[:, :, columns].transpose(1, 0, 2)

    return regressor, columns


def pinocchio_regressor(urdf_path):
    """``regressor(q, qd, qdd) -> (N, n, p)`` from Pinocchio's joint-torque regressor of a
    URDF (ten inertial parameters per body), plus one rotor inertia column per joint
    (``qdd_j`` on joint ``j``, the armature the URDF does not carry)."""
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(urdf_path))
    data = model.createData()

    def regressor(q, qd, qdd):
        rows = np.stack([pin.computeJointTorqueRegressor(model, data, a, b, c).copy()
                         for a, b, c in zip(q, qd, qdd, strict=True)])
        rotor = np.einsum("nj,ij->nij", qdd, np.eye(qdd.shape[1]))
        return np.concatenate([rows, rotor], axis=2)

    regressor.model = model
    return regressor


def pinocchio_inverse_dynamics(urdf_path):
    """``torques(q, qd, qdd) -> (N, n)`` of the URDF's own inertials (no friction): the
    maker's published model, evaluated by Pinocchio's RNEA."""
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(urdf_path))
    data = model.createData()
    return lambda q, qd, qdd: np.stack([pin.rnea(model, data, a, b, c).copy()
                                        for a, b, c in zip(q, qd, qdd, strict=True)])
