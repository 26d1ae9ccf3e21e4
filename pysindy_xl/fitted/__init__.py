"""What a fitted :class:`~pysindy_xl.XLSINDy` says and does: :mod:`.equations` (pure functions of
a catalog and its coefficients), :mod:`.inspection` and :mod:`.dynamics` (the estimator's mixins:
equations and parameters; predictions, scores, simulations, exports). Nothing is imported here,
so that other modules can use the first without the others.
"""
