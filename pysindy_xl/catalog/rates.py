"""The rates of a catalog's exponentials, fitted by variable projection on the training pieces.

The move ``"exponentials"`` of :func:`~pysindy_xl.grow_catalog` adds ``exp(a x)`` and
``exp(2 a x)`` to each linear coordinate's potential (:func:`~.bases.exponential_pair`). The
rate ``a`` enters the equations nonlinearly; every other coefficient linearly. So, for the
catalog the move starts from, each linear coordinate ``i``'s rate minimizes the residual of
its weak-form equations with the linear coefficients eliminated (variable projection):

.. math::

    r_i(a) = \\frac{\\| (I - P_{[B_i,\\, E_i(a)]})\\, k_i \\|}{\\| k_i \\|},

where the rows are coordinate ``i``'s weak-form equations on the search's samples (the test
functions and smoothed positions of the search's fits), ``k_i`` is the column of
``qd_i^2`` (the coordinate's own inertia, which every mechanical law has: it fixes the
equation's scale, forced or not), ``B_i`` the catalog's other columns (forces included), and
``E_i(a)`` the two columns of ``exp(a x_i)`` and ``exp(2 a x_i)``; ``P`` projects on their
span. ``r_i`` is evaluated on a grid of :data:`GRID` values of ``|a|`` times the coordinate's
span on the training data, of both signs; each local minimum on the grid is refined by a
bounded scalar search on ``log |a|`` between its grid neighbours. One least-squares projection
of the catalog's columns per coordinate, then two columns per rate: milliseconds.

On a short range of states a pair of exponentials of another rate (with the powers beside
them) can follow the law almost as closely: the Morse well's training pieces at 1 % noise
leave residuals of 0.40 % at the rate 1.5 and 0.43 % at 4.2. Where a second local minimum is
within :data:`SECOND_MINIMUM` of the best, the growth's held-out criterion chooses between
them (one fit more; ``judge`` of :class:`RateFits`).

The residual is taken on all the search's samples (its held-out blocks too): a wall's rate
shows in the extreme states, which the region block holds out of the training pieces (there,
at 1 % noise, the Morse well's residual has minima at the rates 1.57 and 4.2 within 10 % of each
other, where all the samples put it at 1.50). The catalog of the residual keeps the powers of
the coordinate's own potential at most linear (its higher powers and splines left out; the
other coordinates' functions and the products kept): beside powers up to ``x^2`` (or
``x^4``), exponentials of other rates follow the wall over the recorded range (on the Morse
well at 5 % noise, unforced, the residual's rate is 2.40 with ``x^2``, 1.50 with ``x`` alone;
over six noisy cases within 3.5 % of 1.5 with ``x`` alone, off by up to 2.4 times with ``x^2``).
The held-out refinement then sets it within about 20 %. One nonlinear parameter is then fixed as
a degree is, by the data; the exponentials' coefficients are fitted on the training pieces
and judged on the held-out blocks like any family's, and the near ties judge them again on
every block.
"""

from __future__ import annotations

import copy

import numpy as np

from ..symbols import stack_variables
from .automatic import AutomaticCatalog
from .candidates import parameters_key
from .kinds import coordinate_kinds
from .moves import exponential_base

__all__ = ["RateFits", "GRID", "rate_residual"]

#: The grid of ``|a|`` times the coordinate's span on the training data (both signs) from
#: which the rate's search starts: from a wall over a quarter of an e-fold across the data
#: (nearly a polynomial) to sixteen.
GRID = tuple(float(g) for g in np.geomspace(0.25, 16.0, 13))
#: A second local minimum of the residual within this factor of the best one's is judged by
#: the held-out criterion too (where a judge is given).
SECOND_MINIMUM = 1.5
#: Relative tolerance on ``log |a|`` of the refinement of the residual's minima.
LOG_TOLERANCE = 1e-3
#: The exponentials at the residual's rates must lower the held-out criterion of the catalog
#: the move starts from by this fraction for the rates to be refined on it.
REFINE_GAIN = 0.1
#: The offsets of ``log |a|`` from the residual's rate at which the held-out criterion is
#: first evaluated (then refined between the best one's neighbours).
REFINE_GRID = (-0.2, -0.07, 0.0, 0.07, 0.2)
#: Tolerance on ``log |a|`` of the held-out refinement (about 0.4 % of the rate).
REFINE_TOLERANCE = 4e-3
#: Singular values below this fraction of the largest make no direction of the catalog's span.
RANK_CUTOFF = 1e-10


