"""Serial chains in relative joint angles: the kinetic order one below the potential's.

A planar three-link arm in relative angles ``a, b, c`` has its inertia in ``cos(b)``,
``cos(c)`` and ``cos(b + c)`` (kinetic coefficients over two coordinates' functions) and its
gravity in ``cos(a)``, ``cos(a + b)`` and ``cos(a + b + c)`` (potential products of three):
``AutomaticCatalog(interaction=3, kinetic_interaction=2)``, 143 terms, where one order for
both makes 191. The growth reaches it by the narrowing ``"@k2"`` (:func:`~.moves.narrow`),
by a refused move that keeps the kinetic order its catalog had, and by the move
``"kinetic"`` widening a narrowed order.
"""

import pathlib
import sys
import warnings

import numpy as np
import pytest
from support.catalog_setups import ceiling_climber

import pysindy_xl as px
from pysindy_xl.catalog import AutomaticCatalog
from pysindy_xl.catalog.candidates import parameters_key
from pysindy_xl.catalog.moves import (
    START,
    holds,
    kinetic_order,
    moved,
    narrow,
    narrow_order,
    narrowed,
)
from pysindy_xl.catalog.retries import attempt_within_limits

NAMES, KINDS = ["a", "b", "c"], ["angle"] * 3
BENCHMARKS = pathlib.Path(__file__).resolve().parents[2] / "benchmarks"


def _size(parameters):
    return AutomaticCatalog(NAMES, kinds=KINDS, max_terms=10 ** 6, **parameters).n_terms


ARM = dict(START, kinetic="configuration", interaction=3, kinetic_interaction=2)
SHARED = dict(START, kinetic="configuration", interaction=2)  # kinetic+interaction


def test_the_sizes_of_the_arms_catalogs():
    assert _size(ARM) == 143
    assert _size(dict(ARM, kinetic_interaction=1)) == 71
    assert _size(dict(START, kinetic="configuration", interaction=3)) == 191
    assert _size(SHARED) == 135


def test_the_narrow_suffix_of_any_order():
    assert moved(dict(START), "kinetic+interaction+interaction@k2", KINDS, 3) == ARM
    assert moved(dict(START), "kinetic+interaction+interaction@k1", KINDS, 3) == dict(
        ARM, kinetic_interaction=1)
    # not below the catalog's own order, or constant kinetic coefficients: no narrowing
    assert moved(dict(START), "kinetic+interaction+interaction@k3", KINDS, 3) is None
    assert moved(dict(START), "interaction+interaction@k1", KINDS, 3) is None
    assert moved(SHARED, narrow("", 1), KINDS, 3) == dict(SHARED, kinetic_interaction=1)
    assert narrow("interaction", 2) == "interaction@k2"
    assert narrow_order("interaction@k2") == 2 and narrow_order("interaction") is None
    with pytest.raises(ValueError, match="order"):
        narrow("interaction", 0)


def test_the_kinetic_move_widens_a_narrowed_order_to_the_potentials():
    state = dict(ARM, kinetic_interaction=1)
    wider = moved(state, "kinetic", KINDS, 3)
    assert wider == ARM and kinetic_order(wider) == 2 and holds(wider, state)
    widest = moved(wider, "kinetic", KINDS, 3)
    assert "kinetic_interaction" not in widest and kinetic_order(widest) == 3
    assert moved(widest, "kinetic", KINDS, 3) is None  # the shared order: nothing to widen
    # constant coefficients become configuration-dependent, as before
    assert moved(dict(START), "kinetic", KINDS, 3) == dict(START, kinetic="configuration")


def test_a_joint_move_over_the_ceiling_is_narrowed_to_the_widest_order_within_it():
    joint = ["kinetic+interaction+interaction"]
    assert narrowed(joint, KINDS, 3, _size, 150) == ["kinetic+interaction+interaction@k2"]
    assert narrowed(joint, KINDS, 3, _size, 100) == ["kinetic+interaction+interaction@k1"]
    assert narrowed(joint, KINDS, 3, _size, 60) == []  # none within it
    assert narrowed(joint, KINDS, 3, _size, 191) == []  # not over it


