"""Identified low-order models of a machine from its recordings (issue 22).

- ``model``: the grey-box thermal network in its identifiable (modal) form and the
  transfer-function baseline, fitted by variable projection with SciPy least squares.
- ``estimators``: the scikit-learn regressors (``ThermalNetworkRegressor``,
  ``TransferFunctionRegressor``, ``ObserverRegressor``).
- ``observer``: the steady-state Kalman filter on an identified model.
- the command is ``commands/identify.py`` (``spindlebench identify``).
- ``validation``: the CAIVIAC and synthetic-machine tables of ``docs/twin.md``.
"""
