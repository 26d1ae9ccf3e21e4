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
    """Prediction, scoring, simulation, export and saving of a fitted model.

    Mixed into :class:`~pysindy_xl.XLSINDy`; every method needs the fitted attributes
    ``coef_``, ``dynamics_`` (the identified equations in mass-matrix form
    ``M(q, qd) qdd = f(q, qd, tau, t)``) and ``n_coordinates_``, and raises
    :class:`sklearn.exceptions.NotFittedError` before :meth:`~pysindy_xl.XLSINDy.fit`, or a
    ``ValueError`` when the identified equations contain no acceleration.
    """

    def _require_dynamics(self) -> MassMatrixDynamics:
        check_is_fitted(self, "coef_")
        if self.dynamics_ is None:
            raise ValueError("the identified equations contain no acceleration, so they define "
                             "no dynamics")
        return self.dynamics_

    def predict(self, x, x_dot, u=None):
        """Accelerations of the identified equations (forward dynamics).

        Solves the identified mass-matrix form for the accelerations at every sample,
        ``qdd = M(q, qd)^-1 f(q, qd, tau)``.

        Parameters
        ----------
        x : array, shape (N, n), or list of arrays
            Positions, one trajectory or several.
        x_dot : array, shape (N, n), or list of arrays
            Velocities, same layout as ``x``.
        u : array, shape (N, n), or list of arrays, optional
            Generalized forces, same layout as ``x``; default None (zero forces).

        Returns
        -------
        ndarray, shape (N, n), or list of ndarray
            Accelerations; a list (one array per trajectory) when ``x`` is a list.

        Raises
        ------
        ValueError
            On arrays of the wrong shape, or where the equations are not finite.
        SingularMassMatrixError
            Where the identified mass matrix is singular.

        Examples
        --------
        A spring ``x'' + 3 x = u`` identified from one forced trajectory:

        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
        >>> t = np.linspace(0, 5, 501)[:, None]
        >>> x = np.sin(t) + np.sin(2.3 * t) / 2
        >>> xd, xdd = np.cos(t) + 1.15 * np.cos(2.3 * t), -np.sin(t) - 2.645 * np.sin(2.3 * t)
        >>> model = px.XLSINDy(lib).fit(x, t[:, 0], x_dot=xd, x_ddot=xdd, u=xdd + 3 * x)
        >>> model.predict(np.array([[1.0]]), np.array([[0.0]]), u=np.array([[5.0]])).round(6)
        array([[2.]])
        """
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
        """Generalized forces that produce a motion (inverse dynamics).

        ``tau = M(q, qd) qdd - f(q, qd, 0)``: the forces (a robot's joint torques) under which
        the identified equations hold with the given motion.

        Parameters
        ----------
        x : array, shape (N, n)
            Positions.
        x_dot : array, shape (N, n)
            Velocities.
        x_ddot : array, shape (N, n)
            Accelerations.

        Returns
        -------
        ndarray, shape (N, n)
            The forces, in the units of the ``u`` the model was fitted with.

        Examples
        --------
        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
        >>> t = np.linspace(0, 5, 501)
        >>> x = (np.sin(t) + 0.5 * np.sin(3 * t))[:, None]  # two frequencies
        >>> xd = (np.cos(t) + 1.5 * np.cos(3 * t))[:, None]
        >>> xdd = (-np.sin(t) - 4.5 * np.sin(3 * t))[:, None]
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
        """Held-out error of :meth:`predict_forces` against measured forces.

        The forces predicted from the motion are compared with the measured ``u``, per
        coordinate (RMS and RMS relative to the measured RMS) and in total
        (``||tau_hat - u|| / ||u||``); see :func:`pysindy_xl.held_out.score_forces`.

        Parameters
        ----------
        x : array, shape (N, n), or list of arrays
            Held-out positions, one run or several.
        t : array, shape (N,), or list of arrays
            Their sample times, strictly increasing.
        u : array, shape (N, n), or list of arrays
            Measured generalized forces.
        x_dot, x_ddot : array, shape (N, n), or list of arrays, optional
            Measured velocities and accelerations; default None: estimated by
            :func:`~pysindy_xl.held_out.scoring_derivatives`.
        smoother : object with ``smooth(t, x)``, optional
            Replaces the default smoothing spline of the positions; default None.
        max_frequency : float, default 10.0
            Highest bandwidth (Hz) kept by the default smoothing spline.

        Returns
        -------
        ForceScore
            ``rms``, ``relative`` (per coordinate), ``total``, ``derivatives`` (where the
            velocities and accelerations came from), ``lines()`` and ``plot(path)``.

        Examples
        --------
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
        """Score of the predicted accelerations against those of the data.

        Parameters
        ----------
        x : array, shape (N, n), or list of arrays
            Positions, one trajectory or several.
        t : float, array (N,) or list of arrays, optional
            Time step or sample times; default None: the model's ``t_default``.
        x_dot, x_ddot : array, shape (N, n), or list of arrays, optional
            Measured velocities and accelerations; default None: computed with the model's
            ``differentiation_method`` (as in :meth:`fit`).
        u : array, shape (N, n), or list of arrays, optional
            Generalized forces; default None (unforced).
        metric : callable, default sklearn.metrics.r2_score
            ``metric(true, predicted) -> float`` on the stacked accelerations (S, n).

        Returns
        -------
        float
            ``metric(x_ddot, predict(x, x_dot, u))`` (the coefficient of determination R^2 by
            default: 1 for a perfect prediction).

        Examples
        --------
        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
        >>> t = np.linspace(0, 5, 501)[:, None]
        >>> x = np.sin(t) + np.sin(2.3 * t) / 2
        >>> xd, xdd = np.cos(t) + 1.15 * np.cos(2.3 * t), -np.sin(t) - 2.645 * np.sin(2.3 * t)
        >>> model = px.XLSINDy(lib).fit(x, t[:, 0], x_dot=xd, x_ddot=xdd, u=xdd + 3 * x)
        >>> round(model.score(x, t[:, 0], x_dot=xd, x_ddot=xdd, u=xdd + 3 * x), 6)
        1.0
        """
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
        """Simulate the identified dynamics, open loop (``u``) or closed loop (``feedback``).

        Integrates ``d/dt [q, qd] = [qd, M(q, qd)^-1 f(q, qd, tau, t)]`` with
        ``tau = u(t) + feedback(t, q, qd)``.

        Parameters
        ----------
        x0 : array, shape (2n,)
            Initial state ``[q_1..q_n, qd_1..qd_n]``.
        t : array, shape (T,)
            Strictly increasing output times.
        u : array (T, n), callable ``u(t) -> (n,)`` or None, optional
            Generalized forces as a function of time (open loop); default None (zero). With one
            coordinate, a 1-D array (T,) is accepted.
        feedback : callable, optional
            ``feedback(t, q, qd) -> (n,)``, added to ``u`` at every step (a servo or a
            controller); default None.
        **integrator_options
            ``method`` (default ``"DOP853"``), ``rtol``, ``atol``, ``divergence_bound``,
            ``max_evaluations``, ``timeout``, ``interpolation``, ``step``: as in
            :meth:`MassMatrixDynamics.simulate <pysindy_xl.MassMatrixDynamics.simulate>`.

        Returns
        -------
        ndarray, shape (T, 2n)
            The states at ``t``, laid out like ``x0``.

        Raises
        ------
        SimulationError
            When the run stops early (divergence, singular mass matrix, timeout...), with the
            valid part of the trajectory.

        Examples
        --------
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
        """The identified dynamics as a pure JAX function (needs the ``jax`` extra).

        Returns
        -------
        callable
            ``f(state, u, t=0.0) -> d(state)/dt = [qd, qdd]``, ``state`` (..., 2n) and ``u``
            (..., n) with broadcast batch dimensions; jit-, vmap- and grad-compatible
            (:func:`pysindy_xl.export.jax_dynamics.dynamics_function`).

        Examples
        --------
        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
        >>> t = np.linspace(0, 5, 501)[:, None]
        >>> x = np.sin(t) + np.sin(2.3 * t) / 2
        >>> xd, xdd = np.cos(t) + 1.15 * np.cos(2.3 * t), -np.sin(t) - 2.645 * np.sin(2.3 * t)
        >>> model = px.XLSINDy(lib).fit(x, t[:, 0], x_dot=xd, x_ddot=xdd, u=xdd + 3 * x)
        >>> f = model.to_jax()
        >>> np.asarray(f(np.array([1.0, 0.0]), np.array([5.0]))).round(4).tolist()
        [0.0, 2.0]
        """
        from ..export.jax_dynamics import dynamics_function
        return dynamics_function(self._require_dynamics())

    def save(self, path) -> None:
        """Save the fitted model as JSON, to be read back by :meth:`load`.

        The file holds the catalog's specification (coordinates and terms as strings of a
        restricted grammar), the optimizer's parameters, the estimator's settings and the
        fitted state (:mod:`pysindy_xl.io`); nothing is pickled.

        Parameters
        ----------
        path : str or path-like
            The file to write.

        Examples
        --------
        >>> import os, tempfile
        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
        >>> t = np.linspace(0, 5, 501)[:, None]
        >>> x = np.sin(t) + np.sin(2.3 * t) / 2
        >>> xd, xdd = np.cos(t) + 1.15 * np.cos(2.3 * t), -np.sin(t) - 2.645 * np.sin(2.3 * t)
        >>> model = px.XLSINDy(lib).fit(x, t[:, 0], x_dot=xd, x_ddot=xdd, u=xdd + 3 * x)
        >>> path = os.path.join(tempfile.mkdtemp(), "spring.json")
        >>> model.save(path)
        >>> loaded = px.XLSINDy.load(path)
        >>> bool(np.array_equal(loaded.coefficients(), model.coefficients()))
        True
        """
        from ..io import save_model
        save_model(self, path)

    def to_mjcf(self, path, template) -> dict:
        r"""Write the identified robot as an MJCF file that MuJoCo simulates.

        For a model fitted with the kinematic catalog of an MJCF (or URDF) system
        (:func:`~pysindy_xl.kinematic_catalog`): the identified base parameters ``beta`` are
        realized by physically consistent rigid-body parameters ``pi``
        (:mod:`pysindy_xl.export.mjcf`),

        .. math:: \min_\pi \; \frac{\|C \pi - \beta\|}{\|\beta\|}
                  + \epsilon \frac{\|\pi - \pi_0\|^2}{\|\pi_0\|^2}
                  \quad \text{s.t.} \quad J_b(\pi) \succeq 0, \; a_j \ge 0,

        with ``C`` the catalog's combination matrix, ``J_b`` each body's pseudo-inertia,
        ``a_j`` the armatures, ``pi_0`` the template's parameters and ``epsilon = 1e-6``.
        Bodies get these inertials, joints their armature,
        ``damping`` (viscous friction) and ``frictionloss`` (Coulomb friction); everything else
        (geometry, kinematic tree, actuators) is copied from ``template``.

        Parameters
        ----------
        path : str or path-like
            The MJCF file to write.
        template : str, path-like or MJCFSystem
            Required (positional or keyword): the MJCF (path, XML text or
            :class:`~pysindy_xl.mujoco.MJCFSystem`) whose kinematic tree the model was
            identified on; it places the inertials and supplies the rest of the file.

        Returns
        -------
        dict
            ``physical_parameters``: name -> value written; ``residual``:
            ``|C pi - beta| / |beta|``, zero when the identified parameters are realizable by
            rigid bodies; ``dropped``: ``{joint: {model: value}}``, the joint friction models
            MJCF cannot state (asymmetric, Stribeck, offset).

        Raises
        ------
        ValueError
            When ``template`` is None.

        See Also
        --------
        physical_parameters : The identified parameters by name.
        """
        from ..export.mjcf import to_mjcf
        check_is_fitted(self, "coef_")
        return to_mjcf(self, path, template)

    def to_gymnasium(self, dt, **options):
        """A Gymnasium environment stepping the identified model (needs the ``gym`` extra).

        Parameters
        ----------
        dt : float
            Seconds per environment step (integrated by ``substeps`` Runge-Kutta 4 steps).
        **options
            ``reward``, ``terminated``, ``initial_state``, ``actuated``, ``action_bounds``,
            ``observation_bounds``, ``max_episode_steps``, ``substeps``: as in
            :class:`pysindy_xl.export.gym_env.IdentifiedDynamicsEnv`.

        Returns
        -------
        IdentifiedDynamicsEnv
            A ``gymnasium.Env``: actions are the forces of the actuated coordinates,
            observations the state ``[q, qd]``.

        Examples
        --------
        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
        >>> t = np.linspace(0, 5, 501)[:, None]
        >>> x = np.sin(t) + np.sin(2.3 * t) / 2
        >>> xd, xdd = np.cos(t) + 1.15 * np.cos(2.3 * t), -np.sin(t) - 2.645 * np.sin(2.3 * t)
        >>> model = px.XLSINDy(lib).fit(x, t[:, 0], x_dot=xd, x_ddot=xdd, u=xdd + 3 * x)
        >>> env = model.to_gymnasium(0.01)
        >>> observation, info = env.reset(seed=0)
        >>> observation.shape
        (2,)
        """
        from ..export.gym_env import make_env
        return make_env(self, dt, **options)
