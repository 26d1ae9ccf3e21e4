"""What the catalog optimizers share: the template of a fit (:class:`CatalogOptimizer`: one entry
point ``fit_problem``, one method ``_solve`` to implement, one tags object), persistence
(:func:`optimizer_from_spec`) and column bookkeeping.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import scipy.linalg
from sklearn.base import BaseEstimator, clone

from .._validation import UnexplainedCoordinateWarning
from ..registry import is_plain, register_type
from .problem import CatalogProblem, abs_max, check_support, coordinate_weights, scale_blocks
from .tags import TAG_NAMES, CatalogTags, catalog_tags

__all__ = ["CatalogOptimizer", "OPTIMIZER_TYPES", "coordinates_touched", "independent_columns",
           "optimizer_from_spec", "pilot_optimizer", "solve_problem", "warn_unexplained"]

#: Every catalog optimizer by its ``spec_type``: what a model file may name.
OPTIMIZER_TYPES: dict[str, type] = {}

#: Optimizers nested in a file's optimizer (a mixed fit's parts, an ensemble's base) at most.
_MAX_NESTING = 3
#: Nesting of the lists a spec's parameter may be (the groups of columns: lists of lists).
_MAX_LIST_NESTING = 2


def solve_problem(optimizer, problem: CatalogProblem):
    """Fit ``optimizer`` on ``problem`` and return it.

    The package's optimizers get the whole problem, less the draws of the rows' errors unless
    their tag ``uses_noise_draws`` is set; any other object gets the bare
    ``fit_catalog(theta, n_coordinates, force_columns)``.

    Parameters
    ----------
    optimizer : CatalogOptimizer or object with ``fit_catalog``
        The optimizer, fitted in place.
    problem : CatalogProblem
        The regression problem.

    Returns
    -------
    CatalogOptimizer or object
        The fitted optimizer (what its ``fit_problem`` or ``fit_catalog`` returns).

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> theta = np.column_stack([[1.0, 2.0, 3.0], [0.5, 1.0, 1.5]])
    >>> problem = px.optimizers.CatalogProblem.from_arrays(theta, 1, [0])
    >>> solve_problem(px.ExplicitOptimizer(), problem).coef_
    array([-1.,  2.])
    """
    if isinstance(optimizer, CatalogOptimizer):
        if problem.noise_draws is not None and not catalog_tags(optimizer).uses_noise_draws:
            problem = dataclasses.replace(problem, noise_draws=None)
        return optimizer.fit_problem(problem)
    return optimizer.fit_catalog(problem.theta, problem.n_coordinates, problem.force_columns)


def pilot_optimizer(optimizer):
    """An unfitted optimizer for a cheap first estimate of the law ``optimizer`` would find.

    Its ``pilot()`` method where it has one (an ensemble: one fit of its base optimizer),
    otherwise a clone.

    Parameters
    ----------
    optimizer : estimator

    Returns
    -------
    estimator

    Examples
    --------
    >>> import pysindy_xl as px
    >>> pilot_optimizer(px.EnsembleOptimizer(px.ExplicitOptimizer(threshold=0.05)))
    ExplicitOptimizer(threshold=0.05)
    """
    pilot = getattr(optimizer, "pilot", None)
    return pilot() if callable(pilot) else clone(optimizer)


def coordinates_touched(theta, n_coordinates: int, rtol: float = 1e-10) -> np.ndarray:
    """Which coordinate equations each column enters.

    Parameters
    ----------
    theta : array, shape (n_coordinates * N, F)
        Regression matrix, rows coordinate-major.
    n_coordinates : int
        Number of blocks.
    rtol : float, default 1e-10
        A block is zero when its norm is at most ``rtol`` times the column's largest block's.

    Returns
    -------
    ndarray of bool, shape (n_coordinates, F)
        True where column ``j`` is non-zero in the block of coordinate ``c``.

    Examples
    --------
    >>> import numpy as np
    >>> coordinates_touched(np.array([[1.0, 0.0], [0.0, 2.0]]), 2).tolist()
    [[True, False], [False, True]]
    """
    theta = np.asarray(theta, dtype=float)
    blocks = theta.reshape(n_coordinates, -1, theta.shape[1])
    block_norms = np.linalg.norm(blocks, axis=1)
    top = block_norms.max(axis=0, initial=0.0)
    return (block_norms > 0) & (block_norms > rtol * top)


def warn_unexplained(owner: str, theta, n_coordinates: int, coef, force_columns=(),
                     stacklevel: int = 2, rtol: float = 1e-8) -> np.ndarray:
    """Warn (as ``owner``) when no identified term but the forces enters some coordinate's equation,
    whose model then cannot predict it; return those coordinates.

    A term explains a coordinate when its contribution there exceeds ``rtol`` times the largest
    contribution of any identified column.
    """
    coef = np.asarray(coef, dtype=float)
    used = np.flatnonzero(coef)
    # each term's contribution to each coordinate's equation (round-off ones explain nothing)
    contribution = np.linalg.norm(
        (np.asarray(theta)[:, used] * coef[used]).reshape(n_coordinates, -1, len(used)), axis=1)
    terms = ~np.isin(used, np.asarray(force_columns, dtype=int))
    scale = contribution.max(initial=0.0)
    explained = (contribution[:, terms] > rtol * scale).any(axis=1)
    unexplained = np.flatnonzero(~explained)
    if unexplained.size:
        besides = " besides the forces" if len(force_columns) else ""
        warnings.warn(f"{owner}: no identified term{besides} enters the equation of coordinate(s) "
                      f"{unexplained.tolist()}; the model cannot predict them",
                      UnexplainedCoordinateWarning, stacklevel=stacklevel + 1)
    return unexplained


def independent_columns(theta, priority=None, rtol: float = 1e-9, max_rows: int = 20_000,
                        n_blocks: int = 1, force_columns=None):
    """Split the columns of ``theta`` into a linearly independent set and the rest.

    Columns are visited in ``priority`` order and kept when their component orthogonal to the
    columns before exceeds ``rtol`` times their norm (QR of the column-normalized matrix on at
    most ``max_rows`` evenly spaced rows). The test is scale free: only exactly zero or
    non-finite columns are dropped without it. With ``n_blocks > 1`` the coordinate blocks are
    first balanced by :func:`coordinate_weights`.

    Parameters
    ----------
    theta : array, shape (n_rows, F)
        Regression matrix.
    priority : array of int, shape (F,), optional
        Visiting order, most preferred first. Default: column order.
    rtol : float
        Relative residual below which a column counts as dependent.
    max_rows : int
        Rows used for the test.
    n_blocks : int
        Coordinate blocks of rows (coordinate-major); 1: no balancing.
    force_columns : sequence of int, optional
        Passed to :func:`coordinate_weights`.

    Returns
    -------
    keep : ndarray of int
        Independent columns, sorted.
    dropped : dict of int to str
        Dropped columns and why (``"zero column"``, ``"non-finite column"``,
        ``"linear combination"``).

    Examples
    --------
    >>> import numpy as np
    >>> a = np.linspace(0, 1, 50)
    >>> theta = np.column_stack([a, a ** 2, 2 * a - a ** 2, np.zeros(50)])
    >>> independent_columns(theta * [1e-30, 1.0, 1e30, 1.0])
    (array([0, 1]), {2: 'linear combination', 3: 'zero column'})
    """
    theta = np.asarray(theta, dtype=float)
    n_rows, n_cols = theta.shape
    order = np.arange(n_cols) if priority is None else np.asarray(priority, dtype=int)
    if sorted(order.tolist()) != list(range(n_cols)):
        raise ValueError("priority: expected a permutation of the column indices")
    n_blocks = int(n_blocks)
    if n_blocks < 1 or n_rows % n_blocks:
        raise ValueError(f"n_blocks: {n_rows} rows is not a multiple of n_blocks={n_blocks}")
    finite_columns = np.all(np.isfinite(theta), axis=0)
    if n_blocks > 1:
        # balance on the finite columns; the others are dropped below anyway
        finite = (theta if finite_columns.all() else np.where(finite_columns, theta, 0.0))
        theta = scale_blocks(theta, coordinate_weights(finite, n_blocks, force_columns))
    rows = np.unique(np.linspace(0, n_rows - 1, min(n_rows, max_rows)).astype(int))
    # (no copy where every row is used in column order: ``sub`` is only read until divided)
    sub = (theta if len(rows) == n_rows and np.array_equal(order, np.arange(n_cols))
           else theta[:, order] if len(rows) == n_rows else theta[np.ix_(rows, order)])
    top = (abs_max(sub, axis=0) if n_rows else np.zeros(n_cols))
    finite = np.isfinite(top) & finite_columns[order]
    nonzero = finite & (top > 0)
    dropped = {}
    for j in order[~finite]:
        dropped[int(j)] = "non-finite column"
    for j in order[finite & ~nonzero]:
        dropped[int(j)] = "zero column"
    if not np.any(nonzero):
        return np.array([], dtype=int), dict(sorted(dropped.items()))
    candidates = order[nonzero]
    # max-scaled first: no overflow in the norms
    sub = sub / top if nonzero.all() else sub[:, nonzero] / top[nonzero]
    sub /= np.linalg.norm(sub, axis=0)
    if _below_diagonal(sub):
        # (mode "raw": R's diagonal without the (rows, columns) copy that mode "r" makes)
        diag = np.abs(np.diag(scipy.linalg.qr(sub, mode="raw", overwrite_a=True,
                                              check_finite=False)[1]))
    else:  # already upper triangular (a reduced system visited in order): its own R
        diag = np.abs(np.diag(sub))
    if len(diag) < len(candidates):  # fewer rows than columns: the tail is dependent
        diag = np.concatenate([diag, np.zeros(len(candidates) - len(diag))])
    for j, d in zip(candidates, diag, strict=True):
        if d <= rtol:
            dropped[int(j)] = "linear combination"
    keep = np.array(sorted(set(range(n_cols)) - set(dropped)), dtype=int)
    return keep, dict(sorted(dropped.items()))


def _below_diagonal(matrix) -> bool:
    """Whether ``matrix`` has a non-zero entry below its diagonal (``np.tril(matrix, -1)
    .any()`` without the copy: the rows below the square part first, then its lower part)."""
    k = matrix.shape[1]
    return bool(matrix[k:].any() or np.tril(matrix[:k], -1).any())


class CatalogOptimizer(BaseEstimator):
    """Base class of the catalog optimizers.

    ``fit_problem(problem, support=None)`` (``fit_catalog`` builds the
    :class:`~pysindy_xl.optimizers.problem.CatalogProblem` first) checks the parameters,
    balances the coordinate blocks unless the tag ``balances_rows`` is False and calls
    ``_solve(problem)``, the one method a new optimizer implements: it sets ``coef_`` (F,) with
    ``theta @ coef_ ~ 0``; ``_solve_support(problem, support)`` refits a given support. Tags
    are declared by overriding :meth:`catalog_tags` or as class attributes; every subclass
    enters :data:`OPTIMIZER_TYPES` for :meth:`to_spec` and :func:`optimizer_from_spec`.

    Examples
    --------
    A least-squares solver with the force coefficient fixed to -1 implements ``_solve`` and
    declares its tags:

    >>> import dataclasses, numpy as np
    >>> class LeastSquares(CatalogOptimizer):
    ...     def catalog_tags(self):
    ...         return dataclasses.replace(super().catalog_tags(), requires_forces=True)
    ...     def _solve(self, problem):
    ...         theta, forces = problem.theta, problem.force_columns
    ...         rest = np.setdiff1d(np.arange(problem.n_features), forces)
    ...         sol = np.linalg.lstsq(theta[:, rest], theta[:, forces].sum(1))[0]
    ...         self.coef_ = np.full(problem.n_features, -1.0)
    ...         self.coef_[rest] = sol
    ...         return self
    >>> theta = np.column_stack([[1.0, 2.0, 3.0], [0.5, 1.0, 1.5]])
    >>> LeastSquares().fit_catalog(theta, 1, [0]).coef_
    array([-1.,  2.])
    >>> LeastSquares().requires_forces, LeastSquares().can_refit
    (True, False)
    >>> LeastSquares().to_spec()["type"]
    'pysindy_xl.optimizers._base.LeastSquares'
    """

    #: the name a model file gives this class (default: ``module.QualifiedName``)
    spec_type: str

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        register_type(OPTIMIZER_TYPES, cls)
        # tags set as class attributes (``requires_forces = True``) declare the class's tags
        declared = {name: cls.__dict__[name] for name in TAG_NAMES
                    if name in cls.__dict__ and not isinstance(cls.__dict__[name], property)}
        if declared:
            for name in declared:
                delattr(cls, name)
            inherited = cls.catalog_tags

            def tags(self, _inherited=inherited, _declared=declared):
                return dataclasses.replace(_inherited(self), **_declared)

            cls.catalog_tags = tags

    def catalog_tags(self) -> CatalogTags:
        """What this optimizer can do and needs.

        A subclass extends its parent's with
        ``dataclasses.replace(super().catalog_tags(), ...)``.

        Returns
        -------
        CatalogTags
            The tags (:class:`~pysindy_xl.optimizers.tags.CatalogTags`): ``requires_forces``,
            ``can_refit``, ``balances_rows``, ``derivative_estimate``, ...

        Examples
        --------
        >>> import pysindy_xl as px
        >>> px.ExplicitOptimizer().catalog_tags().requires_forces
        True
        """
        return CatalogTags(
            can_refit=type(self)._solve_support is not CatalogOptimizer._solve_support)

    def fit_catalog(self, theta, n_coordinates, force_columns, noise_moments=None,
                    mass_matrices=None, balance=True, reference_columns=None, physical=None):
        """Solve the catalog problem ``theta @ coef_ ~ 0``.

        Parameters
        ----------
        theta, n_coordinates, force_columns, noise_moments, mass_matrices, balance, \