def rate_residual(rate, q, phi_blocks, target, basis) -> float:
    """The residual :math:`r_i(a)` of the module docstring at one rate.

    Parameters
    ----------
    rate : float
        ``a``.
    q : list of ndarray
        The coordinate's smoothed positions on each piece, centred (a shift scales the
        exponentials, which their coefficients absorb).
    phi_blocks : list of sparse matrix
        Each piece's quadrature-weighted test functions, shape (K_p, N_p).
    target : ndarray, shape (R,)
        The rows' ``qd_i^2`` column, with the catalog's span projected out.
    basis : ndarray, shape (R, r)
        Orthonormal basis of the catalog's other columns.

    Returns
    -------
    float
        The relative residual (``||target||`` is the scale); inf where not finite.

    Examples
    --------
    >>> import numpy as np, scipy.sparse
    >>> q = [np.linspace(-1.0, 1.0, 50)]
    >>> phi = [scipy.sparse.identity(50, format="csr")]
    >>> target = 2.0 * np.exp(-1.5 * q[0])  # (the weak column of exp(-1.5 x), up to a factor)
    >>> basis = np.zeros((50, 0))
    >>> rate_residual(-1.5, q, phi, target, basis) < 1e-12
    True
    """
    with np.errstate(all="ignore"):
        columns = np.vstack([np.c_[phi @ np.exp(rate * qp), phi @ np.exp(2 * rate * qp)]
                             for qp, phi in zip(q, phi_blocks, strict=True)])
        columns /= np.linalg.norm(columns, axis=0)
        if basis.shape[1]:
            columns -= basis @ (basis.T @ columns)
        if not np.all(np.isfinite(columns)):
            return float("inf")
        fit = np.linalg.lstsq(columns, target, rcond=None)[0]
        value = float(np.linalg.norm(target - columns @ fit))
    return value if np.isfinite(value) else float("inf")


