"""Shared helpers of the test suite, importable from every test folder (pytest's
``pythonpath = ["tests"]``): test modules import these, never one another.

* :mod:`support.files`: the MJCF/URDF models of ``tests/models`` and exact pendulum data
  written as the user's own files.
* :mod:`support.paper`: the paper-style catalog of the acceptance systems, its true
  coefficients, noisy runs and the validation by simulation.
* :mod:`support.control`: the true model of a registered system and a fast planner.
* :mod:`support.growth`: a forced Duffing oscillator and the numeric laws of a one-coordinate
  ``LagrangesMethod``, for the automatic catalog's tests.
* :mod:`support.unforced_cells`: one cell of the unforced noise sweep fitted with the defaults.
* :mod:`support.springs`: free runs of a mass hanging on a spring under gravity (scipy).

The reference systems themselves live in ``tests/ground_truth.py`` (sympy.physics.mechanics)
and ``tests/kinematic_models.py`` (MJCF arms), which the benchmarks import too.
"""
