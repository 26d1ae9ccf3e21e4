"""The extra row of the table: plain :class:`pysindy.SINDy`, second order, classical catalog.

SINDy fits the first-order state ``[q, qd]`` with ``x_dot = [qd, qdd]`` and the forces as
control input. Its library holds the classical catalog's terms that an explicit model
``qdd = f(q, qd, u)`` can use (none with an acceleration: ``M(q) qdd`` is beyond SINDy), each
a :class:`pysindy.CustomLibrary` function of all inputs, and the forces linearly; optimizer
:class:`pysindy.STLSQ`. The fitted rows become ``MassMatrixDynamics`` with ``M = I``, so the
baseline is validated like every other row."""

from __future__ import annotations

import numpy as np
import sympy as sp

__all__ = ["SINDyBaseline", "baseline_terms"]


def baseline_terms(catalog) -> list[sp.Expr]:
    """The distinct classical terms without acceleration of a classical catalog (e.g.
    ``reference_catalog(system, "classical")``), in catalog order.

    Parameters
    ----------
    catalog : pysindy_xl.CatalogRepartition
        A classical catalog.

    Returns
    -------
    list of sympy.Expr
        The terms.

    Raises
    ------
    ValueError
        When the catalog has no classical term without acceleration.
    """
    catalog.symbolic_matrix()  # the columns, derived on first use
    accelerations = set(catalog.coords.qdd)
    found = []
    for category, term in zip(catalog.categories_, catalog.feature_terms_, strict=True):
        if (category == "classical" and not (term.free_symbols & accelerations)
                and term not in found):
            found.append(term)
    if not found:
        raise ValueError("catalog: no classical term without acceleration")
    return found


class SINDyBaseline:
    """Plain pysindy.SINDy on ``[q, qd]`` with classical-catalog ``terms`` (module docstring);
    ``optimizer`` defaults to ``pysindy.STLSQ()``. Fitted: ``model_`` (the SINDy model),
    ``forced_`` (n,) (coordinates whose force entered the fit), ``feature_exprs_`` (``terms``
    then those forces), ``coef_`` (n, n_features) (the acceleration rows) and ``dynamics_``.

    Parameters
    ----------
    coords : pysindy_xl.Coordinates
        The generalized coordinates.
    terms : sequence of sympy.Expr
        Library terms in ``q`` and ``qd`` (:func:`baseline_terms`).
    optimizer : pysindy optimizer, default=None
        None: ``pysindy.STLSQ()``.
    """

    def __init__(self, coords, terms, optimizer=None):
        self.coords = coords
        self.terms = terms
        self.optimizer = optimizer

    def fit(self, x, t, x_dot, x_ddot, u=None):
        """Fit on lists of per-trajectory arrays (the layout of ``Dataset.fit_arguments``).

        Parameters
        ----------
        x : list of numpy.ndarray of shape (N, n)
            Positions of each trajectory.
        t : list of numpy.ndarray of shape (N,) or float
            Times or time step.
        x_dot, x_ddot : list of numpy.ndarray of shape (N, n)
            Velocities and accelerations.
        u : list of numpy.ndarray of shape (N, n), default=None
            Generalized forces; None: unforced.

        Returns
        -------
        SINDyBaseline
            The fitted baseline.
        """
        import pysindy as ps

        from ..dynamics import MassMatrixDynamics
        coords = self.coords
        n = coords.n
        if x_dot is None or x_ddot is None:
            raise ValueError("x_dot, x_ddot: the baseline needs measured velocities and "
                             "accelerations (as every configuration of the benchmark)")
        states = [np.hstack([q, qd]) for q, qd in zip(x, x_dot, strict=True)]
        derivatives = [np.hstack([qd, qdd]) for qd, qdd in zip(x_dot, x_ddot, strict=True)]
        forced = np.zeros(n, dtype=bool)
        if u is not None:
            forced = np.any(np.vstack(u) != 0, axis=0)
        inputs = list(coords.q) + list(coords.qd) + [coords.tau[i] for i in np.flatnonzero(forced)]
        controls = [np.asarray(a)[:, forced] for a in u] if forced.any() else None
        features = list(self.terms) + [coords.tau[i] for i in np.flatnonzero(forced)]
        # lambdify gives one positional argument per input, which is how CustomLibrary reads
        # a function's arity: each feature is then applied once, to all inputs in order.
        functions = [sp.lambdify(inputs, f, "numpy") for f in features]
        labels = [(lambda *_, s=str(f): s) for f in features]
        library = ps.CustomLibrary(library_functions=functions, function_names=labels,
                                   include_bias=False)
        optimizer = self.optimizer if self.optimizer is not None else ps.STLSQ()
        model = ps.SINDy(optimizer=optimizer, feature_library=library)
        model.fit(states, t=list(t), x_dot=derivatives, u=controls)
        coef = np.asarray(model.coefficients())[n:]  # the qdd rows
        if coef.shape != (n, len(features)):
            raise RuntimeError(f"internal error: unexpected SINDy coefficients {coef.shape}")
        equations = [
            coords.qdd[i] - sum((sp.Float(c) * f for c, f in zip(coef[i], features, strict=True)
                                 if c != 0), sp.Integer(0))
            for i in range(n)
        ]
        self.model_ = model
        self.forced_ = forced
        self.feature_exprs_ = features
        self.coef_ = coef
        self.dynamics_ = MassMatrixDynamics(coords, equations)
        return self

    def get_feature_names(self) -> list[str]:
        """Names of the features: the terms, then the forces.

        Returns
        -------
        list of str
            One name per feature.
        """
        return [str(f) for f in self.feature_exprs_]

    def simulate(self, x0, t, u=None, **integrator_options) -> np.ndarray:
        """Simulate like :meth:`pysindy_xl.XLSINDy.simulate` (same integrator and checks).

        Parameters
        ----------
        x0 : array_like of shape (2n,)
            Initial state ``[q, qd]``.
        t : array_like of shape (T,)
            Output times.
        u : array_like of shape (T, n) or callable, default=None
            Generalized forces.
        **integrator_options
            Passed to the integrator.

        Returns
        -------
        numpy.ndarray of shape (T, 2n)
            The simulated states.
        """
        return self.dynamics_.simulate(x0, t, u, **integrator_options)
