"""Box plots of a sweep's held-out RMSE: by method and k, by held-out month, by condition.

Drawn with matplotlib's object API (``matplotlib.figure.Figure`` renders with Agg and touches
no global pyplot state), each axes' boxes as a few collections from precomputed statistics:
``Axes.boxplot`` made seven artists per box (1 700 on a sweep's three figures), and making
and drawing them was most of the figures' time.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd
from matplotlib import cbook
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.figure import Figure

from spindlebench.core.atomic import atomic_path
from spindlebench.core.names import ALL_RAW, GROUPS, SIX_DIFF, SIX_RAW
from spindlebench.studies.family.family_file import RIDGE_BASELINE, TOP_K_BASELINE
from spindlebench.studies.family.seasons import MONTHS

METHOD_ORDER = (*GROUPS, TOP_K_BASELINE, RIDGE_BASELINE, "oracle")
COLOURS = {ALL_RAW: "#8c8c8c", SIX_RAW: "#5b8fc9", SIX_DIFF: "#d9622b",
           TOP_K_BASELINE: "#6aa84f", RIDGE_BASELINE: "#9b59b6", "oracle": "#f0c419",
           "measured": "#4c72b0", "noise-free": "#d0d0d0"}
#: Drawn over every box: black contrasts with each fill above (an orange median vanished on
#: the orange six_diff boxes).
MEDIAN = {"color": "black", "linewidth": 1.5}
#: Methods without a k (fitted on all candidates): drawn once, in their own panel.
NO_K = ("ridge", "oracle")
#: Fill opacity of the boxes; flier marker size (points).
BOX_ALPHA = 0.85
FLIER_SIZE = 2


def _save(fig: Figure, path: Path) -> Path:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, bbox_inches="tight", format="png")
    return path


def _present(column: pd.Series) -> set:
    """The distinct values of a column (``set(column)`` walks every cell of a pandas string
    column in Python: most of the plots' time on a 1 000-run sweep's 380 000 rows)."""
    return set(column.unique())


def _methods(frame: pd.DataFrame) -> list[str]:
    present = _present(frame["method"])
    return [m for m in METHOD_ORDER if m in present]


def _rc(part: str) -> dict:
    """matplotlib's style of one part of a box plot (rcParams ``boxplot.<part>props.*``),
    the style ``Axes.boxplot`` gives it, so the collections below draw the same boxes."""
    prefix = f"boxplot.{part}props."
    return {key[len(prefix):]: value for key, value in matplotlib.rcParams.items()
            if key.startswith(prefix)}


def _segments(ax: Axes, segments: list, style: dict, zorder: float,
              capstyle: str = matplotlib.rcParams["lines.solid_capstyle"]) -> None:
    """Straight lines in ``style`` (rcParams ``boxplot.*props`` keys), capped and joined as
    ``Axes.boxplot``'s ``Line2D`` are (a collection's default caps are butt)."""
    ax.add_collection(LineCollection(
        segments, colors=style["color"], linewidths=style["linewidth"],
        linestyles=style["linestyle"], capstyle=capstyle,
        joinstyle=matplotlib.rcParams["lines.solid_joinstyle"], zorder=zorder))


def _draw_boxes(ax: Axes, boxes: list[tuple[float, np.ndarray, str]], width: float) -> None:
    """Box plots of ``boxes`` (position, values, fill colour) as ``Axes.boxplot(...,
    patch_artist=True)`` draws them (its statistics, ``cbook.boxplot_stats``; its geometry,
    styles and draw order; x limits half a slot beyond the outer boxes), in four artists:
    the boxes, the whiskers and caps, the fliers and the medians."""
    if not boxes:
        return
    positions = np.array([position for position, _, _ in boxes])
    stats = cbook.boxplot_stats([values for _, values, _ in boxes])
    half, cap = width / 2, width / 4
    outline = _rc("box")
    ax.add_collection(PolyCollection(
        [[(x - half, s["q1"]), (x + half, s["q1"]), (x + half, s["q3"]), (x - half, s["q3"]),
          (x - half, s["q1"])] for x, s in zip(positions, stats, strict=True)],
        facecolors=[colour for _, _, colour in boxes], edgecolors=outline["color"],
        linewidths=outline["linewidth"], linestyles=outline["linestyle"], alpha=BOX_ALPHA,
        joinstyle="miter", capstyle="butt", zorder=2))  # a patch's joins and caps
    whiskers = [segment for x, s in zip(positions, stats, strict=True) for segment in (
        [(x, s["q1"]), (x, s["whislo"])], [(x, s["q3"]), (x, s["whishi"])],
        [(x - cap, s["whislo"]), (x + cap, s["whislo"])],
        [(x - cap, s["whishi"]), (x + cap, s["whishi"])])]
    _segments(ax, whiskers, _rc("whisker"), zorder=2)
    fliers = [s["fliers"] for s in stats]
    ax.plot(np.repeat(positions, [len(f) for f in fliers]), np.concatenate(fliers),
            **{**_rc("flier"), "markersize": FLIER_SIZE}, label="_nolegend_")
    _segments(ax, [[(x - half, s["med"]), (x + half, s["med"])]
                   for x, s in zip(positions, stats, strict=True)],
              {**_rc("median"), **MEDIAN}, zorder=2.1, capstyle="butt")  # as boxplot's:
    # over the boxes, ending at their edges
    ax.set_xlim(positions.min() - 0.5, positions.max() + 0.5)


def _grouped_boxes(ax: Axes, frame: pd.DataFrame, categories: list, category: str,
                   methods: list[str]) -> None:
    width = 0.8 / max(1, len(methods))
    # each box's values in one grouping pass (in row order, as a mask per box gave them):
    # a mask per method and category compared every row of a 1 000-run sweep's table again
    values = {key: group.dropna().to_numpy() for key, group in
              frame.groupby(["method", category], sort=False)["rmse_um"]}
    boxes = []
    for j, method in enumerate(methods):
        drawn = False
        for i, value in enumerate(categories):
            data = values.get((method, value))
            if data is not None and len(data):
                boxes.append((i - 0.4 + width * (j + 0.5), data, COLOURS.get(method, "white")))
                drawn = True
        if drawn:
            ax.plot([], [], "s", color=COLOURS.get(method, "black"), label=method)
    _draw_boxes(ax, boxes, width * 0.85)
    ax.set_xticks(range(len(categories)))
    ax.set_xticklabels([str(c) for c in categories], rotation=30, ha="right")
    ax.set_ylabel("held-out RMSE (µm)")
    ax.grid(axis="y", alpha=0.3)
    low, high = ax.get_ylim()
    ax.set_ylim(low, high + 0.25 * (high - low))  # room for the legend above the boxes


def by_method_and_k(results: pd.DataFrame, path: Path) -> Path | None:
    """One panel per k with the methods that have one, and one "no k" panel for ridge and the
    oracle (they do not depend on k, so repeating them in every k panel suggested they did);
    measured next to the noise-free truth."""
    ok = results[results["rmse_um"].notna()]
    ks = sorted(int(k) for k in ok["k"].dropna().unique())
    if not ks:
        return None
    no_k = ok[ok["k"].isna()]
    panels: list[tuple[str, pd.DataFrame]] = [(f"k = {k}", ok[ok["k"] == k]) for k in ks]
    if len(no_k):
        panels.append(("no k: " + ", ".join(_methods(no_k)), no_k))
    widths = [max(1, len(_methods(frame))) for _, frame in panels]
    fig = Figure(figsize=(0.85 * sum(widths) + 1.2, 4.4), layout="constrained")
    axes = fig.subplots(1, len(panels), sharey=True, squeeze=False,
                        gridspec_kw={"width_ratios": widths})
    series = [s for s in ("measured", "noise-free") if s in _present(ok["data"])]
    for ax, (title, at) in zip(axes[0], panels, strict=True):
        _grouped_boxes(ax, at.rename(columns={"method": "category", "data": "method"}),
                       _methods(at), "category", series)
        ax.set_title(title, fontsize=10)
    for ax in axes[0][1:]:
        ax.set_ylabel("")
    # A few extreme cases would flatten every box: clip the axis, say so.
    top = float(ok["rmse_um"].quantile(0.99)) * 1.15
    clipped = int((ok["rmse_um"] > top).sum())
    axes[0][0].set_ylim(0, top)
    axes[0][0].legend(loc="upper left", fontsize=8)
    note = f"\n({clipped} of {len(ok)} values above {top:.0f} µm not shown)" if clipped else ""
    fig.suptitle("Held-out RMSE per method: measured vs noise-free truth" + note, fontsize=11)
    return _save(fig, path)


def _no_k_note(frame: pd.DataFrame) -> str:
    names = [m for m in _methods(frame) if m in NO_K]
    return f"; {' and '.join(names)}: no k" if names else ""


def by_month(results: pd.DataFrame, path: Path) -> Path | None:
    """Held-out RMSE by month, one row of panels per k and one column per held-out spindle
    speed: the month alone hardly moves the error, the speed of the held-out run and k do,
    so a single k = 2 panel pooled over speeds looked flat and hid what varies. Methods
    without a k (ridge, oracle) are repeated in every row, as the title says."""
    ok = results[results["rmse_um"].notna() & (results["data"] == "measured")]
    if ok.empty:
        return None
    ks = sorted(int(k) for k in ok["k"].dropna().unique()) or [None]
    speeds = (sorted(float(v) for v in ok["test_speed_rpm"].dropna().unique())
              if "test_speed_rpm" in ok else [None])
    months = [m for m in MONTHS if m in _present(ok["test_month"])]
    n_methods = len(_methods(ok))
    fig = Figure(figsize=(max(5.0, 0.22 * n_methods * len(months) + 1.5) * len(speeds),
                          3.3 * len(ks) + 0.6), layout="constrained")
    axes = fig.subplots(len(ks), len(speeds), squeeze=False, sharey=True)
    for row, k in enumerate(ks):
        at_k = ok[(ok["k"] == k) | ok["k"].isna()] if k is not None else ok
        for column, speed in enumerate(speeds):
            at = at_k if speed is None else at_k[at_k["test_speed_rpm"] == speed]
            ax = axes[row, column]
            _grouped_boxes(ax, at, months, "test_month", _methods(at))
            where = [f"k = {k}" if k is not None else "", f"held-out runs at {speed:g} rpm"
                     if speed is not None else "all held-out runs"]
            ax.set_title(", ".join(w for w in where if w), fontsize=10)
            if column:
                ax.set_ylabel("")
    top = float(ok["rmse_um"].quantile(0.99)) * 1.15
    clipped = int((ok["rmse_um"] > top).sum())
    axes[0, 0].set_ylim(0, top)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, ncols=len(labels), loc="outside lower center",
               frameon=False)  # outside: inside, it hid the tallest boxes
    note = f"; {clipped} of {len(ok)} values above {top:.0f} µm not shown" if clipped else ""
    fig.suptitle(f"Held-out RMSE by month of the held-out run (measured{_no_k_note(ok)}, "
                 f"repeated in every row{note})", fontsize=11)
    return _save(fig, path)


def by_condition(results: pd.DataFrame, path: Path, k: int) -> Path | None:
    ok = results[results["rmse_um"].notna() & (results["data"] == "measured")].copy()
    at = ok[(ok["k"] == k) | ok["k"].isna()].copy()
    if at.empty:
        return None
    at["condition"] = at["noise"] + " / " + at["fault"]
    conditions = list(dict.fromkeys(at["condition"]))
    fig = Figure(figsize=(max(6.0, 1.8 * len(conditions)), 4.2))
    ax = fig.subplots()
    _grouped_boxes(ax, at, conditions, "condition", _methods(at))
    ax.set_title(f"Held-out RMSE by measurement condition (noise / fault, k = {k}"
                 f"{_no_k_note(at)})")
    ax.legend(fontsize=8, ncols=3)
    return _save(fig, path)


def box_plots(results: pd.DataFrame, folder: Path) -> dict[str, Path]:
    """Write every figure into ``folder``; return name → path of those that have data."""
    figures: dict[str, Path | None] = {}
    ks = sorted(int(k) for k in results["k"].dropna().unique())
    figures["by_method"] = by_method_and_k(results, folder / "rmse_by_method.png")
    if ks:
        figures["by_month"] = by_month(results, folder / "rmse_by_month.png")
        figures["by_condition"] = by_condition(results, folder / "rmse_by_condition.png", ks[0])
    return {name: path for name, path in figures.items() if path is not None}