def test_a_refused_interaction_move_keeps_the_kinetic_order_of_its_catalog():
    """From the joint catalog (inertia over two coordinates' functions, 135 terms), the
    move ``"interaction"`` (191 terms) is over a ceiling of 150: it is retried with the
    kinetic order of the catalog it moved from (the arm's law, 143 terms), not with
    constant kinetic coefficients that drop the inertia the climb kept."""
    climber = ceiling_climber(150, NAMES, KINDS)
    target = moved(SHARED, "interaction", KINDS, 3)
    parameters, step = attempt_within_limits(
        climber, target, "interaction", {parameters_key(SHARED)}, state=SHARED)
    assert [move for move, _ in climber.attempts] == ["interaction", "interaction@k2"]
    assert parameters == ARM and step.terms == 143 and not step.note
    assert holds(parameters, SHARED)
    # without the catalog it moved from, the retries are those of a move alone: constant
    # kinetic coefficients first (35 terms, within the ceiling)
    alone = ceiling_climber(150, NAMES, KINDS)
    parameters, _ = attempt_within_limits(alone, target, "interaction", set())
    assert [move for move, _ in alone.attempts] == ["interaction", "interaction-kinetic"]
    assert parameters["kinetic"] == "constant"


def test_a_narrowing_retry_takes_the_widest_order_within_the_ceiling():
    """The move ``"kinetic"`` from constant kinetic coefficients with the potential's
    products of three (35 terms) is 191 terms; its constant retry is the catalog itself, so
    the kinetic order gives way: two coordinates' functions first (143), then one (71)."""
    state = dict(START, interaction=3)
    target = moved(state, "kinetic", KINDS, 3)
    climber = ceiling_climber(150, NAMES, KINDS)
    parameters, step = attempt_within_limits(
        climber, target, "kinetic", {parameters_key(state)}, state=state)
    assert [move for move, _ in climber.attempts] == ["kinetic", "kinetic@k2"]
    assert parameters == ARM and not step.note
    low = ceiling_climber(100, NAMES, KINDS)
    parameters, step = attempt_within_limits(
        low, target, "kinetic", {parameters_key(state)}, state=state)
    assert [move for move, _ in low.attempts] == ["kinetic", "kinetic@k2", "kinetic@k1"]
    assert parameters == dict(ARM, kinetic_interaction=1) and not step.note


def test_a_widening_kinetic_move_over_the_ceiling_does_not_drop_the_inertia():
    """From the arm's narrow catalog (inertia of single coordinates), the move ``"kinetic"``
    to two coordinates' functions (143) over a ceiling of 120 is not retried with constant
    kinetic coefficients (a catalog that the climb's own holds: no move forward)."""
    state = dict(ARM, kinetic_interaction=1)
    climber = ceiling_climber(120, NAMES, KINDS)
    parameters, step = attempt_within_limits(
        climber, moved(state, "kinetic", KINDS, 3), "kinetic", {parameters_key(state)}, state=state)
    assert [move for move, _ in climber.attempts] == ["kinetic"]
    assert step.note.startswith("ceiling")


@pytest.mark.slow
def test_a_three_link_arm_in_relative_angles_is_found():
    """The second blind set's planar three-link arm (``benchmarks/blind2_systems.py``:
    sympy's Euler-Lagrange equations integrated by scipy at 1e-10), forced, noise-free,
    seed 1: 2 x 10 s, whose rows put the data-sized ceiling at 156 terms. The law's catalog
    (143 terms) is reached from the joint catalog (135) by the move ``"interaction"``
    (191, over the ceiling) kept at the kinetic order of its catalog; the model's forces on
    the fresh forced run match the truth's."""
    sys.path.insert(0, str(BENCHMARKS))
    import blind2_systems
    import generic_systems as bench

    system, truth, forced, (runs, test, xs, ts, us) = bench.case_of(
        "three_link_arm:forced:0.0:1", blind2_systems.systems())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = px.grow_catalog(xs, ts, us, coordinates=NAMES, kinds=KINDS)
    assert found.max_terms < 191  # the shared kinetic order is over the ceiling
    assert "interaction 3, kinetic configuration (interaction 2)" in found.catalog.describe()
    predicted = found.model.predict_forces(test["q"], test["qd"], test["qdd"])
    assert np.linalg.norm(predicted - test["u"]) < 1e-6 * np.linalg.norm(test["u"])
