"""Readable forms of a fitted catalog ``library`` and its coefficients ``coef`` (F,):
equations, Lagrangian, uncertainty, physical parameters; ``precision`` is the number of
significant digits printed.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from ..physical.structure import friction_kind, has_parameter_map

__all__ = ["significant", "equation_strings", "identified_lagrangian", "uncertainty_lines"]


def significant(expr: sp.Expr, digits: int) -> sp.Expr:
    """``expr`` with every float rounded to ``digits`` significant digits.

    Parameters
    ----------
    expr : sympy.Expr
        An expression.
    digits : int
        Significant digits kept.

    Returns
    -------
    sympy.Expr
        The expression with its floats rounded.

    Examples
    --------
    >>> import sympy as sp
    >>> significant(sp.Float(3.14159) * sp.Symbol("x"), 3)
    3.14*x
    """
    return expr.xreplace({f: sp.Float(float(f"{float(f):.{digits}g}")) for f in
                          expr.atoms(sp.Float)})


def equation_strings(coef: np.ndarray, library, precision: int) -> list[str]:
    """One ``lhs = forces`` string per coordinate.

    Parameters
    ----------
    coef : numpy.ndarray of shape (F,)
        Coefficients, one per feature of ``library``.
    library : pysindy_xl.CatalogRepartition
        The fitted catalog.
    precision : int
        Significant digits printed.

    Returns
    -------
    list of str
        ``"lhs = forces"``, one per coordinate: the identified terms on the left, the force
        columns on the right.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> lib = px.CatalogRepartition([px.ExternalForces(c),
    ...                              px.LagrangeLibrary(c, [c.qd[0] ** 2])]).fit()
    >>> equation_strings(np.array([-1.0, 0.5]), lib, 3)
    ['1.0*x_ddot = tau_x']
    """
    matrix = library.symbolic_matrix_
    forces = set(library.force_columns_)
    active = np.flatnonzero(coef)
    out = []
    for i in range(matrix.shape[0]):
        lhs = sp.Add(*(sp.Float(coef[j]) * matrix[i, j] for j in active if j not in forces))
        rhs = sp.Add(*(matrix[i, j] if coef[j] == -1 else -sp.Float(coef[j]) * matrix[i, j]
                       for j in forces))
        out.append(f"{significant(sp.expand(lhs), precision)} = "
                   f"{significant(sp.expand(rhs), precision)}")
    return out


def identified_lagrangian(coef: np.ndarray, library) -> sp.Expr:
    """The Lagrange terms of ``library`` weighted by ``coef`` (0 without Lagrange terms).

    Parameters
    ----------
    coef : numpy.ndarray of shape (F,)
        Coefficients, one per feature of ``library``.
    library : pysindy_xl.CatalogRepartition
        The fitted catalog.

    Returns
    -------
    sympy.Expr
        ``sum_j coef_j L_j`` over the Lagrange terms ``L_j`` of the catalog.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> lib = px.CatalogRepartition([px.ExternalForces(c),
    ...                              px.LagrangeLibrary(c, [c.qd[0] ** 2])]).fit()
    >>> identified_lagrangian(np.array([-1.0, 0.5]), lib)
    0.5*x_dot**2
    """
    return sp.Add(*(sp.Float(coef[j]) * library.feature_terms_[j]
                    for j, category in enumerate(library.categories_)
                    if category == "lagrange" and coef[j] != 0))


def uncertainty_lines(names, coef, interval, probability, precision: int) -> list[str]:
    """``name  coefficient  [low, high]  P=p`` for every term an ensemble fit included, most
    probable first.

    Parameters
    ----------
    names : sequence of str
        Feature names.
    coef : numpy.ndarray of shape (F,)
        Coefficients.
    interval : numpy.ndarray of shape (2, F)
        Lower and upper bounds of each coefficient.
    probability : numpy.ndarray of shape (F,)
        Inclusion probability of each feature.
    precision : int
        Significant digits printed.

    Returns
    -------
    list of str
        One line per feature with a non-zero inclusion probability.

    Examples
    --------
    >>> import numpy as np
    >>> uncertainty_lines(["a", "bb"], np.array([1.0, 0.0]), np.array([[0.9, 0], [1.1, 0.2]]),
    ...                   np.array([1.0, 0.3]), 2)
    ['a    1  [ 0.9,  1.1]  P=1.00', 'bb   0  [ 0,  0.2]  P=0.30']
    """
    shown = [j for j in np.argsort(-probability, kind="stable") if probability[j] > 0]
    width = max((len(names[j]) for j in shown), default=0)
    return [f"{names[j]:<{width}}  {coef[j]: .{precision}g}  "
            f"[{interval[0, j]: .{precision}g}, {interval[1, j]: .{precision}g}]  "
            f"P={probability[j]:.2f}" for j in shown]


#: Monomials above which a model with physical parameters prints only its parameters.
SHORT_EQUATIONS = 200


def prints_equations(model, equations=None) -> bool:
    """Whether the model prints its equations: ``equations`` if given, else unless its terms stand
    for physical parameters and the equations are long.

    Parameters
    ----------
    model : pysindy_xl.XLSINDy
        A fitted model.
    equations : bool or None, default=None
        An explicit choice; None decides from the model.

    Returns
    -------
    bool
        Whether the equations are printed.
    """
    if equations is not None:
        return bool(equations)
    dynamics = model.dynamics_
    return not has_parameter_map(model.feature_library_) or (
        dynamics is not None and dynamics.n_terms <= SHORT_EQUATIONS)


def physical_parameters(coef: np.ndarray, library) -> dict:
    """The identified model in physical terms (:meth:`XLSINDy.physical_parameters
    <pysindy_xl.XLSINDy.physical_parameters>`).

    Parameters
    ----------
    coef : numpy.ndarray of shape (F,)
        Coefficients, one per feature of ``library``.
    library : pysindy_xl.CatalogRepartition
        The fitted catalog.

    Returns
    -------
    dict
        ``scale`` (the factor making the force coefficient -1, None without forces),
        ``base_parameters`` (``feature``, ``stands_for``, ``value`` each), ``friction``
        (``{coordinate: {"viscous", "dry"}}``), ``other`` (the remaining classical terms) and,
        with joint models, ``joint_friction``.
    """
    forces = [coef[j] for j in library.force_columns_ if coef[j] != 0]
    scale = -1.0 / forces[0] if forces else None
    factor = 1.0 if scale is None else scale
    base = []
    for lib, columns in zip(library.libraries_, library.slices_, strict=True):
        if lib.category != "lagrange":
            continue
        maps = getattr(lib, "parameters", None)
        for k in range(lib.n_output_features_):
            base.append({"feature": library.feature_names_[columns.start + k],
                         "stands_for": None if maps is None else dict(maps[k]),
                         "value": float(coef[columns.start + k] * factor)})
    friction = {name: {"viscous": 0.0, "dry": 0.0} for name in library.coords.names}
    joints, modelled = joint_friction(coef * factor, library)
    other = {}
    for j, category in enumerate(library.categories_):
        if category != "classical" or coef[j] == 0 or j in modelled:
            continue
        c = next(i for i in range(library.coords.n) if library.symbolic_matrix_[i, j] != 0)
        name = library.coords.names[c]
        kind = friction_kind(library.feature_terms_[j], library.coords.qd[c], library.coords.qdd[c])
        if kind is not None:
            friction[name][kind] += float(coef[j] * factor)
        else:
            other[library.feature_names_[j]] = float(coef[j] * factor)
    for values in joints.values():
        if values["coordinate"] is not None:
            friction[values["coordinate"]]["viscous"] += values.get("viscous", 0.0)
            friction[values["coordinate"]]["dry"] += values.get("coulomb", 0.0)
    out = {"scale": scale, "base_parameters": base, "friction": friction, "other": other}
    if joints:
        out["joint_friction"] = joints
    return out


def joint_friction(coef, library) -> tuple[dict, set]:
    """``({joint: {model: value}}, columns)`` of the catalog's joint models (with
    ``coulomb_positive``/``coulomb_negative`` where asymmetric, and ``coordinate``).

    Parameters
    ----------
    coef : numpy.ndarray of shape (F,)
        Coefficients, one per feature of ``library``.
    library : pysindy_xl.CatalogRepartition
        The fitted catalog.

    Returns
    -------
    joints : dict
        ``{joint: {model: value, "coordinate": name}}``.
    columns : set of int
        The columns of the joint models.
    """
    joints, columns = {}, set()
    for lib, block in zip(library.libraries_, library.slices_, strict=True):
        if getattr(lib, "kinds_", None) is None:
            continue
        for joint, values in lib.coefficients_by_joint(coef[block]).items():
            values["coordinate"] = lib.coordinate_of(joint)
            if "coulomb" in values and "asymmetric" in values:
                values["coulomb_positive"] = values["coulomb"] + values["asymmetric"]
                values["coulomb_negative"] = values["coulomb"] - values["asymmetric"]
            joints[joint] = values
        columns.update(range(block.start, block.stop))
    return joints, columns


def consistency_line(report) -> str | None:
    """The line saying whether a physically constrained fit had to constrain, or None.

    Parameters
    ----------
    report : dict or None
        The ``physical_consistency_`` report of a fit.

    Returns
    -------
    str or None
        The line, None without report.

    Examples
    --------
    >>> consistency_line({"consistent": False, "cost": 0.012, "negative_friction": ["C_a[a_dot]"],
    ...                   "min_pseudo_inertia_eigenvalue": 0.0})[:71]
    'physical consistency: the unconstrained estimate is not that of rigid b'
    """
    if report is None:
        return None
    if report["consistent"]:
        return ("physical consistency: the unconstrained estimate is that of rigid bodies "
                "(kept as it is)")
    friction = report["negative_friction"]
    friction = f"; negative friction: {', '.join(friction)}" if friction else ""
    return (f"physical consistency: the unconstrained estimate is not that of rigid bodies "
            f"(the constraints cost {report['cost']:.2g} of the explained signal{friction}); "
            f"constrained to consistent parameters")


def parameter_lines(parameters: dict, precision: int, reference: dict | None = None) -> list[str]:
    """Printable lines of :func:`physical_parameters` (base parameters with what they stand for,
    friction per coordinate), with a ``reference``'s values beside.

    Parameters
    ----------
    parameters : dict
        Of :func:`physical_parameters`.
    precision : int
        Significant digits printed.
    reference : dict, default=None
        Another :func:`physical_parameters` (the truth), shown beside.

    Returns
    -------
    list of str
        The lines.
    """
    known = ({entry["feature"]: entry["value"] for entry in reference["base_parameters"]}
             if reference is not None else None)
    lines = ["base parameters (value  |  stands for):" if known is None
             else "base parameters (value  |  true value  |  stands for):"]
    for entry in parameters["base_parameters"]:
        true = None if known is None else known.get(entry["feature"])
        if entry["value"] == 0 and not true:
            continue
        meaning = entry["stands_for"]
        meaning = (" + ".join(f"{w:.{precision}g}*{name}" for name, w in meaning.items())
                   if meaning else entry["feature"])
        beside = "" if known is None else f"  |  {true or 0:>12.{precision}g}"
        lines.append(f"  {entry['value']:>12.{precision}g}{beside}  |  {meaning}")
    lines.append("friction per coordinate (viscous, dry):")
    for name, values in parameters["friction"].items():
        line = f"  {name}: {values['viscous']:.{precision}g}, {values['dry']:.{precision}g}"
        if reference is not None and name in reference["friction"]:
            true = reference["friction"][name]
            line += f" (true {true['viscous']:.{precision}g}, {true['dry']:.{precision}g})"
        lines.append(line)
    lines += [f"  {name}: {value:.{precision}g}" for name, value in parameters["other"].items()]
    if parameters.get("joint_friction"):
        lines.append("joint friction and sensor models (0: not needed):")
        lines += [f"  {joint}: " + ", ".join(f"{model} {value:.{precision}g}"
                                             for model, value in values.items()
                                             if model != "coordinate")
                  for joint, values in parameters["joint_friction"].items()]
    if parameters["scale"] is None:
        lines.append("(no force fixes the scale: values up to a common factor)")
    return lines
