"""One-page picture of a recording: the sensor temperatures, the drivers and the drift.

The first thing a student or an engineer looks at when a run comes out of the testbench.
"""

from __future__ import annotations

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import pandas as pd

from spindlebench.atomic import atomic_path

SPINDLE_NEAR = ("T1", "T2", "T3", "T4", "T5", "T7", "T8", "T9")


def plot_recording(frame: pd.DataFrame, out_png: str | os.PathLike[str], title: str) -> None:
    """Temperatures (spindle-near vs feed axes/structure), ambient and drift over hours."""
    hours = frame["time_s"].to_numpy() / 3600.0
    sensors = [f"T{i}" for i in range(1, 21) if f"T{i}" in frame]
    fig, (ax_near, ax_far, ax_drift) = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    for name in sensors:
        ax = ax_near if name in SPINDLE_NEAR else ax_far
        ax.plot(hours, frame[name], lw=1, label=name)
    if "ambient_C" in frame:
        ax_far.plot(hours, frame["ambient_C"], "k--", lw=1, label="ambient (driver)")
    ax_near.set_ylabel("spindle-near sensors (°C)")
    ax_far.set_ylabel("headstock, ambient, feed axes (°C)")
    for ax in (ax_near, ax_far):
        if ax.lines:
            ax.legend(ncol=6, fontsize=7, loc="upper left")
        ax.grid(alpha=0.3)
    ax_drift.plot(hours, frame["drift_um"], lw=1, label="measured (probe)")
    if "true_drift_um" in frame:
        true = frame["true_drift_um"] - frame["true_drift_um"].iloc[0]
        ax_drift.plot(hours, true, "k--", lw=1, label="noise-free")
    ax_drift.set_ylabel("axial drift since start (µm)")
    ax_drift.set_xlabel("time (h)")
    ax_drift.legend(fontsize=8)
    ax_drift.grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    with atomic_path(out_png) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)
