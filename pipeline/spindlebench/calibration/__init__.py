"""Calibrate the model to a recording of a real machine (``spindlebench calibrate``).

``mapping`` reads MAP.toml (recording columns → model inputs and outputs), ``series`` puts a
recording on the calibration grid, ``fitset`` names the default fitted parameters, ``problem``
builds and solves the least-squares problem with CasADi/IPOPT and its covariance, ``design``
ranks candidate excitations, ``report`` writes the machine file, the report and the figure.
"""
