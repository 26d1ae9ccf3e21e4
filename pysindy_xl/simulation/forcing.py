"""Random time-varying forces: sums of sinusoids with random frequencies, phases, amplitudes."""

from __future__ import annotations

import numpy as np

from .._optional import import_mujoco

__all__ = ["SumOfSinusoids", "FORCING_MODES", "REFERENCE_SPEED", "SERVO_BANDWIDTH_FRACTION"]

#: implicit: no force (random initial condition only); explicit: every actuator driven;
#: mixed: a chosen subset of the actuators driven.
FORCING_MODES = ("implicit", "explicit", "mixed")


class SumOfSinusoids:
    """Force signals ``u_a(t) = offset_a + sum_k A_ak sin(2 pi f_ak t + phi_ak)``.

    Parameters
    ----------
    amplitudes, frequencies, phases : array, shape (n_signals, n_components)
        Amplitudes, frequencies (Hz) and phases (rad) of each component; finite.
    offsets : array, shape (n_signals,), optional
        Constant part of each signal (default zero).

    Examples
    --------
    >>> force = SumOfSinusoids([[1.0]], [[0.25]], [[0.0]])
    >>> force(np.array([0.0, 1.0])).round(6)
    array([[0.],
           [1.]])
    """

    def __init__(self, amplitudes, frequencies, phases, offsets=None):
        arrays = []
        for name, a in (("amplitudes", amplitudes), ("frequencies", frequencies),
                        ("phases", phases)):
            a = np.asarray(a, dtype=float)
            if a.ndim != 2:
                raise ValueError(f"{name}: expected shape (n_signals, n_components), got {a.shape}")
            if not np.all(np.isfinite(a)):
                raise ValueError(f"{name}: contains NaN or inf")
            arrays.append(a)
        if not arrays[0].shape == arrays[1].shape == arrays[2].shape:
            raise ValueError("amplitudes, frequencies, phases: expected equal shapes, got "
                             f"{[a.shape for a in arrays]}")
        self.amplitudes, self.frequencies, self.phases = arrays
        n_signals = self.amplitudes.shape[0]
        offsets = np.zeros(n_signals) if offsets is None else np.asarray(offsets, dtype=float)
        if offsets.shape != (n_signals,) or not np.all(np.isfinite(offsets)):
            raise ValueError(f"offsets: expected {n_signals} finite numbers, got {offsets!r}")
        self.offsets = offsets

    @property
    def n_signals(self) -> int:
        """Number of signals (rows of :attr:`amplitudes`)."""
        return self.amplitudes.shape[0]

    @classmethod
    def random(cls, scales, rng: np.random.Generator, n_components: int = 6,
               min_frequency: float = 0.05, max_frequency: float = 1.5, offsets=None):
        """Draw random signals whose component amplitudes sum to ``scales`` (n_signals,).

        ``n_components`` sinusoids per signal, frequencies log-uniform in
        ``[min_frequency, max_frequency]`` (Hz), phases uniform; a zero scale gives a zero signal.

        Parameters
        ----------
        scales : array_like of shape (n_signals,)
            Sum of the component amplitudes of each signal.
        rng : numpy.random.Generator
            The random generator.
        n_components : int, default=6
            Sinusoids per signal.
        min_frequency, max_frequency : float, default=0.05, 1.5
            Frequency band (Hz).
        offsets : array_like of shape (n_signals,), default=None
            Constant part of each signal (None: zero).

        Returns
        -------
        SumOfSinusoids
            The random signals.

        Examples
        --------
        >>> force = SumOfSinusoids.random([2.0, 0.0], np.random.default_rng(0), n_components=3)
        >>> values = force(np.linspace(0.0, 10.0, 1001))
        >>> values.shape, bool(np.abs(values[:, 0]).max() <= 2.0), bool(np.all(values[:, 1] == 0))
        ((1001, 2), True, True)
        """
        scales = np.asarray(scales, dtype=float).reshape(-1)
        if np.any(scales < 0) or not np.all(np.isfinite(scales)):
            raise ValueError(f"scales: expected non-negative finite numbers, got {scales!r}")
        if not isinstance(n_components, (int, np.integer)) or n_components < 1:
            raise ValueError(f"n_components: expected an integer >= 1, got {n_components!r}")
        if not 0 < min_frequency <= max_frequency:
            raise ValueError("min_frequency, max_frequency: expected 0 < min_frequency <= "
                             f"max_frequency, got {min_frequency!r}, {max_frequency!r}")
        shape = (scales.size, n_components)
        weights = rng.uniform(0.2, 1.0, shape)
        amplitudes = weights / weights.sum(axis=1, keepdims=True) * scales[:, None]
        frequencies = np.exp(rng.uniform(np.log(min_frequency), np.log(max_frequency), shape))
        phases = rng.uniform(0.0, 2 * np.pi, shape)
        return cls(amplitudes, frequencies, phases, offsets)

    def __call__(self, t):
        """The signals at times ``t``: shape (n_signals,) for a scalar, (N, n_signals) else.

        Parameters
        ----------
        t : float or array_like of shape (N,)
            Time(s) (s).

        Returns
        -------
        numpy.ndarray of shape (n_signals,) or (N, n_signals)
            The signals.

        Examples
        --------
        >>> SumOfSinusoids([[1.0]], [[0.25]], [[0.0]], offsets=[0.5])(1.0)
        array([1.5])
        """
        t_arr = np.asarray(t, dtype=float)
        angles = 2 * np.pi * self.frequencies[None] * t_arr.reshape(-1, 1, 1) + self.phases[None]
        values = (self.amplitudes[None] * np.sin(angles)).sum(axis=2) + self.offsets
        return values[0] if t_arr.ndim == 0 else values

    def on_grid(self, starts, offsets) -> np.ndarray:
        """The signals at every ``starts[b] + offsets[j]``, ``b`` major: shape (B * J, n_signals).

        Equal to ``self(np.add.outer(starts, offsets).ravel())`` to rounding, by the angle
        addition ``sin(w (T + s) + p) = sin(w T + p) cos(w s) + cos(w T + p) sin(w s)``: sines
        at the starts and offsets only, then one batched product.

        Parameters
        ----------
        starts : array_like of shape (B,)
            Block start times (s).
        offsets : array_like of shape (J,)
            Offsets within a block (s).

        Returns
        -------
        numpy.ndarray of shape (B * J, n_signals)
            The signals, ``starts`` major.

        Examples
        --------
        >>> force = SumOfSinusoids.random([1.0, 2.0], np.random.default_rng(0))
        >>> starts, offsets = np.arange(5) * 0.002, np.arange(4) * 0.0005
        >>> bool(np.allclose(force.on_grid(starts, offsets),
        ...                  force(np.add.outer(starts, offsets).ravel()), atol=1e-12))
        True
        """
        starts = np.asarray(starts, dtype=float).reshape(-1)
        offsets = np.asarray(offsets, dtype=float).reshape(-1)
        omega = 2 * np.pi * self.frequencies  # (S, C)
        at_starts = omega[:, None, :] * starts[None, :, None] + self.phases[:, None, :]
        amplitude = self.amplitudes[:, None, :]
        within = omega[:, :, None] * offsets[None, None, :]  # (S, C, J)
        values = (amplitude * np.sin(at_starts)) @ np.cos(within) + (
            amplitude * np.cos(at_starts)) @ np.sin(within)  # (S, B, J)
        return values.reshape(self.n_signals, -1).T + self.offsets

    def to_dict(self) -> dict:
        """JSON-serializable description (nested lists).

        Returns
        -------
        dict
            ``amplitudes``, ``frequencies``, ``phases`` and ``offsets``.

        Examples
        --------
        >>> SumOfSinusoids([[1.0]], [[0.25]], [[0.0]]).to_dict()
        {'amplitudes': [[1.0]], 'frequencies': [[0.25]], 'phases': [[0.0]], 'offsets': [0.0]}
        """
        return {"amplitudes": self.amplitudes.tolist(), "frequencies": self.frequencies.tolist(),
                "phases": self.phases.tolist(), "offsets": self.offsets.tolist()}

    @classmethod
    def from_dict(cls, data: dict) -> SumOfSinusoids:
        """Inverse of :meth:`to_dict` (``offsets`` optional); ValueError on a malformed dict.

        Parameters
        ----------
        data : dict
            A dict of :meth:`to_dict`.

        Returns
        -------
        SumOfSinusoids
            The signals.

        Examples
        --------
        >>> force = SumOfSinusoids([[1.0, 0.5]], [[0.25, 1.0]], [[0.0, 1.0]])
        >>> bool((SumOfSinusoids.from_dict(force.to_dict())(0.3) == force(0.3)).all())
        True
        """
        try:
            return cls(data["amplitudes"], data["frequencies"], data["phases"], data.get("offsets"))
        except (KeyError, TypeError) as error:
            raise ValueError(f"data: not a SumOfSinusoids description ({error})") from None