class RateFits:
    """The exponentials' rates of one growth, fitted for each catalog it moves from.

    Called with a catalog's parameters, returns ``{name: rate}`` for its linear coordinates
    (fitted once per catalog): the parameter ``exponentials`` of
    :class:`~.automatic.AutomaticCatalog` that the move ``"exponentials"`` adds.

    Parameters
    ----------
    fixed : dict
        The catalog parameters common to the candidates (coordinates, kinds, bounds, ...).
    train : dict
        The samples (``x``, ``t``, ``u``, ``x_dot``: lists of arrays, one per run or piece;
        ``u`` and ``x_dot`` may be None) on which the rates are fitted.
    test_functions : BumpTestFunctions
        The search's test functions (its fits' half-width).
    smoother : object
        The search's smoother (``smooth(t, x) -> (q, qd, qdd)``).
    judge : callable or None, default None
        ``judge(parameters) -> float``: the growth's held-out criterion of a catalog. Where
        the residual of the only linear coordinate has two local minima within
        :data:`SECOND_MINIMUM` of each other (on a short range of states a few exponentials
        of other rates can follow one), it chooses between them (with several linear
        coordinates the lower residual does: each judgment is a fit of a large catalog);
        None: the lower residual does.

    Attributes
    ----------
    residuals : dict
        ``{name: (rate, residual at the rate, residual without exponentials)}`` of the last
        fit, for reports and tests.
    refined : dict
        ``{name: rate}``: the rates last refined on the judge. A later catalog whose residual's
        rate lies within the refinement's reach (:data:`REFINE_GRID`) of one takes it
        unrefined: the rate is the law's, not the catalog's, and each refinement costs a
        dozen fits.

    Examples
    --------
    >>> RateFits.__name__
    'RateFits'
    """

    def __init__(self, fixed, train, test_functions, smoother, judge=None):
        self.fixed, self.train, self.judge = fixed, train, judge
        self.test_functions, self.smoother = test_functions, smoother
        self.residuals, self.refined = {}, {}
        self._pieces = None
        self._cache = {}

    def __call__(self, parameters) -> dict:
        """The fitted rates for the catalog ``parameters`` (see the class docstring).

        Parameters
        ----------
        parameters : dict
            The growing parameters of the catalog the move starts from; the exponentials join
            :func:`~.moves.exponential_base` of it.

        Returns
        -------
        dict
            ``{name: rate}`` per linear coordinate; empty where no rate could be fitted.
        """
        key = parameters_key(parameters)
        if key not in self._cache:
            try:
                self._cache[key] = self._fit(parameters)
            except (ValueError, np.linalg.LinAlgError):
                self._cache[key] = {}  # (the move does not apply)
        return dict(self._cache[key])

    def _prepared(self) -> list:
        """Per usable piece: the library input, the test matrices and the positions."""
        if self._pieces is None:
            from ..weak.regression import shared_half_width
            from ..weak.timegrid import split_at_gaps
            train = self.train
            n_runs = len(train["x"])
            trajectories = [{"t": np.asarray(train["t"][k], dtype=float),
                             "x": np.asarray(train["x"][k], dtype=float),
                             "x_dot": None if train.get("x_dot") is None else train["x_dot"][k],
                             "u": None if train.get("u") is None else train["u"][k]}
                            for k in range(n_runs)]
            h = shared_half_width(self.test_functions, trajectories)
            segments, _, _ = split_at_gaps(trajectories, self.test_functions.max_gap(h))
            smoother = copy.deepcopy(self.smoother)
            pieces = []
            for d in segments:
                if d["t"][-1] - d["t"][0] < 2 * h:
                    continue
                q, qd, qdd = smoother.smooth(d["t"], d["x"])
                if d["x_dot"] is not None:
                    q, qd = d["x"], d["x_dot"]
                u = np.zeros_like(q) if d["u"] is None else d["u"]
                phi, dphi = self.test_functions.matrices(d["t"], half_width=h)[:2]
                pieces.append((stack_variables(q, qd, qdd, u, d["t"]), phi, dphi, q))
            if not pieces:
                raise ValueError("x: no training piece holds a test function")
            self._pieces = pieces
        return self._pieces

    def _fit(self, state) -> dict:
        """The rates for the move from ``state`` (see the class docstring)."""
        parameters = exponential_base(state)
        catalog = AutomaticCatalog(**self.fixed, **parameters)
        library = catalog.fit()
        coords = library.coords
        pieces = self._prepared()
        blocks = [library.weak_transform(z, phi, dphi) for z, phi, dphi, _ in pieces]
        terms, categories = library.feature_terms_, library.categories_
        kinds = coordinate_kinds(coords.names, self.fixed.get("kinds"))
        bounds = self.fixed.get("bounds")
        candidates, self.residuals = {}, {}
        for i, (name, kind) in enumerate(zip(coords.names, kinds, strict=True)):
            if kind != "linear":
                continue
            inertia = coords.qd[i] ** 2
            own = [j for j, (term, category) in enumerate(zip(terms, categories, strict=True))
                   if category == "lagrange" and term == inertia]
            if not own:
                continue
            rows = np.vstack([b[i * phi.shape[0]:(i + 1) * phi.shape[0]]
                              for b, (_, phi, _, _) in zip(blocks, pieces, strict=True)])
            target = rows[:, own[0]]
            # the coordinate's own potential functions but its first power left out: beside
            # x^2 (or x^4, or splines) exponentials of other rates follow the wall over the
            # recorded range
            left = [own[0]] + [j for j, (term, category) in enumerate(
                zip(terms, categories, strict=True)) if category == "lagrange"
                and term.free_symbols == {coords.q[i]} and term != coords.q[i]]
            others = np.delete(rows, left, axis=1)
            scale = np.linalg.norm(others, axis=0)
            others = others[:, scale > 0] / scale[scale > 0]
            if not np.all(np.isfinite(others)) or not np.all(np.isfinite(target)):
                continue
            u, s, _ = np.linalg.svd(others, full_matrices=False)
            basis = u[:, s > RANK_CUTOFF * s[0]] if len(s) else u
            norm = np.linalg.norm(target)
            if norm == 0:
                continue
            projected = target - basis @ (basis.T @ target)
            values = [p[3][:, i] for p in pieces]
            centre = float(np.median(np.concatenate(values)))
            q = [v - centre for v in values]
            phis = [p[1] for p in pieces]
            span = (bounds[i][1] - bounds[i][0]) if bounds is not None else float(np.ptp(
                np.concatenate(values)))
            if not span > 0:
                continue

            def residual(rate, q=q, phis=phis, projected=projected, basis=basis, norm=norm):
                return rate_residual(rate, q, phis, projected, basis) / norm

            found = _minima(residual, span)
            if found:
                candidates[name] = found
                self.residuals[name] = (found[0][0], found[0][1],
                                        float(np.linalg.norm(projected) / norm))
        rates = {name: found[0][0] for name, found in candidates.items()}
        if self.judge is None or not rates:
            return rates
        # two minima of the residual close to each other: the held-out criterion chooses
        # (a few exponentials of other rates can follow one on a short range of states); with
        # one linear coordinate only (one fit each: with several, of a large catalog each)
        best = self.judge(dict(parameters, exponentials=rates))
        for name, found in candidates.items() if len(candidates) == 1 else ():
            for rate, _ in found[1:]:
                other = dict(rates, **{name: rate})
                value = self.judge(dict(parameters, exponentials=other))
                if value < best:
                    rates, best = other, value
        if not best < self.judge(state) * (1 - REFINE_GAIN):
            return rates  # (no better than the catalog the move starts from)
        # the exponentials explain the law: each rate refined on the held-out criterion (the
        # region block holds the extreme states out of the training pieces, where a wall's
        # rate shows most)
        for name in rates:
            earlier = self.refined.get(name)
            if earlier is not None and np.sign(earlier) == np.sign(rates[name]) and abs(
                    np.log(abs(earlier / rates[name]))) <= max(REFINE_GRID):
                rates = dict(rates, **{name: earlier})  # (refined from another catalog)
                continue
            rates, best = self._refined(parameters, rates, name, best)
            self.refined[name] = rates[name]
        for name, rate in rates.items():
            self.residuals[name] = (rate, *self.residuals[name][1:])
        return rates

    def _refined(self, parameters, rates, name, best) -> tuple:
        """``rates`` with ``rates[name]`` refined on the judge: the best of the offsets
        :data:`REFINE_GRID` of ``log |a|``, then a bounded scalar search between its
        neighbours; kept where it lowers the criterion by :data:`REFINE_GAIN` at least (a
        smaller gain is the criterion's noise: at 5 % noise it moves the Morse rate from 1.50
        to 1.62)."""
        from scipy.optimize import minimize_scalar

        sign, centre = np.sign(rates[name]), np.log(abs(rates[name]))
        memo = {0.0: best}

        def judged(offset):
            offset = float(offset)
            if offset not in memo:
                rate = _rounded(sign * np.exp(centre + offset))
                memo[offset] = self.judge(dict(parameters,
                                               exponentials=dict(rates, **{name: rate})))
            return memo[offset]

        grid = sorted(REFINE_GRID)
        scores = [judged(offset) for offset in grid]
        k = int(np.argmin(scores))
        if np.isfinite(scores[k]):
            low, high = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
            minimize_scalar(judged, bounds=(low, high), method="bounded",
                            options={"xatol": REFINE_TOLERANCE})
        offset = min(memo, key=lambda o: (memo[o], abs(o)))
        if not memo[offset] < best * (1 - REFINE_GAIN):
            offset = 0.0  # (within the criterion's noise: the residual's rate)
        rate = _rounded(sign * np.exp(centre + offset))
        return dict(rates, **{name: rate}), memo[offset]


