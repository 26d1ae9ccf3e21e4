"""Noise models: relative Gaussian noise on the recorded series of a trajectory."""

from __future__ import annotations

import numpy as np

from .dataset import Trajectory

__all__ = ["add_noise", "noise_levels", "NOISE_KEYS", "NOISE_MODELS"]

NOISE_KEYS = ("q", "qd", "qdd", "tau")

#: ``positions``: noisy positions only, the fit differentiates; ``all``: the paper's model, the
#: same relative noise on positions, velocities, accelerations and forces.
NOISE_MODELS = ("positions", "all")


def _noise_levels(noise) -> dict:
    if isinstance(noise, dict):
        unknown = set(noise) - set(NOISE_KEYS)
        if unknown:
            raise ValueError(f"noise: unknown keys {sorted(unknown)}; expected {NOISE_KEYS}")
        levels = {k: noise.get(k, 0.0) for k in NOISE_KEYS}
    else:
        levels = dict.fromkeys(NOISE_KEYS, noise)
    for k, v in levels.items():
        if (isinstance(v, bool) or not isinstance(v, (int, float, np.floating))
                or not (np.isfinite(v) and v >= 0)):
            raise ValueError(f"noise: level for {k!r} must be a non-negative number, got {v!r}")
        levels[k] = float(v)
    return levels


def noise_levels(noise, noise_model: str = "positions") -> dict:
    """Per-channel relative noise levels ``{"q", "qd", "qdd", "tau"}`` of a specification.

    Parameters
    ----------
    noise : float or dict
        One relative level (std = level x each coordinate's standard deviation over the
        trajectory), or a dict with some of the keys ``"q", "qd", "qdd", "tau"``.
    noise_model : {"positions", "all"}, default "positions"
        ``positions``: a number perturbs the positions only (a dict may also name ``"tau"``;
        velocity or acceleration noise is refused); ``all``: every series alike.

    Returns
    -------
    dict
        ``{"q": float, "qd": float, "qdd": float, "tau": float}``.

    Examples
    --------
    >>> noise_levels(0.01)
    {'q': 0.01, 'qd': 0.0, 'qdd': 0.0, 'tau': 0.0}
    >>> noise_levels(0.01, "all")
    {'q': 0.01, 'qd': 0.01, 'qdd': 0.01, 'tau': 0.01}
    """
    if noise_model not in NOISE_MODELS:
        raise ValueError(f"noise_model: expected one of {NOISE_MODELS}, got {noise_model!r}")
    levels = _noise_levels(noise)
    if noise_model == "all" or isinstance(noise, dict):
        if noise_model == "positions" and (levels["qd"] or levels["qdd"]):
            raise ValueError("noise: velocity or acceleration noise is not part of "
                             "noise_model='positions' (they are not recorded); use "
                             "noise_model='all'")
        return levels
    return {"q": levels["q"], "qd": 0.0, "qdd": 0.0, "tau": 0.0}


def add_noise(trajectory: Trajectory, noise, rng: np.random.Generator,
              force_matrix=None) -> Trajectory:
    """Gaussian noise at relative levels: sigma = level * std of each column.

    Parameters
    ----------
    trajectory : Trajectory
        Clean data; not modified (a new trajectory is returned).
    noise : float or dict
        One level for every series, or a dict with some of the keys ``"q", "qd", "qdd",
        "tau"``. Force noise goes on the joint forces ``u`` (the measured actuator signal),
        ``tau`` recomputed as ``u @ force_matrix.T``.
    rng : numpy.random.Generator
        The random generator.
    force_matrix : array_like of shape (n, n), default=None
        The matrix ``B`` mapping joint forces to generalized forces; None: identity.

    Returns
    -------
    Trajectory
        A new trajectory with the noisy series.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0.0, 10.0, 10001)
    >>> clean = Trajectory(t, q=np.sin(t), qd=np.cos(t))
    >>> noisy = add_noise(clean, {"q": 0.01}, np.random.default_rng(0))
    >>> error = noisy.q - clean.q
    >>> round(float(error.std() / clean.q.std()), 3), bool(np.all(noisy.qd == clean.qd))
    (0.01, True)
    """
    levels = _noise_levels(noise)

    def noisy(a, level):
        if a is None or level == 0:
            return None if a is None else a.copy()
        return a + level * a.std(axis=0) * rng.standard_normal(a.shape)

    n = trajectory.q.shape[1]
    matrix = np.eye(n) if force_matrix is None else np.asarray(force_matrix, dtype=float)
    u = noisy(trajectory.u, levels["tau"])
    tau = u @ matrix.T if u is not None else noisy(trajectory.tau, levels["tau"])
    return Trajectory(t=trajectory.t.copy(), q=noisy(trajectory.q, levels["q"]),
                      qd=noisy(trajectory.qd, levels["qd"]),
                      qdd=noisy(trajectory.qdd, levels["qdd"]), tau=tau, u=u,
                      info=dict(trajectory.info),
                      tau_constraint=noisy(trajectory.tau_constraint, 0),
                      u_constraint=noisy(trajectory.u_constraint, 0),
                      constraint_active=noisy(trajectory.constraint_active, 0))
