"""How the drift depends on the segment count: the table in docs/model.md.

The explicit equations of a build with ``n`` segments per large part (the same ones the FMU
contains) are integrated with SciPy's BDF for a cold start at 8 degC, 4000 rpm, X/Y at
1500 mm/min, and the drift rise is printed at 1, 2 and 4 h::

    python -m spindlebench.model.discretisation 3 4 6 8 12 24
"""

from __future__ import annotations

import sys

import numpy as np

from spindlebench.core.names import KELVIN_OFFSET
from spindlebench.core.paths import MODELS_DIR
from spindlebench.formats.recording import DRIFT_COLUMN
from spindlebench.model.equations import explicit_ode

HOURS = (1.0, 2.0, 4.0)


def drift_rise(segments: int, hours: tuple[float, ...] = HOURS, ambient_C: float = 8.0,
               speed_rpm: float = 4000.0, feed_mm_per_min: float = 1500.0) -> list[float]:
    """Drift rise (um) at ``hours`` of a cold start with ``segments`` segments per part."""
    import casadi as ca
    from scipy.integrate import solve_ivp

    ode = explicit_ode(MODELS_DIR, segments=segments)
    x = ode.symbols[0]
    inputs = ca.DM([speed_rpm, feed_mm_per_min, feed_mm_per_min, ambient_C])
    params = ca.DM(ode.parameter_vector())
    xdot, y = ode.ode(x, inputs, params)
    rhs = ca.Function("xdot", [x], [xdot])
    jac = ca.Function("xdot_x", [x], [ca.jacobian(xdot, x)])
    drift = ca.Function(DRIFT_COLUMN, [x], [y[ode.outputs.index(DRIFT_COLUMN)]])
    x0 = np.full(len(ode.states), ambient_C + KELVIN_OFFSET)
    times = [h * 3600.0 for h in hours]
    sol = solve_ivp(lambda t, s: np.array(rhs(s)).ravel(), (0.0, times[-1]), x0, method="BDF",
                    t_eval=times, jac=lambda t, s: np.array(jac(s)), rtol=1e-8, atol=1e-8)
    start = float(drift(x0))
    return [float(drift(sol.y[:, k])) - start for k in range(len(times))]


def main(argv: list[str]) -> int:
    counts = [int(a) for a in argv] or [3, 4, 6, 8, 12, 24]
    print("| segments | " + " | ".join(f"{h:g} h" for h in HOURS) + " |")
    print("|---|" + "---|" * len(HOURS))
    for n in counts:
        print(f"| {n} | " + " | ".join(f"{v:.1f}" for v in drift_rise(n)) + " |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
