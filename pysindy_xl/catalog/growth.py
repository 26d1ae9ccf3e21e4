"""Growing an automatic catalog on data: start small, grow while a held-out criterion improves.

The criterion is the relative residual of the fitted model's equations in the weak form
(integrated against test functions on smoothed positions, so that no acceleration is estimated)
on samples the fit never saw: over the generalized forces' part for data with forces; for
unforced data each coordinate's equation over its own kinetic part (the terms that carry
inertia: about the relative error of the accelerations the law predicts), combined as an RMS
over the coordinates (:func:`~.criterion.held_out_error`; an implicit law fixes each equation
only up to a factor: judged over all rows, a law that shrank one equation would hide its
residual; judged over its largest term, a law that shrank its kinetic part behind large
potential terms that nearly cancel would; the strong form where a block is shorter than a
test function). Two blocks of each run are held out (:mod:`.folds`):

- the last of ``n_blocks`` contiguous time blocks (**time**: how the model predicts later);
- the other block reaching farthest from the run's median state (**region**: how it
  extrapolates to states it did not see). An approximation fitted along the trajectories (a
  cosine standing in for ``theta^2``) fails there, where the right structure does not.

The region block lies inside the range the other blocks cover, so at high noise it may not
tell a stand-in from the law. ``region="extremes"`` holds out instead the stretches around
the most extreme states of all the runs: every state beyond a threshold of the scaled
distance from the median, with a test function's half-width of time on either side, a share
:data:`~.folds.EXTREME_SHARE` of the other samples, cut whole so that no test function
straddles the fold. The training states then all lie inside the threshold, and a stand-in must
extrapolate. It is not the default: where a law's nonlinearity shows only in the extreme
states (a hardening spring on a short recording), the fit inside the threshold cannot find it
and the growth stops at the start. ``"both"`` holds out both.

``region="consensus"`` keeps the two folds apart and lets both judge
(:func:`consensus_keeps`). A change that adds terms is kept when the block fold keeps it and
the extremes fold does not find it worse beyond the tolerance: a stand-in that gains a little
on the time blocks (fitted along the trajectories) and loses beyond the recorded states is
refused. Any other change (a family dropped or exchanged for another, the smaller of the two
climbs' ends) is judged by the geometric mean :math:`\\sqrt{c_1 c_2}` of the two folds'
criteria (:func:`consensus_criteria`), where a relative change counts the same on either
fold: the law that a stand-in displaced comes back when what it loses on the time blocks is
less than what it gains beyond the recorded states. The extremes fold never adds terms on its
own: fitted inside the threshold on fewer states, it may prefer a larger catalog that
compensates its own bias. Where both catalogs compared fail the extremes fold (criterion of 1
or more: the residual as large as what the equations should explain), that fold cannot tell
them apart and the block fold decides alone: the hardening spring that the extremes fold
hides is found as by the default. The first moves that the block fold cannot tell apart
(kept, within the tolerance of the best first move) are ranked by the geometric mean, so
that the one that extrapolates is climbed from first. The second fit is paid only for these,
for a larger candidate that the block fold keeps, and for a smaller one within
:data:`CONSENSUS_REACH` of the kept catalog on the block fold.

With ``cross_validate``, every block is held out in turn instead (one fit per block on the
others; the criterion is the RMS of all the blocks' errors): on a recording of a few
seconds the region block holds most of what identifies configuration-dependent terms, and a
fit without it fails for the right catalog too (``region="extremes"`` adds a split judged on
the extreme stretches). ``combine="trimmed"`` then leaves the largest of the block errors
out of the RMS (:func:`~.criterion.combine_errors`): one failing fit out of at least four
is tolerated, and the catalog is still judged on the others.

The criterion is the RMS of the two errors. Splines end at the extreme percentiles of the
training data (:data:`~.growth_data.END_PERCENTILE`) and continue linearly
(:func:`~.bases.natural_splines`: a constant force beyond) or, after the move
``"quadratic_ends"``, quadratically (:func:`~.bases.quadratic_end_splines`: a constant
stiffness beyond), so the region fold judges their continuation as it judges any family's.
A spline's continuation is set by its slope and curvature at the end knot, which the few
samples of the last knot intervals fix unsteadily: a cubic spline on 8 even knots fitted on
the search's training pieces may continue 5 % or 30 % off over the region block, where the
law of a slider on an oblique spring is off by 0.5 %. After the move ``"knots"`` the splines
are written one column per interior knot (:func:`~.bases.truncated_power_splines`, the same
span); the search's sparse selection then leaves out the knots its data do not need, and a
spline with fewer knots has a steadier end slope and curvature. Which writing extrapolates,
the held-out criterion judges (a steep wall needs the knots that the selection may leave
out; the two moves are tried together too, as ``"quadratic_ends+knots"``: B-splines with
quadratic ends may continue worse than natural ones and natural splines written by knots
gain nothing, where quadratic ends written by knots extrapolate a stiffening spring). The
final fit keeps each coordinate's splines whole either way.
From the smallest catalog (constant kinetic coefficients, quadratic potentials of the linear
coordinates, sines and cosines of the angles, viscous friction), each move of :data:`MOVES` but
the splines' (:data:`~.moves.SPLINE_MOVES`) is first tried alone (``"kinetic_trig_degree"``:
configuration-dependent kinetic coefficients with an angle's ``sin^2`` and ``sin cos``, the
inertia ``sin(theta)^2 phi_dot^2`` of a link pitched to an axis), and so is each pair of moves
whose joint catalog holds terms that neither adds alone (``"kinetic+interaction"``:
configuration-dependent kinetic coefficients over products of two coordinates' functions, the
``cos(a - b)`` of a coupling ``cos(a - b) a_dot b_dot``; a climb through single moves reaches it
only after the stand-ins that each move alone favours); the moves are then tried in turn in the
order of what they achieved alone (the family that explains most goes in first: no fixed order
decides between a stand-in and the right family), the splines last (the flexible basis is for
what the families leave; before them the exponentials of the linear coordinates, with a fitted
rate, :mod:`.rates`). The growth climbs twice, from the best and from the second-best first
move, and keeps the better end: the first move is where a stand-in wins (a ``cos(theta)``
inertia for a torsion spring, or a power of an angle for a coupling that takes two moves to
state). The second climb stops once it holds the first one's end (every family at least as far
grown): it is there to leave a stand-in first move, and from there on it adds families to the
first end, which the first climb tried alone from that end and did not keep (a combination of
them that only a longer climb would find is given up: on the forced cart with a spring pendulum
at 5 % noise the growth keeps the 21-term catalog, not a 43-term one holding ``theta^2`` and
gyroscopic terms, 10 % lower held out, with the same fitted law). A move is kept when it lowers
the criterion by the fraction ``tolerance`` at least, or keeps it within that fraction with
fewer terms in the fitted model (a sine series imitating ``theta^2`` needs more terms than
``theta^2``); with ``physical``, a catalog whose fits all have a positive definite mass matrix
on their training states is never given up for one whose fits have not (a model whose mass
matrix is not positive definite cannot be simulated there; the climb may pass through such
stand-ins only while it holds no physical catalog). The degree moves repeat while they do (and
look one degree further before they stop), and the growth stops when a whole pass keeps nothing
or the criterion is settled: below ``good_enough`` (unforced data: :data:`EXACT`), or at its
noise floor (``noise_floor``, below). Before it stops, pairs of the moves that are not repeated
(kinetic, interaction, gyroscopic, Coulomb, the kinetic coefficients' second trigonometric
degree) are tried together: a law may gain from neither
alone (a coupling ``cos(a - b) a_dot b_dot`` needs both the products of two angles' functions
and configuration-dependent kinetic coefficients). With ``steepest``, each step of a climb tries
every move from the kept catalog and keeps the best instead of the first that improves (the
pairs where none does): a move that helps only once another is in (the coupled damping of a
coupling's links, poor alone) is not passed over for a stand-in that the order of the moves
alone tries first. Catalogs over ``max_terms`` are not tried (reported as the ceiling); by
default the ceiling follows the data: ``1 / ROWS_PER_TERM`` (two thirds) of the rows of the
search's fits (a selection over more columns is ill-posed at noise), at most :data:`MAX_TERMS`.
A refused move (over the ceiling, or over the work budget ``work_budget``, :mod:`.budget`) is
tried again with fewer kinetic coefficients (:func:`~.retries.attempt_within_limits`): with the
kinetic order of the catalog it moved from (``"interaction@k2"``: a three-link arm in relative
angles, inertia in ``cos(b + c)``, gravity in ``cos(a + b + c)``, 143 terms, 191 with one order
for both), over fewer coordinates' functions (``kinetic_interaction``, ``"kinetic@k1"``: two
spring-coupled carts, each with a pendulum, 123 terms, 333 with one order), or with constant
ones (``"degree-kinetic"``: three masses on quartic springs). A retry drops no family the
catalog it moved from holds while one that narrows it is within the limits
(:func:`~.retries.retry_order`: from configuration-dependent kinetic coefficients the narrower
orders come before constant ones; a Furuta pendulum's arm spring ``"angle_degree@k1"`` keeps
the ``sin(b)^2`` inertia the climb kept); dropping a family is the backward phase's. A joint
first move over the ceiling is narrowed so too, and the move ``"kinetic"`` widens a narrowed
order by one.

The climb only adds, and the start always holds an angle's sines and cosines: where families
are nearly dependent on the data's range (``cos(phi) = 1 - phi^2/2 + phi^4/24 - ...``), the
fit keeps a stand-in (``2 cos(phi) - 0.58 phi^4`` for ``-phi^2 - 0.5 phi^4``) that the right
family beside it cannot displace. So a backward phase follows (a stepwise forward-backward
search over the families): each family the start or the climb put in is dropped in turn (the
moves ``"-splines"``, ``"-trig"``: an angle's sines and cosines beside its powers,
``"-trig_degree"``, ``"-angle_degree"``: its powers beside sines and cosines, ``"-degree"``,
``"-interaction"``, ``"-kinetic"``, ``"-gyroscopic"``, ``"-coulomb"``,
``"-kinetic_trig_degree"``; one degree step at a
time), and the best drop that the keep rule accepts is kept; at an equal number of fitted
terms the smaller catalog is kept within the tolerance too (the stand-in family goes). A
family whose drop is not kept alone is exchanged for the one it stands in for (sines and
cosines, or a degree of them, for one or two more powers of the angle, powers for a sine
degree, splines for powers: ``"-trig+angle_degree"``, the forward step of the search, taken
where a stand-in leaves, while the criterion is not settled; sines and cosines grown several
degrees also from degree 1: ``"-trig_degree*2+angle_degree"``). The phase repeats, never back
to a catalog already kept, until nothing is dropped (:mod:`.backward`). The two
held-out blocks of each run judge cheaply (one fit per catalog) but on two fifths of the data:
where a stand-in and the law differ by little on the recorded states, that judgment's noise
decides between them. So, last, the near ties of the criterion are judged again on every block
(``tie_break``, :mod:`.ties`): each by ``n_blocks`` fits, every block held out in turn, and the
keep rule of the near ties chooses on those fits (:func:`~.ties.tie_keeps`: the RMS of all the
blocks' errors, and the terms the cross-validated fits keep); each law is stated by the smallest
catalog whose fit kept exactly its terms (a larger one only offers the final fit more columns
to choose stand-ins from).

With noisy positions the criterion of a right law is not small: the held-out rows carry the
noise, and no catalog explains it. So the growth asks, of each catalog it keeps, the criterion's
noise floor (``noise_floor``; :attr:`GrowthStep.noise_floor`): the criterion that the noise of
the positions alone leaves to its fitted laws, from the held-out rows' noise draws
(:mod:`.floor`). A kept catalog within ``tolerance`` of its floor (a discrepancy principle: a
move must lower the criterion by the tolerance to be kept) settles the growth as ``good_enough``
does: the climbs try no further move and the second climb is not made; the backward phase and
the near ties run as below ``good_enough``. Two exceptions keep a stand-in at its own floor from
ending the search. The smallest catalog is not settled by its floor: a law that lacks a family
makes up for it with large coefficients on noisy columns, which raise its floor with its
residual (two coupled carts at 2 % noise: the uncoupled catalog is 1.4 times its floor, the law
0.85 times its own, 2.6 times lower). And the floor stops a climb before a move, not within one:
a kept degree move still looks one degree further, and the backward phase still exchanges a
family that stands in for another (on the quartic rotor at 5 % noise the cosine beside ``phi^2``
is at its floor on the recorded angles; ``phi^4`` is then tried, and the near ties choose it).
Free of noise the floor is round-off, far below :data:`EXACT` and ``good_enough``: the floor
never stops the growth there, and neither does ``good_enough`` above :data:`EXACT` (a stand-in's
error, not the data's precision: on a cart with a torsion-sprung pendulum, ``cos(theta)`` for
``theta^2`` at 0.1 %); the climb goes on. A right law sits at 0.87 to 1.13 times its floor on
the generic systems with two or more coordinates (where the stop applies), 1.2 to 1.7 times with
one (where the climb goes on as without it). The chosen catalog is then fitted on all the data
(:mod:`.final_fit`). A settled choice whose final fit fails the checks below is refused and the
search goes on past it (:mod:`.climb_ends`: the settlement claimed that nothing more was to be
found, which a catalog that is no model of the data cannot claim). Where a final model's mass
matrix is not positive definite on its training states (no mechanical system: it cannot be
simulated along its data) and the search cannot go on, the growth answers with the first of
its other catalogs, by criterion, whose final fit's is
(:func:`~.final_fit.physical_alternative`), or, where none is, with that model (its fit warns).
On unforced data the final fit must also stay in its free runs when simulated from their first
states (:func:`~.final_fit.free_runs_check`; :attr:`GrowthResult.own_runs`). """

