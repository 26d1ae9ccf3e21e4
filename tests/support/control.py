"""Shared pieces of the control tests: the true equations of a registered system as a model,
and a planner small enough for the default test run."""

import pysindy_xl as px
from pysindy_xl.mujoco import get_system

#: MPPI options that keep a swing-up test within seconds.
FAST_PLANNER = {"horizon": 50, "n_samples": 128}


def true_model(name):
    """The system's true equations of motion as a :class:`~pysindy_xl.MassMatrixDynamics`."""
    system = get_system(name)
    equations = [e - tau for e, tau in zip(system.equations_of_motion(), system.coords.tau,
                                           strict=True)]
    return px.MassMatrixDynamics(system.coords, equations)
