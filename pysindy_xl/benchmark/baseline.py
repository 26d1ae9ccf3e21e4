"""The extra row of the table: plain :class:`pysindy.SINDy`, second order, classical catalog.

SINDy fits a first-order system, so the state is ``x = [q, qd]`` with ``x_dot = [qd, qdd]``
(measured, like every configuration) and the generalized forces as control input ``u``. Its
library holds the terms of the same classical catalog as the ``classical`` rows (the smallest
one containing the Euler-Lagrange expansion of the Lagrangian catalog, plus friction) that an
explicit model ``qdd = f(q, qd, u)`` can use: the terms without acceleration (those with one
belong to the left-hand side ``M(q) qdd``, which SINDy cannot express), and the forces
linearly. Each term is a :class:`pysindy.CustomLibrary` function of all inputs, available to
every equation (plain SINDy has no per-equation mask). The optimizer is pysindy's default
:class:`pysindy.STLSQ`.

For validation the fitted ``qdd`` rows become the equations ``qdd_i - f_i(q, qd, u) = 0`` and
are simulated with the same integrator and divergence checks as the XL-SINDy models
(:class:`~pysindy_xl.dynamics.MassMatrixDynamics` with ``M = I``), so every row of the table is
validated the same way.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

__all__ = ["SINDyBaseline", "baseline_terms"]


def baseline_terms(catalog) -> list[sp.Expr]:
    """Terms of a classical catalog (e.g. ``reference_catalog(system, "classical")``) that an
    explicit model ``qdd = f(q, qd, u)`` can use: the distinct classical terms without any
    acceleration symbol, in catalog order."""
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
    """Plain pysindy.SINDy on ``[q, qd]`` with classical-catalog terms (see the module doc).

    Parameters
    ----------
    coords : Coordinates
    terms : list of sympy.Expr
        Candidate terms in ``q`` and ``qd`` (see :func:`baseline_terms`).
    optimizer : pysindy optimizer, optional
        Default ``pysindy.STLSQ()``.

    Attributes
    ----------
    model_ : pysindy.SINDy
    forced_ : ndarray of bool, shape (n,)
        Coordinates whose force entered the fit (non-zero in the data).
    feature_exprs_ : list of sympy.Expr
        The library features: ``terms`` then the forces used.
    coef_ : ndarray, shape (n, n_features)
        The acceleration rows of the SINDy coefficients.
    dynamics_ : MassMatrixDynamics
    """

    def __init__(self, coords, terms, optimizer=None):
        self.coords = coords
        self.terms = terms
        self.optimizer = optimizer

    def fit(self, x, t, x_dot, x_ddot, u=None):
        """Fit on lists of per-trajectory arrays (the layout of ``Dataset.fit_arguments``)."""
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
        return [str(f) for f in self.feature_exprs_]

    def simulate(self, x0, t, u=None, **integrator_options) -> np.ndarray:
        """Simulate like :meth:`pysindy_xl.XLSINDy.simulate` (same integrator and checks)."""
        return self.dynamics_.simulate(x0, t, u, **integrator_options)
