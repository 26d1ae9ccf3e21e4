r"""Friction and sensor models of real joints, linear in their parameters.

Each joint ``k`` of velocity ``v`` may carry any of these terms, a fixed function of ``v``
times an unknown coefficient (``eps`` and ``v_s`` fixed velocity scales):

==============  ================================================  =============================
model           function of the joint velocity ``v``              coefficient
==============  ================================================  =============================
``viscous``     ``v``                                             viscous friction ``f_v``
``coulomb``     ``tanh(v / eps)``                                 Coulomb friction ``f_c``
``asymmetric``  ``tanh(v / eps)^2``                               direction dependence ``f_a``
``stribeck``    ``tanh(v / eps) exp(-(v / v_s)^2)``               Stribeck excess ``f_s``
``offset``      ``1``                                             torque-sensor offset ``o``
==============  ================================================  =============================

The joint's torque acts on the coordinates as ``weights[:, k]`` times it (``B = T^-T`` for
coordinates ``q = T qpos``). Asymmetric Coulomb friction is ``f_c + f_a`` moving forwards,
``-(f_c - f_a)`` backwards; away from rest it is the same torque as an offset, told apart
only by samples near zero velocity.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from .._validation import Collection, InstanceOf, Interval, Options
from ..expressions import format_expression
from ..symbols import Coordinates
from ._base import SymbolicLibrary

__all__ = ["FRICTION_MODELS", "JointFrictionLibrary", "friction_function"]

#: The joint models, in the order of a joint's columns.
FRICTION_MODELS = ("viscous", "coulomb", "asymmetric", "stribeck", "offset")


def friction_function(model: str, velocity, coulomb_scale: float, stribeck_scale: float):
    """The function of a joint velocity that a friction model's coefficient multiplies.

    With ``eps`` = ``coulomb_scale`` and ``v_s`` = ``stribeck_scale`` (module docstring):
    viscous ``v``, coulomb ``tanh(v / eps)``, asymmetric ``tanh(v / eps)^2``, stribeck
    ``tanh(v / eps) exp(-(v / v_s)^2)``, offset ``1``.

    Parameters
    ----------
    model : str
        One of :data:`FRICTION_MODELS`.
    velocity : sympy.Expr
        The joint velocity.
    coulomb_scale : float
        ``eps``, velocity scale of the smooth sign.
    stribeck_scale : float
        ``v_s``, velocity scale of the Stribeck decay.

    Returns
    -------
    sympy.Expr
        The candidate term.

    Examples
    --------
    >>> import sympy as sp
    >>> v = sp.Symbol("v")
    >>> friction_function("stribeck", v, 0.01, 0.1)
    exp(-100.0*v**2)*tanh(100.0*v)
    """
    sign = sp.tanh(velocity / sp.Float(coulomb_scale))
    functions = {"viscous": velocity, "coulomb": sign, "asymmetric": sign**2,
                 "stribeck": sign * sp.exp(-(velocity / sp.Float(stribeck_scale)) ** 2),
                 "offset": sp.Integer(1)}
    if model not in functions:
        raise ValueError(f"models: expected names among {FRICTION_MODELS}, got {model!r}")
    return functions[model]


def _positive(value, name) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)) or not (
            np.isfinite(value) and value > 0):
        raise ValueError(f"{name}: expected a positive number, got {value!r}")
    return float(value)


class JointFrictionLibrary(SymbolicLibrary):
    """Friction and sensor-offset candidates of each joint (see the module docstring).

    One column per (joint, model). A fit that restricts its selection to these columns
    (``ExplicitOptimizer(select="friction")``) decides which model each joint needs.

    Parameters
    ----------
    coords : Coordinates
        The generalized coordinates.
    joints : sequence of str
        Joint names.
    velocities : sequence of sympy.Expr, optional
        Each joint's velocity in the coordinates; default ``coords.qd``.
    weights : array (n, len(joints)), optional
        The generalized force of a unit joint torque; default the identity.
    models : str or sequence of str, default :data:`FRICTION_MODELS`
        The candidate models of every joint, among ``"viscous"``, ``"coulomb"``,
        ``"asymmetric"``, ``"stribeck"`` and ``"offset"``.
    coulomb_scale : float, default 0.01
        ``eps``: velocity scale of the smooth sign.
    stribeck_scale : float, default 0.1
        ``v_s``: velocity scale of the Stribeck decay.

    Attributes
    ----------
    kinds_ : list of (str, str)
        ``(model, joint)`` of each feature.
    joints_ : list of str
        The joint names.
    weights_ : ndarray, shape (n, n_joints)
        The generalized force of a unit torque of each joint.

    Examples
    --------
    >>> import pysindy_xl as px
    >>> c = px.Coordinates(["a"])
    >>> lib = JointFrictionLibrary(c, ["hinge"], models=("viscous", "coulomb", "offset")).fit()
    >>> lib.get_feature_names()
    ['J_hinge.viscous[a_dot]', 'J_hinge.coulomb[tanh(100.0*a_dot)]', 'J_hinge.offset[1]']
    """

    category = "classical"
    column_rank = 2
    spec_type = "JointFrictionLibrary"
    _parameter_constraints = {
        "coords": [InstanceOf(Coordinates, "a pysindy_xl.Coordinates")],
        "joints": [Collection("a sequence of joint names")],
        "velocities": [None, Collection("a sequence of sympy expressions")],
        "weights": [None, Collection("an array of shape (n, n_joints)")],
        "models": [Options(FRICTION_MODELS), Collection("a sequence of friction model names")],
        "coulomb_scale": [Interval("real", 0, low_open=True)],
        "stribeck_scale": [Interval("real", 0, low_open=True)],
    }

    def __init__(self, coords: Coordinates, joints, velocities=None, weights=None,
                 models=FRICTION_MODELS, coulomb_scale=0.01, stribeck_scale=0.1):
        self.coords = coords
        self.joints = joints
        self.velocities = velocities
        self.weights = weights
        self.models = models
        self.coulomb_scale = coulomb_scale
        self.stribeck_scale = stribeck_scale

    def _resolved(self):
        joints = list(self.joints) if not isinstance(self.joints, str) else None
        if not joints or not all(isinstance(j, str) and j for j in joints) or len(
                set(joints)) != len(joints):
            raise ValueError(f"joints: expected distinct non-empty names, got {self.joints!r}")
        n = self.coords.n
        velocities = list(self.coords.qd) if self.velocities is None else [
            sp.sympify(v) for v in self.velocities]
        if len(velocities) != len(joints):
            raise ValueError(f"velocities: expected one per joint ({len(joints)}), got "
                             f"{len(velocities)}")
        allowed = set(self.coords.qd)
        for v in velocities:
            if not v.free_symbols or not v.free_symbols <= allowed:
                raise ValueError(f"velocities: {v} is not a function of the velocities "
                                 f"{[str(s) for s in self.coords.qd]}")
        weights = np.eye(n) if self.weights is None else np.asarray(self.weights, dtype=float)
        if weights.shape != (n, len(joints)) or not np.all(np.isfinite(weights)):
            raise ValueError(f"weights: expected finite numbers of shape {(n, len(joints))}, "
                             f"got shape {np.shape(self.weights)}")
        models = [self.models] if isinstance(self.models, str) else list(self.models)
        unknown = [m for m in models if m not in FRICTION_MODELS]
        if not models or unknown or len(set(models)) != len(models):
            raise ValueError(f"models: expected distinct names among {FRICTION_MODELS}, got "
                             f"{self.models!r}")
        models = [m for m in FRICTION_MODELS if m in models]  # a fixed order
        scales = (_positive(self.coulomb_scale, "coulomb_scale"),
                  _positive(self.stribeck_scale, "stribeck_scale"))
        return joints, velocities, weights, models, scales

    def _build_symbolic(self):
        joints, velocities, weights, models, scales = self._resolved()
        names, columns, kinds, terms = [], [], [], []
        for k, (joint, velocity) in enumerate(zip(joints, velocities, strict=True)):
            for model in models:
                term = friction_function(model, velocity, *scales)
                names.append(f"J_{joint}.{model}[{term}]")
                columns.append([sp.Float(w) * term if w != 1 else term for w in weights[:, k]])
                kinds.append((model, joint))
                terms.append(term)
        self.kinds_, self._terms, self.weights_ = kinds, terms, weights
        self.joints_ = joints
        return names, sp.Matrix(self.coords.n, len(names), lambda i, j: columns[j][i])

    def _feature_terms(self):
        return list(self._terms)

    def coefficients_by_joint(self, coef) -> dict:
        """This library's coefficients by joint and model.

        Parameters
        ----------
        coef : array, shape (F,)
            The coefficients of this library's features, in feature order.

        Returns
        -------
        dict
            ``{joint: {model: coefficient}}``.

        Examples
        --------
        >>> import pysindy_xl as px
        >>> c = px.Coordinates(["a"])
        >>> lib = JointFrictionLibrary(c, ["hinge"], models=("viscous", "coulomb")).fit()
        >>> lib.coefficients_by_joint([0.5, 0.2])
        {'hinge': {'viscous': 0.5, 'coulomb': 0.2}}
        """
        out = {}
        for (model, joint), value in zip(self.kinds_, np.asarray(coef, dtype=float), strict=True):
            out.setdefault(joint, {})[model] = float(value)
        return out

    def coordinate_of(self, joint: str) -> str | None:
        """The coordinate whose force is ``joint``'s torque.

        Parameters
        ----------
        joint : str
            A joint name of this library.

        Returns
        -------
        str or None
            The coordinate's name when the joint's torque enters exactly one coordinate, with
            weight 1; else None.
        """
        column = self.weights_[:, self.joints_.index(joint)]
        reached = np.flatnonzero(column)
        if len(reached) == 1 and column[reached[0]] == 1:
            return self.coords.names[reached[0]]
        return None

    def to_spec(self) -> dict:
        """JSON-serializable description of this library, read back by :meth:`from_spec`.

        Returns
        -------
        dict
            ``{"type": spec_type, ...}``: the parameters as plain JSON values, terms in the
            restricted grammar (:func:`~pysindy_xl.expressions.format_expression`).
        """
        joints, velocities, weights, models, scales = self._resolved()
        return {"type": self.spec_type, "joints": joints,
                "velocities": [format_expression(v) for v in velocities],
                "weights": weights.tolist(), "models": models,
                "coulomb_scale": scales[0], "stribeck_scale": scales[1]}

    @classmethod
    def from_spec(cls, spec, reader):
        """The library a specification describes (the inverse of :meth:`to_spec`).

        Parameters
        ----------
        spec : dict
            The description; untrusted (from a file).
        reader : SpecReader
            Parses its parts within the loader's budget
            (:class:`~pysindy_xl.feature_library.SpecReader`).

        Returns
        -------
        JointFrictionLibrary
            The library, not fitted.
        """
        joints = spec.get("joints")
        reader.expect(isinstance(joints, list) and all(isinstance(j, str) for j in joints),
                      "JointFrictionLibrary: 'joints' must be a list of names")
        velocities = reader.terms(spec, "velocities")
        reader.expect(len(velocities) == len(joints),
                      "JointFrictionLibrary: one velocity per joint expected")
        weights = reader.matrix(spec, "weights", (reader.coords.n, len(joints)),
                                shape_name="(n, n_joints)")
        models = spec.get("models")
        reader.expect(isinstance(models, list) and all(m in FRICTION_MODELS for m in models),
                      f"JointFrictionLibrary: 'models' must name models of {FRICTION_MODELS}")
        scales = [spec.get(key) for key in ("coulomb_scale", "stribeck_scale")]
        reader.expect(all(isinstance(s, (int, float)) and not isinstance(s, bool)
                          and np.isfinite(s) and s > 0 for s in scales),
                      "JointFrictionLibrary: the scales must be positive numbers")
        return cls(reader.coords, joints, velocities, weights, tuple(models), *scales)
