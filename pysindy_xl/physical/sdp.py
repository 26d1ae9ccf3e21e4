r"""Semidefinite programs of physical consistency (cvxpy, imported on first use).

Given a :class:`~pysindy_xl.physical.PhysicalStructure`, rigid bodies' constraints on ``pi``
are linear matrix inequalities (Wensing, Kim and Slotine, 2017): :math:`J_b(\pi) \succeq 0`
per body and :math:`a_j \ge 0` per armature. :func:`realize` finds ``pi`` reproducing base
parameters (the MJCF export); :func:`consistent_least_squares` fits under the constraints.
"""

from __future__ import annotations

import collections
import dataclasses
import functools
import hashlib
import threading

import numpy as np

from .._optional import import_optional

__all__ = ["body_constraints", "realize", "consistent_least_squares"]


def _cvxpy():
    return import_optional("cvxpy", "physically consistent identification")


def body_constraints(structure, pi) -> list:
    r"""Rigid bodies' constraints on a cvxpy variable: :math:`J_b(\pi) \succeq 0`, armatures
    :math:`\ge 0`.

    Parameters
    ----------
    structure : PhysicalStructure
        Which entries of ``pi`` are each body's parameters and the armatures.
    pi : cvxpy.Variable
        The physical parameters.

    Returns
    -------
    list of cvxpy constraints
        One semidefinite constraint per body (:func:`~pysindy_xl.physical.pseudo_inertia_matrix`)
        and the armatures' signs.
    """
    from .structure import pseudo_inertia_matrix

    cp = _cvxpy()
    # J is linear in the ten parameters: one affine map per body (fast to canonicalize)
    basis = np.array([pseudo_inertia_matrix(unit) for unit in np.eye(10)]).reshape(10, 16)
    constraints = []
    for indices in structure.body_indices:
        pseudo = cp.reshape(basis.T @ pi[np.asarray(indices, dtype=int)], (4, 4), order="C")
        constraints.append((pseudo + pseudo.T) / 2 >> 0)
    if len(structure.armature):
        constraints.append(pi[structure.armature] >= 0)
    return constraints


#: Solvers tried in turn when none is named: interior point, then first order (SCS), which
#: proceeds where the former stalls.
DEFAULT_SOLVERS = ("CLARABEL", "SCS")


@functools.cache
def _default_solvers() -> tuple:
    installed = _cvxpy().installed_solvers()
    return tuple(name for name in DEFAULT_SOLVERS if name in installed) or (None,)


def _solve(problem, solver, who):
    cp = _cvxpy()
    solvers = [solver] if solver is not None else _default_solvers()
    for name in solvers:
        try:
            problem.solve(solver=name)
        except cp.error.SolverError as error:
            failure = f"the semidefinite program failed ({error})"
            continue
        if problem.status in ("optimal", "optimal_inaccurate"):
            return
        failure = f"the semidefinite program ended {problem.status!r}"
    raise RuntimeError(f"{who}: {failure}")


def realize(structure, beta, reference=None, closeness: float = 1e-6, solver=None):
    r"""Physically consistent parameters ``pi`` reproducing base parameters ``beta``:

    .. math:: \min_\pi \; \|C \pi - \beta\| / \|\beta\| + \epsilon \|\pi - \pi_0\|^2 /
              \|\pi_0\|^2 \quad \text{s.t.} \quad J_b(\pi) \succeq 0, \; a_j \ge 0

    (the unsquared residual is an exact penalty).

    Parameters
    ----------
    structure : PhysicalStructure
        The meaning of ``beta`` (``combination`` ``C``, bodies, armatures).
    beta : array, shape (k,)
        Base parameters.
    reference : array, shape (len(structure.names),), optional
        ``pi_0``, the parameters to stay close to; default None: zeros.
    closeness : float, default 1e-6
        ``epsilon``.
    solver : str, optional
        cvxpy solver name; default None: as in :func:`consistent_least_squares`.

    Returns
    -------
    pi : ndarray, shape (len(structure.names),)
        Physically consistent parameters.
    residual : float
        ``|C pi - beta| / |beta|``, zero when ``beta`` is realizable by rigid bodies.
    """
    cp = _cvxpy()
    beta = np.asarray(beta, dtype=float)
    combination = structure.combination
    reference = (np.zeros(len(structure.names)) if reference is None
                 else np.asarray(reference, dtype=float))
    pi = cp.Variable(len(structure.names))
    scale_beta = max(np.linalg.norm(beta), 1e-12)
    scale_pi = max(np.linalg.norm(reference), scale_beta, 1e-12)
    objective = (cp.norm(combination @ pi - beta) / scale_beta
                 + closeness * cp.sum_squares(pi - reference) / scale_pi**2)
    problem = cp.Problem(cp.Minimize(objective), body_constraints(structure, pi))
    _solve(problem, solver, "realize")
    if pi.value is None:
        raise RuntimeError("realize: the semidefinite program found no solution")
    value = np.asarray(pi.value, dtype=float)
    return value, float(np.linalg.norm(combination @ value - beta) / scale_beta)


@dataclasses.dataclass
class _Program:
    problem: object
    b: object
    pi: object
    factor: object
    target: object
    base_scale: object
    zero: object
    weight: object
    lock: threading.Lock = dataclasses.field(default_factory=threading.Lock)


_PROGRAMS: collections.OrderedDict = collections.OrderedDict()
_PROGRAMS_LOCK = threading.Lock()


