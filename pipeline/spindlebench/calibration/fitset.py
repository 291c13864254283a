"""Which FMU parameters ``calibrate`` fits by default, and how each fitted one is constrained.

This is the one place that names the default fit set: when the model's parameter names change,
only ``DEFAULT_FIT`` changes. Every fitted parameter ``p`` is estimated as a log-factor
``s = ln(p / p_start)`` on its start value (the model default, or the value in ``--machine``),
so all parameters are of the same order (0 = unchanged), positivity is automatic and a weak
prior ``s ~ N(0, PRIOR_SD_LN**2)`` says "probably within a factor of a few of the
engineering estimate" without pulling a well-measured parameter.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

from spindlebench.core.errors import SpindlebenchError

#: The default fit set (FMU parameter names), with why each is uncertain on a real machine.
DEFAULT_FIT: dict[str, str] = {
    "front_bearing_friction_f0": "front bearing friction (Palmgren f0: preload, grease fill)",
    "rear_bearing_friction_f0": "rear bearing friction (Palmgren f0)",
    "P_spindle_motor_ref": "spindle-motor loss at the reference speed",
    "c_x_motor": "X feed-drive loss per feed rate",
    "c_y_motor": "Y feed-drive loss per feed rate",
    "h_nat": "natural convection (plus radiation) coefficient of all machine surfaces",
    "fb_housing_G": "contact conductance front bearing - housing",
    "headstock_column_G": "contact conductance headstock - column",
    "spindle_shaft_L": "effective expansion length alpha*L of the spindle term",
    "housing_L": "effective expansion length alpha*L of the headstock term",
    "column_L": "effective expansion length alpha*L of the column term",
    "table_L": "effective expansion length alpha*L of the table term",
    # the heat capacities of the three masses that set the error's time scales (issue 22: a
    # real machine's 5-34 h against the model's 0.6-2.4 h could not move without them)
    "spindle_shaft_C": "heat capacity of the spindle shaft (its minutes-to-an-hour response)",
    "housing_C": "heat capacity of the headstock housing (the hours-long rise)",
    "column_C": "heat capacity of the column (the slow pull-back over many hours)",
}

#: Prior standard deviation of each log-factor: a factor e (2.7) is one sigma, so the prior
#: only matters for parameters the recording says nothing about.
PRIOR_SD_LN = 1.0
#: Bounds of each factor: a calibration that wants more than ten times the engineering estimate
#: is compensating for a structural mismatch, and should say so at the bound, not drift off.
FACTOR_BOUNDS = (0.1, 10.0)


def check_fit_names(names: Iterable[str], parameters: Mapping[str, float], what: str) -> list[str]:
    """``names`` as a list, each a known, positive FMU parameter, none twice (one-line errors)."""
    names = list(names)
    if not names:
        raise SpindlebenchError(f"{what}: no parameter to fit")
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise SpindlebenchError(f"{what}: {name} is named twice")
        seen.add(name)
        if name not in parameters:
            raise SpindlebenchError(f"{what}: {name} is not a tunable FMU parameter")
        if not parameters[name] > 0:
            raise SpindlebenchError(
                f"{what}: {name} = {parameters[name]:g} is not positive; only positive "
                "parameters can be fitted as log-factors"
            )
    return names


def log_bounds() -> tuple[float, float]:
    """Bounds of the log-factors."""
    return math.log(FACTOR_BOUNDS[0]), math.log(FACTOR_BOUNDS[1])
