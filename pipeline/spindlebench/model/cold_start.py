"""Cold-start runs of the FMU at constant load: the model's plausibility check and its figure.

From a machine soaked at a constant ambient, the spindle runs at a constant speed with both
feed axes reciprocating. The issue's expectations (spindle-near sensors rise several degC in
~50 min and level off, feed-axis and structure sensors keep rising, drift of tens of um in a few
hours, less at 2000 rpm) are checked on these runs by the tests and shown in
``docs/figures/model_cold_start.png`` (``python -m spindlebench.model.cold_start``); their
numbers (each sensor's rise at 50 min and 5 h, the drift's rise, peak and end) are written as
JSON with their provenance by ``python -m spindlebench.model.cold_start --json FILE``, the file
docs/model.md's magnitudes table is generated from (``docs/hooks/tables.py``, ``cold-start``).
"""

from __future__ import annotations

import argparse
import json
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from spindlebench.core import atomic
from spindlebench.core.names import KELVIN_OFFSET
from spindlebench.core.paths import DATA_ROOT, DEFAULT_FMU
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.formats.recording import DRIFT_COLUMN, TIME_COLUMN

DEFAULT_FIGURE = DATA_ROOT / "docs" / "figures" / "model_cold_start.png"
FIGURE_SENSORS = ("T1_C", "T6_C", "T8_C", "T10_C", "T13_C", "T16_C")


def state_names(fmu_path: str | Path) -> list[str]:
    """Names of the FMU's continuous states (the variables that have a derivative)."""
    from fmpy import read_model_description

    description = read_model_description(str(fmu_path))
    return [d.variable.derivative.name for d in description.derivatives]


def cold_start(
    fmu_path: str | Path = DEFAULT_FMU,
    speed_rpm: float = 4000.0,
    hours: float = 5.0,
    ambient_C: float = 8.0,
    feed_mm_per_min: float = 1500.0,
    output_interval_s: float = 60.0,
    parameters: Mapping[str, float] | None = None,
    solver: str = "CVode",
) -> pd.DataFrame:
    """Simulate a cold start at constant inputs; one row per output interval, ``time_s`` first."""
    from fmpy import simulate_fmu

    start_values: dict[str, float] = dict.fromkeys(state_names(fmu_path), ambient_C + KELVIN_OFFSET)
    start_values.update(
        spindle_speed_rpm=speed_rpm,
        feed_x_mm_per_min=feed_mm_per_min,
        feed_y_mm_per_min=feed_mm_per_min,
        ambient_C=ambient_C,
    )
    start_values.update(parameters or {})
    result = simulate_fmu(
        str(fmu_path),
        start_values=start_values,
        stop_time=hours * 3600.0,
        output_interval=output_interval_s,
        solver=solver,
        fmi_type="ModelExchange",  # FMPy's default for an FMU with both is co-simulation
        # FMPy's Euler takes one step per output interval; it needs a step below ~35 s
        step_size=output_interval_s if solver == "Euler" else None,
        relative_tolerance=1e-6,
    )
    frame = pd.DataFrame({name: result[name] for name in result.dtype.names})
    return frame.rename(columns={"time": TIME_COLUMN})


def rise(frame: pd.DataFrame, column: str, minutes: float) -> float:
    """Change of ``column`` from the first sample to ``minutes`` into the run."""
    times = frame[TIME_COLUMN].to_numpy()
    values = frame[column].to_numpy()
    return float(np.interp(minutes * 60.0, times, values) - values[0])


def plot(fmu_path: str | Path = DEFAULT_FMU, out_path: str | Path = DEFAULT_FIGURE) -> Path:
    """Draw the cold-start figure: six sensors at 4000 rpm, drift at 4000 and 2000 rpm.

    Hours on both axes, as in every other figure; absolute temperatures so the ambient probe
    T10 is seen sitting on the room's 8 °C (as a rise it vanished on the axis); the sensors in
    their machine part's colours (``testbench.sensor_parts``), named at their line ends.
    """
    from matplotlib.figure import Figure

    from spindlebench.testbench.overview import END_LABEL, label_line_ends
    from spindlebench.testbench.sensor_parts import AMBIENT_SENSOR, PARTS, sensor_colours

    ambient_C = 8.0
    fast = cold_start(fmu_path, speed_rpm=4000.0, ambient_C=ambient_C)
    slow = cold_start(fmu_path, speed_rpm=2000.0, ambient_C=ambient_C)
    colours: dict[str, tuple] = {}
    for part in PARTS:
        colours.update(sensor_colours(part))
    fig = Figure(figsize=(11.5, 4.4), layout="constrained")
    fig.get_layout_engine().set(wspace=0.12)  # room for the line-end labels between panels
    left, right = fig.subplots(1, 2, width_ratios=[1.15, 1.0])
    hours = fast[TIME_COLUMN] / 3600.0
    left.plot(hours, np.full(len(hours), ambient_C), color="0.6", lw=4, alpha=0.5,
              gid=END_LABEL, label="room air")
    for output in FIGURE_SENSORS:
        sensor = output.removesuffix("_C")
        ambient = sensor == AMBIENT_SENSOR
        left.plot(hours, fast[output], color="black" if ambient else colours[sensor],
                  ls="--" if ambient else "-", lw=1.3, gid=END_LABEL,
                  label=f"{sensor} (air probe)" if ambient else sensor)
    left.axvline(50 / 60, color="0.4", ls=":", lw=1)
    left.text(50 / 60 + 0.05, 0.97, "50 min", transform=left.get_xaxis_transform(),
              fontsize=8, color="0.3", va="top")
    left.set(xlabel="time (h)", ylabel="temperature (°C)",
             title=f"Cold start at 4000 rpm, X/Y at 1500 mm/min, room at {ambient_C:g} °C")
    left.grid(alpha=0.3)
    for frame, label, style in ((fast, "4000 rpm", "-"), (slow, "2000 rpm", "--")):
        right.plot(frame[TIME_COLUMN] / 3600.0, frame[DRIFT_COLUMN] - frame[DRIFT_COLUMN].iloc[0],
                   color="tab:brown", ls=style, label=label)
    right.axvline(50 / 60, color="0.4", ls=":", lw=1)
    right.set(xlabel="time (h)", ylabel="drift since start (µm)",
              title="Axial drift, tool towards table")
    right.grid(alpha=0.3)
    right.legend()
    fig.canvas.draw()  # final layout before the labels are placed beside the axes
    fig.set_layout_engine("none")
    label_line_ends(left)
    with atomic.atomic_path(Path(out_path).with_suffix(".png")) as tmp:
        fig.savefig(tmp, dpi=110, format="png", bbox_inches="tight")
    return Path(out_path)


