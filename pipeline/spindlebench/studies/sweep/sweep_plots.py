"""Box plots of a sweep's held-out RMSE: by method and k, by held-out month, by condition.

Drawn with matplotlib's object API (``matplotlib.figure.Figure`` renders with Agg and touches
no global pyplot state), each axes' boxes as a few collections from precomputed statistics:
``Axes.boxplot`` made seven artists per box (1 700 on a sweep's three figures), and making
and drawing them was most of the figures' time.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

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
from spindlebench.studies.sweep.summary import NO_K_KEY, Scored

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


def _methods(present: Iterable[str]) -> list[str]:
    """The ``present`` methods in the order the figures show them."""
    present = set(present)
    return [m for m in METHOD_ORDER if m in present]


#: The names of matplotlib's box-plot styles (their values are read when drawing: a style
#: context may change them; walking all rcParams for every part of every axes cost 50 ms).
_BOXPLOT_PROPS = tuple(key for key in matplotlib.rcParams if key.startswith("boxplot.")
                       and "props." in key)


def _rc(part: str) -> dict:
    """matplotlib's style of one part of a box plot (rcParams ``boxplot.<part>props.*``),
    the style ``Axes.boxplot`` gives it, so the collections below draw the same boxes."""
    prefix = f"boxplot.{part}props."
    return {key[len(prefix):]: matplotlib.rcParams[key] for key in _BOXPLOT_PROPS
            if key.startswith(prefix)}


def _segments(ax: Axes, segments: list, style: dict, zorder: float,
              capstyle: str | None = None) -> None:
    """Straight lines in ``style`` (rcParams ``boxplot.*props`` keys), capped (by default)
    and joined as ``Axes.boxplot``'s ``Line2D`` are (a collection's default caps are butt)."""
    ax.add_collection(LineCollection(
        segments, colors=style["color"], linewidths=style["linewidth"],
        linestyles=style["linestyle"],
        capstyle=capstyle or matplotlib.rcParams["lines.solid_capstyle"],
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


def _grouped_boxes(ax: Axes, values: Mapping[tuple[str, Any], np.ndarray], categories: list,
                   methods: list[str]) -> None:
    """One group of boxes per category, one box per method (``values[(method, category)]``,
    drawn if it has values)."""
    width = 0.8 / max(1, len(methods))
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


def _clipped_top(rmse_um: pd.Series) -> tuple[float, int]:
    """The y limit that keeps a few extreme cases from flattening every box, and how many
    values lie above it."""
    top = float(rmse_um.quantile(0.99)) * 1.15
    return top, int((rmse_um > top).sum())


def _rows(scored: Scored, data: str) -> np.ndarray:
    """The scored rows of one data kind (measured or noise-free)."""
    return np.flatnonzero(scored.codes("data") == scored.code("data", data))


def by_method_and_k(results: pd.DataFrame, path: Path, scored: Scored | None = None
                    ) -> Path | None:
    """One panel per k with the methods that have one, and one "no k" panel for ridge and the
    oracle (they do not depend on k, so repeating them in every k panel suggested they did);
    measured next to the noise-free truth."""
    scored = scored or Scored(results)
    boxes = scored.values_by(["k", "method", "data"])  # (k, method, data) -> values
    ks = sorted({k for k, _, _ in boxes if k is not None})
    if not ks:
        return None
    panels = [(f"k = {k}", k) for k in ks]
    no_k = _methods(m for k, m, _ in boxes if k is None)
    if no_k:
        panels.append(("no k: " + ", ".join(no_k), None))
    at = {k: {(data, method): values for (kk, method, data), values in boxes.items() if kk == k}
          for _, k in panels}
    methods = {k: _methods(method for _, method in at[k]) for _, k in panels}
    widths = [max(1, len(methods[k])) for _, k in panels]
    fig = Figure(figsize=(0.85 * sum(widths) + 1.2, 4.4), layout="constrained")
    axes = fig.subplots(1, len(panels), sharey=True, squeeze=False,
                        gridspec_kw={"width_ratios": widths})
    present = {data for _, _, data in boxes}
    series = [s for s in ("measured", "noise-free") if s in present]
    for ax, (title, k) in zip(axes[0], panels, strict=True):
        _grouped_boxes(ax, at[k], methods[k], series)
        ax.set_title(title, fontsize=10)
    for ax in axes[0][1:]:
        ax.set_ylabel("")
    top, clipped = _clipped_top(scored.frame["rmse_um"])
    axes[0][0].set_ylim(0, top)
    axes[0][0].legend(loc="upper left", fontsize=8)
    note = (f"\n({clipped} of {len(scored.frame)} values above {top:.0f} µm not shown)"
            if clipped else "")
    fig.suptitle("Held-out RMSE per method: measured vs noise-free truth" + note, fontsize=11)
    return _save(fig, path)


def _no_k_note(methods: Iterable[str]) -> str:
    names = [m for m in _methods(methods) if m in NO_K]
    return f"; {' and '.join(names)}: no k" if names else ""


def by_month(results: pd.DataFrame, path: Path, scored: Scored | None = None) -> Path | None:
    """Held-out RMSE by month, one row of panels per k and one column per held-out spindle
    speed: the month alone hardly moves the error, the speed of the held-out run and k do,
    so a single k = 2 panel pooled over speeds looked flat and hid what varies. Methods
    without a k (ridge, oracle) are repeated in every row, as the title says."""
    scored = scored or Scored(results)
    rows = _rows(scored, "measured")
    if not len(rows):
        return None
    by_speed = "test_speed_rpm" in scored.frame
    boxes = scored.values_by(["k", "test_speed_rpm", "method", "test_month"] if by_speed
                             else ["k", "method", "test_month"], rows)
    if not by_speed:  # one column of panels: every run at speed None
        boxes = {(k, None, *rest): values for (k, *rest), values in boxes.items()}
    ks = sorted({k for k, *_ in boxes if k is not None}) or [None]
    speeds = sorted({float(speed) for _, speed, _, _ in boxes}) if by_speed else [None]
    months = [m for m in MONTHS if m in {month for *_, month in boxes}]
    all_methods = {method for _, _, method, _ in boxes}
    fig = Figure(figsize=(max(5.0, 0.22 * len(_methods(all_methods)) * len(months) + 1.5)
                          * len(speeds), 3.3 * len(ks) + 0.6), layout="constrained")
    axes = fig.subplots(len(ks), len(speeds), squeeze=False, sharey=True)
    for row, k in enumerate(ks):
        for column, speed in enumerate(speeds):
            at = {(method, month): values for (kk, sp, method, month), values in boxes.items()
                  if (k is None or kk in (k, None)) and (speed is None or sp == speed)}
            ax = axes[row, column]
            _grouped_boxes(ax, at, months, _methods(method for method, _ in at))
            where = [f"k = {k}" if k is not None else "", f"held-out runs at {speed:g} rpm"
                     if speed is not None else "all held-out runs"]
            ax.set_title(", ".join(w for w in where if w), fontsize=10)
            if column:
                ax.set_ylabel("")
    top, clipped = _clipped_top(scored.frame["rmse_um"].iloc[rows])
    axes[0, 0].set_ylim(0, top)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, ncols=len(labels), loc="outside lower center",
               frameon=False)  # outside: inside, it hid the tallest boxes
    note = f"; {clipped} of {len(rows)} values above {top:.0f} µm not shown" if clipped else ""
    fig.suptitle(f"Held-out RMSE by month of the held-out run (measured"
                 f"{_no_k_note(all_methods)}, repeated in every row{note})", fontsize=11)
    return _save(fig, path)


def by_condition(results: pd.DataFrame, path: Path, k: int, scored: Scored | None = None
                 ) -> Path | None:
    scored = scored or Scored(results)
    rows = _rows(scored, "measured")
    rows = rows[np.isin(scored.codes("k")[rows], [k, NO_K_KEY])]
    if not len(rows):
        return None
    boxes = {(method, f"{noise} / {fault}"): values for (method, noise, fault), values in
             scored.values_by(["method", "noise", "fault"], rows).items()}
    # the conditions in the order they come, as the table lists them
    conditions = [f"{scored.label('noise', n)} / {scored.label('fault', f)}" for n, f in
                  scored.reduced(["noise", "fault"], "size", rows, sort=False).index]
    methods = _methods(method for method, _ in boxes)
    fig = Figure(figsize=(max(6.0, 1.8 * len(conditions)), 4.2))
    ax = fig.subplots()
    _grouped_boxes(ax, boxes, conditions, methods)
    ax.set_title(f"Held-out RMSE by measurement condition (noise / fault, k = {k}"
                 f"{_no_k_note(methods)})")
    ax.legend(fontsize=8, ncols=3)
    return _save(fig, path)


def box_plots(results: pd.DataFrame, folder: Path, scored: Scored | None = None
              ) -> dict[str, Path]:
    """Write every figure into ``folder``; return name → path of those that have data.
    ``scored``: the results' coded rows when the summary already made them."""
    scored = scored or Scored(results)
    figures: dict[str, Path | None] = {}
    ks = sorted(int(k) for k in results["k"].dropna().unique())
    figures["by_method"] = by_method_and_k(results, folder / "rmse_by_method.png", scored)
    if ks:
        figures["by_month"] = by_month(results, folder / "rmse_by_month.png", scored)
        figures["by_condition"] = by_condition(results, folder / "rmse_by_condition.png",
                                               ks[0], scored)
    return {name: path for name, path in figures.items() if path is not None}
