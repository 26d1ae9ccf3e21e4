"""The search's work budget: a bound on what one catalog growth fits.

A candidate catalog's fit costs about the cube of its terms: the selections' paths and swap
searches factor and decompose every support size along them (the implicit law selection of
unforced data cross-validates every support of its backward and forward paths: on the
half-car, four coordinates, a catalog of 267 terms costs 20 CPU s, one of 353 terms 40 s,
one of 51 terms 1.3 s). The ceiling (``max_terms``) bounds one fit; nothing bounded their
number, and a growth that kept a large stand-in early (configuration-dependent kinetic
coefficients of four coordinates, ten velocity monomials times the potential's products:
267 terms) tried every move from it, each a catalog of 280 to 390 terms: over 13 CPU
minutes. So the search counts its work in fits of a 100-term catalog,

.. math:: W = \\sum_{\\text{fitted}} c\\,(k / 100)^3,

with ``c = 1`` on forced data and :data:`IMPLICIT_COST` on unforced data, whose implicit law
selection costs several times an explicit one of the same size (per unit of ``(k / 100)^3``,
2 to 6 CPU s on the half-car's unforced growths, 0.7 to 1.2 s on forced growths of three and
four coordinates), the sum over the fits made: a candidate whose catalogs hold what an
earlier one's hold (other parameters, the same columns) is that fit, not refitted
(:meth:`~.candidates.CandidateFits.fit_key`), and adds nothing;

and a candidate whose fit would take ``W`` over the budget is not fitted (its step's note
says ``"budget"``); the climbs retry it smaller, as a move over the ceiling (kinetic
coefficients of the catalog's order or over fewer coordinates' functions, or constant ones:
:mod:`.retries`). Smaller catalogs
still fit while the budget allows them: the climbs, their pairs and the backward phase go on
among those. The budget bounds the search's CPU; the near ties' cross-validation and the
final fit come on top (a few fits of the smallest catalogs of the laws found).

The default, :data:`WORK_BUDGET`, is above the work of every growth known to end right: the
development grid's growths stay under 27 (its unforced ones under 0.5), the unseen set's two
carts with pendulums (forced, 1 %, seed 0) does 46 and the second blind set's three-link arm
(forced, 1 %, seed 0) 64. A growth whose work without a
budget stays within it is the same with it, bit for bit: no candidate is refused.
"""

from __future__ import annotations

__all__ = ["WORK_BUDGET", "WORK_UNIT", "IMPLICIT_COST", "OVER", "REFUSED", "work_cost",
           "budget_note"]

#: The default budget of a growth's search, in fits of a :data:`WORK_UNIT`-term catalog.
WORK_BUDGET = 100.0
#: The catalog size of one unit of work.
WORK_UNIT = 100
#: The work of an implicit fit (unforced data) relative to a forced one of the same size.
IMPLICIT_COST = 4.0
#: The notes of candidates refused before a fit for their size: over the ceiling, or over the
#: budget (the climbs retry them smaller).
OVER = ("ceiling", "budget")
#: The notes of candidates that were not fitted (no work paid).
REFUSED = (*OVER, "too few samples")


def work_cost(terms, implicit: bool = False) -> float:
    """The work of fitting a catalog of ``terms`` terms: ``c (terms / WORK_UNIT)^3``.

    Parameters
    ----------
    terms : int
        The catalog's terms.
    implicit : bool, default False
        An implicit fit (unforced data): ``c =`` :data:`IMPLICIT_COST`, else 1.

    Returns
    -------
    float
        In fits of a :data:`WORK_UNIT`-term catalog.

    Examples
    --------
    >>> work_cost(200), work_cost(200, implicit=True)
    (8.0, 32.0)
    """
    return (IMPLICIT_COST if implicit else 1.0) * (terms / WORK_UNIT) ** 3


def budget_note(work, terms, budget, implicit: bool = False) -> str:
    """Why a catalog of ``terms`` terms is not fitted after ``work`` was spent, or ``""``.

    Parameters
    ----------
    work : float
        The work spent (:func:`work_cost` summed over the catalogs fitted).
    terms : int
        The candidate's terms.
    budget : float or None
        The budget; None: none.
    implicit : bool, default False
        An implicit fit (:func:`work_cost`).

    Returns
    -------
    str
        ``""`` where the fit is within the budget, else the note of the refused step.

    Examples
    --------
    >>> budget_note(29.0, 100, 30.0)
    ''
    >>> budget_note(29.5, 120, 30.0)
    'budget: 120 terms would take the search to 31.2 fits of 100 terms, over work_budget 30'
    """
    cost = work_cost(terms, implicit)
    if budget is None or work + cost <= budget:
        return ""
    return (f"budget: {terms} terms would take the search to {work + cost:.3g} "
            f"fits of {WORK_UNIT} terms, over work_budget {budget:g}")
