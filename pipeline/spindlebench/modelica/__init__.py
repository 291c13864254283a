"""Modelica → FMU: pymoca front end, causalisation, CasADi FMI 3.0 export, post-build fixes."""

MODEL_FILE = "SpindleBench.mo"
MODEL_CLASS = "SpindleBench.MachiningCentre"
FMU_NAME = "SpindleBench"
DEFAULT_SEGMENTS = 12
