"""The analogues of the paper's Figures 3-6, plus the dendrogram the paper lacks.

Drawn with matplotlib's object API (``matplotlib.figure.Figure`` renders with Agg and touches
no global pyplot state), saved as PNG atomically.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from scipy.cluster.hierarchy import dendrogram

from spindlebench.core import atomic
from spindlebench.core.names import ALL_RAW, GROUP_LABELS, SIX_DIFF, SIX_RAW
from spindlebench.formats.recording import TIME_COLUMN
from spindlebench.selection import linkage_from_similarity
from spindlebench.studies.paper.analysis import StudyResult

DPI = 110
GROUP_COLORS = {ALL_RAW: "tab:blue", SIX_RAW: "tab:orange", SIX_DIFF: "tab:green"}


def _save(figure: Figure, path: Path) -> Path:
    figure.tight_layout()
    with atomic.atomic_path(path) as tmp:
        figure.savefig(tmp, format="png", dpi=DPI)
    return path


def _hours(result: StudyResult, name: str) -> np.ndarray:
    frame = result.frames[name]
    if TIME_COLUMN in frame.columns:
        return frame[TIME_COLUMN].to_numpy(dtype=float) / 3600.0
    return np.arange(len(frame)) / 3600.0


#: The quantity every target is (the study reports RMSE in µm); the column name goes in the
#: title, where a reader looks for which channel it is.
ERROR_LABEL = "thermal error (µm)"


def _legend_outside(ax, **kwargs) -> None:
    """A legend right of the axes: inside, it hides curves or branches wherever it goes."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, **kwargs)


def error_curves(result: StudyResult, path: Path) -> Path:
    """Fig. 3: the measured thermal error of every experiment."""
    figure = Figure(figsize=(8.5, 4))
    ax = figure.add_subplot()
    for name in result.config.experiments:
        label = f"{name} (train)" if name == result.config.train else name
        ax.plot(_hours(result, name), result.frames[name][result.config.target], label=label)
    ax.set_xlabel("time (h)")
    ax.set_ylabel(ERROR_LABEL)
    ax.set_title(f"Measured thermal error of every experiment (column {result.config.target})",
                 fontsize="medium")
    ax.grid(alpha=0.3)
    _legend_outside(ax, fontsize="small")
    return _save(figure, path)


def _rise(values: np.ndarray) -> np.ndarray:
    """Change since the first finite sample (a missing first sample must not blank it)."""
    values = np.asarray(values, dtype=float)
    finite = values[np.isfinite(values)]
    return values - finite[0] if finite.size else values


def six_temperatures(result: StudyResult, path: Path) -> Path:
    """Fig. 4: the six sensors in the training experiment, as rises since its start.

    Rises, because the method works on rises, and because absolute values of different
    levels (a warm spindle beside a cold air probe) flatten each curve's shape."""
    name = result.config.train
    figure = Figure(figsize=(7.5, 4))
    ax = figure.add_subplot()
    for sensor in result.six:
        ax.plot(_hours(result, name), _rise(result.frames[name][sensor].to_numpy()),
                label=sensor)
    ax.set_xlabel("time (h)")
    ax.set_ylabel("rise since the start (K)")
    ax.set_title(f"The six sensors in {name}, as rises since the start")
    ax.grid(alpha=0.3)
    _legend_outside(ax, fontsize="small")
    return _save(figure, path)


def measured_vs_predicted(result: StudyResult, path: Path) -> Path:
    """Fig. 5 as small multiples: every predicted experiment (rows) × every k (columns),
    measured error and the three groups' predictions, each panel with the groups' RMSE.

    Rows share their y axis, so the k columns of one experiment compare at a glance; one
    legend serves the figure."""
    ks = list(result.config.clusters)
    tests = list(result.config.tests)
    figure = Figure(figsize=(3.3 * len(ks) + 2.2, 2.0 * len(tests) + 0.8))
    axes = figure.subplots(len(tests), len(ks), squeeze=False, sharex="row", sharey="row")
    for row, experiment in enumerate(tests):
        hours = _hours(result, experiment)
        measured = result.frames[experiment][result.config.target]
        for column, k in enumerate(ks):
            ax = axes[row, column]
            ax.plot(hours, measured, color="black", lw=1.8, label="measured")
            scores = []
            for group in result.groups:
                cell = result.cell(group, k)
                ax.plot(hours, cell.predictions_um[experiment], color=GROUP_COLORS[group],
                        lw=1.1, label=GROUP_LABELS[group])
                scores.append((f"{cell.rmse_um[experiment]:.1f}", GROUP_COLORS[group]))
            for i, (text, colour) in enumerate(scores):  # RMSE of each group, in its colour
                ax.text(1.0 - 0.1 * (len(scores) - i), 0.97, text, color=colour,
                        transform=ax.transAxes, ha="right", va="top", fontsize="x-small",
                        fontweight="bold", zorder=5,
                        bbox={"facecolor": "white", "alpha": 0.8, "pad": 1.0, "lw": 0})
            ax.grid(alpha=0.3)
            ax.tick_params(labelsize="x-small")
            if row == 0:
                ax.set_title(f"k = {k}", fontsize="medium")
            if column == 0:
                ax.set_ylabel(f"{experiment}\n{ERROR_LABEL}", fontsize="small")
            if row == len(tests) - 1:
                ax.set_xlabel("time (h)", fontsize="small")
    _legend_outside(axes[0, -1], fontsize="x-small",
                    title="numbers: RMSE (µm)", title_fontsize="x-small")
    figure.suptitle(f"Measured and predicted {result.config.target} of every predicted "
                    f"experiment (trained on {result.config.train})", fontsize="medium")
    return _save(figure, path)


