"""The ISO 230-3 report figure: drift per direction, tilts and temperatures on one time axis."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from spindlebench.core.atomic import atomic_path
from spindlebench.studies.iso230_3.channels import TestData


def draw(data: TestData, title: str, path: Path, *, phase_end_s: float | None = None,
         stable_at_s: float | None = None) -> Path:
    """Write the report figure (PNG, atomically): linear drifts (µm), tilts (µrad) and the
    temperatures (°C, the air drawn bold) against time in hours; the spindle-on phase
    shaded, the time the stability criterion was met marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    hours = data.time_s / 3600.0
    rows = 3 if data.tilts else 2
    fig, axes = plt.subplots(rows, 1, figsize=(9.0, 2.6 * rows + 0.6), sharex=True,
                             constrained_layout=True)
    lin_ax, temp_ax = axes[0], axes[-1]
    for name, values in data.linear.items():
        lin_ax.plot(hours, values, lw=1.3, label=f"{name} ({data.sources.get(name, name)})"
                    if name in data.sources else name)
    lin_ax.set_ylabel("drift (µm)")
    lin_ax.axhline(0.0, color="0.6", lw=0.6)
    lin_ax.legend(loc="best", fontsize=8, ncol=2)
    if data.tilts:
        tilt_ax = axes[1]
        for name, values in data.tilts.items():
            tilt_ax.plot(hours, values, lw=1.0, label=f"tilt {name}")
        tilt_ax.set_ylabel("tilt (µrad)")
        tilt_ax.axhline(0.0, color="0.6", lw=0.6)
        tilt_ax.legend(loc="best", fontsize=8)
    for label, values in data.temperatures.items():
        bold = label == data.air
        temp_ax.plot(hours, values, lw=2.0 if bold else 1.0, color="k" if bold else None,
                     label=label + (" (air)" if bold and "air" not in label else ""))
    temp_ax.set_ylabel("temperature (°C)")
    temp_ax.set_xlabel("time (h)")
    temp_ax.legend(loc="best", fontsize=8, ncol=2)
    if data.speed_rpm is not None and np.any(data.speed_rpm > 0):
        on = data.speed_rpm > 0
        edges = np.flatnonzero(np.diff(np.concatenate([[0], on.astype(int), [0]])))
        for start, stop in zip(edges[::2], edges[1::2], strict=True):
            for ax in axes:
                ax.axvspan(hours[start], hours[min(stop, hours.size - 1)], color="tab:orange",
                           alpha=0.08, lw=0)
    if stable_at_s is not None:
        for ax in axes:
            ax.axvline(stable_at_s / 3600.0, color="tab:green", ls="--", lw=1.0)
        lin_ax.annotate("stability criterion met", (stable_at_s / 3600.0, 0.0),
                        xytext=(4, 4), textcoords="offset points", fontsize=8,
                        color="tab:green")
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.suptitle(title, fontsize=10)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png", metadata={"Software": None})
    plt.close(fig)
    return path
