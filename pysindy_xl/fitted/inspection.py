"""What a fitted model says: :class:`InspectionMixin`, the part of :class:`~pysindy_xl.XLSINDy`
that reads ``coef_`` and ``feature_library_`` and reports them.
"""

from __future__ import annotations

import copy

import numpy as np
import sympy as sp
from sklearn.utils.validation import check_is_fitted

from .._inputs import check_array, sample_times
from ..fit import differentiation_function
from ..fit.still import held_note
from ..physical.structure import has_parameter_map
from ..weak import WhittakerSmoother
from .equations import (
    consistency_line,
    equation_strings,
    identified_lagrangian,
    parameter_lines,
    physical_parameters,
    prints_equations,
    significant,
    uncertainty_lines,
)

__all__ = ["InspectionMixin"]


class InspectionMixin:
    """Coefficients, names, equations, Lagrangian, physical parameters and printing."""

    def coefficients(self) -> np.ndarray:
        """Identified coefficient vector.

        Returns
        -------
        ndarray, shape (F,)
            In the order of :meth:`get_feature_names`.
        """
        check_is_fitted(self, "coef_")
        return self.coef_.copy()

    @property
    def complexity(self) -> int:
        """Number of non-zero coefficients (as ``pysindy.SINDy.complexity``).

        Returns
        -------
        int
        """
        check_is_fitted(self, "coef_")
        return int(np.count_nonzero(self.coef_))

    def differentiate(self, x, t=None):
        """Velocities of positions ``x`` as the model estimates them (as ``SINDy.differentiate``):
        its ``differentiation_method``, else the weak form's smoother.

        Parameters
        ----------
        x : array (N, n) or (N,) for one coordinate
        t : float or array (N,), optional
            Time step or sample times; default ``t_default``.

        Returns
        -------
        ndarray, shape (N, n)

        Examples
        --------
        >>> import numpy as np, pysindy_xl as px
        >>> t = np.linspace(0, 6, 601)
        >>> xd = px.XLSINDy().differentiate(np.sin(t), t)
        >>> bool(np.abs(xd[:, 0] - np.cos(t)).max() < 1e-4)
        True
        """
        x = check_array(x, "x", n_columns=1 if np.ndim(x) == 1 else None)
        t = sample_times(self.t_default if t is None else t, x.shape[0], "t")
        if self.differentiation_method is not None:
            return differentiation_function(self.differentiation_method)(x, t)
        return (copy.deepcopy(self.smoother) or WhittakerSmoother()).smooth(t, x)[1]

    def get_feature_names(self) -> list[str]:
        """Names of the catalog features.

        Returns
        -------
        list of str
            In coefficient order: ``F[...]`` forces, ``L[...]`` Lagrangian terms,
            ``C_<coordinate>[...]`` classical terms.
        """
        check_is_fitted(self, "coef_")
        return self.feature_library_.get_feature_names()

    def equations(self, precision: int = 4) -> list[str]:
        """Identified equations of motion, one per coordinate, as ``lhs = forces``.

        Parameters
        ----------
        precision : int
            Significant digits of the printed coefficients.

        Returns
        -------
        list of str
            A coordinate held still reads ``<name>_ddot = 0 (held still)``.
        """
        check_is_fitted(self, "coef_")
        coords = self.feature_library_.coords
        held = set(getattr(self, "still_coordinates_", ()))
        return [f"{coords.qdd[i]} = 0 (held still)" if name in held else equation
                for i, (name, equation) in enumerate(zip(
                    coords.names, equation_strings(self.coef_, self.feature_library_,
                                                   precision), strict=True))]

    def lagrangian(self) -> sp.Expr:
        """Identified Lagrangian.

        Returns
        -------
        sympy.Expr
            The Lagrange terms weighted by their coefficients (0 without Lagrange terms).
        """
        check_is_fitted(self, "coef_")
        return identified_lagrangian(self.coef_, self.feature_library_)

    def physical_parameters(self) -> dict:
        """The identified model in physical terms: base parameters, friction per coordinate.

        A kinematic catalog's Lagrange terms stand for combinations of inertial parameters; the
        classical terms ``qd_c`` and ``tanh(k qd_c)`` are the viscous and dry friction of ``c``.
        Values are scaled to a force coefficient of -1 (unforced: no scale).

        Returns
        -------
        dict
            ``base_parameters``: ``{"feature", "stands_for", "value"}`` per Lagrange term;
            ``friction``: ``{coordinate: {"viscous", "dry"}}``; ``other``: other classical terms;
            ``scale``: the factor applied (None unforced). With joint friction models,
            ``joint_friction``: ``{joint: {model: value}}`` (``viscous``, ``coulomb``,
            ``asymmetric``, ``stribeck``, ``offset``, ``coulomb_positive``/``coulomb_negative``,
            ``coordinate``).

        Examples
        --------
        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2]) + px.ClassicalLibrary(
        ...     c, [c.qd[0]])
        >>> t = np.linspace(0, 5, 501)
        >>> x, xd, xdd = np.sin(t)[:, None], np.cos(t)[:, None], -np.sin(t)[:, None]
        >>> model = px.XLSINDy(lib).fit(x, t, x_dot=xd, x_ddot=xdd, u=2 * xdd + 0.5 * xd + x)
        >>> friction = model.physical_parameters()["friction"]["x"]
        >>> round(friction["viscous"], 6), friction["dry"]
        (0.5, 0.0)
        """
        check_is_fitted(self, "coef_")
        return physical_parameters(self.coef_, self.feature_library_)

    def print(self, precision: int = 4, uncertainty: bool = False,
              equations: bool | None = None) -> None:
        """Print the identified model.

        Parameters
        ----------
        precision : int
            Significant digits of the printed coefficients.
        uncertainty : bool, default False
            After an ensemble fit, also print each included term's interval and probability.
        equations : bool, optional
            Print the Lagrangian and equations; default True unless the terms stand for physical
            parameters and the equations are long. Physical parameters, the held-still note and the
            consistency line are printed in any case.
        """
        check_is_fitted(self, "coef_")
        note = held_note(getattr(self, "still_coordinates_", ()))
        if uncertainty:
            if self.inclusion_probability_ is None:
                raise ValueError("uncertainty: needs a fit with an EnsembleOptimizer")
            for line in uncertainty_lines(self.get_feature_names(), self.coef_, self.coef_interval_,
                                          self.inclusion_probability_, precision):
                print(line)
        if has_parameter_map(self.feature_library_):
            for line in parameter_lines(self.physical_parameters(), precision):
                print(line)
        consistency = consistency_line(getattr(self, "physical_consistency_", None))
        if consistency:
            print(consistency)
        if prints_equations(self, equations):
            lagrangian = self.lagrangian()
            if lagrangian != 0:
                print(f"L = {significant(lagrangian, precision)}")
            for name, eq in zip(self.feature_library_.coords.names, self.equations(precision),
                                strict=True):
                print(f"({name}) {eq}")
        if note:
            print(note)
