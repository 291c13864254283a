"""spindlebench: a Modelica/FMU testbench for machine-tool thermal-error modelling.

Two halves: a synthetic machine (Modelica thermal network -> FMU -> co-simulated recordings)
and the temperature-sensitive point selection pipeline of Xu et al. (2023) that runs on any
recording, synthetic or real.
"""

__version__ = "0.1.0"
