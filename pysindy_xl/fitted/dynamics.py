"""What a fitted :class:`~pysindy_xl.XLSINDy` does with its equations: predictions, scores,
simulations, exports. Reads only ``coef_``, ``dynamics_``, ``n_coordinates_`` and the
host's parameters."""

from __future__ import annotations

import numpy as np
from sklearn.metrics import r2_score
from sklearn.utils.validation import check_is_fitted

from .._inputs import aligned, as_list, check_array
from .._validation import check_instance
from ..dynamics.mass_matrix import MassMatrixDynamics

__all__ = ["DynamicsMixin"]


class DynamicsMixin:
    """Prediction, scoring, simulation, export and saving (mixed into ``XLSINDy``)."""

    def _require_dynamics(self) -> MassMatrixDynamics:
        check_is_fitted(self, "coef_")
        if self.dynamics_ is None:
            raise ValueError("the identified equations contain no acceleration, so they define "
                             "no dynamics")
        return self.dynamics_

    def predict(self, x, x_dot, u=None):
        """Accelerations (N, n) of the identified equations at positions ``x`` and velocities
        ``x_dot`` (N, n) under forces ``u`` (zero when absent); lists of arrays give a list."""
        dynamics = self._require_dynamics()
        n = self.n_coordinates_
        xs, is_list = as_list(x, "x")
        xds, us = aligned(x_dot, "x_dot", xs, is_list), aligned(u, "u", xs, is_list)
        out = []
        for k, (xk, xdk, uk) in enumerate(zip(xs, xds, us, strict=True)):
            label = f"[{k}]" if is_list else ""
            xk = check_array(xk, f"x{label}", n_columns=n)
            xdk = check_array(xdk, f"x_dot{label}", xk.shape)
            uk = None if uk is None else check_array(uk, f"u{label}", xk.shape)
            with np.errstate(all="ignore"):
                acc = dynamics.accelerations(xk, xdk, uk)
            if not np.all(np.isfinite(acc)):
                bad = np.flatnonzero(~np.all(np.isfinite(acc), axis=1))
                raise ValueError(f"x{label}: the identified equations are not finite (overflow "
                                 f"or outside their domain) at {len(bad)} of {len(acc)} "
                                 f"samples, first at sample {bad[0]}; the values are too large "
                                 "for the model or outside its range")
            out.append(acc)
        return out if is_list else out[0]

    def predict_forces(self, x, x_dot, x_ddot):
        """Inverse dynamics ``M(q, qd) qdd - f(q, qd, 0)`` (N, n): the forces (a robot's joint
        torques) under which the identified equations hold with the motion ``x``, ``x_dot``,
        ``x_ddot`` (N, n).

        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
        >>> t = np.linspace(0, 5, 501)
        >>> x, xd, xdd = np.sin(t)[:, None], np.cos(t)[:, None], -np.sin(t)[:, None]
        >>> model = px.XLSINDy(lib).fit(x, t, x_dot=xd, x_ddot=xdd, u=2 * xdd + 3 * x)
        >>> bool(np.allclose(model.predict_forces(x, xd, xdd), 2 * xdd + 3 * x))
        True
        """
        dynamics = self._require_dynamics()
        n = self.n_coordinates_
        x = check_array(x, "x", n_columns=n)
        x_dot = check_array(x_dot, "x_dot", x.shape)
        x_ddot = check_array(x_ddot, "x_ddot", x.shape)
        from ..symbols import stack_variables
        mass, free = dynamics.mass_and_forcing(stack_variables(x, x_dot))
        return np.einsum("sij,sj->si", mass, x_ddot) - free

    def score_forces(self, x, t, u, x_dot=None, x_ddot=None, smoother=None,
                     max_frequency=10.0):
        """Held-out error of :meth:`predict_forces` against measured forces ``u``: a ``ForceScore``
        with ``rms``, ``relative`` (per coordinate), ``total``, ``lines()`` and ``plot(path)``;
        arguments as in :func:`pysindy_xl.held_out.score_forces`.

        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
        >>> t = np.linspace(0, 5, 501)[:, None]
        >>> x = np.sin(t) + np.sin(2.3 * t) / 2
        >>> xd, xdd = np.cos(t) + 1.15 * np.cos(2.3 * t), -np.sin(t) - 2.645 * np.sin(2.3 * t)
        >>> model = px.XLSINDy(lib).fit(x, t[:, 0], x_dot=xd, x_ddot=xdd, u=2 * xdd + 3 * x)
        >>> score = model.score_forces(x, t[:, 0], 2 * xdd + 3 * x + 0.02, xd, xdd)
        >>> round(float(score.rms[0]), 6), score.derivatives
        (0.02, 'measured')
        """
        from ..evaluation.held_out import score_forces
        self._require_dynamics()
        return score_forces(self, x, t, u, x_dot, x_ddot, smoother, max_frequency)

    def score(self, x, t=None, x_dot=None, x_ddot=None, u=None, metric=r2_score):
        """``metric(true, predicted)`` of the accelerations (default R^2); ``x, t, x_dot,
        x_ddot, u`` as in :meth:`fit`."""
        self._require_dynamics()
        check_instance("metric", metric, "a function metric(true, predicted)", "__call__")
        from ..fit import estimator_trajectories
        data = estimator_trajectories(self, x, t, x_dot, x_ddot, u, self.n_coordinates_)
        true = np.vstack([d["x_ddot"] for d in data])
        predicted = np.vstack([
            self.dynamics_.accelerations(d["x"], d["x_dot"], d["u"], d["t"]) for d in data
        ])
        return metric(true, predicted)

    def simulate(self, x0, t, u=None, feedback=None, **integrator_options) -> np.ndarray:
        """Simulate the identified dynamics, open loop (``u``) or closed loop (``feedback``);
        returns the states (T, 2n). Arguments and errors as in :meth:`MassMatrixDynamics.simulate
        <pysindy_xl.MassMatrixDynamics.simulate>` (``u`` may be 1-D for one coordinate).

        A spring ``x'' + 2 x = u``, identified, then brought to ``x = 0.5`` by a PD law:

        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
        >>> t = np.linspace(0, 5, 501)
        >>> x = (np.sin(t) + np.sin(3 * t))[:, None]
        >>> xd = (np.cos(t) + 3 * np.cos(3 * t))[:, None]
        >>> xdd = (-np.sin(t) - 9 * np.sin(3 * t))[:, None]
        >>> model = px.XLSINDy(lib).fit(x, t, x_dot=xd, x_ddot=xdd, u=xdd + 2 * x)
        >>> pd = lambda t, q, qd: 20.0 * (0.5 - q) - 6.0 * qd + 1.0
        >>> states = model.simulate([0.0, 0.0], np.linspace(0.0, 10.0, 11), feedback=pd)
        >>> round(float(states[-1, 0]), 4)
        0.5
        """
        dynamics = self._require_dynamics()
        if u is not None and not callable(u) and np.ndim(u) == 1 and self.n_coordinates_ == 1:
            u = np.asarray(u)[:, None]  # one coordinate: a 1-D force as fit accepts it
        if feedback is not None:
            integrator_options["feedback"] = feedback
        return dynamics.simulate(x0, t, u, **integrator_options)

    def to_jax(self):
        """Pure JAX function ``f(state, u) -> d(state)/dt`` (jit-, vmap- and grad-compatible;
        :func:`pysindy_xl.export.jax_dynamics.dynamics_function`)."""
        from ..export.jax_dynamics import dynamics_function
        return dynamics_function(self._require_dynamics())

    def save(self, path) -> None:
        """Save the catalog specification and coefficients as JSON (:mod:`pysindy_xl.io`)."""
        from ..io import save_model
        save_model(self, path)

    def to_mjcf(self, path, template=None) -> dict:
        """Write the identified robot to ``path`` as MJCF: physically consistent body inertials,
        joint armature, ``damping`` and ``frictionloss``, the rest from ``template``, the MJCF it
        was identified on (:mod:`pysindy_xl.export.mjcf`). Returns ``physical_parameters`` (name
        -> value written), ``residual`` (``|C pi - beta| / |beta|``, zero when realizable by rigid
        bodies) and ``dropped`` (``{joint: {model: value}}``, joint models MJCF cannot state)."""
        from ..export.mjcf import to_mjcf
        check_is_fitted(self, "coef_")
        return to_mjcf(self, path, template)

    def to_gymnasium(self, dt, **options):
        """A Gymnasium environment stepping the identified model; ``dt`` and ``**options`` as in
        :class:`pysindy_xl.export.gym_env.IdentifiedDynamicsEnv`."""
        from ..export.gym_env import make_env
        return make_env(self, dt, **options)
