"""Steps of building a kinematic catalog (:mod:`.kinematic`): random states, the derivation of
the Lagrangian part reduced to independent columns, and the classical (friction, spring)
candidates.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg
import sympy as sp
import threadpoolctl

from ...feature_library.joint_friction import FRICTION_MODELS
from ...feature_library.trigpoly import euler_lagrange_many, evaluate_many, state_values
from ...physical.friction import regularized_dry_friction
from ..systems.friction import dry_friction_scales
from ..systems.registry import MuJoCoSystem
from ._kinematic_tree import INERTIAL_PARAMETERS, body_functions

# A column whose part orthogonal to the kept columns is below this fraction of its norm is
# dependent; exact dependencies leave ~1e-14, independent columns O(1e-3) or more.
_INDEPENDENCE_TOL = 1e-9
# Columns taken in preference order only when at least this fraction of them is new.
_WELL_CONDITIONED = 0.05
#: Laws of the Coulomb candidate (:func:`_dry_friction_terms`).
COULOMB_LAWS = ("smooth", "mujoco")


def independent_regressor_columns(matrix: np.ndarray) -> list[int]:
    """A well-conditioned set of independent columns, earlier columns preferred.

    The rank comes from a column-pivoted QR (exact dependencies leave ``|R_ii| ~ 1e-15``,
    independent columns ``1e-3`` or more). Columns are then taken in order when their part
    orthogonal to those already taken is a sizeable fraction of their norm, and the remaining
    rank is filled by the column with the largest orthogonal part, so that the dependent
    columns are combinations of the kept ones with moderate weights (a nearly dependent basis
    would amplify round-off in the base parameters).
    """
    norms = np.linalg.norm(matrix, axis=0)
    candidates = np.flatnonzero(norms > 0)
    if candidates.size == 0:
        return []
    unit = matrix[:, candidates] / norms[candidates]
    diagonal = np.abs(np.diag(scipy.linalg.qr(unit, mode="r", pivoting=True)[0]))
    rank = int(np.sum(diagonal > _INDEPENDENCE_TOL * diagonal[0]))
    basis = np.zeros((matrix.shape[0], 0))
    kept: list[int] = []

    def orthogonal_part(column):
        for _ in range(2):  # re-orthogonalize: one pass loses digits on near-parallel columns
            column = column - basis @ (basis.T @ column)
        return column

    for j in range(unit.shape[1]):
        if len(kept) == rank:
            break
        residual = orthogonal_part(unit[:, j])
        if np.linalg.norm(residual) > _WELL_CONDITIONED:
            basis = np.column_stack([basis, residual / np.linalg.norm(residual)])
            kept.append(j)
    while len(kept) < rank:
        rest = [j for j in range(unit.shape[1]) if j not in kept]
        residuals = np.column_stack([orthogonal_part(unit[:, j]) for j in rest])
        best = int(np.argmax(np.linalg.norm(residuals, axis=0)))
        basis = np.column_stack([basis, residuals[:, best] / np.linalg.norm(residuals[:, best])])
        kept.append(rest[best])
    return sorted(int(candidates[j]) for j in kept)


def random_joint_values(system: MuJoCoSystem, n_samples: int, rng) -> np.ndarray:
    n = system.n
    q = rng.uniform(-1.0, 1.0, (n_samples, n))
    q[:, list(system.angle_coordinates)] *= np.pi
    qd, qdd = rng.normal(size=(2, n_samples, n))
    angles = [j in system.angle_coordinates for j in range(n)]
    return state_values(q, qd, qdd, angles)


def joint_coordinates(system, model):
    """Each joint's position and velocity in the system's coordinates (``qpos = T^-1 q``)."""
    inverse = np.linalg.inv(system.joint_to_coordinates)
    integer = np.allclose(inverse, np.round(inverse))  # keep integer maps readable: th2 - th1
    out = []
    for symbols in (system.coords.q, system.coords.qd):
        rows = [sp.expand(sum(sp.Float(a) * s for a, s in zip(inverse[k], symbols, strict=True)
                              if a != 0)) for k in range(model.njnt)]
        out.append([sp.nsimplify(e, rational=True) for e in rows] if integer else rows)
    return tuple(out)


def _dry_friction_terms(system, model, qvel, coulomb_scale, coulomb_law):
    """Per joint, the unit law of its dry friction: MuJoCo's regularization of the joint's
    ``frictionloss`` (:func:`~pysindy_xl.physical.friction.regularized_dry_friction`) for
    ``coulomb_law="mujoco"`` where the joint has one, else ``tanh(qvel / coulomb_scale)``."""
    to_acceleration = dict(zip(system.coords.qd, system.coords.qdd, strict=True))
    scale, lead = dry_friction_scales(model)
    scale, lead = scale[model.jnt_dofadr], lead[model.jnt_dofadr]
    return [regularized_dry_friction(qvel[k], qvel[k].subs(to_acceleration), float(scale[k]),
                                     float(lead[k]))
            if coulomb_law == "mujoco" and scale[k] > 0
            else sp.tanh(qvel[k] / coulomb_scale) for k in range(model.njnt)]


def classical_candidates(system, model, coulomb, coulomb_scale, friction=True,
                         coulomb_law="smooth"):
    """Friction (unless not ``friction``) and spring candidates per joint, in the
    coordinates, with their MJCF values; the Coulomb candidate's law is
    :func:`_dry_friction_terms`'s."""
    coords = system.coords
    force_map = system.force_matrix()
    qpos, qvel = joint_coordinates(system, model)
    dry = (_dry_friction_terms(system, model, qvel, coulomb_scale, coulomb_law)
           if coulomb and friction else None)
    terms, mask, kinds, values = [], [], [], []
    for k in range(model.njnt):
        name = system.joint_names[k]
        dof = model.jnt_dofadr[k]
        reaches = np.abs(force_map[:, k]) > 1e-12
        candidates = [("viscous", qvel[k], model.dof_damping[dof])] if friction else []
        if coulomb and friction:
            candidates.append(("coulomb", dry[k], model.dof_frictionloss[dof]))
        if model.jnt_stiffness[k] > 0:
            rest = float(model.qpos_spring[model.jnt_qposadr[k]])
            candidates.append(("spring", qpos[k] - rest, model.jnt_stiffness[k]))
        for kind, term, value in candidates:
            terms.append(term)
            mask.append(reaches)
            kinds.append((kind, name))
            # the joint force -value * term reaches equation i as B[i, k] times it
            values.extend(float(value) * force_map[reaches, k])
    mask = np.array(mask, dtype=bool).reshape(-1, coords.n)
    return terms, mask, kinds, np.array(values)


