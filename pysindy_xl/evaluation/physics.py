"""The identified mass matrix and unforced dynamics against MuJoCo's, at random states."""

from __future__ import annotations

import numpy as np

from .._optional import import_mujoco
from ..mujoco.systems.friction import sliding_velocities
from ..mujoco.systems.registry import get_system

__all__ = ["compare_physics"]


def compare_physics(model, system, n_states: int = 5, seed=0, scale: float = 0.8) -> dict:
    """Compare the identified mass matrix and unforced dynamics with MuJoCo's at a few states.

    At ``n_states`` random states (``system.random_initial_state(scale=scale)``; states with
    an active contact are drawn again) the identified ``M(q, qd) qdd = f(q, qd, u)`` at
    ``u = 0`` is compared with ``mj_fullM`` and ``qfrc_passive - qfrc_bias +
    qfrc_constraint``, mapped to the coordinates (``B M B^T``, ``B f``). An implicit law is
    first scaled by the least-squares factor matching the mass matrices. The mass matrix is
    read where every joint with ``frictionloss`` slides
    (:func:`~pysindy_xl.mujoco.systems.friction.sliding_velocities`).

    Returns a dict: ``mass_error``, ``force_error``, ``gravity_error`` (at rest), each the
    largest error relative to MuJoCo's largest entry; ``scale``; ``positive_definite`` and
    ``condition`` of the identified mass matrix; ``unidentified`` (coordinates whose mass row
    is zero); ``held`` (``still_coordinates_``, left out); ``contact_states_skipped``.
    ValueError when contacts act at all of ``20 * n_states`` draws.

    Parameters
    ----------
    model : pysindy_xl.XLSINDy
        A fitted model.
    system : MuJoCoSystem or str
        The system that generated its data.
    n_states : int, default=5
        Number of random states compared.
    seed : int, default=0
        Seed of the random states.
    scale : float, default=0.8
        The ``scale`` of :meth:`~MuJoCoSystem.random_initial_state`.

    Returns
    -------
    dict
        ``mass_error``, ``force_error``, ``gravity_error``, ``scale``, ``positive_definite``,
        ``condition``, ``unidentified``, ``held`` and ``contact_states_skipped`` (see above).

    Raises
    ------
    ValueError
        When contacts act at all of ``20 * n_states`` draws.

    Examples
    --------
    >>> import pysindy_xl as px
    >>> from pysindy_xl.mujoco import generate_dataset, reference_catalog
    >>> data = generate_dataset("cart-pole", n_trajectories=1, duration=1.0, seed=0,
    ...                         progress=False)
    >>> catalog = reference_catalog("cart-pole", "mixed", trig_degree=1)
    >>> model = px.XLSINDy(catalog, px.ExplicitOptimizer()).fit(**data.fit_arguments())
    >>> physics = compare_physics(model, "cart-pole")
    >>> bool(physics["mass_error"] < 1e-6 and physics["force_error"] < 1e-6)
    True
    """
    mujoco = import_mujoco()
    from ..symbols import stack_variables
    system = get_system(system)
    dynamics = model._require_dynamics() if hasattr(model, "_require_dynamics") else None
    if dynamics is None:
        raise TypeError("model: expected a fitted XLSINDy with dynamics")
    rng = np.random.default_rng(seed)
    mj_model = system.mj_model()
    data = mujoco.MjData(mj_model)
    matrix = system.force_matrix()
    q, qd, force_ref, gravity_ref = np.empty((4, n_states, system.n))
    mass_ref = np.empty((n_states, system.n, system.n))
    full = np.empty((mj_model.nv, mj_model.nv))
    skipped = 0
    for k in range(n_states):
        while True:  # MuJoCo evaluates one state per call
            q[k], qd[k] = system.random_initial_state(rng, scale=scale)
            data.qpos[:], data.qvel[:] = system.from_generalized(q[k], qd[k])
            data.ctrl[:] = 0.0
            mujoco.mj_forward(mj_model, data)
            if data.ncon == 0:
                break
            skipped += 1
            if skipped >= 20 * n_states:
                raise ValueError(f"system: contacts act at {skipped} random states of "
                                 f"{system!r}; lower scale or disable the contacts")
        try:
            mujoco.mj_fullM(mj_model, data, full)  # MuJoCo >= 3.4
        except TypeError:
            mujoco.mj_fullM(mj_model, full, data.qM)
        mass_ref[k] = matrix @ full @ matrix.T
        force_ref[k] = matrix @ (data.qfrc_passive - data.qfrc_bias + data.qfrc_constraint)
        data.qvel[:] = 0.0  # at rest: gravity and springs only
        mujoco.mj_forward(mj_model, data)
        gravity_ref[k] = matrix @ (data.qfrc_spring - data.qfrc_bias)
    z = stack_variables(q, qd, None, np.zeros_like(q), np.zeros(n_states))
    force = dynamics.mass_and_forcing(z)[1]
    mass = dynamics.mass_and_forcing(stack_variables(q, sliding_velocities(system, mj_model, q, qd),
                                                     None, np.zeros_like(q), np.zeros(n_states)))[0]
    gravity = dynamics.mass_and_forcing(stack_variables(
        q, np.zeros_like(qd), None, np.zeros_like(q), np.zeros(n_states)))[1]
    held = np.isin(system.coordinate_names, list(getattr(model, "still_coordinates_", ())))
    names = [name for name, h in zip(system.coordinate_names, held, strict=True) if not h]
    mass, mass_ref = (m[:, ~held][:, :, ~held] for m in (mass, mass_ref))
    force, force_ref = force[:, ~held], force_ref[:, ~held]
    gravity, gravity_ref = gravity[:, ~held], gravity_ref[:, ~held]
    factor = float(np.sum(mass * mass_ref) / np.sum(mass * mass)) if np.any(mass) else 1.0
    forces = model.feature_library_.force_columns_
    if np.allclose(model.coefficients()[forces], -1.0):
        factor = 1.0  # force-normalized: compare in absolute terms
    mass, force, gravity = mass * factor, force * factor, gravity * factor
    eigenvalues = np.linalg.eigvalsh((mass + np.swapaxes(mass, 1, 2)) / 2)
    empty = np.all(np.abs(mass) <= 1e-12 * max(np.abs(mass).max(), 1e-300), axis=(0, 2))
    return {"unidentified": [names[i] for i in np.flatnonzero(empty)],
            "held": [name for name, h in zip(system.coordinate_names, held, strict=True) if h],
            "contact_states_skipped": skipped,
            "mass_error": float(np.abs(mass - mass_ref).max() / np.abs(mass_ref).max()),
            "force_error": float(np.abs(force - force_ref).max()
                                 / max(np.abs(force_ref).max(), 1e-300)),
            "gravity_error": float(np.abs(gravity - gravity_ref).max()
                                   / max(np.abs(gravity_ref).max(), 1e-300)),
            "scale": factor,
            "positive_definite": bool(np.all(eigenvalues > 0)),
            "condition": float(np.max(np.abs(eigenvalues).max(axis=1)
                                      / np.maximum(np.abs(eigenvalues).min(axis=1), 1e-300)))}