from __future__ import annotations

import numpy as np

from .._inputs import as_list, trajectory_arrays
from .anchors import AnchorFits
from .automatic import AutomaticCatalog
from .budget import WORK_BUDGET
from .candidate_fit import support_criterion
from .candidates import CandidateFits
from .climb_ends import resumed_end, search_end
from .climbs import Climber
from .final_fit import (
    final_answer,
    fit_chosen,
    free_runs_check,
    restore_judged_terms,
    warn_free_runs,
)
from .floor import EXACT
from .folds import held_out_splits
from .growth_data import END_PERCENTILE as END_PERCENTILE  # (where it was first)
from .growth_data import GROWTH_REGIONS as GROWTH_REGIONS  # (where it was first)
from .growth_data import check_growth_data, check_growth_options, data_span, thinned
from .keep_rules import single_keeps
from .kinds import coordinate_kinds, coordinate_names
from .moves import LATE_MOVES, MORE_MOVES, MOVES, START, is_repeated, joint_moves, moved, narrowed
from .path import GrowthResult, GrowthStep
from .rates import RateFits
from .search_data import SearchData, SearchSplit, judge_data, search_rows

__all__ = ["grow_catalog", "GrowthStep", "GrowthResult", "MOVES", "MORE_MOVES",
           "check_growth_data", "GROWTH_REGIONS"]

