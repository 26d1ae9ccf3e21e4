"""What a fitted model says: :mod:`.equations` (pure functions of a catalog and its
coefficients) and :mod:`.inspection` (the estimator's mixin). Nothing is imported here, so
that the fit stage can use the former without the latter.
"""
