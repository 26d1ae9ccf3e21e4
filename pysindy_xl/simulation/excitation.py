"""Excitation trajectories: Fourier series optimized for the conditioning of the regressor.

A robot's torques are linear in its parameters, ``tau = W(q, qd, qdd) beta``; their
least-squares estimate is as good as ``W`` is well conditioned. Following Swevers et al.
(1997), :func:`excitation_trajectory` minimizes ``log cond W`` over one period of a
:class:`~pysindy_xl.mujoco.FourierTrajectory` by SLSQP under joint and torque limits
(:doc:`/robot_arms`). A sample's rows depend on its own state only: ``6 n`` central
differences give every row's derivative, and ``d s_i = u_i^T dW v_i`` the gradient.
"""

from __future__ import annotations

import numpy as np
import threadpoolctl

from .._optional import import_mujoco
from .fourier import FourierTrajectory, checked_positive, fourier_basis

__all__ = ["excitation_trajectory"]

#: Samples per period and per harmonic of the optimization grid, and of the finer grid on which
#: limits are checked and condition numbers reported (a multiple: the coarse grid is a subset).
_OPTIMIZE_DENSITY, _CHECK_DENSITY = 20, 100
#: Share of each MJCF joint range (and servo control range) kept free at each end.
_RANGE_MARGIN = 0.05


