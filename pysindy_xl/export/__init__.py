"""Identified models out of the package: pure JAX dynamics (:mod:`.jax_dynamics`), Gymnasium
environments (:mod:`.gym_env`) and MJCF files (:mod:`.mjcf`), each from the model's
:class:`~pysindy_xl.MassMatrixDynamics` or catalog; optional dependencies imported on use."""
