"""The path of a catalog growth: each tried catalog (:class:`GrowthStep`) and the outcome
(:class:`GrowthResult`: the chosen catalog, its fitted model and the table of the steps)."""

from __future__ import annotations

import dataclasses

import numpy as np

from .._validation import check_option
from .automatic import AutomaticCatalog

__all__ = ["GrowthStep", "GrowthResult"]


@dataclasses.dataclass
class GrowthStep:
    """One tried catalog: the move, its size, its held-out errors and the verdict.

    Parameters
    ----------
    move : str
        ``"start"``, one of :data:`~.growth.MOVES`, two of them joined by ``"+"`` (tried
        together), or a removal of the backward phase (``"-"`` and the family dropped,
        possibly followed by ``"+"`` and the move it is exchanged for).
    description : str
        :meth:`AutomaticCatalog.describe` of the catalog.
    terms : int
        Candidate terms (forces left out).
    active : int
        Terms the fit kept.
    time_error, region_error, criterion : float
        Held-out relative errors on the time and region blocks, and the criterion: the RMS
        of all the held-out blocks' errors, or of all but the largest with
        ``combine="trimmed"`` (inf when the fit failed or exceeded the ceiling).
    chosen : bool
        Whether the growth kept this catalog (the last one kept is the result).
    note : str, default ""
        Why a step was not evaluated or failed.
    seconds : float, default 0.0
        Time of the step's fit and scoring.
    cpu_seconds : float, default 0.0
        CPU time of the step's fit and scoring (in the process that ran it).
    definite : float, default 1.0
        Smallest fraction, over the step's fits, of the training states at which the fitted
        mass matrix is positive definite (0 when the catalog was not fitted, or one of its
        fits failed).
    second_error : float, default nan
        The criterion of the second fold (``region="consensus"`` of
        :func:`~.growth.grow_catalog`: fitted outside, judged on the extreme states); NaN
        where the second fold was not asked.
    second_cpu_seconds : float, default 0.0
        CPU time of the step's fit and scoring on the second fold (0 where it was not asked).
    block_errors : tuple of float, default ()
        The held-out error of each block, in order over the splits, that the criterion
        combines (:func:`~.criterion.combine_errors`; empty when not fitted).
    tie_error : float, default nan
        The step's criterion cross-validated on every block, where the step was one of the
        near ties judged again (:func:`~.ties.break_ties`); NaN elsewhere.
    support : tuple of tuple of str, default ()
        The names of the terms each split's fit kept (``XLSINDy.get_feature_names`` with a
        nonzero coefficient), in order over the splits; empty when not fitted or when a fit
        failed. Two catalogs with the same support hold the same law on the search's data.
    noise_floor : float, default nan
        The criterion's noise floor: its value for the residual that the positions' noise
        alone leaves to the step's fitted laws on the held-out blocks, combined over the
        blocks as the criterion is (:func:`~.floor.held_out_scores`); 0 where the noise is
        not propagated. :func:`~.growth.grow_catalog` computes it for the catalogs whose
        criterion decides whether a climb goes on (the ones it keeps), NaN elsewhere and
        where the catalog was not fitted. A criterion within the tolerance of it stops the
        climb as ``good_enough`` does.

    Examples
    --------
    >>> step = GrowthStep("degree", "x: x..x^3", 5, 3, 0.02, 0.04, 0.0316, False)
    >>> step.move, step.chosen
    ('degree', False)
    """

    move: str
    description: str
    terms: int
    active: int
    time_error: float
    region_error: float
    criterion: float
    chosen: bool
    note: str = ""
    seconds: float = 0.0
    cpu_seconds: float = 0.0
    definite: float = 1.0
    second_error: float = float("nan")
    second_cpu_seconds: float = 0.0
    block_errors: tuple = ()
    tie_error: float = float("nan")
    support: tuple = ()
    noise_floor: float = float("nan")