class _Design:
    """The optimization problem: the regressor along a trajectory, its criterion and limits."""

    def __init__(self, catalog, period, n_harmonics, limits):
        self.library = catalog.library().fit()
        self.rest = np.setdiff1d(np.arange(len(self.library.get_feature_names())),
                                 self.library.force_columns_)
        self.beta = catalog.true_coefficients()[self.rest]
        self.n, self.L, self.w = catalog.coords.n, n_harmonics, 2 * np.pi / period
        self.period = period
        self.position, self.velocity, self.acceleration, self.torque = limits
        self._cache = {}

    def grid(self, density):
        t = np.arange(density * self.L) * self.period / (density * self.L)
        return np.stack([fourier_basis(t, self.w, self.L, k) for k in range(3)])  # (3, N, 2L)

    def split(self, x):
        return x[:self.n], x[self.n:].reshape(self.n, 2 * self.L)

    def states(self, x, bases):
        q0, ab = self.split(x)
        states = bases @ ab.T  # (3, N, n)
        states[0] += q0
        return states

    def regressor(self, states):
        """``W`` of stacked states (3, N, n): shape (n, N, p), coordinate-major rows."""
        from ..symbols import stack_variables
        theta = self.library.transform(stack_variables(*states, np.zeros_like(states[0])))
        return theta[:, self.rest].reshape(self.n, states.shape[1], -1)

    def condition(self, x, bases):
        W = self.regressor(self.states(x, bases))
        s = np.linalg.svd(W.reshape(-1, W.shape[-1]), compute_uv=False)
        return float(s[0] / s[-1]) if s[-1] > 0 else np.inf

    def torques(self, x, bases):
        return np.einsum("rkp,p->kr", self.regressor(self.states(x, bases)), self.beta)

    def evaluate(self, x, bases):
        """``log cond W``, its gradient, the torques (N, n) and their Jacobian (N n, len(x))."""
        key = x.tobytes()
        if key not in self._cache:
            self._cache = {key: self._evaluate(x, bases)}
        return self._cache[key]

    def _evaluate(self, x, bases):
        n, N = self.n, bases.shape[1]
        states = self.states(x, bases)
        steps = 1e-6 * (1 + np.abs(states).max(axis=(1, 2)))  # per kind
        sets = [states]
        for kind in range(3):
            for j in range(n):
                for sign in (1, -1):
                    moved = states.copy()
                    moved[kind, :, j] += sign * steps[kind]
                    sets.append(moved)
        W_all = self.regressor(np.concatenate(sets, axis=1)).reshape(n, 1 + 6 * n, N, -1)
        W = W_all[:, 0]
        moved = W_all[:, 1:].reshape(n, 3, n, 2, N, -1)
        dW = (moved[:, :, :, 0] - moved[:, :, :, 1]) / (2 * steps[None, :, None, None, None])
        # dW[r, kind, j, k, :]: row (r, k) derivative along state (kind, j) of sample k
        U, s, Vt = np.linalg.svd(W.reshape(n * N, -1), full_matrices=False)
        u_max, u_min = U[:, 0].reshape(n, N), U[:, -1].reshape(n, N)
        along = dW @ np.column_stack([Vt[0], Vt[-1], self.beta])  # (r, kind, j, k, 3)
        g = (np.einsum("rcjk,rk->cjk", along[..., 0], u_max) / s[0]
             - np.einsum("rcjk,rk->cjk", along[..., 1], u_min) / s[-1])  # (3, n, N)
        gradient = np.concatenate([g[0].sum(axis=-1),
                                   np.einsum("cjk,ckm->jm", g, bases).ravel()])
        torques = np.einsum("rkp,p->kr", W, self.beta)
        d_tau = along[..., 2]  # (r, kind, j, k)
        jac_q0 = np.transpose(d_tau[:, 0], (2, 0, 1))  # (k, r, j)
        jac_ab = np.einsum("rcjk,ckm->krjm", d_tau, bases)
        jacobian = np.concatenate([jac_q0, jac_ab.reshape(N, n, -1)], axis=-1)
        return float(np.log(s[0] / s[-1])), gradient, torques, jacobian.reshape(N * n, -1)

    def linear_constraints(self, bases):
        """``A x + c >= 0`` for the position, velocity and acceleration limits: ``A`` of shape
        (N, C, len(x)), ``c`` of shape (C,), one column per limited (kind, side, joint)."""
        n, m = self.n, 2 * self.L
        blocks, offsets = [], []
        for kind, (low, high) in enumerate([self.position.T, (-self.velocity, self.velocity),
                                            (-self.acceleration, self.acceleration)]):
            A = np.zeros((bases.shape[1], n, n + n * m))
            for j in range(n):
                A[:, j, n + j * m:n + (j + 1) * m] = bases[kind]
                A[:, j, j] = 1.0 if kind == 0 else 0.0
            for sign, bound in ((1, -low), (-1, high)):
                keep = np.isfinite(bound)
                blocks.append(sign * A[:, keep])
                offsets.append(bound[keep])
        return np.concatenate(blocks, axis=1), np.concatenate(offsets)

    def rest_equalities(self):
        """``E x = 0``: zero velocity and acceleration at ``t = 0``."""
        n, L = self.n, self.L
        E = np.zeros((2 * n, n + 2 * n * L))
        for j in range(n):
            E[2 * j, n + 2 * j * L:n + 2 * j * L + L] = 1.0
            E[2 * j + 1, n + 2 * j * L + L:n + 2 * (j + 1) * L] = np.arange(1, L + 1)
        return E

    def fit_to_limits(self, x, bases, grow):
        """Scale each joint's harmonics to its tightest limit (``grow``) or back inside them,
        then all of them together under the torque limits."""
        q0, ab = self.split(x.copy())
        q = bases[0] @ ab.T
        low, high = self.position[:, 0] - q0, self.position[:, 1] - q0
        if np.any(low >= 0) or np.any(high <= 0):
            raise ValueError(f"position_limits: offsets {q0} outside the limits")
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = np.nanmin(np.stack([
                np.where(q > 0, high / q, np.inf).min(axis=0),
                np.where(q < 0, low / q, np.inf).min(axis=0),
                self.velocity / np.abs(bases[1] @ ab.T).max(axis=0),
                self.acceleration / np.abs(bases[2] @ ab.T).max(axis=0)]), axis=0)
        scale = np.where(np.isfinite(scale), scale, 1.0)
        ab *= (scale if grow else np.minimum(scale, 1.0))[:, None]
        x = np.concatenate([q0, ab.ravel()])
        if not np.isfinite(self.torque).any():
            return x

        def excess(factor):
            moved = np.concatenate([q0, factor * ab.ravel()])
            return np.max(np.abs(self.torques(moved, bases)) / self.torque)

        if excess(0.0) > 1:
            raise ValueError("torque_limits: the nominal arm needs more torque than allowed to "
                             f"hold its mean pose {np.round(q0, 3).tolist()}")
        if excess(1.0) <= 1:
            return x
        low, high = 0.0, 1.0
        for _ in range(30):
            middle = (low + high) / 2
            low, high = (middle, high) if excess(middle) <= 1 else (low, middle)
        return np.concatenate([q0, low * ab.ravel()])

    def random_start(self, rng, bases, rest_at_start):
        q0 = np.mean(self.position, axis=1)
        ab = rng.standard_normal((self.n, 2 * self.L)) / np.tile(np.arange(1, self.L + 1), 2)
        x = np.concatenate([q0, ab.ravel()])
        if rest_at_start:  # project onto the null space of the rest equalities
            E = self.rest_equalities()
            x = x - np.linalg.pinv(E) @ (E @ x)
        return self.fit_to_limits(x, bases, grow=True)

    def optimize(self, x, bases, rest_at_start, max_iter, callback=None):
        """SLSQP from ``x``. Each limit enters through its margin at the lowest local minima
        along the period (``L + 1``; ``3 L`` for the torques), not one row per sample."""
        from scipy.optimize import minimize
        A, c = self.linear_constraints(bases)
        columns = np.arange(A.shape[1])

        def linear(x):
            index = _dips(A @ x + c, self.L + 1)
            return (A @ x + c)[index, columns].ravel(), A[index, columns].reshape(-1, len(x))

        constraints = [{"type": "ineq", "fun": lambda x: linear(x)[0],
                        "jac": lambda x: linear(x)[1]}]
        limited = np.flatnonzero(np.isfinite(self.torque))
        if limited.size:
            bound = np.tile(self.torque[limited], 2)
            sides = np.r_[-np.ones(limited.size), np.ones(limited.size)]
            N, pair = bases.shape[1], np.arange(2 * limited.size)

            def torque(x):
                _, _, tau, jac = self.evaluate(x, bases)
                jac = jac.reshape(N, self.n, len(x))[:, limited]
                margin = bound + sides * np.tile(tau[:, limited], 2)
                index = _dips(margin, 3 * self.L)
                jac = sides[None, :, None] * np.concatenate([jac, jac], axis=1)
                return margin[index, pair].ravel(), jac[index, pair].reshape(-1, len(x))

            constraints.append({"type": "ineq", "fun": lambda x: torque(x)[0],
                                "jac": lambda x: torque(x)[1]})
        if rest_at_start:
            E = self.rest_equalities()
            constraints.append({"type": "eq", "fun": lambda x: E @ x, "jac": lambda x: E})
        result = minimize(lambda x: self.evaluate(x, bases)[0], x,
                          jac=lambda x: self.evaluate(x, bases)[1], method="SLSQP",
                          constraints=constraints, options={"maxiter": max_iter}, callback=callback)
        return result.x, result