reference_columns, physical
            The fields of a :class:`~pysindy_xl.optimizers.problem.CatalogProblem`, checked by
            :meth:`CatalogProblem.from_arrays
            <pysindy_xl.optimizers.problem.CatalogProblem.from_arrays>`.

        Returns
        -------
        self
        """
        return self.fit_problem(CatalogProblem.from_arrays(
            theta, n_coordinates, force_columns, noise_moments, mass_matrices, balance,
            reference_columns, physical))

    def fit_problem(self, problem: CatalogProblem, support=None):
        """Solve a checked :class:`~pysindy_xl.optimizers.problem.CatalogProblem`.

        Parameters
        ----------
        problem : CatalogProblem
            The regression problem.
        support : array of bool, shape (F,), optional
            Fit only these terms on every row, selecting nothing (needs the tag ``can_refit``).

        Returns
        -------
        self
        """
        self._check_params()
        problem = problem.balanced() if self.catalog_tags().balances_rows else problem
        if support is None:
            fitted = self._solve(problem)
        else:
            fitted = self._solve_support(problem, check_support(support, problem.n_features))
        self.n_features_in_ = problem.n_features
        return fitted

    def _solve(self, problem: CatalogProblem):  # pragma: no cover - abstract
        raise NotImplementedError(f"{type(self).__name__}: _solve(problem) is not implemented")

    def _solve_support(self, problem: CatalogProblem, support):
        raise TypeError(f"{type(self).__name__}: cannot refit a given support (no _solve_support)")

    def _check_params(self):
        """Raise ``TypeError``/``ValueError`` naming a parameter with a bad value."""

    def pilot(self):
        """Unfitted optimizer for a first estimate of the law (see :func:`pilot_optimizer`).

        The reweighted weak fit (:func:`~pysindy_xl.fit.solve`) whitens the rows by the residual
        of this pilot's law before the final fit.

        Returns
        -------
        CatalogOptimizer
            By default a clone of this optimizer.
        """
        return clone(self)

    def to_spec(self) -> dict:
        """JSON description ``{"type": spec_type, "params": {...}}``: plain parameters as they are,
        sequences of them (or of such sequences, two levels deep) as lists, nested optimizers as
        specs; other objects are left out (the loaded optimizer uses their default).

        Returns
        -------
        dict
        """
        params = {}
        for key, value in self.get_params(deep=False).items():
            if isinstance(value, CatalogOptimizer):
                params[key] = value.to_spec()
            elif is_plain(value):
                params[key] = value
            elif (listed := _plain_lists(value)) is not None:
                params[key] = listed
        return {"type": self.spec_type, "params": params}


def _plain_lists(value, depth: int = 0):
    """``value`` as a JSON list where it is a sequence of plain values or of such sequences
    (at most :data:`_MAX_LIST_NESTING` deep: the columns of a
    :class:`~.restricted.RestrictedOptimizer`, the groups of a
    :class:`~.grouped.GroupedOptimizer`), numpy scalars as Python ones; None otherwise."""
    if depth >= _MAX_LIST_NESTING or isinstance(value, (str, bytes, dict)) or not isinstance(
            value, (list, tuple, np.ndarray)):
        return None
    out = []
    for item in value:
        item = item.item() if isinstance(item, np.generic) else item
        if is_plain(item):
            out.append(item)
        elif (nested := _plain_lists(item, depth + 1)) is not None:
            out.append(nested)
        else:
            return None
    return out


def _tag_attribute(name: str) -> property:
    return property(lambda self: getattr(self.catalog_tags(), name),
                    doc=f"Tag ``{name}`` (:meth:`CatalogOptimizer.catalog_tags`).")


for _name in TAG_NAMES:  # the tags answer as read-only attributes too
    setattr(CatalogOptimizer, _name, _tag_attribute(_name))


def optimizer_from_spec(spec, where: str = "optimizer", depth: int = 0):
    """The optimizer an untrusted spec describes: registered type, known plain parameters,
    nested optimizers as specs (bounded depth), its parameter checks passed.

    Parameters
    ----------
    spec : dict
        As written by :meth:`CatalogOptimizer.to_spec`.
    where : str
        Where the spec sits in its file, for the messages.
    depth : int
        Nesting of this spec in the file's optimizer.

    Returns
    -------
    CatalogOptimizer

    Raises
    ------
    ValueError
        Naming ``where`` and what is wrong.

    Examples
    --------
    >>> import pysindy_xl as px
    >>> spec = px.EnsembleOptimizer(px.ExplicitOptimizer(), n_models=5).to_spec()
    >>> optimizer_from_spec(spec).get_params()["n_models"]
    5
    >>> optimizer_from_spec({"type": "os.system"})
    Traceback (most recent call last):
    ...
    ValueError: optimizer: 'type' must name a catalog optimizer, got 'os.system'
    """
    if not (isinstance(spec, dict) and isinstance(spec.get("type"), str)):
        raise ValueError(f"{where}: expected an object with a 'type' and 'params'")
    cls = OPTIMIZER_TYPES.get(spec["type"])
    if cls is None:
        raise ValueError(f"{where}: 'type' must name a catalog optimizer, got {spec['type']!r}")
    if depth > _MAX_NESTING:
        raise ValueError(f"{where}: optimizers nested deeper than {_MAX_NESTING} levels")
    params = spec.get("params", {})
    known = cls().get_params(deep=False)
    if not (isinstance(params, dict) and set(params) <= set(known)):
        raise ValueError(f"{where}.params must be an object with keys among {sorted(known)}")
    values = {}
    for key, value in params.items():
        if isinstance(value, dict):
            values[key] = optimizer_from_spec(value, f"{where}.params.{key}", depth + 1)
        elif is_plain(value) or (isinstance(value, list)
                                 and _plain_lists(value) is not None):
            values[key] = value
        else:
            raise ValueError(f"{where}.params.{key} must be a plain value, a list of them or "
                             "an optimizer")
    optimizer = cls(**values)
    try:
        optimizer._check_params()
    except (TypeError, ValueError) as error:
        raise ValueError(f"{where}: {error}") from None
    return optimizer