def _minima(residual, span) -> list:
    """The best local minimum of ``residual`` over the signed rates of :data:`GRID` (over
    ``span``), refined, and the second best where its residual is within
    :data:`SECOND_MINIMUM` times the best's: ``[(rate, residual), ...]``, best first."""
    from scipy.optimize import minimize_scalar

    out = []
    for sign in (-1.0, 1.0):
        scores = np.array([residual(sign * g / span) for g in GRID])
        if not np.any(np.isfinite(scores)):
            continue
        padded = np.r_[np.inf, scores, np.inf]
        # (a minimum at the grid's smallest rate is the residual falling towards a = 0,
        # where the exponentials are powers: no rate of an exponential law)
        minima = np.flatnonzero((scores <= padded[:-2]) & (scores <= padded[2:])
                                & np.isfinite(scores))
        for k in minima[minima > 0]:
            low = np.log(GRID[max(k - 1, 0)] / span)
            high = np.log(GRID[min(k + 1, len(GRID) - 1)] / span)
            found = minimize_scalar(lambda v, sign=sign: residual(sign * np.exp(v)),
                                    bounds=(low, high), method="bounded",
                                    options={"xatol": LOG_TOLERANCE})
            rate, value = sign * GRID[k] / span, float(scores[k])
            if found.fun < value:
                rate, value = sign * float(np.exp(found.x)), float(found.fun)
            out.append((_rounded(rate), value))
    out.sort(key=lambda item: item[1])
    return out[:1] + [item for item in out[1:2] if item[1] <= SECOND_MINIMUM * out[0][1]]


def _rounded(rate) -> float:
    """``rate`` to six significant digits (the printed model's)."""
    return float(f"{rate:.6g}")
