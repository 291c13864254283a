"""Modelica → FMU: pymoca front end, causalisation, CasADi FMI 3.0 export, post-build fixes."""

MODEL_FILE = "SpindleBench.mo"
MODEL_CLASS = "SpindleBench.MachiningCentre"
FMU_NAME = "SpindleBench"
DEFAULT_SEGMENTS = 12
#: Most segments per large part a build accepts: 50 gives 5 × 50 field nodes, far finer than
#: the sensors resolve; 100 000 ran for minutes before failing or finishing.
MAX_SEGMENTS = 50
