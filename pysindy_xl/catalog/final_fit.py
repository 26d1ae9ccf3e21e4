"""The final fit of a catalog growth: the chosen catalog on all the data.

The chosen catalog of a growth is fitted on all the data, each coordinate's splines kept whole
or left out (:class:`~pysindy_xl.optimizers.GroupedOptimizer`), with the weak-form test
functions that the search's fits used (:class:`~pysindy_xl.weak.BumpTestFunctions` of one
half-width: the default width of the longest run, at most a third of the shortest run's time
block). The criterion judged the catalog by fits with these test functions; the default ones of
a fit on all the data (as wide or wider; for unforced data, three widths) make another
regression, whose selection the growth never judged: on the log-cosh well, unforced and free of
noise, that selection keeps a combination of the spline columns that nearly vanishes on the
data, with almost no kinetic part (accelerations off by a factor of tens to hundreds), where
the search's test functions give the law within 0.5 %. That fit selects again, on all the data;
where it keeps more terms than the judged fits did, and some they did not hold, it is refitted
among the judged terms only (:class:`~pysindy_xl.optimizers.RestrictedOptimizer`). It may
exchange a term or leave one out (more data tell a stand-in from the law), but a larger model
was never judged (on a pendulum with a sprung vertical pivot, unforced and free of noise, it
took 14 terms where the judged fits kept the law's 8, 9 % off on a fresh run). Its selection,
or the refit's, may also leave out a term that every judged fit kept: in the growth's answer,
once the search has settled and where the noise does not account for its criterion, such
terms are refitted with the model's, nothing selected, and kept where they lower the search's
criterion by the growth's keep tolerance
(:func:`restore_judged_terms`; the same pendulum, where rounding made the refit drop the
pivot's viscous term: 2.8 % off on a fresh run, 6e-11 with it). The refit is
not taken where its mass matrix is not positive definite on the training states and the fit
on all the columns' is (:func:`~pysindy_xl.fit.diagnostics.mass_matrix_failure`): such a
model is no mechanical system and cannot be simulated along its own data, and a growth does
not answer with one where it has another. Where the chosen catalog's final fit fails the check
either way, the growth answers with the first of its other catalogs, by criterion, whose
search fits passed it and whose final fit does (:func:`physical_alternative`; at most
:data:`PHYSICAL_ALTERNATIVES` of them fitted), or with the failing model where none does (its
fit warns): :func:`final_answer`.

On unforced data the final fit must also be a model of its free runs
(:func:`free_runs_check`): simulated from each run's first state, it stays within ten times
the recorded range (:func:`~pysindy_xl.fit.own_runs.own_runs_divergence`; a free run keeps or
loses the energy it starts with). A stand-in can hold the rows and not the motion (the
unforced half-car at 1 % noise: ``differences`` traded two suspension springs for a third of
the wrong sign, a saddle where the body rests, 0.14 held out and a wheel's velocity ten times
its range within a second); such a model is replaced like one without a positive definite
mass matrix, and where no other catalog's stays in the runs the growth warns and says why
(:func:`warn_free_runs`). Forced runs are not asked: forces recorded under feedback, replayed
open loop, do not hold an unstable system, and its right model would leave them too.
"""

from __future__ import annotations

import numpy as np

from .automatic import AutomaticCatalog
from .floor import EXACT, noise_explains

__all__ = ["fit_chosen", "final_answer", "failure", "free_runs_check", "mass_matrix_fails",
           "physical_alternative", "restore_judged_terms", "warn_free_runs",
           "PHYSICAL_ALTERNATIVES"]

#: Most other catalogs whose final fit a growth tries where its choice's fails the mass-matrix
#: check (:func:`physical_alternative`).
PHYSICAL_ALTERNATIVES = 3


