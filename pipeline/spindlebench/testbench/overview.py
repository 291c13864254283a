"""One-page picture of a recording: the sensor temperatures, the drivers and the drift.

The first thing a student or an engineer looks at when a run comes out of the testbench.
``docs/figures/exp1_overview.png`` is this figure of ``scenarios/paper/exp1.toml``::

    spindlebench simulate scenarios/paper/exp1.toml -o results/paper/exp1.csv
    python -m spindlebench.testbench.overview results/paper/exp1.csv \
        docs/figures/exp1_overview.png \
        "Synthetic experiment 1: 4000 rpm, January ambient 5.3-10.4 °C"
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from spindlebench.atomic import atomic_path

SPINDLE_NEAR = ("T1", "T2", "T3", "T4", "T5", "T7", "T8", "T9")
#: The paper's ambient air probe: drawn in black, apart from the machine's sensors.
AMBIENT_SENSOR = "T10"
# tab20's ten saturated colours, then their ten light partners, greys left out: up to 18
# sensors per panel get a colour of their own (a 10-colour cycle repeated T6's colour on T19).
_TAB20 = plt.get_cmap("tab20").colors
PALETTE = tuple(_TAB20[i] for i in [*range(0, 20, 2), *range(1, 20, 2)] if i not in (14, 15))


def overview_figure(frame: pd.DataFrame, title: str) -> Figure:
    """Temperatures (spindle-near vs feed axes/structure), ambient and drift over hours."""
    fig, axes = plt.subplots(3, 1, figsize=(9, 9.6), sharex=True)
    try:
        _draw(frame, title, fig, *axes)
    except BaseException:
        plt.close(fig)
        raise
    return fig


def _draw(frame: pd.DataFrame, title: str, fig: Figure, ax_near: Axes, ax_far: Axes,
          ax_drift: Axes) -> None:
    hours = frame["time_s"].to_numpy() / 3600.0
    sensors = [f"T{i}" for i in range(1, 21) if f"T{i}" in frame]
    for ax, group in ((ax_near, [s for s in sensors if s in SPINDLE_NEAR]),
                      (ax_far, [s for s in sensors if s not in SPINDLE_NEAR])):
        machine = [s for s in group if s != AMBIENT_SENSOR]
        if len(machine) > len(PALETTE):
            raise ValueError(f"{len(machine)} sensors in one panel, {len(PALETTE)} colours")
        for name, colour in zip(machine, PALETTE, strict=False):
            ax.plot(hours, frame[name], color=colour, lw=1, label=name)
        if AMBIENT_SENSOR in group:
            ax.plot(hours, frame[AMBIENT_SENSOR], color="black", ls="--", lw=1.2,
                    label=f"{AMBIENT_SENSOR} (ambient probe)")
    if "ambient_C" in frame:  # a wide grey band under the probe that measures it
        ax_far.plot(hours, frame["ambient_C"], color="0.6", lw=3.5, alpha=0.6, zorder=1,
                    label="ambient air (driver)")
    ax_near.set_title("spindle-near sensors", fontsize=10, loc="left")
    ax_far.set_title("headstock, feed axes and ambient", fontsize=10, loc="left")
    for ax in (ax_near, ax_far):
        ax.set_ylabel("temperature (°C)")
        if ax.lines:
            n = len(ax.lines)
            ax.legend(ncol=n if n <= 8 else -(-n // 2), fontsize=7, loc="upper left")
        ax.grid(alpha=0.3)
    ax_drift.plot(hours, frame["drift_um"], lw=1, label="measured (probe)")
    if "true_drift_um" in frame:
        true = frame["true_drift_um"] - frame["true_drift_um"].iloc[0]
        ax_drift.plot(hours, true, "k--", lw=1, label="noise-free")
    ax_drift.set_title("axial drift, tool towards table, since the start", fontsize=10,
                       loc="left")
    ax_drift.set_ylabel("drift (µm)")
    ax_drift.set_xlabel("time (h)")
    ax_drift.legend(fontsize=8)
    ax_drift.grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()


def plot_recording(frame: pd.DataFrame, out_png: str | os.PathLike[str], title: str) -> None:
    """Draw ``overview_figure`` into ``out_png`` atomically."""
    fig = overview_figure(frame, title)
    try:
        with atomic_path(out_png) as tmp:
            fig.savefig(tmp, format="png", dpi=110)
    finally:
        plt.close(fig)


def main(argv: list[str]) -> int:
    """``python -m spindlebench.testbench.overview RECORDING.csv OUT.png [TITLE]``."""
    from spindlebench.recordings import read_recording

    if len(argv) not in (2, 3):
        print(main.__doc__, file=sys.stderr)
        return 2
    title = argv[2] if len(argv) == 3 else Path(argv[0]).stem
    plot_recording(read_recording(argv[0]), argv[1], title)
    print(argv[1])
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