@dataclasses.dataclass
class GrowthResult:
    """What :func:`~.growth.grow_catalog` found.

    Parameters
    ----------
    model : XLSINDy
        The chosen catalog fitted on all the data.
    catalog : AutomaticCatalog
    steps : list of GrowthStep
    criterion : str
        ``"forces"`` or ``"accelerations"``: what the held-out errors measure.
    held_out_error : float
        The chosen catalog's criterion.
    max_terms : int or None, default None
        The ceiling of the growth: catalogs over it were not tried.
    work : float, default nan
        The work of the search's fits (the climbs and the backward phase): the sum of
        :func:`~.budget.work_cost` over the catalogs fitted (``work_budget`` of
        :func:`~.growth.grow_catalog` bounds it).
    own_runs : str or None, default None
        Unforced data: where ``model``, simulated from each run's first state, leaves its
        recorded runs (:func:`~pysindy_xl.fit.own_runs.own_runs_divergence`: no catalog's
        final fit the growth tried stays in them); None where it stays in them, or for forced
        data (not asked: recorded forces may hold an unstable system by feedback).

    Examples
    --------
    >>> steps = [GrowthStep("start", "", 4, 3, 0.5, 0.7, 0.61, True),
    ...          GrowthStep("degree", "", 5, 4, 0.01, 0.02, 0.016, True)]
    >>> print(GrowthResult(None, None, steps, "forces", 0.016).table())
    step  move          terms  kept  time err  region err  criterion  chosen
    ------------------------------------------------------------------------
       0  start             4     3    50.00%      70.00%     61.00%  yes
       1  degree            5     4     1.00%       2.00%      1.60%  yes
    """

    model: object
    catalog: AutomaticCatalog
    steps: list
    criterion: str
    held_out_error: float
    max_terms: int | None = None
    work: float = float("nan")
    own_runs: str | None = None

    def table(self) -> str:
        """The growth path as a plain-text table (one row per tried catalog).

        Returns
        -------
        str
            Header and one line per step: move, terms, kept terms, the held-out errors on the
            time block and on the region block, the criterion, its noise floor
            (:attr:`GrowthStep.noise_floor`; where a step reports one: a criterion within the
            tolerance of it stopped the climb), where near ties were judged
            again its cross-validation on all the blocks (:func:`~.ties.break_ties`; ``-``
            for the other steps), and whether it was chosen: ``yes`` for a catalog kept on
            the way, ``result`` for the one the model was fitted with (the near ties may
            choose a catalog kept before later ones, or a smaller one stating the same law).
        """
        ties = any(np.isfinite(step.tie_error) for step in self.steps)
        floors = any(np.isfinite(step.noise_floor) for step in self.steps)
        header = (f"{'step':>4}  {'move':<13}{'terms':>6}{'kept':>6}{'time err':>10}"
                  f"{'region err':>12}{'criterion':>11}"
                  + (f"{'noise floor':>13}" if floors else "")
                  + (f"{'all blocks':>12}" if ties else "") + "  chosen")
        lines = [header, "-" * len(header)]

        def pct(value):
            if not np.isfinite(value):
                return f"{'-':>10}"
            return f"{100 * value:9.2f}%" if value < 100 else f"{'>1e4%':>10}"
        final = (self.catalog.describe() if isinstance(self.catalog, AutomaticCatalog)
                 else None)
        result = max((k for k, step in enumerate(self.steps)
                      if step.chosen and step.description == final), default=None)
        for k, step in enumerate(self.steps):
            verdict = "result" if k == result else "yes" if step.chosen else "no"
            if step.note:
                verdict += f" ({step.note})"
            lines.append(f"{k:>4}  {step.move:<13}{step.terms:>6}{step.active:>6}"
                         f"{pct(step.time_error)}{pct(step.region_error):>12}"
                         f"{pct(step.criterion):>11}"
                         + (f"{pct(step.noise_floor):>13}" if floors else "")
                         + (f"{pct(step.tie_error):>12}" if ties else "") + f"  {verdict}")
        return "\n".join(lines)

    def spline_potentials(self, n_points: int = 9) -> dict:
        """The identified spline part of the potential of each coordinate that keeps one.

        ``V_spline(q) = -sum_k c_k B_k(q)`` (the Lagrangian holds ``-V``), sampled on the
        coordinate's range.

        Parameters
        ----------
        n_points : int, default 9
            Number of evenly spaced points of the coordinate's range.

        Returns
        -------
        dict of str to (ndarray, ndarray)
            ``{name: (grid, values)}``, each of shape (n_points,), for the coordinates whose
            model keeps a spline term.
        """
        import sympy as sp
        check_option("n_points", n_points, "int", low=2)
        library, coef = self.model.feature_library_, self.model.coef_
        out = {}
        for i, (q, name) in enumerate(zip(library.coords.q, library.coords.names,
                                          strict=True)):
            parts = [coef[j] * term for j, (term, category) in enumerate(
                zip(library.feature_terms_, library.categories_, strict=True))
                if category == "lagrange" and coef[j] != 0 and term.has(sp.Abs)
                and term.free_symbols == {q}]
            if parts:
                low, high = self.catalog.bounds[i]
                grid = np.linspace(low, high, n_points)
                values = -sp.lambdify(q, sp.Add(*parts), "numpy")(grid)
                out[name] = (grid, np.broadcast_to(values, grid.shape).astype(float))
        return out

    def to_dict(self) -> dict:
        """JSON-ready figures of the growth.

        Returns
        -------
        dict
            ``criterion``, ``held_out_error``, ``max_terms`` (the ceiling), ``catalog`` (its
            description), ``own_runs`` and ``steps`` (one dict per :class:`GrowthStep`); a
            figure that is not finite (a failed fit's inf, a fold not asked: NaN) is None, so
            that the dict is strict JSON.
        """
        return {"criterion": self.criterion, "held_out_error": _finite(self.held_out_error),
                "max_terms": self.max_terms,
                "catalog": self.catalog.describe(), "own_runs": self.own_runs,
                "steps": [{key: _finite(value) for key, value in dataclasses.asdict(s).items()}
                          for s in self.steps]}


def _finite(value):
    """``value``, or None for a float that is not finite; a tuple as a list of such values."""
    if isinstance(value, tuple):
        return [_finite(item) for item in value]
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value