def _dips(margins, k):
    """Rows (k, C) of the ``k`` lowest local minima of each column of ``margins`` (N, C),
    periodic along N; padded with the column's largest margins (inactive rows)."""
    before, after = np.roll(margins, 1, axis=0), np.roll(margins, -1, axis=0)
    dip = (margins <= before) & (margins < after)
    order = np.lexsort((np.where(dip, margins, -margins), ~dip), axis=0)
    return order[:min(k, len(margins))]


def _restart(design, rng, coarse, fine, optimize, rest_at_start, max_iter, best, runs,
             bar):
    """One random start, optimized or not (``bar`` advanced per iteration); the better of it
    and ``best``."""
    x = design.random_start(rng, fine, rest_at_start)
    run = {"start": design.condition(x, fine)}
    if optimize:
        x, result = design.optimize(x, coarse, rest_at_start, max_iter,
                                    callback=lambda _: bar.update())
        bar.update(max_iter - int(result.nit))  # stopped early: the rest of its share
        x = design.fit_to_limits(x, fine, grow=False)
        run.update(message=str(result.message), iterations=int(result.nit))
    run["condition_number"] = design.condition(x, fine)
    runs.append(run)
    return best if best is not None and best[1] <= run["condition_number"] else (
        x, run["condition_number"])


