"""What a fitted model says: its equations, Lagrangian, uncertainty and physical parameters.

* :mod:`~pysindy_xl.report.equations`: pure functions of a fitted catalog and its
  coefficients (equations, Lagrangian, physical parameters, their printed lines);
* :mod:`~pysindy_xl.report.inspection`: the part of :class:`~pysindy_xl.XLSINDy` that reads
  its fitted state and reports it.

Nothing is imported here, so that the fit stage can read the equations' helpers without
importing the estimator's mixin.
"""
