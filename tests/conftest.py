"""Shared pytest fixtures: the ground-truth systems, derived once per test session."""

import pytest
from ground_truth import cart_double_pendulum, cart_pole, double_pendulum


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
