"""The anchors of a catalog's springs, fitted by variable projection on the training pieces.

The move ``"anchored_springs"`` of :func:`~pysindy_xl.grow_catalog` adds to a coordinate's
potential the length ``d`` of a spring between a point that the coordinate moves and an anchor
off its path (:func:`~.bases.anchored_spring`): a linear spring's potential
``k/2 (d - l0)^2 = k/2 d^2 - k l0 d + const`` holds ``d^2`` (a quadratic, or a first-degree
sine and cosine, in the first catalog already) and ``d``, which no polynomial, trigonometric or
spline family continues beyond the data. ``d`` has two parameters ``p`` (an angle's
``(e, phi)`` in ``sqrt(1 - e cos(theta - phi))``; a linear coordinate's ``(c, h)`` in
``sqrt((x - c)^2 + h^2)``) which enter the equations nonlinearly, every coefficient linearly.
As for the exponentials' rate (:mod:`.rates`), coordinate ``i``'s anchor minimizes the residual
of its weak-form equations with the linear coefficients eliminated (variable projection):

.. math::

    r_i(p) = \\frac{\\| (I - P_{[B_i,\\, D_i(p)]})\\, k_i \\|}{\\| k_i \\|},

where the rows are coordinate ``i``'s weak-form equations on the search's samples, ``k_i`` the
column of ``qd_i^2`` (the coordinate's own inertia: it fixes the equation's scale), ``B_i``
the other columns of the catalog the move starts from (its degrees back to the first
catalog's, no splines; forces included), and ``D_i(p)`` the column of the length's force
``-d'(q_i)`` (the weak form of a potential term ``f(q)`` is the test functions' quadrature of
``f'(q)``); ``P`` projects on their span. ``r_i`` is evaluated on a coarse grid of the two
parameters in scale-free units (an angle: ``log(1 - e)`` by ``phi``, periodic; a linear
coordinate: ``c`` and ``log h`` in units of its span on the training data); each of the
:data:`MINIMA` best local minima on the grid is refined by a bounded Nelder-Mead search. A
minimum at the grid's smallest ``e`` (or largest ``h``), or refined to it, is refused: there the
length is nearly a first-degree cosine (or a quadratic) plus higher degrees, and it stands in
for a higher trigonometric degree (a rotating arm's ``sin^2``), not a spring. The refinement
stays within the grid, and a minimum refined to its edge nearest the path (``e = 0.98``, ``h``
a twentieth of the span) is refused too: an anchor that close to the path makes the length
nearly a kink (``|x - c|``, ``|sin((theta - phi) / 2)|``), which stands in for a torsion
spring's ``theta^2``, a three-link arm's higher harmonics or asymmetric stiffness.
Where a second minimum is within :data:`~.rates.SECOND_MINIMUM` of the best, the growth's
held-out criterion chooses between them (one coordinate only, as for the rates). A coordinate
whose residual the length lowers by less than :data:`GAIN` gets none (a column more that the
data do not ask for). The coefficients are then fitted on the training pieces and judged on the
held-out blocks like any family's.

This family was designed after two blind benchmark systems (``offset_spring_pendulum``,
``oblique_spring_slider``) showed the need; it became a default move once every row of the five
benchmark sets had run with it (``benchmarks/results/anchored_springs_default.md``).
"""

from __future__ import annotations

import numpy as np

from .automatic import AutomaticCatalog
from .kinds import coordinate_kinds
from .moves import anchor_base
from .rates import RANK_CUTOFF, SECOND_MINIMUM, RateFits

__all__ = ["AnchorFits", "anchor_residual", "length_force", "ANGLE_GRID", "LINEAR_GRID",
           "GAIN", "MINIMA"]

#: The grid of an angle's anchor: ``1 - e`` from 0.02 to 0.8 (geometric; ``e`` from 0.2, a
#: length close to a first-degree cosine, to 0.98, an anchor near the circle) by 24 values of
#: ``phi`` around the circle.
ANGLE_GRID = (tuple(float(v) for v in np.geomspace(0.02, 0.8, 10)),
              tuple(float(v) for v in np.linspace(-np.pi, np.pi, 24, endpoint=False)))
#: The grid of a linear coordinate's anchor, in units of its span on the training data: ``c``
#: from the median position (both sides, to one span beyond) by ``h`` from 0.05 to 4 spans
#: (geometric).
LINEAR_GRID = (tuple(float(v) for v in np.linspace(-1.0, 1.0, 13)),
               tuple(float(v) for v in np.geomspace(0.05, 4.0, 10)))
#: A coordinate gets an anchored spring only where the length lowers its residual by this
#: fraction at least.
GAIN = 0.1
#: The local minima of the grid refined (best first).
MINIMA = 3
#: Tolerance of the refinement on the scale-free parameters.
TOLERANCE = 1e-4


