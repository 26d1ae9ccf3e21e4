"""A narrowed move (``"a+b@k<m>"``) narrows what it adds, never what the climb holds.

The growth's joint first moves over the ceiling are narrowed (:func:`~.moves.narrowed`:
``"interaction+kinetic_trig_degree@k1"``, kinetic coefficients of single coordinates'
functions) and stay in the climbs' order, so a climb makes them from later catalogs too.
From a catalog whose kinetic coefficients are over two coordinates' functions already (the
three-link arm's joint catalog ``"kinetic+interaction"``, 135 terms, with the ``cos(b + c)``
of its inertia) the suffix ``@k1`` took them back to single coordinates': a "move" that
dropped the inertia the climb had kept for ``sin(b)^2`` stand-ins (107 terms), which the keep
rule kept for its fewer fitted terms, and the growth of the arm's seed 2 free of noise ended
on a stand-in (held out 23.6 %). A climb only adds: every move from a catalog holds it.

The arm's growth itself (about 150 CPU s) is a benchmark row
(``benchmarks/blind2_systems.py``, ``benchmarks/results/arm_merged_method.md``); the three-link
arm's end-to-end test is ``test_growth_chains.py``.
"""

import pytest

from pysindy_xl.catalog import AutomaticCatalog
from pysindy_xl.catalog.moves import (
    LATE_MOVES,
    MOVES,
    START,
    holds,
    joint_moves,
    moved,
    narrow,
)

ARM_NAMES, ARM_KINDS = ["a", "b", "c"], ["angle"] * 3
SHARED = dict(START, kinetic="configuration", interaction=2)  # "kinetic+interaction"


def _sizer(names, kinds):
    def size(parameters):
        return AutomaticCatalog(names, kinds=kinds, max_terms=10 ** 6, **parameters).n_terms
    return size


def test_a_narrowed_joint_move_does_not_drop_the_arms_inertia():
    """From the joint catalog (inertia over two angles' functions), the narrowed joint first
    move ``"interaction+kinetic_trig_degree@k1"`` does not apply: it would hold the kinetic
    coefficients to single angles' functions and drop ``cos(b) cos(c)``, ``sin(b) sin(c)``."""
    size = _sizer(ARM_NAMES, ARM_KINDS)
    assert size(SHARED) == 135
    assert moved(SHARED, "interaction+kinetic_trig_degree@k1", ARM_KINDS, 3) is None
    assert moved(SHARED, "interaction@k1", ARM_KINDS, 3) is None
    # from the first catalog (constant kinetic coefficients) the joint move narrows as before
    first = moved(dict(START), "interaction+kinetic_trig_degree@k1", ARM_KINDS, 3)
    assert first["kinetic_interaction"] == 1 and size(first) == 99
    # and the unnarrowed move from the joint catalog keeps its inertia (over the ceiling:
    # its retries narrow what the move adds, :mod:`~pysindy_xl.catalog.retries`)
    full = moved(SHARED, "interaction+kinetic_trig_degree", ARM_KINDS, 3)
    assert holds(full, SHARED)
    # the suffix alone (a refused move's retry) narrows the catalog itself, as before
    assert moved(SHARED, narrow("", 1), ARM_KINDS, 3) == dict(SHARED, kinetic_interaction=1)


@pytest.mark.parametrize("names, kinds", [
    (ARM_NAMES, ARM_KINDS),
    (["x1", "x2", "a", "b"], ["linear", "linear", "angle", "angle"]),
])
def test_every_climb_move_holds_the_catalog_it_moves_from(names, kinds):
    """Every move a climb makes (the families, their qualifying pairs and each pair
    narrowed to every order) from catalogs a climb reaches (constant, shared, narrowed
    kinetic coefficients, of the first and of the second trigonometric degree) gives a
    catalog that holds it, or none."""
    n, size = len(names), _sizer(names, kinds)
    families = [m for m in MOVES if m not in LATE_MOVES]
    joint = joint_moves(MOVES, kinds, n, size)
    assert "interaction+kinetic_trig_degree" in joint
    names_of_moves = families + joint + [narrow(m, order) for m in joint
                                         for order in range(1, n)]
    states = [dict(START), SHARED, dict(START, interaction=2),
              dict(SHARED, interaction=3), dict(SHARED, interaction=3, kinetic_interaction=2),
              dict(SHARED, interaction=3, kinetic_interaction=1),
              dict(SHARED, kinetic_trig_degree=2),
              dict(SHARED, interaction=3, kinetic_interaction=1, kinetic_trig_degree=2)]
    checked = 0
    for state in states:
        state = {key: value for key, value in state.items()
                 if not (key == "interaction" and value > n)}
        for move in names_of_moves:
            new = moved(state, move, kinds, n)
            if new is not None:
                checked += 1
                assert holds(new, state), (state, move, new)
    assert checked > 50