def _judged_terms_only(model, judged, catalog, data):
    """``model`` refitted on the terms that the judged fits kept (``judged``: the names of each
    split's), where it keeps more terms than any of them and some that none held; a
    coordinate's splines count as judged (their knots, and so their names, follow each fit's
    data).

    The criterion judged the chosen catalog by its fits on the search's pieces: models of the
    size those fits kept. The fit on all the data is another selection: it may exchange a
    term (more data tell a stand-in from the law: ``a_dot x_dot cos(a)`` for the judged
    ``a_dot x_dot`` on a cart with two pendulums) or find fewer, but terms it adds beyond
    that size were never judged. The refit is returned unless its mass matrix fails the
    check on the training states where ``model``'s passes (:func:`mass_matrix_fails`).
    """
    judged = [names for names in judged if names]
    if not judged:  # (a split's fit failed: nothing to restrict to)
        return model
    held = set().union(*judged)
    names = model.get_feature_names()
    allowed = np.array([name in held for name in names])
    for group in catalog.spline_columns():
        allowed[list(group)] = True  # (kept whole or left out by the final fit's optimizer)
    kept = np.asarray(model.coefficients()) != 0
    if not np.any(kept & ~allowed) or kept.sum() <= max(len(names) for names in judged):
        return model
    from sklearn.base import clone

    from ..optimizers import RestrictedOptimizer
    restricted = clone(model).set_params(optimizer=RestrictedOptimizer(
        clone(model.optimizer_), columns=np.flatnonzero(allowed).tolist()))
    restricted.fit(**data)
    # a model whose mass matrix is not positive definite on its own training states is no
    # mechanical system (it cannot be simulated along its data): the judged terms alone do
    # not buy one where the fit on all the columns has none
    if mass_matrix_fails(restricted) and not mass_matrix_fails(model):
        return model
    return restricted


def restore_judged_terms(model, judged, data, judge, tolerance=0.05, check=None,
                         floor=float("nan")):
    r"""A final fit with the terms that every judged fit kept and it left out, where they lower
    the search's criterion by ``tolerance`` at least; else the final fit itself.

    The fit on all the data may leave out a term that the judged fits kept, rightly (more data
    tell a spurious term) or not: its selection can drop a small true term and let the other
    coefficients absorb it (a pendulum with a sprung vertical pivot, unforced and free of
    noise: the viscous term of the pivot dropped, the others 30-90 % off, 2.8 % on a fresh
    run, where the judged fit kept the law at a criterion of 3e-9; its rounding decided). With
    :math:`S` the model's terms and :math:`D` the dropped ones, both supports are fitted as
    the search fits a catalog, nothing selected, and scored on the search's held-out blocks
    (``judge``); the terms come back where

    .. math:: J(S \cup D) < (1 - \mathrm{tolerance})\, J(S),

    the rule by which the growth keeps a larger catalog (on all the data spurious terms lower
    the error too: two of them by 5-14 % on a Duffing oscillator at 1 % noise). Not where the
    model is exact already (:math:`J(S) \le` :data:`~.floor.EXACT`: a rounding's gain is no
    term's), nor where the positions' noise accounts for :math:`J(S)`
    (:func:`~.floor.noise_explains` with ``floor``: a model as right as the data can tell has
    lost nothing, and the terms that would lower its criterion further are stand-ins fitting
    the noise: eight of them on a Furuta pendulum at 1 % noise, 2.8x its held-out error), nor
    where the refit fails a check that the model passes (its mass matrix:
    :func:`mass_matrix_fails`; ``check``), nor where the optimizer cannot refit a given
    support. The growth applies it to its answer only, once the search has settled, so that
    the path it took is the one without it.

    Parameters
    ----------
    model : XLSINDy
        A final fit (:func:`fit_chosen`).
    judged : sequence of sequence of str
        The terms that each search fit of its catalog kept (a failed fit's empty).
    data : dict
        The data of the final fit (``XLSINDy.fit``'s keyword arguments).
    judge : callable
        ``judge(optimizer, columns) -> float``: the search's criterion of the catalog fitted
        on the given columns with ``optimizer``'s refit, nothing selected
        (:func:`~.candidate_fit.support_criterion`).
    tolerance : float, default 0.05
        Relative decrease of the criterion that brings the terms back (the growth's keep
        tolerance).
    check : callable or None, default None
        ``check(model) -> str or None``: a further judgment that the refit must pass where
        ``model`` passes it (:func:`failure`'s); None: none.
    floor : float, default nan
        The noise floor of the catalog's criterion (:func:`~.floor.models_floor`); not
        finite: unknown, and the noise is taken to account for any criterion (nothing is
        restored).

    Returns
    -------
    XLSINDy
        The refit on the model's terms and the dropped ones
        (:class:`~pysindy_xl.optimizers.RestrictedOptimizer` with ``select=False``), or
        ``model``.

    Examples
    --------
    A model that kept every judged term is returned as it is (``judge`` is not called):

    >>> import numpy as np, pysindy_xl as px
    >>> t = np.linspace(0, 20, 2001)
    >>> x = np.c_[np.sin(t) + 0.5 * np.sin(2.7 * t)]
    >>> u = 2 * (-np.sin(t) - 3.645 * np.sin(2.7 * t))[:, None] + 3 * x
    >>> model = px.XLSINDy(px.AutomaticCatalog(["x"], kinetic="constant")).fit(x, t, u=u)
    >>> judged = [[name for name, value in zip(model.get_feature_names(), model.coefficients())
    ...            if value != 0]]
    >>> restore_judged_terms(model, judged, {"x": x, "t": t, "u": u}, judge=None) is model
    True
    """
    judged = [names for names in judged if names]
    if not judged:  # (a split's fit failed: nothing every judged fit kept)
        return model
    names = model.get_feature_names()
    core = set(judged[0]).intersection(*judged[1:])
    kept = np.asarray(model.coefficients()) != 0
    dropped = np.array([name in core for name in names]) & ~kept
    if not dropped.any():
        return model
    from sklearn.base import clone

    from ..optimizers import RestrictedOptimizer
    optimizer = model.optimizer_  # (the fit on all the columns, or the one a refit wraps)
    if isinstance(optimizer, RestrictedOptimizer):
        optimizer = optimizer.optimizer
    before = judge(optimizer, np.flatnonzero(kept))
    if not before > EXACT or noise_explains(before, floor) or not judge(
            optimizer, np.flatnonzero(kept | dropped)) < (1 - tolerance) * before:
        return model
    restored = clone(model).set_params(optimizer=RestrictedOptimizer(
        clone(optimizer), columns=np.flatnonzero(kept | dropped).tolist(), select=False))
    try:
        restored.fit(**data)
    except (TypeError, ValueError, RuntimeError):  # (no refit of a given support, or no law)
        return model
    if failure(restored, check) is not None and failure(model, check) is None:
        return model
    return restored


