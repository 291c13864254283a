"""Modelica → FMU: pymoca front end, causalisation, CasADi FMI 3.0 export, post-build fixes."""

from spindlebench.core.names import FMU_NAME

__all__ = ["DEFAULT_SEGMENTS", "FMU_NAME", "MAX_SEGMENTS", "MODEL_CLASS", "MODEL_FILE"]

MODEL_FILE = "SpindleBench.mo"
MODEL_CLASS = "SpindleBench.MachiningCentre"
DEFAULT_SEGMENTS = 12
#: Most segments per large part a build accepts: 50 gives 5 × 50 field nodes, far finer than
#: the sensors resolve; 100 000 ran for minutes before failing or finishing.
MAX_SEGMENTS = 50
