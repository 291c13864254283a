"""The fingerprint figure: the shape of the drift next to the shape of the sensors.

Two panels, the default machine's paper experiments on the left and the given recordings on
the right. Per recording, its error rise (solid) and the median of its sensor rises (dashed,
sensors rising at least 0.1 K), each smoothed and divided by its own final value as in
:mod:`spindlebench.studies.fingerprint.statistics`: a curve at 1 has reached its final value,
one above 1 has overshot. A real spindle's error rises first and falls back while the sensors
keep climbing;
an ambient-following machine's error tracks its sensors.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from spindlebench.core.atomic import atomic_path
from spindlebench.studies.fingerprint.statistics import MIN_SENSOR_RISE_K, final, smooth

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from spindlebench.studies.fingerprint.recordings import Fingerprinted


def normalised(x: np.ndarray) -> np.ndarray | None:
    """``smooth(x) / final(x)``, or None when the final value is 0."""
    end = final(x)
    return None if end == 0.0 else smooth(x) / end


def sensor_median(rises: np.ndarray) -> np.ndarray | None:
    """Median over the sensors that rise at least 0.1 K of their normalised rises."""
    curves = []
    for j in range(rises.shape[1]):
        column = rises[:, j]
        if abs(final(column) - smooth(column)[0]) >= MIN_SENSOR_RISE_K:
            curve = normalised(column)
            if curve is not None:
                curves.append(curve)
    return np.median(np.column_stack(curves), axis=1) if curves else None


def _panel(ax: Axes, items: Sequence[Fingerprinted], title: str) -> None:
    colours = plt.get_cmap("tab10").colors
    for item, colour in zip(items, colours * (len(items) // 10 + 1), strict=False):
        hours = (item.time - item.time[0]) / 3600.0  # the time column is in seconds (roles)
        error = normalised(item.error)
        if error is not None:
            ax.plot(hours, error, color=colour, lw=1.6, label=item.path.stem)
        sensors = sensor_median(item.rises)
        if sensors is not None:
            ax.plot(hours, sensors, color=colour, lw=1.0, ls="--")
    stats = [item.stats for item in items]
    summary = ", ".join(
        f"{label} {np.median(values):.3f}" for label, key in
        (("raw ψ", "best_raw_psi"), ("diff ψ", "best_diff_psi"), ("early", "early_fraction"))
        if (values := [s[key] for s in stats if math.isfinite(s[key])]))
    ax.set_title(f"{title}\nmedian: {summary}" if summary else title, fontsize=10)
    ax.axhline(1.0, color="grey", lw=0.6)
    ax.set_xlabel("time since start (h)")
    ax.legend(fontsize=7, loc="lower right")
    ax.grid(alpha=0.3)


def write_figure(path: Path, items: Sequence[Fingerprinted],
                 reference: Sequence[Fingerprinted],
                 reference_title: str = "default machine, paper experiments") -> None:
    """Draw the reference and the given recordings side by side into ``path`` (atomic)."""
    panels = [(reference, reference_title), (items, "given recordings")]
    panels = [(group, title) for group, title in panels if group]
    fig, axes = plt.subplots(1, len(panels), figsize=(6 * len(panels), 4.6), sharey=True,
                             squeeze=False)
    try:
        for ax, (group, title) in zip(axes[0], panels, strict=True):
            _panel(ax, group, title)
        axes[0][0].set_ylabel("rise / final rise (solid: error, dashed: median sensor)")
        fig.tight_layout()
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", dpi=110)
    finally:
        plt.close(fig)