def rmse_bars(result: StudyResult, path: Path) -> Path:
    """Fig. 6: RMSE of every prediction, grouped by experiment, one panel per k."""
    ks = result.config.clusters
    tests = list(result.config.tests)
    figure = Figure(figsize=(3.2 * len(ks) + 1, 3.8))
    width = 0.8 / len(result.groups)
    x = np.arange(len(tests) + 1)
    top = max(max(c.rmse_um.values()) for c in result.cells) * 1.1
    for column, k in enumerate(ks, start=1):
        ax = figure.add_subplot(1, len(ks), column)
        for i, group in enumerate(result.groups):
            cell = result.cell(group, k)
            heights = [cell.rmse_um[t] for t in tests] + [cell.mean_rmse_um]
            ax.bar(x + (i - (len(result.groups) - 1) / 2) * width, heights, width,
                   color=GROUP_COLORS[group], label=GROUP_LABELS[group])
        ax.set_xticks(x, [*tests, "mean"], rotation=45, ha="right", fontsize="small")
        ax.set_title(f"{k} clusters", fontsize="medium")
        ax.set_ylim(0, top)
        ax.grid(axis="y", alpha=0.3)
        if column == 1:
            ax.set_ylabel("RMSE (µm)")
            ax.legend(fontsize="x-small")
    return _save(figure, path)


def cut_height(merge_heights: np.ndarray, eta: float) -> float:
    """A y position for the cut line at η: between the last merge kept and the first one cut."""
    level = 1.0 - eta
    kept = merge_heights[merge_heights <= level + 1e-12]
    cut = merge_heights[merge_heights > level + 1e-12]
    low = kept.max() if kept.size else 0.0
    high = cut.min() if cut.size else low + 0.05 * (merge_heights.max() or 1.0)
    return float((low + high) / 2.0)


def closure_dendrogram(result: StudyResult, group: str, path: Path) -> Path:
    """Fuzzy equivalence hierarchy of a group on the training experiment, with the η cuts."""
    names, closure = result.closure(group)
    tree = linkage_from_similarity(closure)  # heights 1 - t(R); cut at 1 - η = λ-cut
    figure = Figure(figsize=(max(7.5, 0.35 * len(names) + 4), 4.5))
    ax = figure.add_subplot()
    dendrogram(tree, labels=names, ax=ax, leaf_rotation=90, color_threshold=0,
               above_threshold_color="0.3")
    styles = ["--", "-.", ":", (0, (5, 1))]
    for i, k in enumerate(result.config.clusters):
        eta = result.cell(group, k).eta
        ax.axhline(cut_height(tree[:, 2], eta), color=f"C{i + 1}", ls=styles[i % len(styles)],
                   label=f"cut for k = {k}\n(η = {eta:.4f})")
    ax.set_ylabel("merge height 1 − t(R)")
    ax.set_title(f"{GROUP_LABELS[group]}: fuzzy equivalence hierarchy on {result.config.train}",
                 fontsize="medium")
    # The line sits midway between the merges it separates, not at 1 − η: drawn at 1 − η it
    # would touch the merge at that height and leave it unclear on which side that merge is.
    _legend_outside(ax, fontsize="small", title="λ-cut at t(R) ≥ η,\ndrawn between merges",
                    title_fontsize="x-small")
    return _save(figure, path)


def write_all(result: StudyResult, out_dir: Path) -> dict[str, Path]:
    """Every figure; keys name them for the README."""
    figures = {
        "error_curves": error_curves(result, out_dir / "fig3_error_curves.png"),
        "six_temperatures": six_temperatures(result, out_dir / "fig4_six_temperatures.png"),
        "measured_vs_predicted": measured_vs_predicted(
            result, out_dir / "fig5_measured_vs_predicted.png"
        ),
        "rmse_bars": rmse_bars(result, out_dir / "fig6_rmse_bars.png"),
    }
    for group in result.groups:
        figures[f"dendrogram_{group}"] = closure_dendrogram(
            result, group, out_dir / f"dendrogram_{group}.png"
        )
    return figures