def length_force(kind, anchor, q) -> np.ndarray:
    """``d'(q)``: the derivative of the spring's length (:func:`~.bases.anchored_spring`).

    Parameters
    ----------
    kind : {"linear", "angle"}
        The coordinate's kind.
    anchor : tuple of 2 float
        ``(e, phi)`` of an angle, ``(c, h)`` of a linear coordinate.
    q : ndarray
        The coordinate's values.

    Returns
    -------
    ndarray
        ``e sin(q - phi) / (2 sqrt(1 - e cos(q - phi)))`` or ``(q - c) / sqrt((q - c)^2 + h^2)``.

    Examples
    --------
    >>> import numpy as np
    >>> float(length_force("linear", (0.0, 1.0), np.array([0.0]))[0])
    0.0
    """
    a, b = anchor
    with np.errstate(all="ignore"):
        if kind == "angle":
            return a * np.sin(q - b) / (2 * np.sqrt(1 - a * np.cos(q - b)))
        return (q - a) / np.hypot(q - a, b)


def anchor_residual(kind, anchor, q, phi_blocks, target, basis) -> float:
    """The residual of the module docstring at one anchor, times ``||k_i||``.

    Parameters
    ----------
    kind : {"linear", "angle"}
        The coordinate's kind.
    anchor : tuple of 2 float
        ``(e, phi)`` or ``(c, h)``.
    q : list of ndarray
        The coordinate's smoothed positions on each piece.
    phi_blocks : list of sparse matrix
        Each piece's quadrature-weighted test functions, shape (K_p, N_p).
    target : ndarray, shape (R,)
        The rows' ``qd_i^2`` column, with the catalog's span projected out.
    basis : ndarray, shape (R, r)
        Orthonormal basis of the catalog's other columns.

    Returns
    -------
    float
        The residual; inf where not finite.

    Examples
    --------
    >>> import numpy as np, scipy.sparse
    >>> q = [np.linspace(-1.0, 1.0, 50)]
    >>> phi = [scipy.sparse.identity(50, format="csr")]
    >>> target = 3.0 * length_force("linear", (0.2, 0.5), q[0])
    >>> anchor_residual("linear", (0.2, 0.5), q, phi, target, np.zeros((50, 0))) < 1e-12
    True
    """
    column = np.concatenate([phi @ length_force(kind, anchor, qp)
                             for qp, phi in zip(q, phi_blocks, strict=True)])
    norm = np.linalg.norm(column)
    if not (np.isfinite(norm) and norm > 0):
        return float("inf")
    column = column / norm
    if basis.shape[1]:
        column = column - basis @ (basis.T @ column)
    size = float(column @ column)
    if not size > 1e-14:
        return float(np.linalg.norm(target))
    value = float(np.linalg.norm(target - column * (column @ target) / size))
    return value if np.isfinite(value) else float("inf")


class AnchorFits(RateFits):
    """The springs' anchors of one growth, fitted for each catalog it moves from.

    Called with a catalog's parameters, returns ``{name: (a, b)}`` for the coordinates whose
    residual an anchored spring lowers (fitted once per catalog): the parameter ``anchors`` of
    :class:`~.automatic.AutomaticCatalog` that the move ``"anchored_springs"`` adds. The
    samples, test functions and smoother are those of :class:`~.rates.RateFits`.

    Parameters
    ----------
    fixed : dict
        The catalog parameters common to the candidates (coordinates, kinds, bounds, ...).
    train : dict
        The samples (``x``, ``t``, ``u``, ``x_dot``: lists of arrays, one per run or piece;
        ``u`` and ``x_dot`` may be None) on which the anchors are fitted.
    test_functions : BumpTestFunctions
        The search's test functions.
    smoother : object
        The search's smoother (``smooth(t, x) -> (q, qd, qdd)``).
    judge : callable or None, default None
        ``judge(parameters) -> float``: the growth's held-out criterion of a catalog; where
        the residual of the only fitted coordinate has a second minimum within
        :data:`~.rates.SECOND_MINIMUM` of the best, it chooses between them. None: the lower
        residual does.

    Attributes
    ----------
    residuals : dict
        ``{name: (anchor, residual at the anchor, residual without the length)}`` of the last
        fit, for reports and tests.

    Examples
    --------
    >>> AnchorFits.__name__
    'AnchorFits'
    """

    def _fit(self, state) -> dict:
        """The anchors for the move from ``state`` (see the class docstring)."""
        parameters = anchor_base(state)
        library = AutomaticCatalog(**self.fixed, **dict(parameters, splines=None)).fit()
        coords = library.coords
        pieces = self._prepared()
        blocks = [library.weak_transform(z, phi, dphi) for z, phi, dphi, _ in pieces]
        terms, categories = library.feature_terms_, library.categories_
        kinds = coordinate_kinds(coords.names, self.fixed.get("kinds"))
        candidates, self.residuals = {}, {}
        for i, (name, kind) in enumerate(zip(coords.names, kinds, strict=True)):
            own = [j for j, (term, category) in enumerate(zip(terms, categories, strict=True))
                   if category == "lagrange" and term == coords.qd[i] ** 2]
            if not own:
                continue
            rows = np.vstack([b[i * phi.shape[0]:(i + 1) * phi.shape[0]]
                              for b, (_, phi, _, _) in zip(blocks, pieces, strict=True)])
            target = rows[:, own[0]]
            others = np.delete(rows, own, axis=1)
            scale = np.linalg.norm(others, axis=0)
            others = others[:, scale > 0] / scale[scale > 0]
            norm = np.linalg.norm(target)
            if not (np.all(np.isfinite(others)) and np.all(np.isfinite(target)) and norm > 0):
                continue
            u, s, _ = np.linalg.svd(others, full_matrices=False)
            basis = u[:, s > RANK_CUTOFF * s[0]] if len(s) else u
            projected = target - basis @ (basis.T @ target)
            q = [p[3][:, i] for p in pieces]
            found = _minima(kind, q, [p[1] for p in pieces], projected / norm, basis)
            without = float(np.linalg.norm(projected) / norm)
            if found and found[0][1] <= (1 - GAIN) * without:
                candidates[name] = found
                self.residuals[name] = (found[0][0], found[0][1], without)
        anchors = {name: found[0][0] for name, found in candidates.items()}
        if self.judge is None or len(candidates) != 1:
            return anchors
        (name, found), = candidates.items()
        if len(found) > 1:  # two close minima: the held-out criterion chooses
            scores = [self.judge(dict(parameters, anchors={name: anchor}))
                      for anchor, _ in found]
            k = int(np.argmin(scores))
            anchors = {name: found[k][0]}
            self.residuals[name] = (found[k][0], found[k][1], self.residuals[name][2])
        return anchors


