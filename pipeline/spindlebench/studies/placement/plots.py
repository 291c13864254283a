"""The comparison figure: cross-season RMSE of every method against the sensor budget."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import pandas as pd

from spindlebench.atomic import atomic_path
from spindlebench.studies.placement.schematic import METHOD_COLOURS


def comparison(table: pd.DataFrame, path: Path) -> Path:
    """Left: test RMSE vs m (bars: best and worst season); right: design RMSE vs m."""
    seasons = [c for c in table.columns
               if c.startswith("test_") and c.endswith("_rmse_um")
               and c not in ("test_mean_rmse_um", "test_worst_rmse_um")]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    ok = table[table["test_mean_rmse_um"].notna()]
    for label, at in ok.groupby("label", sort=False):
        at = at.sort_values("m")
        method = at["method"].iloc[0]
        style = "--" if bool(at["differences"].iloc[0]) else "-"
        colour = METHOD_COLOURS.get(method, "purple")
        mean = at["test_mean_rmse_um"].to_numpy(float)
        if seasons:
            per_season = at[seasons].to_numpy(float)
            low = mean - per_season.min(axis=1)
            high = per_season.max(axis=1) - mean
            left.errorbar(at["m"], mean, yerr=[low, high], fmt="o" + style, color=colour,
                          capsize=3, label=label, ms=4, lw=1.4)
        else:
            left.plot(at["m"], mean, "o" + style, color=colour, label=label)
        right.plot(at["m"], at["design_rmse_um"], "o" + style, color=colour, label=label,
                   ms=4, lw=1.4)
    left.set_title("test days: mean held-out RMSE (bars: best / worst season)", fontsize=9)
    right.set_title("design day: held-out RMSE (what greedy and exhaustive optimise)",
                    fontsize=9)
    for ax in (left, right):
        ax.set_xlabel("budget m (model variables)")
        ax.grid(alpha=0.3)
        ax.set_yscale("log")
    left.set_ylabel("RMSE (µm)")
    left.legend(fontsize=8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=120, bbox_inches="tight", format="png")
    plt.close(fig)
    return path
