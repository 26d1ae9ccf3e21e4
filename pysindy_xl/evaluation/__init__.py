"""Evaluation of an identified model: held-out torques, fit quality, validation against MuJoCo,
the physics check, figures.

:mod:`.held_out` scores the torques the model predicts on data the fit never saw;
:mod:`.quality` reports how well it explains its own data; :mod:`.validation` replays a fresh
MuJoCo trajectory with the identified model (open loop, or closed loop through the MJCF's
actuator law); :mod:`.physics` compares mass matrices and forces state by state; :mod:`.plots`
draws the figures.
"""