def _minima(kind, q, phis, target, basis) -> list:
    """The best local minimum of the residual over the kind's grid, refined, and the second
    best where within :data:`~.rates.SECOND_MINIMUM` of it: ``[(anchor, residual), ...]``."""
    from scipy.optimize import minimize

    values = np.concatenate(q)
    if kind == "angle":
        first, second = np.log(ANGLE_GRID[0]), np.array(ANGLE_GRID[1])

        def anchor(v):  # (log(1 - e), phi)
            return (1 - float(np.exp(v[0])), float(np.angle(np.exp(1j * v[1]))))

        bounds = [(first[0], first[-1]), (-2 * np.pi, 2 * np.pi)]
        periodic, edge = True, (0, first[-1])
    else:
        centre = float(np.median(values))
        span = float(np.ptp(values))
        if not span > 0:
            return []
        first, second = np.array(LINEAR_GRID[0]), np.log(LINEAR_GRID[1])

        def anchor(v):  # (c / span from the median, log(h / span))
            return (centre + span * float(v[0]), span * float(np.exp(v[1])))

        bounds = [(-2.0, 2.0), (second[0], second[-1])]
        periodic, edge = False, (1, second[-1])

    def residual(v):
        return anchor_residual(kind, anchor(v), q, phis, target, basis)

    scores = np.array([[residual((a, b)) for b in second] for a in first])
    if not np.any(np.isfinite(scores)):
        return []
    padded = np.pad(scores, 1, constant_values=np.inf)
    if periodic:
        padded[1:-1, 0], padded[1:-1, -1] = scores[:, -1], scores[:, 0]
    local = np.isfinite(scores)
    for da in (-1, 0, 1):
        for db in (-1, 0, 1):
            if da or db:
                local &= scores <= padded[1 + da:1 + da + scores.shape[0],
                                          1 + db:1 + db + scores.shape[1]]
    # (a minimum at the grid's smallest e, or largest h, is the residual falling towards a
    # length that is a first-degree cosine or a quadratic, in the catalog already: no anchor,
    # a stand-in for a higher degree; so is a refined one on that side of the grid)
    if edge[0] == 0:
        local[-1, :] = False
    else:
        local[:, -1] = False
    cells = sorted(zip(*np.nonzero(local), strict=True), key=lambda c: scores[c])[:MINIMA]
    out = []
    for a, b in cells:
        start = np.array([first[a], second[b]])
        found = minimize(residual, start, method="Nelder-Mead", bounds=bounds,
                         options={"xatol": TOLERANCE, "fatol": 1e-12, "maxfev": 300})
        v, value = (found.x, float(found.fun)) if found.fun < scores[a, b] else (
            start, float(scores[a, b]))
        # (refined to the grid's edge nearest the path, the length nears a kink, |x - c| or
        # |sin((theta - phi) / 2)|, smooth on the data as a half-angle cosine or a line: a
        # degenerate geometry that stands in for what a family states, as on the far side)
        if v[edge[0]] >= edge[1] - 1e-3 or v[edge[0]] <= bounds[edge[0]][0] + 1e-3:
            continue
        out.append((tuple(_rounded(x) for x in anchor(v)), value))
    out.sort(key=lambda item: item[1])
    kept = out[:1]
    for item in out[1:]:  # (a refined minimum equal to the best is the same one)
        if item[1] <= SECOND_MINIMUM * out[0][1] and not np.allclose(item[0], out[0][0],
                                                                      atol=1e-3):
            kept.append(item)
            break
    return kept


def _rounded(value) -> float:
    """``value`` to six significant digits (the printed model's)."""
    return float(f"{value:.6g}")
