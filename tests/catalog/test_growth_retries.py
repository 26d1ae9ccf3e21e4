"""A refused move's retries narrow before they drop: from a catalog whose kinetic coefficients
are configuration-dependent, a move over the ceiling is retried with them over fewer
coordinates' functions before it is retried with constant ones (which drop the family the
climb kept; dropping a family is the backward phase's job). The work budget pays each fit
once: a catalog met before under other parameters (the same columns) is that fit, not
refitted, and not charged again.

The Furuta pendulum (an arm ``a`` turning about a vertical axis on a return spring, a rod ``b``
swinging in the plane normal to the arm) has the Lagrangian
``0.07 a_dot^2 + 0.015 sin(b)^2 a_dot^2 + 0.03 cos(b) a_dot b_dot + 0.015 b_dot^2
+ 1.4715 cos(b) - 0.5 a^2`` (``benchmarks/blind3_systems.py``). At 1 % noise (seed 0) its growth
kept an 85-term catalog (kinetic coefficients over both angles' functions with ``sin^2``, the
potential's products of two angles); the move ``"angle_degree"`` (98 terms) was over the
ceiling of 96, and its retry with constant kinetic coefficients (26 terms) dropped the inertia:
no catalog holding the arm's spring ``a^2`` beside the law's inertia was ever fitted.
"""

import numpy as np
import sympy as sp
from support.catalog_setups import ceiling_climber, duffing_search

from pysindy_xl.catalog import AutomaticCatalog
from pysindy_xl.catalog.budget import work_cost
from pysindy_xl.catalog.candidates import CandidateFits, parameters_key
from pysindy_xl.catalog.climbs import Climber
from pysindy_xl.catalog.moves import START, kinetic_order, kinetic_trig_degree, moved
from pysindy_xl.catalog.retries import (
    RETRIES,
    attempt_within_limits,
    retry_catalogs,
    retry_order,
)

NAMES, KINDS = ["a", "b"], ["angle", "angle"]
A, B = sp.symbols("a b")
AD, BD = sp.symbols("a_dot b_dot")
#: The Furuta pendulum's Lagrangian terms (the benchmark's truth).
FURUTA_TERMS = [A ** 2, sp.sin(B) ** 2 * AD ** 2, sp.cos(B) * AD * BD, sp.cos(B), AD ** 2, BD ** 2]


def _size(parameters):
    return AutomaticCatalog(NAMES, kinds=KINDS, max_terms=10 ** 6, **parameters).n_terms


def _states(parameters):
    """Whether a catalog's span holds each of the Furuta pendulum's Lagrangian terms: its
    terms evaluated on random states, each law term's least-squares residual."""
    terms = AutomaticCatalog(NAMES, kinds=KINDS, max_terms=10 ** 6,
                             **parameters).lagrange_terms()
    rng = np.random.default_rng(0)
    values = dict(zip(("a", "b", "a_dot", "b_dot"), rng.uniform(-1.5, 1.5, (4, 400)),
                      strict=True))

    def columns(expressions):
        out = []
        for e in expressions:
            symbols = sorted(e.free_symbols, key=str)
            f = sp.lambdify(symbols, e, "numpy")
            out.append(np.broadcast_to(f(*(values[str(s)] for s in symbols)), (400,)))
        return np.column_stack(out)

    matrix = columns(terms)
    residuals = []
    for target in columns(FURUTA_TERMS).T:
        fit = np.linalg.lstsq(matrix, target, rcond=None)[0]
        residuals.append(np.linalg.norm(matrix @ fit - target) / np.linalg.norm(target))
    return np.array(residuals) < 1e-8


#: The Furuta growth's kept catalog: configuration-dependent kinetic coefficients over both
#: angles' functions with sin^2 and sin cos, the potential's products of two angles.
KEPT = moved(dict(START), "interaction+kinetic_trig_degree", KINDS, 2)