def mass_matrix_fails(model) -> bool:
    """Whether a fitted model's mass matrix check finds it wrong on its training states.

    Parameters
    ----------
    model : XLSINDy
        Fitted.

    Returns
    -------
    bool
        True where the identified mass matrix is not positive definite on every checked
        training state (:func:`~pysindy_xl.fit.diagnostics.mass_matrix_failure`), or the
        model has no accelerations.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> t = np.linspace(0, 20, 2001)
    >>> x = np.c_[np.sin(t) + 0.5 * np.sin(2.7 * t)]
    >>> xdd = -np.sin(t) - 3.645 * np.sin(2.7 * t)
    >>> catalog = px.AutomaticCatalog(["x"], kinetic="constant")
    >>> model = px.XLSINDy(catalog).fit(x, t, u=2 * xdd[:, None] + 3 * x)
    >>> mass_matrix_fails(model)
    False
    """
    from ..fit.diagnostics import mass_matrix_failure
    return model.dynamics_ is None or mass_matrix_failure(model.mass_matrix_check_) is not None


def physical_alternative(steps, best, fit, check=None):
    """The growth's answer where its chosen catalog's final fit fails the mass-matrix check
    (or ``check``).

    The other catalogs the growth fitted whose search fits all passed the check
    (:attr:`~.path.GrowthStep.definite` 1, criterion finite), by increasing criterion (then
    terms), at most :data:`PHYSICAL_ALTERNATIVES` of them: the first whose final fit passes it
    and ``check``.

    Parameters
    ----------
    steps : list of GrowthStep
        Every catalog the growth tried.
    best : GrowthStep
        The chosen one (left out).
    fit : callable
        ``fit(step) -> XLSINDy``: a step's final fit.
    check : callable or None, default None
        ``check(model) -> str or None``: a further judgment a final fit must pass (None: it
        passes; a string says why not), after the mass-matrix check.

    Returns
    -------
    tuple or None
        ``(step, model)``, or None where no alternative's final fit passes.

    Examples
    --------
    >>> from pysindy_xl.catalog.path import GrowthStep
    >>> best = GrowthStep("start", "", 4, 3, 0.1, 0.1, 0.1, True)
    >>> physical_alternative([best], best, fit=None) is None   # nothing else was fitted
    True
    """
    others = sorted((step for step in steps if step is not best and step.definite >= 1
                     and np.isfinite(step.criterion) and not step.note),
                    key=lambda step: (step.criterion, step.terms))
    for step in others[:PHYSICAL_ALTERNATIVES]:
        model = fit(step)
        if failure(model, check) is None:
            return step, model
    return None