def _per_joint(value, name, n, default):
    if value is None:
        return np.full(n, default, dtype=float)
    out = np.broadcast_to(np.asarray(value, dtype=float), (n,)) if np.ndim(value) == 0 else \
        np.asarray(value, dtype=float)
    if out.shape != (n,) or np.any(np.isnan(out)) or np.any(out <= 0):
        raise ValueError(f"{name}: expected a positive number or {n} positive numbers (inf: no "
                         f"limit), got {value!r}")
    return out.astype(float)


def _mjcf_limits(system, position_limits, torque_limits):
    """Default position limits (joint ranges within the servos' reach, 5 % margin) and torque
    limits (actuator force ranges) of an MJCF whose coordinates are its joints."""
    mujoco = import_mujoco()
    model = system.mj_model()
    n = system.n
    identity = np.allclose(system.joint_to_coordinates, np.eye(n))
    if position_limits is None:
        if not identity:
            raise ValueError("position_limits: the system's coordinates are not its joints; "
                             "give the limits of the coordinates, shape (n, 2)")
        unlimited = [system.joint_names[j] for j in range(n) if not model.jnt_limited[j]]
        if unlimited:
            raise ValueError(f"position_limits: joints {unlimited} have no range in the MJCF; "
                             "give position_limits, shape (n, 2)")
        low, high = model.jnt_range[:, 0].copy(), model.jnt_range[:, 1].copy()
        for u in range(model.nu):  # a position servo's reach: its control range
            dof = model.jnt_dofadr[model.actuator_trnid[u, 0]]
            bias, gain = model.actuator_biasprm[u, :3], model.actuator_gainprm[u, 0]
            if (model.actuator_ctrllimited[u] and bias[1] < 0 and gain != 0
                    and int(model.actuator_trntype[u]) == int(mujoco.mjtTrn.mjTRN_JOINT)):
                reach = -(gain * model.actuator_ctrlrange[u] + bias[0]) / bias[1]
                reach = np.sort(reach / model.actuator_gear[u, 0])
                low[dof], high[dof] = max(low[dof], reach[0]), min(high[dof], reach[1])
        width = high - low
        position_limits = np.column_stack([low + _RANGE_MARGIN * width,
                                           high - _RANGE_MARGIN * width])
    position = np.asarray(position_limits, dtype=float)
    if position.shape != (n, 2) or not np.all(np.isfinite(position)) or np.any(
            position[:, 1] <= position[:, 0]):
        raise ValueError(f"position_limits: expected finite (low, high) pairs with low < high, "
                         f"shape ({n}, 2), got {position_limits!r}")
    if torque_limits is None and identity:
        torque = np.full(n, np.inf)
        for j in range(n):
            if model.jnt_actfrclimited[j]:
                torque[j] = np.abs(model.jnt_actfrcrange[j]).min()
        for u in range(model.nu):
            if model.actuator_forcelimited[u] and int(model.actuator_trntype[u]) == int(
                    mujoco.mjtTrn.mjTRN_JOINT):
                dof = model.jnt_dofadr[model.actuator_trnid[u, 0]]
                torque[dof] = min(torque[dof], np.abs(model.actuator_forcerange[u]).min()
                                  * abs(model.actuator_gear[u, 0]))
        torque_limits = torque
    return position, _per_joint(torque_limits, "torque_limits", n, np.inf)