#: A servo's reference stays below this fraction of its bandwidth (:func:`servo_bandwidths`).
SERVO_BANDWIDTH_FRACTION = 0.5
#: Peak speed of a servo's reference: hinge joints (rad/s), slide joints (m/s), typical of
#: the velocity limits of real arms (MJCF has none).
REFERENCE_SPEED = {"hinge": np.pi, "slide": 1.0}


def within_servo_reach(signals: SumOfSinusoids, model) -> SumOfSinusoids:
    """The position servos' references of ``signals`` (one per actuator) slowed to their reach.

    Each servo's band is scaled below ``SERVO_BANDWIDTH_FRACTION`` of its bandwidth
    (:func:`~pysindy_xl.mujoco.systems.actuation.servo_bandwidths`) and its amplitudes so that
    the speed bound ``sum_k 2 pi f_k A_k`` (joint units) stays below ``REFERENCE_SPEED``: a
    faster reference saturates the servo. ``signals`` itself when no driven actuator is one.

    Parameters
    ----------
    signals : SumOfSinusoids
        One reference per actuator.
    model : mujoco.MjModel
        The compiled model whose actuators receive them.

    Returns
    -------
    SumOfSinusoids
        The slowed references (``signals`` itself when no driven actuator is a servo).
    """
    mujoco = import_mujoco()
    from ..mujoco.systems.actuation import servo_bandwidths
    bandwidth = servo_bandwidths(model)
    servo = np.isfinite(bandwidth) & np.any(signals.amplitudes != 0, axis=1)
    if not servo.any():
        return signals
    top = SERVO_BANDWIDTH_FRACTION * np.where(servo, bandwidth, 0.0) / (2 * np.pi)
    highest = signals.frequencies.max(axis=1)
    band = np.where(servo & (highest > top), top / highest, 1.0)
    frequencies = signals.frequencies * band[:, None]
    # joint reference = ctrl * gain / (kp * gear)
    kp = np.where(servo, -model.actuator_biasprm[:, 1], 1.0)
    per_joint = np.abs(model.actuator_gainprm[:, 0] / (kp * model.actuator_gear[:, 0]))
    speed = (2 * np.pi * frequencies * np.abs(signals.amplitudes)).sum(axis=1) * per_joint
    slide = model.jnt_type[model.actuator_trnid[:, 0]] == int(mujoco.mjtJoint.mjJNT_SLIDE)
    limit = np.where(slide, REFERENCE_SPEED["slide"], REFERENCE_SPEED["hinge"])
    factor = np.where(servo & (speed > limit), limit / np.maximum(speed, 1e-300), 1.0)
    return SumOfSinusoids(signals.amplitudes * factor[:, None], frequencies, signals.phases,
                          signals.offsets)