def failure(model, check=None) -> str | None:
    """Why a final fit is no model of its data: its mass matrix (:func:`mass_matrix_fails`),
    then ``check``; None where it passes both.

    Parameters
    ----------
    model : XLSINDy
        Fitted.
    check : callable or None, default None
        ``check(model) -> str or None``: the further judgment (None: none).

    Returns
    -------
    str or None

    Examples
    --------
    A fitted model's figures (here stand-ins: a positive definite mass matrix on every
    training state):

    >>> from types import SimpleNamespace
    >>> model = SimpleNamespace(dynamics_=object(), mass_matrix_check_={
    ...     "positive_definite_fraction": 1.0, "median_condition": 2.0})
    >>> failure(model) is None, failure(model, lambda model: "leaves its runs")
    (True, 'leaves its runs')
    """
    if mass_matrix_fails(model):
        return "its mass matrix is not positive definite on its training states"
    return None if check is None else check(model)


def free_runs_check(x, t, x_dot, kinds):
    """The check of a final fit on unforced runs: a callable for :func:`final_answer`.

    Parameters
    ----------
    x, t : list of array
        The runs' positions (N, n) and times (N,).
    x_dot : list of array or None
        Their measured velocities (None: estimated).
    kinds : sequence of str
        Each coordinate's kind.

    Returns
    -------
    callable
        ``check(model) -> str or None``:
        :func:`~pysindy_xl.fit.own_runs.own_runs_divergence` on the runs.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> t = np.linspace(0, 20, 2001)
    >>> x = np.c_[np.sin(t) + 0.5 * np.sin(2.7 * t)]
    >>> u = 2 * (-np.sin(t) - 3.645 * np.sin(2.7 * t))[:, None] + 3 * x
    >>> model = px.XLSINDy(px.AutomaticCatalog(["x"], kinetic="constant")).fit(x, t, u=u)
    >>> free = np.c_[np.cos(np.sqrt(1.5) * t)]   # the spring's free run
    >>> free_runs_check([free], [t], None, ["linear"])(model) is None
    True
    """
    from ..fit.own_runs import own_runs_divergence

    def check(model):  # a free run's own energy bounds its model's simulation
        return own_runs_divergence(model, x, t, x_dot=x_dot, kinds=kinds)

    return check


def warn_free_runs(failed: str) -> None:
    """The growth's warning where its model leaves its free runs and no other catalog's stays.

    Parameters
    ----------
    failed : str
        Where it leaves them (:func:`free_runs_check`'s verdict).

    Returns
    -------
    None
        Warns (:class:`~pysindy_xl.IdentificationWarning`).

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     warn_free_runs("run 0 leaves its recorded range (x_dot) at t = 0.6 s")
    >>> "no model of its free runs" in str(caught[0].message)
    True
    """
    import warnings

    from .._validation import IdentificationWarning
    from ..fit.own_runs import FREE_RUNS_ADVICE
    warnings.warn(f"grow_catalog: the grown model is no model of its free runs ({failed}, "
                  "simulated from the run's first state; no other catalog's final fit stays in "
                  f"them either); {FREE_RUNS_ADVICE}", IdentificationWarning, stacklevel=3)