def excitation_trajectory(system, n_harmonics: int = 5, period: float = 10.0,
                          position_limits=None, velocity_limits=None, acceleration_limits=None,
                          torque_limits=None, restarts: int = 3, seed: int = 0,
                          optimize: bool = True, rest_at_start: bool = True,
                          max_iter: int = 100, progress=None) -> FourierTrajectory:
    """A periodic trajectory that excites a robot's dynamics for identification.

    Parameters
    ----------
    system : MuJoCoSystem, str or os.PathLike
        The robot; its MJCF's nominal inertials give the torques checked against
        ``torque_limits``.
    n_harmonics, period : int, float
        Harmonics ``L`` per joint and period (s); the top frequency is ``L / period`` Hz.
    position_limits : array (n, 2), optional
        ``(low, high)`` per coordinate. Default: the MJCF's joint ranges, narrowed to a
        position servo's reach, less 5 % of the width at each end.
    velocity_limits, acceleration_limits, torque_limits : float or array (n,), optional
        Largest ``|qd_j|``, ``|qdd_j|`` and nominal ``|tau_j|`` (``inf``: none). Default
        torques: the MJCF's actuator force ranges.
    restarts, seed, max_iter : int
        Random starts (the best optimum is returned), their seed, SLSQP iterations per start.
    optimize : bool, default True
        False: the best random start (scaled to touch the limits), the baseline.
    rest_at_start : bool, default True
        Start and end at rest (``qd = qdd = 0`` at ``t = 0``).
    progress : bool, optional
        Show a tqdm progress bar (default: only on a terminal).

    Returns
    -------
    FourierTrajectory
        Named by the system's coordinates, with ``condition_number`` and ``info``
        (``restarts``: each start's condition number before and after; ``limits``).

    Examples
    --------
    >>> xml = '''<mujoco><option gravity="0 0 -9.81"/><worldbody><body>
    ...   <joint name="a" axis="0 1 0" range="-1 1" damping="0.1"/>
    ...   <inertial pos="0.1 0 -0.3" mass="1" diaginertia="0.01 0.01 0.01"/>
    ... </body></worldbody></mujoco>'''
    >>> best = excitation_trajectory(xml, n_harmonics=3, period=4.0, restarts=1)
    >>> plain = excitation_trajectory(xml, n_harmonics=3, period=4.0, restarts=1,
    ...                               optimize=False)
    >>> bool(best.condition_number < plain.condition_number)
    True
    """
    from tqdm.auto import tqdm

    from ..mujoco.catalogs.kinematic import kinematic_catalog
    from ..mujoco.systems.registry import get_system as resolve_system
    system = resolve_system(system)
    if isinstance(n_harmonics, bool) or not isinstance(n_harmonics, (int, np.integer)) \
            or n_harmonics < 1:
        raise ValueError(f"n_harmonics: expected an integer >= 1, got {n_harmonics!r}")
    for name, value in (("restarts", restarts), ("max_iter", max_iter)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise ValueError(f"{name}: expected an integer >= 1, got {value!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise TypeError(f"seed: expected an integer, got {type(seed).__name__}")
    period = checked_positive(period, "period")
    n = system.n
    position, torque = _mjcf_limits(system, position_limits, torque_limits)
    limits = (position, _per_joint(velocity_limits, "velocity_limits", n, np.inf),
              _per_joint(acceleration_limits, "acceleration_limits", n, np.inf), torque)
    design = _Design(kinematic_catalog(system), period, int(n_harmonics), limits)
    coarse, fine = design.grid(_OPTIMIZE_DENSITY), design.grid(_CHECK_DENSITY)
    rng = np.random.default_rng(seed)
    best, runs = None, []
    # small SVDs and products: BLAS threads only compete
    bar = tqdm(total=restarts * max_iter if optimize else 0, desc="excitation design",
               unit="iteration", leave=False, disable=None if progress is None else not progress)
    with bar, threadpoolctl.threadpool_limits(limits=1, user_api="blas"):
        for _ in range(restarts):
            best = _restart(design, rng, coarse, fine, optimize, rest_at_start, max_iter,
                            best, runs, bar)
            bar.set_postfix(condition=f"{best[1]:.3g}")
    q0, ab = design.split(best[0])
    L = int(n_harmonics)
    out = FourierTrajectory(q0, ab[:, :L], ab[:, L:], period, names=system.coordinate_names)
    out.condition_number = best[1]
    out.info = {"restarts": runs, "optimized": bool(optimize), "seed": int(seed),
                "limits": {"position": position.tolist(), "velocity": limits[1].tolist(),
                           "acceleration": limits[2].tolist(), "torque": torque.tolist()}}
    return out