def test_a_refused_move_from_a_configuration_catalog_narrows_before_it_drops_the_inertia():
    refused = moved(KEPT, "angle_degree", KINDS, 2)
    assert (_size(KEPT), _size(refused)) == (85, 98)
    climber = ceiling_climber(96, NAMES, KINDS)
    parameters, step = attempt_within_limits(
        climber, refused, "angle_degree", {parameters_key(KEPT)}, state=KEPT)
    assert climber.attempts == [("angle_degree", 98), ("angle_degree@k1", 50)]
    assert not step.note and parameters == dict(refused, kinetic_interaction=1)
    # the retry keeps the configuration-dependent family (its sin^2) and adds the angle's powers
    assert parameters["kinetic"] == "configuration" and kinetic_trig_degree(parameters) == 2
    assert kinetic_order(parameters) == 1 and parameters["angle_degree"] == 2
    # it holds every term of the Furuta law; the constant retry of before lacks the inertia
    assert _states(parameters).all()
    constant = retry_catalogs(refused, "angle_degree", KEPT, KINDS, 2)["constant"][0][1]
    assert _size(constant) == 26
    assert not _states(constant)[1] and _states(constant)[0]  # no sin(b)^2 a_dot^2; a^2


def test_the_constant_retry_comes_last_from_a_configuration_catalog():
    """Where the narrower catalog is over the ceiling too, the constant retry still comes."""
    refused = moved(KEPT, "angle_degree", KINDS, 2)
    climber = ceiling_climber(40, NAMES, KINDS)
    parameters, step = attempt_within_limits(
        climber, refused, "angle_degree", {parameters_key(KEPT)}, state=KEPT)
    assert climber.attempts == [("angle_degree", 98), ("angle_degree@k1", 50),
                                ("angle_degree-kinetic", 26)]
    assert parameters["kinetic"] == "constant" and not step.note


def test_from_constant_kinetic_coefficients_the_constant_retry_comes_first():
    """From constant kinetic coefficients the constant retry drops only what the move adds:
    it comes before the narrower ones (the order before this change)."""
    assert retry_order(dict(START)) == ("state_order", "constant", "narrower")
    assert retry_order(KEPT) == ("state_order", "narrower", "constant")
    assert retry_order(None) == ("state_order", "constant", "narrower")
    refused = moved(dict(START), "kinetic+interaction+kinetic_trig_degree", KINDS, 2)
    climber = ceiling_climber(80, NAMES, KINDS)
    parameters, _ = attempt_within_limits(
        climber, refused, "joint", {parameters_key(START)}, state=dict(START))
    assert climber.attempts == [("joint", 85), ("joint-kinetic", 13)]
    assert parameters == dict(START, interaction=2)
    # every kind is listed, whatever the order
    retries = retry_catalogs(refused, "joint", dict(START), KINDS, 2)
    assert set(retries) == set(RETRIES)
    assert [name for name, _ in retries["narrower"]] == ["joint@k1"]


def test_a_catalog_met_before_under_other_parameters_is_charged_once(monkeypatch):
    """Two parameters of one catalog (one coordinate: no product of two) are one fit; the work
    budget pays it once, and the fit is not made again (the cache hits)."""
    from pysindy_xl.catalog import candidates

    fitted = []
    original = candidates.evaluate_candidate

    def recorded(search, parameters):
        fitted.append(dict(parameters))
        return original(search, parameters)

    monkeypatch.setattr(candidates, "evaluate_candidate", recorded)
    search = duffing_search()
    fixed = search.splits[0].fixed
    fits = CandidateFits(search)
    climber = Climber(fits, None, fixed, ["linear"], tolerance=0.05, good_enough=1e-6,
                      physical=False, retry_kinetic=True, criterion="forces")
    quartic = dict(START, degree=4)
    same = dict(quartic, interaction=2)
    first = climber.attempt(quartic, "degree")
    assert climber.work == work_cost(first.terms)
    again = climber.attempt(same, "interaction")
    assert fits.fit_key(same) == fits.fit_key(quartic) != parameters_key(same)
    assert again.terms == first.terms and again.criterion == first.criterion
    assert fitted == [quartic]  # the second is the first one's fit
    assert [kind for kind, _ in fits.events] == ["local", "same"]
    assert climber.work == work_cost(first.terms)  # not paid again
    # a catalog that differs is fitted and paid
    cubic = climber.attempt(dict(START, degree=3), "degree")
    assert len(fitted) == 2
    assert climber.work == work_cost(first.terms) + work_cost(cubic.terms)