def _least_squares_program(structure, n_columns: int) -> _Program:
    """The program of :func:`consistent_least_squares` for one structure and width, with its data
    as cvxpy parameters: canonicalized once, then solved for each new fit (cached, at most 16).
    """
    key = hashlib.sha1(b"".join(np.ascontiguousarray(a, dtype=float).tobytes() + str(
        np.shape(a)).encode() for a in (
            structure.combination, structure.base_columns, structure.friction_columns,
            structure.armature, structure.body_indices, [n_columns]))).hexdigest()
    with _PROGRAMS_LOCK:
        if key in _PROGRAMS:
            _PROGRAMS.move_to_end(key)
            return _PROGRAMS[key]
    cp = _cvxpy()
    base = structure.base_columns
    b = cp.Variable(n_columns)
    pi = cp.Variable(len(structure.names))
    factor = cp.Parameter((n_columns, n_columns))
    target = cp.Parameter(n_columns)
    base_scale = cp.Parameter(len(base))
    zero = cp.Parameter(n_columns, nonneg=True)
    weight = cp.Parameter(nonneg=True)
    constraints = body_constraints(structure, pi)
    # base parameters: b_j / scale_j = C_j pi (in the unit-RMS columns)
    if len(base):
        constraints.append(b[base] == cp.multiply(base_scale, structure.combination @ pi))
    if len(structure.friction_columns):
        constraints.append(b[structure.friction_columns] >= 0)
    constraints.append(cp.multiply(zero, b) == 0)
    problem = cp.Problem(cp.Minimize(cp.norm(factor @ b - target)
                                     + weight * cp.sum_squares(pi)), constraints)
    program = _Program(problem, b, pi, factor, target, base_scale, zero, weight)
    with _PROGRAMS_LOCK:
        _PROGRAMS[key] = program
        while len(_PROGRAMS) > 16:
            _PROGRAMS.popitem(last=False)
    return program


def consistent_least_squares(x, structure, coef, normal=None, zero=None, solver=None,
                             regularization: float = 1e-9):
    r"""Least squares under physical consistency, as the projection of an unconstrained fit.

    With ``b_u`` the unconstrained fit and ``A`` its normal matrix,
    ``|x b - y|^2 = |x b_u - y|^2 + (b - b_u)^T A (b - b_u)``, so the constrained fit is

    .. math:: \min_{b, \pi} \; (b - b_u)^T A (b - b_u) \quad \text{s.t.} \quad
              b_{\mathcal B} = C \pi, \; J_k(\pi) \succeq 0, \; a_j \ge 0, \;
              b_{\mathcal F} \ge 0,

    solved as the norm of :math:`A^{1/2} (b - b_u)` on unit-RMS columns, plus
    ``regularization * |pi|^2`` (relative) to bound what the data leave free. A consistent
    ``b_u`` is its own solution.

    Parameters
    ----------
    x : array, shape (n_rows, F)
        The regression's columns.
    structure : PhysicalStructure
        In the column indices of ``x``.
    coef : array, shape (F,)
        ``b_u``.
    normal : array, shape (F, F), optional
        ``A``; default ``x^T x``.
    zero : array of bool, shape (F,), optional
        Coefficients held at zero; default None.
    solver : str, optional
        cvxpy solver name; default the first of :data:`DEFAULT_SOLVERS` that succeeds.
    regularization : float, default 1e-9
        Weight of the relative ``|pi|^2`` term.

    Returns
    -------
    coef : ndarray, shape (F,)
        Consistent coefficients (base parameters exactly ``C pi``).
    pi : ndarray, shape (len(structure.names),)
        One realization, exactly consistent.
    cost : float
        ``(b - b_u)^T A (b - b_u) / b_u^T A b_u``, the share of the explained signal lost.
    """
    x = np.asarray(x, dtype=float)
    coef = np.asarray(coef, dtype=float)
    scale = np.sqrt(np.mean(x**2, axis=0))
    scale[scale == 0] = 1.0
    # relative column scales only: the constraints tying b to pi stay of order one
    scale = scale / np.exp(np.mean(np.log(scale)))
    normal = x.T @ x if normal is None else np.asarray(normal, dtype=float)
    normal = normal / np.outer(scale, scale)
    scaled = coef * scale
    values, vectors = np.linalg.eigh((normal + normal.T) / 2)
    factor = np.sqrt(np.clip(values, 0.0, None))[:, None] * vectors.T
    size = max(float(np.linalg.norm(factor @ scaled)), 1e-300)
    factor = factor / size
    # pi's own scale: that of the base parameters it makes
    base = structure.base_columns
    pi_scale = max(float(np.linalg.norm(coef[base])), 1e-12) if len(base) else 1.0
    program = _least_squares_program(structure, len(coef))
    with program.lock:  # the program's parameters are set, then it is solved
        program.factor.value = factor
        program.target.value = factor @ scaled
        program.base_scale.value = scale[base]
        program.zero.value = (np.zeros(len(coef)) if zero is None
                              else np.asarray(zero, dtype=float))
        program.weight.value = regularization / pi_scale**2
        _solve(program.problem, solver, "consistent_least_squares")
        b, pi = program.b.value, program.pi.value
    if b is None or pi is None:
        raise RuntimeError("consistent_least_squares: the semidefinite program found no solution")
    b, pi = np.array(b, dtype=float), np.array(pi, dtype=float)
    pi_value = structure.nearest_consistent(pi)
    out = b / scale
    out[base] = structure.combination @ pi_value  # exactly the realized base parameters
    if zero is not None:
        out[np.asarray(zero, dtype=bool)] = 0.0
    if len(structure.friction_columns):
        out[structure.friction_columns] = np.maximum(out[structure.friction_columns], 0.0)
    return out, pi_value, float(np.sum((factor @ (out * scale - scaled)) ** 2))
