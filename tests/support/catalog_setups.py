"""Set-ups shared by the automatic catalog's tests.

Plain functions, not fixtures: a ``conftest.py`` in ``tests/catalog`` would be imported as the
module ``conftest`` beside ``tests/conftest.py`` when ``--doctest-modules`` collects both.
"""

import numpy as np

from pysindy_xl.catalog import AutomaticCatalog
from pysindy_xl.catalog.climbs import Climber
from pysindy_xl.catalog.path import GrowthStep
from pysindy_xl.catalog.search_data import SearchData, SearchSplit
from support.growth import noisy_duffing


def ceiling_climber(ceiling, names, kinds):
    """A :class:`~pysindy_xl.catalog.climbs.Climber` (retrying refused moves) over the
    coordinates ``names`` of ``kinds`` whose attempts fit nothing: a catalog of more than
    ``ceiling`` terms is refused as the ceiling refuses it, any other scores 0.1.
    ``climber.attempts`` records each attempt's ``(move, terms)``."""
    climber = Climber.__new__(Climber)
    climber.retry_kinetic, climber.attempts = True, []
    climber.kinds, climber.n = kinds, len(kinds)

    def attempt(parameters, move, ahead=()):
        size = AutomaticCatalog(names, kinds=kinds, max_terms=10 ** 6, **parameters).n_terms
        climber.attempts.append((move, size))
        over = size > ceiling
        return GrowthStep(move=move, chosen=False, terms=size, active=0, description="",
                          time_error=np.nan, region_error=np.nan,
                          criterion=np.inf if over else 0.1,
                          note=f"ceiling: {size} > max_terms {ceiling}" if over else "")

    climber.attempt = attempt
    return climber


def duffing_search(**fixed):
    """A growth's search data on the forced Duffing oscillator
    (:func:`support.growth.noisy_duffing`, 1 % noise): a
    :class:`~pysindy_xl.catalog.search_data.SearchData` of one split (trained on the first 5 s,
    two held-out blocks after), the coordinate ``x`` (linear, splines' bounds +-2) and the
    catalog parameters ``fixed``, weak-form fits by ``ExplicitOptimizer`` with test functions
    of half-width 0.5 s, at most 50 terms."""
    from pysindy_xl import XLSINDy
    from pysindy_xl.fit import RememberedSmoother
    from pysindy_xl.optimizers import ExplicitOptimizer
    from pysindy_xl.weak import BumpTestFunctions

    x, t, u = noisy_duffing()
    fixed = {"coordinates": ["x"], "kinds": ["linear"], "bounds": [(-2.0, 2.0)], **fixed}
    train = {"x": [x[:2500]], "t": [t[:2500]], "u": [u[:2500]], "x_dot": None, "x_ddot": None}
    blocks = [{"x": [x[2500:3250]], "t": [t[2500:3250]], "u": [u[2500:3250]]},
              {"x": [x[3250:]], "t": [t[3250:]], "u": [u[3250:]]}]
    template = XLSINDy(optimizer=ExplicitOptimizer(), formulation="weak",
                       test_functions=BumpTestFunctions(width=0.5),
                       smoother=RememberedSmoother())
    return SearchData([SearchSplit(fixed, train, blocks)], template, max_terms=50, forced=True)
