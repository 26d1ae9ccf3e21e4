"""Periodic joint trajectories: a finite Fourier series per joint (Swevers et al. 1997).

With the base pulsation ``w = 2 pi / period``:

.. math::

    q_j(t) = q_{0j} + \\sum_{l=1}^{L} \\frac{a_{jl}}{w l}\\sin(w l t)
                                    - \\frac{b_{jl}}{w l}\\cos(w l t), \\qquad
    \\dot q_j(t) = \\sum_l a_{jl}\\cos(w l t) + b_{jl}\\sin(w l t), \\qquad
    \\ddot q_j(t) = \\sum_l w l\\,(b_{jl}\\cos(w l t) - a_{jl}\\sin(w l t)).

Periodic, with exact derivatives, linear in ``(q_0, a, b)``;
:func:`~pysindy_xl.mujoco.excitation_trajectory` designs one for identification.
"""

from __future__ import annotations

import csv
import os

import numpy as np

from .._optional import import_mujoco
from .forcing import SumOfSinusoids

__all__ = ["FourierTrajectory"]

class FourierTrajectory:
    """A periodic joint trajectory: a finite Fourier series per joint (Swevers et al. 1997).

    Parameters
    ----------
    q0 : array, shape (n,)
        Offsets ``q_0j`` (the mean positions).
    a, b : array, shape (n, L)
        Velocity amplitudes of the sine and cosine parts of harmonic ``l`` (rad/s or m/s).
    period : float
        Period ``2 pi / w`` (s).
    names : list of str, optional
        Joint (coordinate) names; default ``q0``, ``q1``...

    Attributes
    ----------
    condition_number, info
        Set by :func:`excitation_trajectory`: the condition number of the identification
        matrix the trajectory excites, and how it was designed.

    Notes
    -----
    Joint ``j`` follows

    .. math::

        q_j(t) = q_{0j} + \\sum_{l=1}^{L} \\frac{a_{jl}}{l\\omega} \\sin(l\\omega t)
        - \\frac{b_{jl}}{l\\omega} \\cos(l\\omega t), \\qquad \\omega = 2\\pi / T ,

    whose velocity and acceleration are exact.

    Examples
    --------
    >>> trajectory = FourierTrajectory([0.1], [[1.0]], [[0.0]], period=2 * np.pi)
    >>> trajectory.q(np.pi / 2).round(6), trajectory.qd(0.0), trajectory.qdd(0.0)
    (array([1.1]), array([1.]), array([0.]))
    """

    def __init__(self, q0, a, b, period, names=None):
        q0 = np.asarray(q0, dtype=float).reshape(-1)
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        for name, value in (("q0", q0), ("a", a), ("b", b)):
            if not np.all(np.isfinite(value)):
                raise ValueError(f"{name}: contains NaN or inf")
        if a.ndim != 2 or a.shape[0] != q0.size or a.shape[1] < 1 or b.shape != a.shape:
            raise ValueError(f"a, b: expected two arrays of shape (n={q0.size}, n_harmonics), "
                             f"got {a.shape} and {b.shape}")
        self.q0, self.a, self.b = q0, a, b
        self.period = checked_positive(period, "period")
        names = [f"q{j}" for j in range(q0.size)] if names is None else [str(s) for s in names]
        if len(names) != q0.size or len(set(names)) != len(names):
            raise ValueError(f"names: expected {q0.size} distinct names, got {names!r}")
        self.names = names
        self.condition_number = None
        self.info = {}

    @property
    def n_harmonics(self) -> int:
        """Number of harmonics ``L``."""
        return self.a.shape[1]

    @property
    def pulsation(self) -> float:
        """Base pulsation ``w = 2 pi / period`` (rad/s)."""
        return 2 * np.pi / self.period

    def _evaluate(self, t, order: int) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        if not np.all(np.isfinite(t)):
            raise ValueError("t: contains NaN or inf")
        basis = fourier_basis(t.reshape(-1), self.pulsation, self.n_harmonics, order)
        values = basis @ np.hstack([self.a, self.b]).T + (self.q0 if order == 0 else 0.0)
        return values[0] if t.ndim == 0 else values

    def q(self, t) -> np.ndarray:
        """Positions at times ``t``: shape (n,) for a scalar ``t``, (N, n) for an array.

        Parameters
        ----------
        t : float or array_like of shape (N,)
            Time(s) (s).

        Returns
        -------
        numpy.ndarray of shape (n,) or (N, n)
            Positions.
        """
        return self._evaluate(t, 0)

    def qd(self, t) -> np.ndarray:
        """Velocities at times ``t`` (exact), shaped as :meth:`q`.

        Parameters
        ----------
        t : float or array_like of shape (N,)
            Time(s) (s).

        Returns
        -------
        numpy.ndarray of shape (n,) or (N, n)
            Velocities.
        """
        return self._evaluate(t, 1)

    def qdd(self, t) -> np.ndarray:
        """Accelerations at times ``t`` (exact), shaped as :meth:`q`.

        Parameters
        ----------
        t : float or array_like of shape (N,)
            Time(s) (s).

        Returns
        -------
        numpy.ndarray of shape (n,) or (N, n)
            Accelerations.
        """
        return self._evaluate(t, 2)

    def controls(self, system) -> SumOfSinusoids:
        """The controls (one signal per actuator) that make the position servos follow this
        trajectory: the ``reference`` seam of :func:`~pysindy_xl.mujoco.generate_dataset`.

        Each actuator must be a position servo on a joint (fixed gain ``p``, affine bias with
        ``b_1 < 0``); its control puts the target length on the reference,
        ``ctrl = -(b_0 + b_1 g qpos_ref) / p`` (gear ``g``). A ValueError says when the sizes
        differ, an actuator is not such a servo or a coordinate has none.

        Parameters
        ----------
        system : MuJoCoSystem or str
            The system whose position servos follow the trajectory.

        Returns
        -------
        SumOfSinusoids
            One control signal per actuator.

        Raises
        ------
        ValueError
            When the sizes differ, an actuator is not a position servo on a joint, or a coordinate
            has none.
        """
        from ..mujoco.systems.registry import get_system
        system = get_system(system)
        gain_map, offset = _position_servos(system, "reference")  # ctrl = offset + gain_map @ q
        if len(self.q0) != system.n:
            raise ValueError(f"reference: a trajectory of {len(self.q0)} joints for a system "
                             f"of {system.n} coordinates")
        harmonics = self.pulsation * np.arange(1, self.n_harmonics + 1)
        radius = np.hypot(self.a, self.b) / harmonics  # (n, L)
        phase = np.arctan2(-self.b, self.a)
        amplitudes = (gain_map[:, :, None] * radius[None]).reshape(len(offset), -1)
        frequencies = np.tile(harmonics / (2 * np.pi), (len(offset), system.n))
        phases = np.tile(phase.reshape(-1), (len(offset), 1))
        return SumOfSinusoids(amplitudes, frequencies, phases, offset + gain_map @ self.q0)

    def to_csv(self, path, rate: float = 1000.0, periods: int = 1) -> None:
        """Write the trajectory as a table a robot controller can play.

        Columns ``t``, then per joint ``NAME``, ``NAME_dot``, ``NAME_ddot`` (the package's
        table format, :func:`~pysindy_xl.read_csv`), ``rate`` rows per second from 0 to
        ``periods * period`` inclusive.

        Parameters
        ----------
        path : str or os.PathLike
            The file to write.
        rate : float, default=1000.0
            Rows per second.
        periods : int, default=1
            Number of periods written.

        Examples
        --------
        >>> import os, tempfile
        >>> path = os.path.join(tempfile.mkdtemp(), "excitation.csv")
        >>> FourierTrajectory([0.0], [[1.0]], [[0.0]], 1.0, names=["j0"]).to_csv(path, rate=4)
        >>> open(path).readline().strip()
        't,j0,j0_dot,j0_ddot'
        """
        rate = checked_positive(rate, "rate")
        if isinstance(periods, bool) or not isinstance(periods, (int, np.integer)) or periods < 1:
            raise ValueError(f"periods: expected an integer >= 1, got {periods!r}")
        t = np.arange(int(round(periods * self.period * rate)) + 1) / rate
        series = np.stack([self.q(t), self.qd(t), self.qdd(t)], axis=2)  # (N, joint, order)
        columns = np.column_stack([t, series.reshape(len(t), -1)])
        header = ["t"] + [f"{s}{suffix}" for s in self.names for suffix in ("", "_dot", "_ddot")]
        with open(os.fspath(path), "w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(header)
            writer.writerows([[repr(float(v)) for v in row] for row in columns])

    def to_dict(self) -> dict:
        """JSON-serializable description (:meth:`from_dict` reads it back).

        Returns
        -------
        dict
            ``q0``, ``a``, ``b``, ``period``, ``names`` and ``condition_number``.
        """
        return {"q0": self.q0.tolist(), "a": self.a.tolist(), "b": self.b.tolist(),
                "period": self.period, "names": list(self.names),
                "condition_number": self.condition_number}

    @classmethod
    def from_dict(cls, data: dict) -> FourierTrajectory:
        """Inverse of :meth:`to_dict` (``names``, ``condition_number`` optional); ValueError on
        a malformed dict.

        Parameters
        ----------
        data : dict
            A dict of :meth:`to_dict`.

        Returns
        -------
        FourierTrajectory
            The trajectory.
        """
        try:
            out = cls(data["q0"], data["a"], data["b"], data["period"], data.get("names"))
        except (KeyError, TypeError) as error:
            raise ValueError(f"data: not a FourierTrajectory description ({error})") from None
        out.condition_number = data.get("condition_number")
        return out

    def __repr__(self) -> str:
        cond = "" if self.condition_number is None else f", cond={self.condition_number:.4g}"
        return (f"FourierTrajectory(n={len(self.q0)}, harmonics={self.n_harmonics}, "
                f"period={self.period:g}{cond})")


def checked_positive(value, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not (np.isfinite(value) and value > 0):
        raise ValueError(f"{name}: expected a positive number, got {value!r}")
    return float(value)


def fourier_basis(t, w: float, L: int, order: int) -> np.ndarray:
    """Matrix (N, 2L) mapping ``[a_j, b_j]`` to the ``order``-th derivative of ``q_j - q0_j``."""
    harmonics = w * np.arange(1, L + 1)
    angle = np.outer(t, harmonics)
    sin, cos = np.sin(angle), np.cos(angle)
    if order == 0:
        return np.hstack([sin / harmonics, -cos / harmonics])
    if order == 1:
        return np.hstack([cos, sin])
    return np.hstack([-sin * harmonics, cos * harmonics])


def _position_servos(system, argument: str):
    """``(G, c)`` with ``ctrl = c + G q`` putting every position servo on the positions ``q``."""
    mujoco = import_mujoco()
    model = system.mj_model()
    inverse = np.linalg.inv(system.joint_to_coordinates)  # qpos = T^-1 q
    gain_map, offset = np.zeros((model.nu, system.n)), np.zeros(model.nu)
    driven = np.zeros(model.nv, dtype=bool)
    for u in range(model.nu):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, u) or f"actuator{u}"
        p, bias = model.actuator_gainprm[u, :3], model.actuator_biasprm[u, :3]
        if (int(model.actuator_trntype[u]) != int(mujoco.mjtTrn.mjTRN_JOINT)
                or int(model.actuator_dyntype[u]) != int(mujoco.mjtDyn.mjDYN_NONE)
                or int(model.actuator_gaintype[u]) != int(mujoco.mjtGain.mjGAIN_FIXED)
                or int(model.actuator_biastype[u]) != int(mujoco.mjtBias.mjBIAS_AFFINE)
                or not bias[1] < 0 or p[0] == 0):
            raise ValueError(f"{argument}: actuator {name!r} is not a position servo on a joint; "
                             "a reference trajectory is played through position servos")
        dof = model.jnt_dofadr[model.actuator_trnid[u, 0]]
        gear = model.actuator_gear[u, 0]
        gain_map[u] = -bias[1] * gear * inverse[dof] / p[0]
        offset[u] = -bias[0] / p[0]
        driven[dof] = True
    if not driven.all():
        raise ValueError(f"{argument}: joints {np.flatnonzero(~driven).tolist()} have no "
                         "position servo to follow the reference")
    return gain_map, offset