def final_answer(best, state, steps, parameters_of, fixed, fit, check=None, model=None):
    """The growth's answer: its chosen catalog fitted on all the data, or, where that model is
    no mechanical system (:func:`mass_matrix_fails`) or fails ``check``, the first physical
    alternative's (:func:`physical_alternative`).

    Parameters
    ----------
    best : GrowthStep
        The growth's choice.
    state : dict
        Its catalog parameters (the growing ones).
    steps : list of GrowthStep
        Every catalog the growth tried.
    parameters_of : callable
        ``parameters_of(step) -> dict``: a step's catalog parameters (the growing ones).
    fixed : dict
        The catalog parameters that do not grow (the splines' end knots: those of all the
        data).
    fit : callable
        ``fit(catalog, judged) -> XLSINDy``: ``catalog`` fitted on all the data,
        ``judged`` the terms that each of its search fits kept (:func:`fit_chosen`).
    check : callable or None, default None
        ``check(model) -> str or None``: a further judgment of a final fit (the growth's, on
        unforced data: :func:`~pysindy_xl.fit.own_runs.own_runs_divergence`); None: none.
    model : XLSINDy or None, default None
        ``best``'s final fit where it is already made (None: ``fit`` makes it).

    Returns
    -------
    step : GrowthStep
        The answer's step: ``best``, or the alternative that replaces it.
    catalog : AutomaticCatalog
        Its catalog.
    model : XLSINDy
        Its final fit.
    failed : str or None
        Why the answer's final fit fails the checks (:func:`failure`) where no alternative
        passes them, else None.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> from pysindy_xl.catalog.path import GrowthStep
    >>> t = np.linspace(0, 20, 2001)
    >>> x = np.c_[np.sin(t) + 0.5 * np.sin(2.7 * t)]
    >>> u = 2 * (-np.sin(t) - 3.645 * np.sin(2.7 * t))[:, None] + 3 * x
    >>> best = GrowthStep("start", "", 4, 3, 0.1, 0.1, 0.1, True)
    >>> step, catalog, model, failed = final_answer(
    ...     best, {"kinetic": "constant"}, [best], None, {"coordinates": ["x"]},
    ...     fit=lambda catalog, judged: px.XLSINDy(catalog).fit(x, t, u=u))
    >>> step is best, failed
    (True, None)
    """
    catalog = AutomaticCatalog(**fixed, **state)
    if model is None:
        model = fit(catalog, best.support)
    failed = failure(model, check)
    if failed is not None:  # no mechanical system: another catalog's, where one is
        found = physical_alternative(steps, best, lambda step: fit(
            AutomaticCatalog(**fixed, **parameters_of(step)), step.support), check)
        if found is not None:
            (best, model), failed = found, None
            catalog = AutomaticCatalog(**fixed, **parameters_of(best))
    return best, catalog, model, failed


def _grouped_optimizer(optimizer, catalog, forced, estimated):
    """``optimizer`` keeping each coordinate's splines whole or leaving them out (a spline
    basis is one potential: a selection of single functions bends its shape and its
    continuation), or ``optimizer`` itself for a catalog without splines. None or a kind is
    the default optimizer for the data (``forced``: the forced coordinates; ``estimated``:
    columns from noisy positions, the weak form)."""
    groups = catalog.spline_columns()
    if not groups:
        return optimizer
    from ..optimizers import GroupedOptimizer, default_optimizer
    if optimizer is None or isinstance(optimizer, str):
        optimizer = default_optimizer(forced, estimated, kind=optimizer)
    return GroupedOptimizer(optimizer, groups=groups)


def fit_chosen(template, catalog, optimizer, data, judged, active, estimated):
    """The growth's final model: ``catalog`` fitted on all the data.

    Parameters
    ----------
    template : XLSINDy
        The search's model (its test functions and formulation).
    catalog : AutomaticCatalog
        The chosen catalog.
    optimizer : None, str or optimizer
        The final fit's optimizer (None or a kind: the default for the data), each
        coordinate's splines kept whole or left out (:func:`_grouped_optimizer`).
    data : dict
        ``x``, ``t``, ``u``, ``x_dot``, ``x_ddot`` of :meth:`~pysindy_xl.XLSINDy.fit`.
    judged : list of list of str
        The terms that each of the search's fits of ``catalog`` kept.
    active : ndarray of bool, shape (n,)
        The forced coordinates.
    estimated : bool
        Whether the columns come from noisy positions (the weak form).
    Returns
    -------
    XLSINDy
        Fitted, refitted among the judged terms where :func:`_judged_terms_only` says so.
    """
    from sklearn.base import clone

    # the search's test functions: the regression whose selection the criterion judged
    model = clone(template).set_params(
        feature_library=catalog, smoother=None,
        optimizer=_grouped_optimizer(optimizer, catalog, active, estimated))
    model.fit(**data)
    return _judged_terms_only(model, judged, catalog, data)
