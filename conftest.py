"""Root pytest configuration, shared by the tests and the doctests of the package."""

import linecache

import numpy  # noqa: F401  (loads the BLAS libraries that the limit below reaches)
import scipy.linalg  # noqa: F401
import threadpoolctl

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
    # One BLAS thread per test process. The default run spreads the files over one worker per
    # core, and OpenBLAS' own threads on top of them oversubscribe the cores: its waiting
    # threads spin, and a test of small matrices ran 5-7x slower under load than on one thread.
    # The package's results do not depend on the thread count (tests compare to tolerances
    # that hold across BLAS kernels).
    config._blas_limit = threadpoolctl.threadpool_limits(limits=1, user_api="blas")
