"""The search of a catalog growth: the candidate catalogs tried, the keep rules, the climbs.

:class:`Climber` holds what one growth has tried (each catalog fitted once, whichever path
tries it) and walks from the smallest catalog: each move alone (:meth:`Climber.first_moves`),
a climb through the moves in turn or by the best move (:func:`~.ascents.climb`,
:func:`~.ascents.steepest_climb`), and the backward phase dropping families
(:func:`~.backward.backward_phase`). :func:`~.growth.grow_catalog` sets up the data and the folds,
orders the moves and fits the chosen catalog; the module docstring of :mod:`.growth` states
the method.
"""

from __future__ import annotations

import numpy as np

from .automatic import AutomaticCatalog
from .budget import REFUSED, budget_note, work_cost
from .candidates import parameters_key, unfitted
from .floor import EXACT, floor_reached, models_floor, noise_explains
from .keep_rules import CONSENSUS_REACH, consensus_criteria, consensus_keeps, single_keeps
from .moves import (
    START,
    moved,
)
from .path import GrowthStep

__all__ = ["Climber"]


class Climber:
    """The catalogs one growth tries, its keep rules and its climbs.

    Parameters
    ----------
    fits : CandidateFits
        The search's fits of candidate catalogs (:class:`~.candidates.CandidateFits`).
    second_fits : CandidateFits or None
        The second fold's fits (``region="consensus"``), None for one fold.
    fixed : dict
        The :class:`AutomaticCatalog` parameters common to every candidate (coordinates,
        kinds, bounds of a search split, ...).
    kinds : list of str
        ``"linear"`` or ``"angle"`` per coordinate.
    tolerance : float
        The keep rules' fraction (:func:`~.keep_rules.single_keeps`).
    good_enough : float
        The criterion below which a climb stops.
    physical : bool
        Never give up a catalog whose fits are physical for one whose fits are not.
    retry_kinetic : bool
        Retry a move that the ceiling refuses with constant kinetic coefficients.
    criterion : str
        The criterion's name in the progress lines (``"forces"``, ``"accelerations"``).
    progress : callable or None
        Called with a line of text after each step.
    noise_floor : bool, default True
        A criterion at its noise floor stops a climb as one below ``good_enough`` does
        (:meth:`settled`).
    rates : callable or None, default None
        ``rates(parameters) -> {name: rate}``: the exponentials' rates fitted for a catalog
        (:class:`~.rates.RateFits`), which the move ``"exponentials"`` adds; None: that move
        does not apply.
    anchors : callable or None, default None
        ``anchors(parameters) -> {name: (a, b)}``: the springs' anchors fitted for a catalog
        (:class:`~.anchors.AnchorFits`), which the move ``"anchored_springs"`` adds; None: that
        move does not apply.
    budget : float or None, default None
        The search's work budget (:mod:`.budget`): a candidate whose fit would take
        :attr:`work` over it is not fitted (its step's note says ``"budget"``; the climbs
        retry it smaller, as over the ceiling). None: no budget.

    Attributes
    ----------
    steps : list of GrowthStep
        Every catalog tried, in order.
    first : GrowthStep
        The smallest catalog's step (after :meth:`start`).
    work : float
        The work of the catalogs fitted so far (:func:`~.budget.work_cost` summed), each fit
        once: parameters whose catalogs hold what an earlier candidate's hold share its fit
        (:meth:`~.candidates.CandidateFits.fit_key`) and add nothing.

    Examples
    --------
    >>> Climber.__name__
    'Climber'
    """

    def __init__(self, fits, second_fits, fixed, kinds, *, tolerance, good_enough, physical,
                 retry_kinetic, criterion, progress=None, noise_floor=True, rates=None,
                 budget=None, anchors=None):
        self.fits, self.second_fits, self.fixed = fits, second_fits, fixed
        self.kinds, self.n = list(kinds), len(kinds)
        self.tolerance, self.good_enough, self.physical = tolerance, good_enough, physical
        self.retry_kinetic, self.criterion, self.progress = retry_kinetic, criterion, progress
        self.consensus, self.noise_floor = second_fits is not None, noise_floor
        self.rates, self.budget, self.work = rates, budget, 0.0
        self.anchors = anchors
        self.steps, self.first = [], None
        self._cache = {}  # every catalog is fitted once, whichever path tries it
        self._paid = set()  # the fits paid for in :attr:`work` (their fit_key)
        self._parameters = {}  # the parameters of each step, by the step's id
        self._models = {}  # the fitted models of each step (its floor asked later), by id
        self._seconds = {}  # the second judge's steps, by the first's (of "consensus")
        self._refused = set()  # the steps never kept again (:meth:`refuse`), by id

    # -- fitting and judging ---------------------------------------------------------------
    def evaluate(self, parameters, move, ahead=()) -> GrowthStep:
        """The step of the catalog ``parameters``, fitted by the search.

        Parameters
        ----------
        parameters : dict
            The candidate's :class:`AutomaticCatalog` parameters (beyond ``fixed``).
        move : str
            The move's name in the path.
        ahead : sequence of dict, default ()
            The candidates the workers may fit meanwhile (the growth's guess).

        Returns
        -------
        GrowthStep
        """
        fields = self.fits.get(parameters, ahead)
        fit = self.fits.fit_key(parameters)
        if (fields.get("terms", 0) > 0 and not fields.get("note", "").startswith(REFUSED)
                and fit not in self._paid):
            # (a failed fit was paid too; unforced data: the implicit fit's cost); a catalog
            # whose content was fitted before under other parameters is that fit, not paid
            # again (:meth:`~.candidates.CandidateFits.get`)
            self._paid.add(fit)
            self.work += work_cost(fields["terms"], self.criterion != "forces")
        step = GrowthStep(move=move, chosen=False,
                          **{key: value for key, value in fields.items() if key != "models"})
        self._models[id(step)] = fields.get("models")
        if self.physical and step.definite < 1 and not step.note:
            step.note = (f"mass matrix not positive definite on {1 - step.definite:.0%} of "
                         "the training states")
        self._parameters[id(step)] = parameters
        return step

    def parameters_of(self, step) -> dict:
        """The catalog parameters (beyond ``fixed``) of a step this climber evaluated.

        Parameters
        ----------
        step : GrowthStep
            One of :attr:`steps`.

        Returns
        -------
        dict
        """
        return self._parameters[id(step)]

    def start(self, ahead=()) -> GrowthStep:
        """Fit the smallest catalog (:data:`~.moves.START`); it is chosen.

        Parameters
        ----------
        ahead : sequence of dict, default ()
            The candidates the workers may fit meanwhile.

        Returns
        -------
        GrowthStep
        """
        self.first = self.evaluate(dict(START), "start", ahead)
        self.first.chosen = True
        self.steps.append(self.first)
        return self.first

    def attempt(self, parameters, move, ahead=()) -> GrowthStep:
        """The step of ``parameters``, fitted and reported the first time it is tried.

        Parameters
        ----------
        parameters : dict
            The candidate's :class:`AutomaticCatalog` parameters (beyond ``fixed``).
        move : str
            The move's name in the path (of the first path that tries it).
        ahead : sequence of dict, default ()
            The candidates the workers may fit meanwhile.

        Returns
        -------
        GrowthStep
        """
        key = parameters_key(parameters)
        if key not in self._cache:
            refused = self._over_budget(parameters, move)
            self._cache[key] = refused or self.evaluate(parameters, move, ahead)
            self.steps.append(self._cache[key])
            self.report(self._cache[key])
        return self._cache[key]

    def _over_budget(self, parameters, move):
        """The unfitted step of a candidate whose fit would take :attr:`work` over the budget
        (None where it is within the budget, or over the ceiling: that refuses it first)."""
        if self.budget is None:
            return None
        implicit, ceiling = self.criterion != "forces", self.fits.search.max_terms
        if self.work + work_cost(ceiling, implicit) <= self.budget:
            return None  # (nothing within the ceiling can exceed it: no catalog built)
        size = self.size(parameters)
        note = budget_note(self.work, size, self.budget, implicit)
        if size <= 0 or size > ceiling or not note:
            return None
        step = GrowthStep(move=move, chosen=False, **unfitted(
            note, size, AutomaticCatalog(**self.fixed, **parameters).describe()))
        self._parameters[id(step)] = parameters
        return step

    def second_step(self, step) -> GrowthStep:
        """``step``'s catalog judged by the second fold (fitted once), recorded in the step's
        ``second_error``.

        Parameters
        ----------
        step : GrowthStep
            A step this climber fitted.

        Returns
        -------
        GrowthStep
        """
        if id(step) not in self._seconds:
            fields = self.second_fits.get(self._parameters[id(step)])
            self._seconds[id(step)] = GrowthStep(move=step.move, chosen=False, **fields)
            step.second_error = self._seconds[id(step)].criterion
            step.second_cpu_seconds = self._seconds[id(step)].cpu_seconds
        return self._seconds[id(step)]

    def compared(self, step, best) -> tuple:
        """The criteria the keep rules compare: the first fold's, or with ``"consensus"``
        the combined ones (:func:`~.keep_rules.consensus_criteria`; the candidate is not
        fitted on the second fold where it is more than :data:`CONSENSUS_REACH` times worse
        on the first, and then compares as infinite).

        Parameters
        ----------
        step, best : GrowthStep
            The candidate and the kept catalog.

        Returns
        -------
        tuple of float
            The candidate's and the kept catalog's criteria.
        """
        if not self.consensus:
            return step.criterion, best.criterion
        if not step.criterion <= best.criterion * CONSENSUS_REACH:
            return np.inf, best.criterion
        return consensus_criteria(step, best, self.second_step(step), self.second_step(best))

    def refuse(self, step, why: str) -> None:
        """Never keep ``step`` again (:meth:`keeps`, the backward phase, the near ties): its
        catalog cannot be the growth's answer.

        Parameters
        ----------
        step : GrowthStep
            A step this climber fitted.
        why : str
            The reason, which becomes the step's ``note`` (shown in the path's table).

        Returns
        -------
        None
        """
        step.note = why
        self._refused.add(id(step))

    def refused(self, step) -> bool:
        """Whether :meth:`refuse` refused ``step``.

        Parameters
        ----------
        step : GrowthStep
            A step this climber fitted.

        Returns
        -------
        bool
        """
        return id(step) in self._refused

    def keeps(self, step, best) -> bool:
        """Whether ``step`` replaces ``best``: the keep rule of one fold
        (:func:`~.keep_rules.single_keeps`) or, with ``"consensus"``, of two
        (:func:`~.keep_rules.consensus_keeps`: the second fold is asked only about a larger
        candidate that the first keeps, or another within :data:`CONSENSUS_REACH`); with
        ``physical``, a catalog whose fits have a positive definite mass matrix is not given
        up for one whose fits have not. A refused step (:meth:`refuse`) is never kept.

        Parameters
        ----------
        step, best : GrowthStep
            The candidate and the kept catalog.

        Returns
        -------
        bool
        """
        if self.refused(step):
            return False
        if not self.consensus:
            judged = single_keeps(step, best, self.tolerance)
        elif (not single_keeps(step, best, self.tolerance) if step.terms > best.terms
              else not step.criterion <= best.criterion * CONSENSUS_REACH):
            judged = False
        else:
            judged = consensus_keeps(step, best, self.second_step(step),
                                     self.second_step(best), self.tolerance)
        return judged and (not self.physical or step.definite >= 1 or best.definite < 1)

    def size(self, parameters) -> int:
        """The terms of the catalog ``parameters`` (-1 where it cannot be built).

        Parameters
        ----------
        parameters : dict
            The candidate's :class:`AutomaticCatalog` parameters (beyond ``fixed``).

        Returns
        -------
        int
        """
        try:
            return AutomaticCatalog(**self.fixed, **parameters).n_terms
        except ValueError:
            return -1

    def report(self, step) -> None:
        """Pass ``step``'s progress line to ``progress``.

        Parameters
        ----------
        step : GrowthStep
            The step reported.
        """
        if self.progress is not None:
            self.progress(
                f"{step.move:<13} {step.terms:>5} terms  held-out {self.criterion} error "
                + (f"{100 * step.criterion:.2f} %" if np.isfinite(step.criterion) else "-")
                + ("  kept" if step.chosen else "") + (f"  ({step.note})" if step.note else ""))

    # -- the paths ---------------------------------------------------------------------------
    def moved(self, state, move, skip=0):
        """:func:`~.moves.moved` with the growth's coordinates.

        Parameters
        ----------
        state : dict
            The catalog's parameters.
        move : str
            The move (:data:`~.moves.MOVES`, :data:`~.moves.MORE_MOVES`, or a joint move).
        skip : int, default 0
            Degrees skipped (a degree move looking one degree further).

        Returns
        -------
        dict or None
            The moved parameters, None where the move does not apply.
        """
        return moved(state, move, self.kinds, self.n, skip, self.rates, self.anchors)

    def first_moves(self, queue) -> tuple:
        """Each move of ``queue`` (``(move, parameters)`` pairs) alone from the first catalog:
        a degree move looks one degree further unless its first degree is kept.

        Parameters
        ----------
        queue : list of (str, dict)
            The moves and their parameters from the first catalog.

        Returns
        -------
        alone : dict
            The best criterion of each move, by move.
        steps : dict
            The step of that criterion, by move.
        """
        alone, alone_steps, stopped = {}, {}, set()
        for index, (move, parameters) in enumerate(queue):
            if move in stopped:
                continue  # (its first degree was kept: no look further)
            step = self.attempt(parameters, move, [p for _, p in queue[index + 1:]])
            if step.criterion < alone.get(move, np.inf):
                alone[move], alone_steps[move] = step.criterion, step
            if single_keeps(step, self.first, self.tolerance):  # (the first fold's rule)
                stopped.add(move)
        return alone, alone_steps

    def settled(self, step, floor=True) -> bool:
        """Whether ``step``'s criterion leaves nothing for a larger catalog to find: below
        ``good_enough``, or (with ``noise_floor``) at its noise floor
        (:func:`~.floor.floor_reached` with the keep tolerance: the residual is what the
        positions' noise alone leaves to a right law, and a move that lowers it by less than
        the tolerance is not kept). The smallest catalog is not settled by its floor: a law
        that lacks a family makes up for it with large coefficients on noisy columns, which
        raise its floor with its residual (two coupled carts at 2 % noise: 1.42 times its
        floor where the law is at 0.85 times its own, 2.6 times lower); the first moves and
        the climb's first pass compare it with the catalogs one move away.

        Parameters
        ----------
        step : GrowthStep
            A step this climber fitted.
        floor : bool, default True
            Whether the noise floor counts (False: ``good_enough`` only).

        Returns
        -------
        bool
        """
        if not step.criterion > self.good_enough:
            # good enough where the positions' noise could account for it: free of noise
            # (a floor of round-off) a stand-in at 0.1 % is not what the data allow, and the
            # climb goes on (a cosine and a cos(theta) inertia for a torsion spring on a cart)
            return (step.criterion <= EXACT or not self.noise_floor or step is self.first
                    or noise_explains(step.criterion, self.floor(step)))
        if not (floor and self.noise_floor and step is not self.first):
            return False
        return floor_reached(step.criterion, self.floor(step), self.tolerance)

    def floor(self, step) -> float:
        """A step's noise floor, computed from its stored fits when first asked (the floor
        is computed only for the catalogs whose criterion decides a climb, and for the
        growth's answer).

        Parameters
        ----------
        step : GrowthStep
            A step of this climber.

        Returns
        -------
        float
            Its criterion's noise floor (:func:`~.floor.models_floor`), NaN where its fits
            are not stored.
        """
        models = self._models.get(id(step))
        if np.isnan(step.noise_floor) and models is not None and np.isfinite(step.criterion):
            step.noise_floor = models_floor(self.fits.search, models, step.block_errors)
        return step.noise_floor
