"""Evaluation of an identified model against MuJoCo: validation, the physics check, figures.

:mod:`.validation` replays a fresh MuJoCo trajectory with the identified model (open loop, or
closed loop through the MJCF's actuator law); :mod:`.physics` compares mass matrices and forces
state by state; :mod:`.plots` draws the figures.
"""
