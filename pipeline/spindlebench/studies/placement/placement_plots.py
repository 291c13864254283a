"""The comparison figure: cross-season RMSE of every method against the sensor budget."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import matplotlib.ticker as ticker
import pandas as pd

from spindlebench.core.atomic import atomic_path
from spindlebench.studies.placement.schematic import method_colour


def comparison(table: pd.DataFrame, path: Path,
               references: Mapping[str, float] | None = None, note: str = "") -> Path:
    """Left: test RMSE vs m (bars: best and worst season); right: design RMSE vs m.

    ``references`` are drawn as labelled horizontal lines (e.g. predicting no drift at all,
    the probe's noise), so the reader sees the scale of the differences between methods.
    """
    seasons = [c for c in table.columns
               if c.startswith("test_") and c.endswith("_rmse_um")
               and c not in ("test_mean_rmse_um", "test_worst_rmse_um")]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    ok = table[table["test_mean_rmse_um"].notna()]
    for label, at in ok.groupby("label", sort=False):
        at = at.sort_values("m")
        method = at["method"].iloc[0]
        style = "--" if bool(at["differences"].iloc[0]) else "-"
        colour = method_colour(method, list(ok["method"]))
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
        for (name, value), shade in zip((references or {}).items(), ("#777777", "#bbbbbb"),
                                        strict=False):
            ax.axhline(value, color=shade, lw=1.0, ls="-.", zorder=0)
            ax.text(ax.get_xlim()[0], value * 1.04, f" {name}: {value:.2f} µm", fontsize=7,
                    color="#555555", va="bottom")
        ax.set_xlabel("budget m (model variables)")
        ax.grid(alpha=0.3)
        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(ticker.FormatStrFormatter("%g"))
        ax.yaxis.set_minor_formatter(ticker.FormatStrFormatter("%g"))
        ax.xaxis.set_major_locator(ticker.MaxNLocator(integer=True))
    left.set_ylabel("RMSE (µm)")
    if note:
        fig.suptitle(f"Cross-season RMSE of each placement ({note})", fontsize=10)
    left.legend(fontsize=8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=120, bbox_inches="tight", format="png")
    plt.close(fig)
    return path
