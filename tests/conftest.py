"""Shared pytest fixtures: the ground-truth systems, derived once per test session."""

import atexit
import os
import shutil
import tempfile

import pytest
from ground_truth import cart_double_pendulum, cart_pole, double_pendulum

# The kinematic catalogs' derivation cache (on by default, in the user's cache directory) goes
# to a directory of this run: the tests neither read a user's cache nor leave files behind.
_DERIVATION_CACHE = tempfile.mkdtemp(prefix="pysindy_xl_cache_")
os.environ["PYSINDY_XL_CACHE"] = _DERIVATION_CACHE
atexit.register(shutil.rmtree, _DERIVATION_CACHE, ignore_errors=True)

#: Test files of one long test, handed to a worker first in a parallel run. ``--dist loadfile``
#: hands out the files with the most tests first, so a file of one test goes near the end: the
#: docs build with its executed gallery (a fifth of the ``slow`` run's time) then ran alone on
#: one worker while the other had finished (about 85 s of the CI's ``slow`` run on 2 cores,
#: estimated: ``benchmarks/results/ci_time.md``).
LONG_FILES = ("tests/test_docs.py",)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadfile`` with :data:`LONG_FILES` handed out first (other modes: xdist's)."""
    if config.getoption("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class LongFilesFirst(LoadFileScheduling):
        def _assign_work_unit(self, node):
            queue = getattr(self, "workqueue", None)  # (xdist's internals: where they differ,
            for scope in reversed(LONG_FILES):       # the order stays xdist's own)
                if hasattr(queue, "move_to_end") and scope in queue:
                    queue.move_to_end(scope, last=False)
            super()._assign_work_unit(node)

    return LongFilesFirst(config, log)


@pytest.fixture(scope="session")
def cart_pole_system():
    """Cart-pole with the default parameters of :func:`ground_truth.cart_pole`."""
    return cart_pole()


@pytest.fixture(scope="session")
def double_pendulum_system():
    """Double pendulum with the default parameters of :func:`ground_truth.double_pendulum`."""
    return double_pendulum()


@pytest.fixture(scope="session")
def cart_double_pendulum_system():
    """Cart double pendulum, defaults of :func:`ground_truth.cart_double_pendulum`."""
    return cart_double_pendulum()