#: The runs of the figure and of the docs' table: a soak at 8 degC, X/Y at 1500 mm/min, 5 h.
SPEEDS_RPM = (4000.0, 2000.0)
AMBIENT_C = 8.0
HOURS = 5.0
#: When the sensors' and the drift's rises are read (min): the issue's 50 min and the end.
READ_AT_MIN = (50.0, HOURS * 60.0)
COMMAND = "python -m spindlebench.model.cold_start"


def numbers(fmu_path: str | Path = DEFAULT_FMU, command: str = COMMAND) -> dict[str, Any]:
    """The cold-start runs' numbers, as ``--json`` writes them: per speed, every sensor's rise
    (K) and the drift's rise (um) at ``READ_AT_MIN``, the drift's peak rise and its time; the
    provenance names the FMU by its SHA-256."""
    runs = {}
    for speed in SPEEDS_RPM:
        frame = cold_start(fmu_path, speed_rpm=speed, hours=HOURS, ambient_C=AMBIENT_C)
        drift = frame[DRIFT_COLUMN].to_numpy() - frame[DRIFT_COLUMN].iloc[0]
        peak = int(np.argmax(drift))
        sensors = [c for c in frame.columns if re.fullmatch(r"T\d+_C", c)]
        runs[f"{speed:g}"] = {
            "sensor_rise_K": {s: [rise(frame, s, m) for m in READ_AT_MIN] for s in sensors},
            "drift_rise_um": [rise(frame, DRIFT_COLUMN, m) for m in READ_AT_MIN],
            "drift_peak_um": float(drift[peak]),
            "drift_peak_h": float(frame[TIME_COLUMN].iloc[peak] / 3600.0)}
    fmu = file_entry(fmu_path)
    record = provenance(command=command, fmu=fmu, ambient_C=AMBIENT_C, hours=HOURS,
                        feed_mm_per_min=1500.0, output_interval_s=60.0,
                        solver="FMPy CVode, model exchange, relative tolerance 1e-6")
    return {"provenance": record, "read_at_min": list(READ_AT_MIN), "runs": runs}


def markdown(document: Mapping[str, Any]) -> str:
    """docs/model.md's table: one row per sensor (rise in K) and one for the drift (um), a
    column per speed and reading time, then the drift's peak (um, and when) per speed (two
    reading times per speed: the peak's value under the first, its time under the second)."""
    runs = document["runs"]
    times = [f"{m:g} min" if m < 60 else f"{m / 60:g} h" for m in document["read_at_min"]]
    header = ["rise since the start"] + [f"{speed} rpm, {t}" for speed in runs for t in times]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    first = next(iter(runs.values()))
    for sensor in sorted(first["sensor_rise_K"], key=lambda s: int(s[1:-2])):
        cells = [f"{v:+.1f}" for run in runs.values() for v in run["sensor_rise_K"][sensor]]
        lines.append(f"| {sensor.removesuffix('_C')} (K) | " + " | ".join(cells) + " |")
    lines.append("| **drift (µm)** | " + " | ".join(
        f"**{v:.1f}**" for run in runs.values() for v in run["drift_rise_um"]) + " |")
    lines.append("| drift's peak (µm; when) | " + " | ".join(
        f"{run['drift_peak_um']:.1f} | at {run['drift_peak_h']:.1f} h" for run in runs.values())
        + " |")
    return "\n".join(lines)


def write_json(path: Path, document: Mapping[str, Any]) -> Path:
    """The numbers as JSON (sorted keys), written atomically."""
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic.write_text(path, json.dumps(document, indent=2, sort_keys=True) + "\n")
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog=COMMAND, description=__doc__.split("\n\n")[0])
    parser.add_argument("figure", nargs="?", type=Path, default=DEFAULT_FIGURE,
                        help="the figure to draw (default: docs/figures/model_cold_start.png)")
    parser.add_argument("--json", type=Path, default=None, metavar="FILE.json",
                        help="write the runs' numbers with their provenance instead of the "
                        "figure")
    args = parser.parse_args(argv)
    if args.json is not None:
        document = numbers(DEFAULT_FMU, " ".join([COMMAND, *(argv or [])]))
        print(markdown(document))
        print(write_json(args.json, document))
    else:
        print(plot(DEFAULT_FMU, args.figure))
    return 0


if __name__ == "__main__":
    import sys

    raise SystemExit(main(sys.argv[1:]))
