"""Cold-start runs of the FMU at constant load: the model's plausibility check and its figure.

From a machine soaked at a constant ambient, the spindle runs at a constant speed with both
feed axes reciprocating. The issue's expectations (spindle-near sensors rise several degC in
~50 min and level off, feed-axis and structure sensors keep rising, drift of tens of um in a few
hours, less at 2000 rpm) are checked on these runs by the tests and shown in
``docs/figures/model_cold_start.png`` (``python -m spindlebench.modelica.cold_start``).
"""

from __future__ import annotations

import sys
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from spindlebench import atomic
from spindlebench.names import KELVIN_OFFSET
from spindlebench.paths import DATA_ROOT, DEFAULT_FMU

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
        # FMPy's Euler takes one step per output interval; it needs a step below ~35 s
        step_size=output_interval_s if solver == "Euler" else None,
        relative_tolerance=1e-6,
    )
    frame = pd.DataFrame({name: result[name] for name in result.dtype.names})
    return frame.rename(columns={"time": "time_s"})


def rise(frame: pd.DataFrame, column: str, minutes: float) -> float:
    """Change of ``column`` from the first sample to ``minutes`` into the run."""
    times = frame["time_s"].to_numpy()
    values = frame[column].to_numpy()
    return float(np.interp(minutes * 60.0, times, values) - values[0])


def plot(fmu_path: str | Path = DEFAULT_FMU, out_path: str | Path = DEFAULT_FIGURE) -> Path:
    """Draw the cold-start figure: six sensors at 4000 rpm, drift at 4000 and 2000 rpm."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fast = cold_start(fmu_path, speed_rpm=4000.0)
    slow = cold_start(fmu_path, speed_rpm=2000.0)
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    minutes = fast["time_s"] / 60.0
    for sensor in FIGURE_SENSORS:
        left.plot(minutes, fast[sensor] - fast[sensor].iloc[0], label=sensor.removesuffix("_C"))
    left.axvline(50, color="grey", linestyle=":", linewidth=1)
    left.set(
        xlabel="time (min)",
        ylabel="temperature rise (K)",
        title="Cold start at 4000 rpm, X/Y at 1500 mm/min, 8 °C",
    )
    left.legend(ncol=2, fontsize=8)
    for frame, label in ((fast, "4000 rpm"), (slow, "2000 rpm")):
        right.plot(
            frame["time_s"] / 60.0, frame["drift_um"] - frame["drift_um"].iloc[0], label=label
        )
    right.set(
        xlabel="time (min)",
        ylabel="drift since start (µm)",
        title="Axial drift, tool towards table",
    )
    right.legend()
    with atomic.atomic_path(Path(out_path).with_suffix(".png")) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return Path(out_path)


if __name__ == "__main__":
    target = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT_FIGURE
    print(plot(DEFAULT_FMU, target))
