"""Simulation: forcing signals, trajectory generation, the choice of integration, excitation design.

Random sums of sinusoids (:mod:`.forcing`) or designed periodic trajectories (:mod:`.fourier`,
:mod:`.excitation`) drive a system; :mod:`.generate` integrates it in MuJoCo with an integrator
and step chosen and checked by :mod:`.integration`, the steps between two samples taken in C
(:mod:`.stepping`), and adds noise.
"""
