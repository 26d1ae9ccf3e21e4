"""Catalogs of candidate terms for MuJoCo systems: reference catalogs and kinematic-tree catalogs.

The reference catalogs of the paper's comparison and their true coefficients (:mod:`.reference`),
catalogs derived from the kinematic tree of any MJCF model (:mod:`.kinematic`), and the
identification of a payload on such a catalog (:mod:`.payload`).
"""
