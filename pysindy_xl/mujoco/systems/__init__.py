"""The systems: the paper's MJCF models, any MJCF or URDF model, their registry and actuator law.

Each system is an MJCF model with the textbook description of the same mechanism (:mod:`.base`):
the paper's systems (:mod:`.paper`), any MJCF model (:mod:`.mjcf`) or URDF (:mod:`.urdf`), looked
up by name or by the metadata of a dataset (:mod:`.registry`); :mod:`.actuation` turns the MJCF's
actuators into the force law of a closed loop.
"""
