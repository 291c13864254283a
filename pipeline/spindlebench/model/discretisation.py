"""How the drift depends on the segment count: the table in docs/model.md.

The explicit equations of a build with ``n`` segments per large part (the same ones the FMU
contains) are integrated with SciPy's BDF for a cold start at 8 degC, 4000 rpm, X/Y at
1500 mm/min, and the drift rise is printed at 1, 2 and 4 h, with each count's largest
difference from the default count's; ``--out`` also writes it as JSON
with its provenance (the model source's SHA-256, the conditions, the package versions), the
file the docs' table is generated from (``docs/hooks/tables.py``, ``discretisation``)::

    python -m spindlebench.model.discretisation --out results/discretisation/discretisation.json

(segment counts 3 4 6 8 12 24 unless given; minutes of CPU: each count is translated and
causalised anew).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from spindlebench.core import atomic
from spindlebench.core.names import KELVIN_OFFSET
from spindlebench.core.paths import MODELS_DIR
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.formats.recording import DRIFT_COLUMN
from spindlebench.model import DEFAULT_SEGMENTS, MODEL_FILE
from spindlebench.model.equations import explicit_ode

HOURS = (1.0, 2.0, 4.0)
COUNTS = (3, 4, 6, 8, 12, 24)
#: The cold start every count is integrated from (what the docs' sentence above the table
#: says), recorded in the file.
AMBIENT_C, SPEED_RPM, FEED_MM_PER_MIN = 8.0, 4000.0, 1500.0
COMMAND = "python -m spindlebench.model.discretisation"


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


def study(counts: Sequence[int], command: str = COMMAND,
          say=lambda line: None) -> dict[str, Any]:
    """The drift rise per segment count, as the JSON document ``--out`` writes: ``hours``,
    ``default_segments``, ``rows`` (``segments``, ``drift_rise_um`` per hour) and the
    provenance (model source, conditions, solver, packages)."""
    rows = []
    for n in counts:
        rows.append({"segments": int(n), "drift_rise_um": drift_rise(
            int(n), ambient_C=AMBIENT_C, speed_rpm=SPEED_RPM, feed_mm_per_min=FEED_MM_PER_MIN)})
        say(f"{n} segments: drift rise " + ", ".join(
            f"{v:.1f} um at {h:g} h" for v, h in zip(rows[-1]["drift_rise_um"], HOURS,
                                                      strict=True)))
    model = file_entry(MODELS_DIR / MODEL_FILE)
    model["path"] = f"models/{MODEL_FILE}"
    record = provenance(command=command, model=model, ambient_C=AMBIENT_C, speed_rpm=SPEED_RPM,
                        feed_mm_per_min=FEED_MM_PER_MIN,
                        solver="scipy.integrate.solve_ivp BDF, rtol = atol = 1e-8, the "
                        "build's explicit equations (model.equations.explicit_ode)")
    return {"provenance": record, "hours": list(HOURS), "default_segments": DEFAULT_SEGMENTS,
            "rows": rows}


def _name(segments: int, default: int) -> str:
    return f"**{segments} (default)**" if segments == default else str(segments)


def difference_from_default_pct(document: Mapping[str, Any]) -> dict[int, float] | None:
    """Per segment count, the largest relative difference (%) of its drift rise from the
    default count's over the hours; None when the default count was not run."""
    rows = {row["segments"]: row["drift_rise_um"] for row in document["rows"]}
    reference = rows.get(document["default_segments"])
    if reference is None:
        return None
    return {n: max(100.0 * abs(v - r) / abs(r) for v, r in zip(values, reference, strict=True))
            for n, values in rows.items()}


def markdown(document: Mapping[str, Any]) -> str:
    """The table of docs/model.md: one row per segment count, the drift rise (um, one
    decimal) at each hour and its largest difference from the default count's (%, over the
    hours; only when the default count is among the rows); the default count in bold."""
    hours = document["hours"]
    default = document["default_segments"]
    difference = difference_from_default_pct(document)
    header = ["segments", *(f"{h:g} h" for h in hours)]
    if difference is not None:
        header.append(f"largest difference from {default} segments")
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for row in document["rows"]:
        cells = [_name(row["segments"], default), *(f"{v:.1f}" for v in row["drift_rise_um"])]
        if difference is not None:
            cells.append(f"{difference[row['segments']]:.1f} %")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def write(path: Path, document: Mapping[str, Any]) -> Path:
    """The document as JSON (sorted keys, two-space indent), written atomically."""
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic.write_text(path, json.dumps(document, indent=2, sort_keys=True) + "\n")
    return path


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog=COMMAND, description=__doc__.split("\n\n")[0])
    parser.add_argument("segments", nargs="*", type=int, default=list(COUNTS),
                        help=f"segment counts (default: {' '.join(map(str, COUNTS))})")
    parser.add_argument("--out", type=Path, default=None, metavar="FILE.json",
                        help="also write the table as JSON with its provenance")
    args = parser.parse_args(argv)
    from spindlebench.core.errors import SpindlebenchError
    from spindlebench.model.frontend import check_segments

    try:
        for n in args.segments:
            check_segments(n)
    except SpindlebenchError as error:
        parser.error(str(error))  # one line, exit status 2
    command = " ".join([COMMAND, *argv])
    document = study(args.segments, command, say=lambda line: print(line, flush=True))
    print(markdown(document))
    if args.out is not None:
        print(f"wrote {write(args.out, document)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
