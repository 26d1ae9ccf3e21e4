"""Control on identified models: trajectory optimization, model-predictive control, computed
torque, and the loop that explores a plant, identifies it and controls it.

One concept per module: :mod:`.discrete` (the model as ``x_{k+1} = F(x_k, u_k)``),
:mod:`.costs`, :mod:`.sampling` (MPPI), :mod:`.ilqr`, :mod:`.lqr`, :mod:`.mpc` (the
receding-horizon controller), :mod:`.computed_torque`, :mod:`.plant` (MuJoCo as the plant),
:mod:`.tasks`, :mod:`.catalogs`, :mod:`.exploration` (excitation kept on the track) and
:mod:`.loop` (explore, identify, control, repeat). Public
names load on first use: importing this package imports neither JAX nor MuJoCo.

>>> from pysindy_xl.control import get_task
>>> get_task("cart-double-pendulum").force_limit
20.0
"""

from __future__ import annotations

from .._optional import lazy_attributes

_LAZY = {
    **dict.fromkeys(("actuation_matrix", "continuous_dynamics", "discrete_dynamics"),
                    "discrete"),
    **dict.fromkeys(("Cost", "angle_error", "quadratic_cost", "swing_up_cost"), "costs"),
    **dict.fromkeys(("SamplingPlanner", "interpolation_matrix", "rollout", "sampling_planner",
                     "trajectory_cost"), "sampling"),
    **dict.fromkeys(("ILQRSolution", "ilqr"), "ilqr"),
    **dict.fromkeys(("LQRGain", "discrete_lqr", "linearize"), "lqr"),
    "PredictiveController": "mpc",
    "ComputedTorque": "computed_torque",
    **dict.fromkeys(("Episode", "MuJoCoPlant"), "plant"),
    **dict.fromkeys(("TASKS", "SwingUpTask", "get_task"), "tasks"),
    **dict.fromkeys(("AutomaticGrowth", "CATALOGS", "catalog_identifier", "generic_catalog",
                     "kinematic_catalog_of", "resolve_catalog", "system_kinds"), "catalogs"),
    **dict.fromkeys(("TrackGuard", "exploration_policy"), "exploration"),
    **dict.fromkeys(("LearningResult", "learn_to_control", "noisy_positions"), "loop"),
}

__all__ = list(_LAZY)

__getattr__, __dir__ = lazy_attributes(__name__, _LAZY)
