r"""Errors-in-variables selection of homogeneous laws ``Theta xi = 0`` (unforced, noisy data).

Candidate supports (the noise ratio's backward and forward paths, the paths inside the
admissible lasso's supports, swap refinements) are scored by the held-out noise ratio of
their law (:mod:`~pysindy_xl.optimizers.noise_ratio`: about 1 for a law that holds) in
h-block cross-validation (a gap of :data:`FOLD_GAP` keeps the training rows off the held-out
rows' noise). Admissible laws (every coordinate explained, definite mass matrix) compete
alone when there are any; the smallest within one standard error of the best is chosen.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..weak.noise import draw_moments
from ._base import coordinates_touched
from ._sparse import column_norms, triangular_factor
from .admissible import admissible_supports
from .laws import definite_mass, explained_coordinates
from .noise_ratio import (
    eliminate_one,
    law_elimination_path,
    law_forward_path,
    noise_ratio_law,
    refine_law_by_swaps,
    smallest_pair,
)
from .selection import ChosenSupport, fold_labels, fold_summary

__all__ = ["LawSelection", "RowMoments", "select_law", "select_laws"]


#: Rows left out of the training rows on each side of a held-out fold (fraction of a fold).
FOLD_GAP = 0.3

#: Path supports of each size refined by swaps (those of lowest held-out ratio).
STARTS_PER_SIZE = 3


@dataclasses.dataclass(frozen=True)
class RowMoments:
    """Noise moments of any set of rows, from Monte Carlo draws of the rows' errors.

    The propagated noise varies along a trajectory, so a held-out ratio divides by the held-out
    rows' own moments. Called with a row mask or indices, returns ``E[E_rows^T E_rows]``
    (F, F).

    Parameters
    ----------
    draws : ndarray, shape (D, n_rows, F)
        Draws of the rows' errors.
    floor : float, default 0.0
        Added to the diagonal per row.

    Examples
    --------
    >>> import numpy as np
    >>> moments = RowMoments(np.ones((2, 4, 1)))
    >>> moments(np.array([0, 1])).tolist()
    [[2.0]]
    """

    draws: np.ndarray
    floor: float = 0.0

    def __call__(self, rows) -> np.ndarray:
        """``E[E_rows^T E_rows]`` (F, F) of the rows selected by a mask or indices."""
        chosen = self.draws[:, rows]
        return draw_moments(chosen, 1)[0] + self.floor * chosen.shape[1] * np.eye(chosen.shape[-1])

    def columns(self, keep) -> RowMoments:
        """The moments of some columns only.

        Parameters
        ----------
        keep : array of int or bool
            The columns kept.

        Returns
        -------
        RowMoments
            The draws of those columns.
        """
        return dataclasses.replace(self, draws=self.draws[:, :, keep])


@dataclasses.dataclass
class LawSelection(ChosenSupport):
    """What the errors-in-variables selection chose and why (returned by :func:`select_law`).

    Parameters
    ----------
    order : ndarray of int
        Columns from most to least needed.
    cv_ratio, cv_spread : ndarray
        Mean held-out noise ratio of the best support of each size (index ``k - 1``; inf where
        none) and its standard error over the folds.
    size : int
        Chosen number of terms.
    best_size : int
        Size with the lowest held-out ratio.
    rule : str
        How ``size`` was chosen.
    rivals : list of ndarray of int
        Other admissible supports that hold as well and are not the chosen one with terms
        added: the data do not decide between them. Smallest first.
    admissible : bool
        Whether the chosen law is admissible (False when no candidate was).
    cv_relative : float
        The chosen law's mean held-out relative squared residual.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> a, b = rng.normal(size=(2, 2000))
    >>> theta = np.column_stack([a, b, a - 2 * b]) + 0.05 * rng.normal(size=(2000, 3))
    >>> law, ratio, selection = select_law(theta, 0.0025 * 2000 * np.eye(3)[None])
    >>> selection.size, len(selection.order)
    (3, 3)
    """

    order: np.ndarray
    cv_ratio: np.ndarray
    cv_spread: np.ndarray
    size: int
    best_size: int
    rule: str
    rivals: list = dataclasses.field(default_factory=list)
    admissible: bool = True
    cv_relative: float = np.nan


def _held_out_ratios(theta, moments, supports, n_blocks, n_folds, row_moments=None):
    """Held-out noise ratios and relative squared residuals ``||Theta xi||^2 / sum_j ||Theta_j
    xi_j||^2``, each (n_folds, len(supports)), inf where a support cannot be fitted; the rows'
    own moments from ``row_moments``, else each block's spread evenly over its rows.
    """
    ratios = np.full((n_folds, len(supports)), np.inf)
    relative = np.full((n_folds, len(supports)), np.inf)
    longest = np.asarray(max(supports, key=len))
    nested = all(np.array_equal(s, longest[:len(s)]) for s in supports)
    # only the columns of the supports: nested ones in path order (see above)
    used = longest if nested else np.unique(np.concatenate(supports))
    theta = theta[:, used]
    moments = moments[:, used][:, :, used]
    if row_moments is not None:
        row_moments = row_moments.columns(used)
    supports = ([np.arange(len(s)) for s in supports] if nested
                else [np.searchsorted(used, s) for s in supports])
    labels = fold_labels(theta.shape[0], n_blocks, n_folds)
    per_block = theta.shape[0] // n_blocks
    blocks = np.arange(theta.shape[0]) // per_block
    position = np.arange(theta.shape[0]) % per_block
    gap = int(FOLD_GAP * per_block / n_folds)
    folds = []  # (fold, train factor, test factor, train moments, test moments)
    for fold in range(n_folds):
        test = labels == fold
        if not test.any() or test.all():
            continue
        # h-block: the rows next to the held-out ones share their noise
        first, last = position[test].min(), position[test].max()
        training = ~test & ((position < first - gap) | (position > last + gap))
        if row_moments is not None:  # the rows' own noise
            test_moments, train_moments = row_moments(test), row_moments(training)
        else:  # each block's moments spread evenly over its rows: the rows' share
            count = np.bincount(blocks)
            test_moments = np.einsum("b,bfg->fg", np.bincount(
                blocks[test], minlength=n_blocks) / count, moments)
            train_moments = np.einsum("b,bfg->fg", np.bincount(
                blocks[training], minlength=n_blocks) / count, moments)
        folds.append((fold, triangular_factor(theta[training]), triangular_factor(theta[test]),
                      train_moments, test_moments))
    for size in {len(support) for support in supports}:
        members = [m for m, support in enumerate(supports) if len(support) == size]
        columns = np.array([supports[m] for m in members])  # (g, size)
        fitted_folds = [f for f in folds if 2 <= size <= f[1].shape[0]]
        if not fitted_folds:
            continue
        # every fold's pencils in one stack (per matrix, the same as one stack per fold);
        # leading columns of a triangular factor: its leading rows are all that is needed
        trains = [r_train[:size] if nested else r_train for _, r_train, *_ in fitted_folds]
        heights = {train.shape[0] for train in trains}
        # each support's smallest-ratio law, (g, size) per fold
        if len(heights) == 1:
            stacked = smallest_pair(
                np.concatenate([np.swapaxes(train[:, columns], 0, 1) for train in trains]),
                np.concatenate([f[3][columns[:, :, None], columns[:, None, :]]
                                for f in fitted_folds]))[1]
            fold_laws = np.split(stacked, len(fitted_folds))
        else:  # factors of different heights (a fold of fewer rows than columns)
            fold_laws = [smallest_pair(np.swapaxes(train[:, columns], 0, 1),
                                       f[3][columns[:, :, None], columns[:, None, :]])[1]
                         for train, f in zip(trains, fitted_folds, strict=True)]
        for (fold, _, r_test, _, test_moments), laws in zip(fitted_folds, fold_laws,
                                                             strict=True):
            noise = np.einsum("gi,gij,gj->g", laws,
                              test_moments[columns[:, :, None], columns[:, None, :]], laws)
            test_factor = r_test[:, columns]  # (rows, g, size)
            residual = np.sum(np.einsum("rgi,gi->rg", test_factor, laws) ** 2, axis=0)
            signal = np.sum((test_factor * laws) ** 2, axis=(0, 2))
            fitted = (noise > 0) & (signal > 0)
            with np.errstate(divide="ignore", invalid="ignore"):
                ratios[fold, members] = np.where(fitted, residual / noise, np.inf)
                relative[fold, members] = np.where(fitted, residual / signal, np.inf)
    return ratios, relative


def select_law(theta, noise_moments, n_blocks: int = 1, n_folds: int = 5,
               resolution: float = 1e-8, swaps: bool = True, mass_matrices=None,
               noise_draws=None) -> tuple[np.ndarray, float, LawSelection]:
    """Sparsest homogeneous law of noisy columns, by held-out noise ratio (module documentation).

    Parameters
    ----------
    theta : array, shape (n_rows, F)
        Regression matrix, rows in ``n_blocks`` equal blocks (coordinates).
    noise_moments : array, shape (n_blocks, F, F)
        ``E[E_b^T E_b]`` of each block's errors.
    n_blocks : int, default 1
        Number of coordinate blocks of the rows.
    n_folds : int, default 5
        Contiguous held-out folds per block.
    resolution : float, default 1e-8
        Held-out relative squared residuals this close to the best count as equal (clean data).
    swaps : bool, default True
        Add the swap-refined supports.
    mass_matrices : array, shape (S, F, n_blocks, n_blocks), optional
        Each column's contribution to the mass matrix on sample states
        (:func:`~pysindy_xl.fit.diagnostics.column_mass_matrices`): laws indefinite there are not
        candidates unless none is definite.
    noise_draws : array, shape (D, n_rows, F), optional
        Draws of the rows' errors: each fold's rows get their own moments (:class:`RowMoments`).

    Returns
    -------
    law : ndarray, shape (F,)
        Unit-norm law on the selected support (largest entry positive).
    ratio : float
        Its noise ratio on all the rows.
    selection : LawSelection
        What was chosen and why.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> a, b, c, d = rng.normal(size=(4, 2000))
    >>> clean = np.column_stack([a, b, a - 2 * b, c, d])
    >>> theta = clean + 0.05 * rng.normal(size=clean.shape)
    >>> law, ratio, selection = select_law(theta, 0.0025 * 2000 * np.eye(5)[None])
    >>> (law / law[0]).round(1) + 0.0, selection.size
    (array([ 1., -2., -1.,  0.,  0.]), 3)
    """
    theta = np.asarray(theta, dtype=float)
    moments = np.asarray(noise_moments, dtype=float)
    scale = np.sqrt(np.mean(theta**2, axis=0))
    scale[scale == 0] = 1.0
    theta = theta / scale
    moments = moments / np.outer(scale, scale)[None]
    # a floor far below the noise for the columns without noise (a known force)
    floor = 1e-10 * np.mean(np.diagonal(moments, axis1=1, axis2=2)) / len(moments)
    moments = moments + floor * np.eye(theta.shape[1])[None]
    total = moments.sum(axis=0)
    row_moments = None
    if noise_draws is not None:
        noise_draws = np.asarray(noise_draws, dtype=float)
        if noise_draws.ndim != 3 or noise_draws.shape[1:] != theta.shape:
            raise ValueError(f"noise_draws: expected shape (D, {theta.shape[0]}, "
                             f"{theta.shape[1]}), got {noise_draws.shape}")
        row_moments = RowMoments(noise_draws / scale, floor * n_blocks / theta.shape[0])

    def scored(supports, how):
        return _scored(theta, moments, supports, how, n_blocks, n_folds, row_moments)

    r_factor = triangular_factor(theta)
    order = law_elimination_path(r_factor, total)
    forward = law_forward_path(r_factor, total)
    # (how, nested supports): each list is cross-validated at once (see _held_out_ratios)
    paths = [("backward path", [order[:k] for k in range(2, len(order) + 1)]),
             ("forward path", [forward[:k] for k in range(2, len(forward) + 1)])]
    if mass_matrices is not None:
        paths += [("admissible start", supports) for supports in _admissible_starts(
            r_factor, total, mass_matrices / scale[None, :, None, None],
            {frozenset(s.tolist()) for _, supports in paths for s in supports})]
    # Admissible laws only, when there are any: a law leaving a coordinate out says nothing
    # of it (the unforced cart-pole's Routhian holds exactly), one with an indefinite mass
    # matrix defines no motion (its momentum balance: det M = 0).
    verdicts = {}  # admissibility of each support, decided once and only where needed

    def admissible_support(support):
        key = frozenset(support.tolist())
        if key not in verdicts:
            law = noise_ratio_law(r_factor[:, support], total[np.ix_(support, support)])[1]
            verdicts[key] = bool(explained_coordinates(theta[:, support], law, n_blocks).all()
                                 and (mass_matrices is None or definite_mass(
                                     mass_matrices[:, support], law / scale[support])))
        return verdicts[key]

    def admissible(candidate):
        return admissible_support(candidate.support)

    # when some path support is admissible, only those are cross-validated
    kept = [(how, [s for s in supports if admissible_support(s)]) for how, supports in paths]
    if not any(supports for _, supports in kept):
        kept = paths
    candidates = [c for how, supports in kept for c in scored(supports, how)]
    if not candidates and kept is not paths:  # no admissible one can be cross-validated
        candidates = [c for how, supports in paths for c in scored(supports, how)]
    if not candidates:
        raise ValueError("theta: no law can be cross-validated on these rows")

    def best_admissible(candidates):
        """The admissible candidate of smallest ratio (the smallest overall if none is)."""
        ordered = sorted(candidates, key=lambda c: c.ratio)
        return next((c for c in ordered if admissible(c)), ordered[0])

    def choice(candidates):
        """``(chosen, within, best, competes)``: the smallest competing candidate within one
        standard error of the best (the larger of the two), or within ``resolution`` on the
        relative residual converted to ratio units.
        """
        best = best_admissible(candidates)
        # only admissible laws compete, unless there is none
        competes = admissible if admissible(best) else (lambda c: True)
        resolution_in_ratio = resolution * best.ratio / max(best.relative, 1e-300)
        within = [c for c in candidates if competes(c) and c.ratio <= best.ratio + max(
            best.spread, c.spread, resolution_in_ratio)]
        return min(within, key=lambda c: (len(c.support), c.ratio)), within, best, competes

    if swaps:
        # the swap-refined path from the best admissible path law, then the best few path
        # supports of every size up to the law chosen so far, refined at their size
        best_path = best_admissible(candidates)
        seen = {frozenset(s.tolist()) for _, supports in paths for s in supports}
        memo = {}  # many starts meet on their way: each search is done once

        def unseen(supports):
            fresh = [s for s in supports if frozenset(s.tolist()) not in seen]
            seen.update(frozenset(s.tolist()) for s in fresh)
            return fresh

        candidates += scored(unseen(_refined_path(r_factor, total, best_path.support, memo)),
                             "swap-refined")
        largest = min(len(best_path.support), len(choice(candidates)[0].support))
        starts = {}
        for candidate in sorted(candidates, key=lambda c: c.ratio):
            size = len(candidate.support)
            if candidate.how != "swap-refined" and size <= largest \
                    and len(starts.setdefault(size, [])) < STARTS_PER_SIZE \
                    and (admissible(candidate) or not admissible(best_path)):
                starts[size].append(candidate.support)
        candidates += scored(unseen([refine_law_by_swaps(r_factor, total, start, memo=memo)
                                     for size in sorted(starts) for start in starts[size]]),
                             "swap-refined")
    chosen, within, best, competes = choice(candidates)
    support = chosen.support
    rivals = _rivals(within, support)
    ratio, values = noise_ratio_law(r_factor[:, support], total[np.ix_(support, support)])
    law = np.zeros(theta.shape[1])
    law[support] = values / scale[support]
    law /= np.linalg.norm(law)
    cv_ratio, cv_spread = np.full(len(order), np.inf), np.full(len(order), np.inf)
    for c in sorted(candidates, key=lambda c: c.ratio):  # the best competing one of each size
        if not np.isfinite(cv_ratio[len(c.support) - 1]) and competes(c):
            cv_ratio[len(c.support) - 1], cv_spread[len(c.support) - 1] = c.ratio, c.spread
    selection = LawSelection(
        order=np.concatenate([np.sort(support), order[~np.isin(order, support)]]),
        cv_ratio=cv_ratio, cv_spread=cv_spread, size=len(support),
        best_size=len(best.support), rule=f"one standard error of the noise ratio ({chosen.how})",
        rivals=rivals, admissible=admissible(chosen), cv_relative=float(chosen.relative))
    return law * np.sign(law[np.argmax(np.abs(law))]), ratio, selection


@dataclasses.dataclass
class _Candidate:
    support: np.ndarray
    ratio: float  # mean held-out noise ratio
    spread: float  # its standard error over the folds
    relative: float  # mean held-out relative squared residual
    how: str


def _rivals(candidates, support, max_rivals: int = 5) -> list:
    """Supports of ``candidates`` containing neither ``support`` nor another rival, smallest first.
    """
    chosen, rivals = set(support.tolist()), []
    for candidate in sorted(candidates, key=lambda c: (len(c.support), c.ratio)):
        terms = set(candidate.support.tolist())
        if terms >= chosen or any(terms >= set(r.tolist()) for r in rivals):
            continue
        rivals.append(np.sort(candidate.support))
        if len(rivals) == max_rivals:
            break
    return rivals


def _scored(theta, moments, supports, how, n_blocks, n_folds, row_moments=None) -> list:
    """Candidates of the supports that can be cross-validated."""
    if not supports:
        return []
    ratios, relative = _held_out_ratios(theta, moments, supports, n_blocks, n_folds, row_moments)
    (mean, spread), (relative_mean, _) = fold_summary(ratios), fold_summary(relative)
    return [_Candidate(np.asarray(s), mean[m], spread[m], relative_mean[m], how)
            for m, s in enumerate(supports) if np.isfinite(mean[m])]


def _admissible_starts(r_factor, moments, mass_matrices, seen) -> list:
    """The admissible lasso's supports, each with the backward path inside it (one list per start),
    less the supports in ``seen``.
    """
    paths, starts = [], set()
    for start in admissible_supports(r_factor, mass_matrices):
        if tuple(start.tolist()) in starts:  # its path's supports are all seen
            paths.append([])
            continue
        starts.add(tuple(start.tolist()))
        inside = start[law_elimination_path(r_factor[:, start], moments[np.ix_(start, start)])]
        path = [inside[:k] for k in range(2, len(start) + 1)
                if frozenset(inside[:k].tolist()) not in seen]
        seen.update(frozenset(support.tolist()) for support in path)
        paths.append(path)
    return paths


def _refined_path(r_factor, moments, start, memo=None) -> list:
    """From ``start`` down to two columns, each support swap-refined before the next elimination."""
    supports, support = [], np.asarray(start)
    while len(support) >= 2:
        support = refine_law_by_swaps(r_factor, moments, support, memo=memo)
        supports.append(support)
        if len(support) == 2:
            break
        support = eliminate_one(r_factor, moments, support)
    return supports


def select_laws(theta, noise_moments, n_blocks: int, mass_matrices=None,
                max_ratio_factor: float = 10.0, noise_draws=None) -> tuple[list, list, list]:
    """Laws for all the coordinates, uncoupled subsystems included.

    :func:`select_law`, then again on the coordinates left unexplained with the columns that
    leave the explained ones alone (uncoupled subsystems), a further law kept when its ratio is
    within ``max_ratio_factor`` of the first's.

    Parameters
    ----------
    theta : array, shape (n_blocks * N, F)
        Regression matrix with balanced blocks.
    noise_moments : array, shape (n_blocks, F, F)
        As in :func:`select_law`.
    n_blocks : int
        Number of coordinate blocks.
    mass_matrices : array, shape (S, F, n_blocks, n_blocks), optional
        As in :func:`select_law`; default None.
    max_ratio_factor : float, default 10.0
        A further law is kept when its noise ratio is within this factor of the first's.
    noise_draws : array, shape (D, n_rows, F), optional
        As in :func:`select_law`; default None.

    Returns
    -------
    laws : list of ndarray, shape (F,)
        The laws, the first one first.
    ratios : list of float
        Their noise ratios.
    selections : list of LawSelection
        How each was chosen.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> a, b = rng.normal(size=(2, 1000))
    >>> zero = np.zeros(1000)
    >>> clean = np.vstack([np.column_stack([a, 2 * a, zero, zero]),
    ...                    np.column_stack([zero, zero, b, -b])])
    >>> theta = clean + 0.05 * rng.normal(size=clean.shape) * (clean != 0)
    >>> moments = np.stack([np.diag([2.5, 2.5, 0, 0]), np.diag([0, 0, 2.5, 2.5])])
    >>> laws, ratios, _ = select_laws(theta, moments, 2)
    >>> sorted(np.flatnonzero(law).tolist() for law in laws)
    [[0, 1], [2, 3]]
    """
    theta = np.asarray(theta, dtype=float)
    n_features = theta.shape[1]
    n_samples = theta.shape[0] // n_blocks
    nonzero = column_norms(theta)[1]
    touches = coordinates_touched(theta, n_blocks)
    laws, ratios, selections = [], [], []
    explained = np.zeros(n_blocks, dtype=bool)
    while not explained.all():
        left = ~explained
        columns = np.flatnonzero(nonzero & ~touches[explained].any(axis=0)
                                 & touches[left].any(axis=0))
        if columns.size < 2:
            break
        mass = (None if mass_matrices is None
                else mass_matrices[:, columns][:, :, left][:, :, :, left])
        rows = np.repeat(left, n_samples)
        try:
            law, ratio, selection = select_law(
                theta[np.ix_(rows, columns)], noise_moments[left][:, columns][:, :, columns],
                n_blocks=int(left.sum()), mass_matrices=mass,
                noise_draws=None if noise_draws is None else noise_draws[:, rows][:, :, columns])
        except ValueError:  # too few rows or columns left to cross-validate
            break
        if laws and ratio > max_ratio_factor * max(ratios[0], 1e-12):
            break
        selection.rivals = [columns[r] for r in selection.rivals]  # the problem's columns
        full = np.zeros(n_features)
        full[columns] = law
        laws.append(full)
        ratios.append(ratio)
        selections.append(selection)
        explained |= explained_coordinates(theta, full, n_blocks)
    return laws, ratios, selections
