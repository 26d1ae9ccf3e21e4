"""Identified models out of the package: pure JAX dynamics for batched simulation and gradients
(:mod:`.jax_dynamics`), Gymnasium environments (:mod:`.gym_env`).

Each export reads the model's :class:`~pysindy_xl.MassMatrixDynamics`; JAX and Gymnasium are
optional and imported when an export is asked for.
"""
