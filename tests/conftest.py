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
