"""MuJoCo as the plant: a controller acts on the simulated system, every second counted.

The controller is called every control period with the plant's state in the generalized
coordinates and returns actuator commands, held over the MuJoCo steps of the period
(zero-order hold) and clipped to the force limit. The recording keeps every MuJoCo step: what a
position sensor would read (the identification adds noise to it) and the true state."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Episode", "MuJoCoPlant"]


@dataclass
class Episode:
    """One run on the plant (:meth:`MuJoCoPlant.run`).

    Parameters
    ----------
    t : array (N,)
        Times of the MuJoCo steps (s), from 0.
    q, qd : array (N, n)
        True positions and velocities in the generalized coordinates.
    tau : array (N, n)
        Generalized forces applied over the step that starts at each sample.
    controls : array (K, m)
        Commands applied per control period, after clipping.
    duration : float
        Plant seconds the episode took.
    stopped : str
        Why it ended: ``"duration"`` or the reason returned by the stop rule.

    Examples
    --------
    >>> episode = Episode(np.zeros(1), np.zeros((1, 2)), np.zeros((1, 2)), np.zeros((1, 2)),
    ...                   np.zeros((0, 1)), 0.0, "duration")
    >>> episode.states.shape
    (1, 4)
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    tau: np.ndarray
    controls: np.ndarray
    duration: float
    stopped: str

    @property
    def states(self) -> np.ndarray:
        """``[q, qd]`` (N, 2n)."""
        return np.concatenate([self.q, self.qd], axis=1)


class MuJoCoPlant:
    """A MuJoCo system driven by actuator commands on chosen coordinates.

    Parameters
    ----------
    system : MuJoCoSystem or str
        The plant (a registry name such as ``"cart-pole"`` or a system object).
    actuated : sequence of str
        Coordinates pushed by the ``m`` commands (the others get no force).
    force_limit : float or array (m,)
        Commands are clipped to ``|u_j| <= force_limit_j``.
    control_dt : float, default 0.02
        Control period (s), a whole number of MuJoCo steps.

    Attributes
    ----------
    interaction_s : float
        Plant seconds run so far, every episode included.

    Examples
    --------
    >>> plant = MuJoCoPlant("cart-pole", ["x"], force_limit=10.0)
    >>> episode = plant.run(lambda state, t: np.array([100.0]), duration=0.1)
    >>> float(np.abs(episode.controls).max()), round(plant.interaction_s, 3)
    (10.0, 0.1)
    """

    def __init__(self, system, actuated, force_limit, control_dt: float = 0.02):
        from ..mujoco import get_system, import_mujoco
        from .discrete import actuation_matrix
        self._mujoco = import_mujoco()
        self.system = get_system(system)
        self.actuation = actuation_matrix(self.system.coordinate_names, actuated)
        m = self.actuation.shape[1]
        limit = np.asarray(force_limit, dtype=float).reshape(-1)
        limit = np.full(m, limit[0]) if limit.size == 1 else limit
        if limit.shape != (m,) or not np.all(limit > 0) or not np.all(np.isfinite(limit)):
            raise ValueError(f"force_limit: expected a positive number or {m} of them (one per "
                             f"actuated coordinate), got {np.asarray(force_limit).tolist()!r}")
        self.force_limit = limit
        self.model = self.system.mj_model()
        self.data = self._mujoco.MjData(self.model)
        timestep = self.model.opt.timestep
        self.substeps = int(round(float(control_dt) / timestep))
        if self.substeps < 1 or abs(self.substeps * timestep - control_dt) > 1e-9:
            raise ValueError(f"control_dt: expected a positive multiple of the MuJoCo step "
                             f"{timestep}, got {control_dt!r}")
        self.control_dt = self.substeps * timestep
        # joint forces u with B u = tau (B: the system's force matrix)
        self._joint_forces = np.linalg.pinv(self.system.force_matrix()) @ self.actuation
        self.interaction_s = 0.0

    @property
    def n(self) -> int:
        """Number of coordinates."""
        return self.system.n

    def state(self) -> np.ndarray:
        """The plant's current state.

        Returns
        -------
        numpy.ndarray
            ``[q, qd]`` (2n,) in the generalized coordinates.
        """
        q, qd, _ = self.system.to_generalized(self.data.qpos, self.data.qvel)
        return np.concatenate([q, qd])

    def reset(self, q=None, qd=None) -> None:
        """Put the plant at a state (MuJoCo's data reset, then set).

        Parameters
        ----------
        q : array (n,), optional
            Positions in the generalized coordinates; default zero (hanging).
        qd : array (n,), optional
            Velocities; default zero (at rest).
        """
        self._mujoco.mj_resetData(self.model, self.data)
        n = self.n
        q = np.zeros(n) if q is None else np.asarray(q, dtype=float)
        qd = np.zeros(n) if qd is None else np.asarray(qd, dtype=float)
        if q.shape != (n,) or qd.shape != (n,):
            raise ValueError(f"q, qd: expected shapes ({n},), got {q.shape} and {qd.shape}")
        self.data.qpos[:], self.data.qvel[:] = self.system.from_generalized(q, qd)
        self._mujoco.mj_forward(self.model, self.data)

    def run(self, policy, duration: float, stop=None) -> Episode:
        """Run ``policy`` from the current state for at most ``duration`` seconds.

        Parameters
        ----------
        policy : callable
            ``policy(state (2n,), t) -> u (m,)``, called every control period.
        duration : float
            Longest episode (s).
        stop : callable, optional
            ``stop(state (2n,), t) -> str or None``, checked every control period: a
            non-empty reason ends the episode.

        Returns
        -------
        Episode
        """
        duration = float(duration)
        if not (np.isfinite(duration) and duration > 0):
            raise ValueError(f"duration: expected a positive number of seconds, got {duration!r}")
        mj, model, data = self._mujoco, self.model, self.data
        n_periods = int(np.ceil(duration / self.control_dt - 1e-9))
        n, m = self.n, self.actuation.shape[1]
        dt = model.opt.timestep
        qpos = np.empty((n_periods * self.substeps + 1, model.nq))
        qvel = np.empty_like(qpos)
        tau = np.zeros((n_periods * self.substeps + 1, n))
        controls = np.zeros((n_periods, m))
        reason, k, row = "duration", 0, 0
        for k in range(n_periods):
            t = k * self.control_dt
            state = self.state()
            if stop is not None:
                why = stop(state, t)
                if why:
                    reason = str(why)
                    break
            u = np.asarray(policy(state, t), dtype=float).reshape(-1)
            if u.shape != (m,) or not np.all(np.isfinite(u)):
                raise ValueError(f"policy: expected {m} finite commands, got {u.tolist()!r}")
            u = np.clip(u, -self.force_limit, self.force_limit)
            controls[k] = u
            data.ctrl[:] = self._joint_forces @ u
            generalized = self.actuation @ u
            for _ in range(self.substeps):
                qpos[row], qvel[row], tau[row] = data.qpos, data.qvel, generalized
                mj.mj_step(model, data)
                row += 1
        else:
            k = n_periods
        qpos[row], qvel[row] = data.qpos, data.qvel
        if row:
            tau[row] = tau[row - 1]
        q, qd, _ = self.system.to_generalized(qpos[:row + 1], qvel[:row + 1])
        elapsed = row * dt
        self.interaction_s += elapsed
        return Episode(np.arange(row + 1) * dt, q, qd, tau[:row + 1], controls[:k], elapsed,
                       reason)
