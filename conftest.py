"""Root pytest configuration, shared by the tests and the doctests of the package."""

import linecache

_checkcache = linecache.checkcache


def _tolerant_checkcache(filename=None):
    """``linecache.checkcache`` that survives an entry removed while it runs.

    SymPy's ``lambdify`` registers each generated source in ``linecache`` and removes it when the
    function is garbage collected; a collection between the listing and the lookup of
    ``checkcache`` (called by doctest's debugger reset) raises ``KeyError`` in Python 3.11.
    """
    try:
        _checkcache(filename)
    except KeyError:
        pass


def pytest_configure(config):
    linecache.checkcache = _tolerant_checkcache