def friction_models(friction) -> tuple:
    """``friction=`` as a tuple of model names in :data:`FRICTION_MODELS` order."""
    if friction is None:
        return ()
    if isinstance(friction, str):
        friction = FRICTION_MODELS if friction == "all" else (friction,)
    try:
        names = list(friction)
    except TypeError:
        names = [friction]
    unknown = [f for f in names if f not in FRICTION_MODELS]
    if unknown or not names:
        raise ValueError(f"friction: expected 'all' or names among {FRICTION_MODELS}, got "
                         f"{friction!r}")
    return tuple(m for m in FRICTION_MODELS if m in names)


def with_joint_models(catalog, system, model, friction, scales):
    """The catalog with the joint models ``friction`` instead of its viscous and Coulomb
    candidates (springs stay classical)."""
    terms, mask, kinds, values = classical_candidates(system, model, False, scales[0],
                                                      friction=False)
    return dataclasses.replace(
        catalog, classical_terms=terms, classical_mask=mask, classical_kinds=kinds,
        classical_values=values, friction_models=friction, friction_scales=scales,
        joint_velocities=joint_coordinates(system, model)[1])


def derive_lagrangian(system, model, bodies, seed) -> dict:
    """The catalog's Lagrangian part from the kinematic tree: every body's ten functions and
    every joint's armature term, reduced to independent Euler-Lagrange columns (see
    :func:`._derivation_cache.load` for the entries)."""
    n = system.coords.n
    functions, joints = body_functions(system, model)
    candidates, names = [], []
    for b, functions_of_body in functions.items():
        candidates.extend(functions_of_body)
        names.extend(f"{bodies[b]}.{p}" for p in INERTIAL_PARAMETERS)
    for k in range(model.njnt):
        candidates.append(0.5 * (joints[k]["velocity"] * joints[k]["velocity"]))
        names.append(f"{system.joint_names[k]}.armature")
    columns = euler_lagrange_many(candidates)
    rng = np.random.default_rng(seed)
    n_samples = 2 * len(candidates) // n + 20
    evaluated = evaluate_many([e for column in columns for e in column],
                              random_joint_values(system, n_samples, rng))
    # rows coordinate-major like the feature libraries: (equation, sample)
    regressor = evaluated.reshape(n_samples, len(candidates), n).transpose(2, 0, 1)
    regressor = regressor.reshape(n * n_samples, len(candidates))
    # small dense problems: one BLAS thread (threads only contend, as in XLSINDy.fit)
    with threadpoolctl.threadpool_limits(limits=1, user_api="blas"):
        kept = independent_regressor_columns(regressor)
        # every column is a combination of the kept ones: base = combination @ physical
        combination, *_ = np.linalg.lstsq(regressor[:, kept], regressor, rcond=None)
    # exact combinations come out within ~1e-14: round the noise away (0.9999999999999999)
    combination = np.round(combination, 12)
    combination[np.abs(combination) < 1e-10] = 0.0
    return {"bodies": list(functions), "names": names, "combination": combination,
            "n_candidates": len(candidates), "terms": [candidates[j] for j in kept],
            "columns": [columns[j] for j in kept]}