#: Ceiling of the catalog's size with ``max_terms="auto"``, whatever the data.
MAX_TERMS = 400

#: With ``max_terms="auto"``, rows of the search's fits per catalog term at least: catalogs
#: over ``rows // ROWS_PER_TERM`` terms are not tried (least squares inflate the rows' noise
#: ``p / (r - p)`` times on ``p`` columns, ``r`` rows: 2 here; 143 of 234 fit an arm, 191 not).
ROWS_PER_TERM = 1.5


def grow_catalog(x, t, u=None, x_dot=None, x_ddot=None, *, coordinates, kinds=None,
                 max_terms: int | str = "auto", optimizer=None, formulation: str = "auto",
                 n_blocks: int = 5, tolerance: float = 0.05, good_enough: float = 0.002,
                 moves=MOVES, search_optimizer="auto", search_samples: int | None = 6000,
                 cross_validate: bool = False, region: str = "block",
                 physical: bool = False, steepest: bool = False, progress=None,
                 n_jobs=None, combine: str = "rms", tie_break: bool = True,
                 noise_floor: bool = True, work_budget: float | None = WORK_BUDGET):
    """Grow an :class:`AutomaticCatalog` on data (see the module docstring).

    Parameters
    ----------
    x : array (N, n) or list of arrays
        Positions, one run or several.
    t : float, array (N,) or list of arrays
        Time step, or strictly increasing times matching ``x`` (one array for every run, or
        a list of one per run).
    u : same layout as ``x``, optional
        Generalized forces (zero columns: unforced coordinates); None: unforced data.
    x_dot, x_ddot : same layout as ``x``, optional
        Measured velocities and accelerations.
    coordinates : list of str
        The coordinates' names.
    kinds : None, str, sequence or mapping
        ``"linear"`` or ``"angle"`` per coordinate (:func:`coordinate_kinds`).
    max_terms : int or "auto", default "auto"
        Ceiling of the catalog's size: larger catalogs are not tried. ``"auto"``:
        ``min(MAX_TERMS, R // ROWS_PER_TERM)``, with ``R`` the fewest rows (equations) of
        the search's fits over its splits (in the weak form, the coordinates times the test
        functions on the training pieces; :func:`~.search_data.search_rows`), reported as
        :attr:`GrowthResult.max_terms`.
    optimizer : optional
        Of :class:`~pysindy_xl.XLSINDy` (default: chosen from the forces).
    formulation : {"auto", "strong", "weak"}, default "auto"
    n_blocks : int, default 5
        Blocks per run (two are held out).
    tolerance : float, default 0.05
        Relative decrease of the criterion that keeps a move (or relative increase within
        which a move that fits fewer terms is kept).
    good_enough : float, default 0.002
        With forces, the growth stops once the criterion is below this relative error
        (unforced data: below :data:`EXACT`, a law exact to the data's precision), or at its
        noise floor (``noise_floor``); every move is tried otherwise. With ``noise_floor``, a
        criterion between :data:`EXACT` and ``good_enough`` stops the growth only where the
        positions' noise could account for it (within
        :data:`~pysindy_xl.catalog.floor.EXPLAINED` times its floor): free of noise, a
        stand-in at 0.1 % is not what the data allow.
    moves : sequence of str, default MOVES
        The moves tried (some of :data:`MOVES` and :data:`MORE_MOVES`); the backward phase
        drops the families of these moves only (``"trig_degree"``: the sines and cosines too).
        ``"differences"`` adds ``(q_j - q_i)^2``, then higher powers, of each pair of
        coordinates of one kind (a joint's spring in one column; ``AutomaticCatalog``'s
        ``differences``).
        ``"exponentials"`` adds ``exp(a x)`` and ``exp(2 a x)`` of each linear coordinate,
        with the rate ``a`` fitted for the catalog it moves from (:class:`~.rates.RateFits`:
        by variable projection on the search's samples, then, where the exponentials lower
        the criterion by :data:`~.rates.REFINE_GAIN`, on the criterion itself); it is tried
        after the families, alone, as the splines' moves (:data:`~.moves.LATE_MOVES`).
        ``"anchored_springs"`` adds the length of a spring anchored off each coordinate's
        path (``sqrt(1 - e cos(theta - phi))``, ``sqrt((x - c)^2 + h^2)``), its geometry
        fitted likewise (:class:`~.anchors.AnchorFits`); it is tried after the exponentials,
        before the splines.
    search_optimizer : "auto", str or optimizer, default "auto"
        Optimizer of the search's fits; ``"auto"``: ``optimizer`` when given, else one
        selection per fit (``ExplicitOptimizer()``, ``MixedOptimizer()``, or XLSINDy's default
        for unforced data) where the final fit bags selections on noisy positions.
    search_samples : int or None, default 6000
        The search fits runs thinned to about this many samples in all (every k-th sample); the
        final fit uses all. None: no thinning.
    cross_validate : bool, default False
        Hold out every block in turn (``n_blocks`` fits per catalog, each on the other
        blocks; the criterion is the RMS of the ``n_blocks`` errors, the steps report the last
        block's and the region block's) instead of the time and region blocks at once. On
        recordings of a few seconds the region block holds most of what identifies
        configuration-dependent terms (the largest swings): fitted without it, the right
        catalog's fit fails and the growth keeps a smaller one.
    region : {"block", "extremes", "both"}, default "block"
        What the region fold holds out besides the last block of each run
        (:func:`~.folds.held_out_splits`): the block reaching farthest from the run's median;
        the stretches around the most extreme states of all the runs (the training states
        then all lie inside a threshold that the held-out ones cross: a stand-in fitted along
        the trajectories must extrapolate, but so must the law, whose nonlinear terms may show
        only beyond the threshold); or both. Cross-validated, ``"extremes"`` and ``"both"``
        add a fit outside the extreme stretches, judged on them. ``"consensus"``: the
        ``"block"`` fold and the ``"extremes"`` fold judge each change together
        (:func:`consensus_keeps`: a larger catalog must be kept by the first and not be
        worse on the second, the others are judged by the geometric mean of the two
        criteria); :attr:`GrowthStep.second_error` reports the second where it was asked.
        Cross-validated, the first fold is the cross-validation's.
    physical : bool, default False
        Never give up a catalog whose fits are physical (the mass matrix of each fit
        positive definite on all its training states: :attr:`GrowthStep.definite` is 1)
        for one whose fits are not, in the climb and in the backward phase, and prefer a
        physical end of the two climbs. Until a physical catalog is kept (the first
        catalog may not be), the climb keeps any better one. A stand-in that lowers the
        criterion with an indefinite mass matrix (sine harmonics of each angle for the
        coupling of two) gives a model that cannot be simulated where the matrix is
        singular.
    steepest : bool, default False
        Climb by the best move instead of the first that improves: from each kept catalog
        every move (a degree move also one degree further) is tried and the best kept, the
        pairs of moves where none is. A move that helps only once another is in (the
        coupled damping of a coupling's links) then goes in before a stand-in that the
        order of the moves alone would try first and that leaves it over ``max_terms``.
        As in the default climb, a move that the data-sized ceiling refuses is tried with
        constant kinetic coefficients, and the second climb stops once it holds the first
        one's end.
    progress : callable, optional
        Called with a line of text after each step.
    n_jobs : int or None, default None
        Processes of the search: while one candidate is fitted, ``n_jobs - 1`` joblib
        workers fit the ones the growth will probably try next (those that follow if the
        current one is not kept). The path and the result do not depend on it. None: 1
        (joblib's convention; -1: all cores).
    combine : {"rms", "trimmed"}, default "rms"
        How the held-out blocks' errors :math:`e_1, \\dots, e_n` make the criterion
        (:func:`~.criterion.combine_errors`): their RMS, or the RMS of all but the largest,

        .. math:: c = \\sqrt{\\tfrac{1}{n - 1} \\textstyle\\sum_{i=1}^{n-1} e_{(i)}^2}
                  \\quad (e_{(1)} \\le \\dots \\le e_{(n)}).

        ``"trimmed"`` needs ``cross_validate`` and ``n_blocks >= 4`` (at least four
        held-out blocks: a catalog is still judged on three or more fits on other data, so
        a stand-in that fails wherever it extrapolates is not excused; the two blocks of
        the default split are not enough). With it, a split whose fit raises scores inf on
        its block rather than failing the catalog. Cross-validated on a few seconds, the
        fit without the block of the largest swings can fail for the right catalog (the
        cart double pendulum's coupled damping: below 1 % on four blocks, 30-95 % on the
        fifth), and the RMS then refuses it.

    tie_break : bool, default True
        Judge the near ties again: the catalogs whose criterion is within
        :data:`~.ties.TIE_REACH` of the chosen one's (at most :data:`~.ties.TIE_CANDIDATES`,
        one per fitted law, each the smallest catalog whose fit kept exactly that law's terms)
        are each cross-validated on every block, one fit per block on the others, and the
        keep rule chooses among them on the RMS of the blocks' errors
        (:func:`~.ties.break_ties`; :attr:`GrowthStep.tie_error`). The two held-out blocks
        of each run make a noisy judgment where a stand-in and the law differ by little on
        the recorded states; all the blocks make a sharper one (with ``region="extremes"``
        or ``"both"``, and a split judged on the extreme stretches). Unused with
        ``cross_validate`` (the criterion already holds out every block) and with
        ``region="consensus"`` (whose second fold judges what the blocks cannot tell apart:
        the blocks alone would undo its choice).

    noise_floor : bool, default True
        Settle the growth, as ``good_enough`` does, once a kept catalog's criterion is within
        ``tolerance`` of its noise floor (:attr:`GrowthStep.noise_floor`: the criterion
        that the noise of the positions alone leaves to the step's fitted laws,
        :func:`~.floor.held_out_scores`):

        .. math:: c \\le (1 + \\text{tolerance})\\, f, \\qquad
                  f = \\frac{\\sqrt{\\tfrac1D \\sum_d \\|\\Delta_d \\xi\\|^2}}{s},

        with ``Delta_d`` the held-out rows' noise draws and ``s`` the criterion's scale
        (computed for the kept catalogs; the smallest catalog is not settled by it). The
        climbs try no further move (a kept degree move still looks one degree further) and
        the second climb is not made; the backward phase (its exchanges too) and the near
        ties run as below ``good_enough``. Free of noise the floor is round-off, and the
        growth is the same either way. False: the floor is neither computed nor used.
    work_budget : float or None, default WORK_BUDGET
        Bound of the search's work, in fits of a 100-term catalog (:mod:`.budget`: a catalog
        of ``k`` terms costs ``(k / 100)^3``, four times that unforced): one over it is not
        fitted and the climbs retry it smaller; :attr:`GrowthResult.work` reports the work.
        None: unbounded.

    Returns
    -------
    GrowthResult

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 20, 2001)
    >>> x = np.c_[np.sin(t) + 0.5 * np.sin(2.7 * t)]
    >>> xdd = -np.sin(t) - 3.645 * np.sin(2.7 * t)
    >>> u = 2 * xdd[:, None] + 3 * x + x ** 3      # m = 2, a hardening spring
    >>> found = grow_catalog(x, t, u, coordinates=["x"], moves=("degree",))
    >>> found.model.print(precision=3)
    L = -0.25*x**4 - 1.5*x**2 + 1.0*x_dot**2
    (x) 1.0*x**3 + 3.0*x + 2.0*x_ddot = tau_x
    >>> [(step.move, step.terms, step.chosen) for step in found.steps]
    [('start', 4, True), ('degree', 5, False), ('degree', 6, True)]
    """
    from ..model import XLSINDy

    if progress is not None and not callable(progress):
        raise TypeError("progress: expected a callable (given each line of text) or None, got "
                        f"{type(progress).__name__}")
    names = coordinate_names(coordinates)
    first_run, is_list = as_list(x, "x")
    if np.ndim(first_run[0]) in (1, 2):  # (anything else: the data's own error, below)
        n = np.shape(first_run[0])[1] if np.ndim(first_run[0]) == 2 else 1
        if len(names) != n:
            raise ValueError(f"coordinates: expected {n} names (the columns of x), got {names}")
    # XLSINDy.fit's validation of the data: the same errors at the same boundary
    runs = trajectory_arrays(x, t, x_dot, x_ddot, u, None, len(names))
    xs, ts = [run["x"] for run in runs], [run["t"] for run in runs]
    us, xds, xdds = (None if given is None else [run[key] for run in runs]
                     for key, given in (("u", u), ("x_dot", x_dot), ("x_ddot", x_ddot)))
    kinds = coordinate_kinds(names, kinds)
    check_growth_options(max_terms=max_terms, n_blocks=n_blocks, cross_validate=cross_validate,
                         region=region, physical=physical, steepest=steepest,
                         tie_break=tie_break, noise_floor=noise_floor, work_budget=work_budget,
                         combine=combine, tolerance=tolerance, good_enough=good_enough,
                         moves=moves, search_optimizer=search_optimizer,
                         search_samples=search_samples)
    check_growth_data(xs, names)  # (a constant coordinate, before its range is a catalog's)
    moves = tuple(dict.fromkeys(moves))  # a move named twice (MOVES + ("differences",)) once
    forced = us is not None and any(np.any(np.asarray(uk) != 0) for uk in us)
    criterion = "forces" if forced else "accelerations"
    velocity_scale = [float(np.std(np.gradient(xk, tk, axis=0), axis=0).mean())
                      for xk, tk in zip(xs, ts, strict=True)]
    fixed = {"coordinates": names, "kinds": list(kinds),
             "max_terms": MAX_TERMS if max_terms == "auto" else max_terms,
             "bounds": data_span(xs),  # the splines' end knots
             "coulomb_scale": max(1e-3, 0.02 * float(np.mean(velocity_scale)))}
    first = AutomaticCatalog(**fixed, **START)
    check_growth_data(xs, names, first.n_terms)

    total = sum(len(tk) for tk in ts)
    stride = 1 if search_samples is None else max(1, int(np.ceil(total / search_samples)))
    arrays = {"x": xs, "t": ts, "u": us if forced else None, "x_dot": xds, "x_ddot": xdds}
    # test functions short enough for the held-out blocks and the training pieces
    from ..weak import BumpTestFunctions
    block = min(len(tk) for tk in ts) // n_blocks
    longest = int(np.argmax([len(tk) for tk in ts]))
    width = min(BumpTestFunctions().half_width(ts[longest], xs[longest]),
                min(tk[block - 1] - tk[0] for tk in ts) / 3)
    consensus = region == "consensus"
    splits, reported = held_out_splits(arrays, n_blocks, stride, cross_validate,
                                       "block" if consensus else region, margin=width)
    # the search's splines end where its training data do: the region blocks test their
    # continuation as the chosen model's is used beyond the data
    searched = [dict(fixed, bounds=data_span(train["x"])) for train, _ in splits]
    # the second judge of "consensus": fitted inside the extreme states, judged on them
    second_splits = (held_out_splits(arrays, n_blocks, stride, False, "extremes",
                                     margin=width)[0] if consensus else [])
    active = np.any(np.vstack(us) != 0, axis=0) if forced else np.zeros(n, dtype=bool)
    # the default optimizers bag selections on columns estimated from noisy positions (the
    # weak form, where no derivatives are measured)
    from ..fit import resolve_formulation
    final_weak = resolve_formulation(formulation, xds is not None and xdds is not None) == "weak"
    if search_optimizer == "auto":  # one selection per step, not a bag of them
        from ..optimizers import ExplicitOptimizer, MixedOptimizer
        search_optimizer = (optimizer if optimizer is not None or not forced else
                            ExplicitOptimizer() if active.all() else MixedOptimizer())
    # the search's fits smooth the same pieces (and noise draws) at every step: once
    from ..fit import RememberedSmoother
    template = XLSINDy(optimizer=search_optimizer, formulation=formulation,
                       test_functions=BumpTestFunctions(width=width),
                       smoother=RememberedSmoother())

    search = SearchData([SearchSplit(bounds, train, held)
                         for bounds, (train, held) in zip(searched, splits, strict=True)],
                        template, fixed["max_terms"], forced, reported, combine,
                        floor="later" if noise_floor else "off")
    rows = search_rows(search, final_weak)
    if max_terms == "auto":  # a selection over more columns is ill-posed at noise
        search.max_terms = min(MAX_TERMS, int(rows // ROWS_PER_TERM))
    fits = CandidateFits(search, n_jobs)
    fits.warm_up()  # the workers start while the first catalog is fitted here
    # the second judge is asked only about candidates the first does not refuse: no guesses
    second_fits = CandidateFits(judge_data(second_splits, fixed, template, search.max_terms,
                                           forced)) if consensus else None

    if not forced:  # no force sets the scale, an approximation can look small already: only
        good_enough = EXACT  # a law exact to the data's precision stops the growth
    climber = Climber(fits, second_fits, searched[0], kinds, tolerance=tolerance,
                      good_enough=good_enough, physical=physical,
                      retry_kinetic=max_terms == "auto", criterion=criterion,
                      progress=progress, noise_floor=noise_floor,
                      rates=RateFits(searched[0], thinned(arrays, stride),
                                     template.test_functions,
                                     template.smoother,
                                     lambda parameters: fits.get(parameters)["criterion"])
                      if "exponentials" in moves else None, budget=work_budget,
                      anchors=AnchorFits(searched[0], thinned(arrays, stride),
                                         template.test_functions, template.smoother,
                                         lambda parameters: fits.get(parameters)["criterion"])
                      if "anchored_springs" in moves else None)

    # pairs of moves whose joint catalog holds terms that neither adds alone (kinetic
    # coefficients over products of two coordinates' functions): tried as one move too
    joint = joint_moves(moves, kinds, n, climber.size)
    if max_terms == "auto":  # (cos(a) a_dot x1_dot beside the spring x1 x2)
        joint += narrowed(joint, kinds, n, climber.size, search.max_terms)
    # the moves from the first catalog, each alone, then the pairs (a degree move, or a pair
    # with one, also one degree further)
    queue = []
    for move in [m for m in moves if m not in LATE_MOVES] + joint:
        for skip in (0, 1) if is_repeated(move) else (0,):
            parameters = moved(dict(START), move, kinds, n, skip)
            if parameters is None:
                break
            queue.append((move, parameters))
    first = climber.start([p for _, p in queue])
    if first.note.startswith("ceiling"):
        raise ValueError(f"max_terms: the smallest catalog has {first.terms} terms, more than "
                         f"max_terms={search.max_terms}" + (
                             f" ('auto': {rows} rows of the search's fits / {ROWS_PER_TERM}; "
                             "record longer, or pass an int" if max_terms == "auto" else "; raise")
                         + " max_terms")
    if progress is not None:
        progress(f"ceiling       {search.max_terms:>5} terms  ({rows} rows per fit)")
    climber.report(first)

    # rank the family moves by what each achieves alone from the first catalog (a degree move
    # looking one degree further); the flexible basis comes last, for what the families leave
    alone, alone_steps = climber.first_moves([] if climber.settled(first) else queue)
    rank = {m: (1, c) for m, c in alone.items()}
    if consensus and alone:
        # the first fold's near ties (the moves it keeps within the tolerance of the best
        # first move) ranked by the combined criterion, before the others
        low = min(alone.values())
        near = [m for m, c in alone.items() if c <= low * (1 + tolerance)
                and single_keeps(alone_steps[m], first, tolerance)]
        beyond = {m: climber.second_step(alone_steps[m]).criterion for m in near}
        if beyond and min(beyond.values()) < 1:
            rank.update({m: (0, float(np.sqrt(alone[m] * beyond[m]))) for m in near})
    # a pair with a degree move (a product of two coordinates' powers above the degree: the
    # x^2 y of a cubic coupling) is climbed only where it is kept alone from the first
    # catalog: from a larger catalog the degree and interaction moves are tried in turn
    joint = [m for m in joint if not is_repeated(m)
             or (m in alone_steps and single_keeps(alone_steps[m], first, tolerance))]
    order = sorted([m for m in moves if m not in LATE_MOVES] + joint,
                   key=lambda m: rank.get(m, (1, np.inf)))
    order += [m for m in LATE_MOVES if m in moves]  # (the fitted families before the splines)
    if "quadratic_ends" in moves and "knots" in moves:  # both at once: neither may gain alone
        order.append("quadratic_ends+knots")

    def every_block():  # the near ties' judge: each block held out by a fit on the others
        folds, _ = held_out_splits(arrays, n_blocks, stride, True, region, margin=width)
        return CandidateFits(judge_data(folds, fixed, template, search.max_terms, forced), n_jobs)

    def search_again():  # (climbs, backward phase, near ties: each catalog fitted once)
        judged = tie_break and not cross_validate and not consensus
        return search_end(climber, order, alone, moves, steepest=steepest, physical=physical,
                          judge_ties=every_block if judged else None, progress=progress)

    full = {"x": xs, "t": ts, "u": us if forced else None, "x_dot": xds, "x_ddot": xdds}
    if not is_list:
        full = {key: None if value is None else value[0] for key, value in full.items()}

    def fit_all(catalog, judged):  # the final fit (final_fit.py): all the data, judged terms
        return fit_chosen(template, catalog, optimizer, full, judged, active, final_weak)

    # a settled end whose final fit fails is refused and the climbs go on (climb_ends.py)
    check = None if forced else free_runs_check(xs, ts, xds, kinds)
    state, best, path, model = resumed_end(
        climber, search_again, lambda state, step: fit_all(
            AutomaticCatalog(**fixed, **state), step.support), check, progress)
    answer, best_catalog, model, failed = final_answer(
        best, state, climber.steps, climber.parameters_of, fixed, fit_all, check, model=model)
    if answer is not best:  # a physical alternative: the choice's final fit is no mechanics
        if progress is not None:
            progress(f"answer        {answer.move} ({answer.terms} terms): the chosen "
                     "catalog's final fit is no mechanical system along its data")
        best = answer
        path.append(best)
    if failed is None:  # (the path settled without it: a term back changes no catalog)
        growing = climber.parameters_of(best)
        restored = restore_judged_terms(model, best.support, full, lambda selection, columns:
                                        support_criterion(search, growing, selection, columns),
                                        tolerance, check, climber.floor(best))
        if restored is not model and progress is not None:
            back = (np.asarray(restored.coefficients()) != 0) & (
                np.asarray(model.coefficients()) == 0)
            progress("restored      " + ", ".join(np.asarray(model.get_feature_names())[back])
                     + ": judged terms the final fit left out lower the criterion")
        model = restored
    elif not forced:
        warn_free_runs(failed)
    if consensus:
        for step in path:
            climber.second_step(step)  # (each kept step reports both folds)
    for step in path:
        step.chosen = True
    return GrowthResult(model, best_catalog, climber.steps, criterion, best.criterion,
                        search.max_terms, climber.work, failed if not forced else None)
