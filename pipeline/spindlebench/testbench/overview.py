"""One-page picture of one or more recordings: temperatures, thermal error and inputs.

The first thing a student or an engineer looks at when a run comes out of the testbench
(``spindlebench plot``, ``spindlebench simulate --plot``). Twenty sensors in one panel are
a tangle, so the sensors are grouped by machine part (``testbench.sensor_parts``): the
spindle and headstock in one panel, the feed axes and the air in the next, each part in one
colour family, and every line is named at its right end instead of in a legend. Columns the
part table does not know (a real recording's ``t1_C`` …) get a panel of their own. Each
recording is one column of panels; rows share their y axis so recordings compare at a glance.

``docs/figures/exp1_overview.png`` is this figure of ``scenarios/paper/exp1.toml``::

    spindlebench simulate scenarios/paper/exp1.toml -o results/paper/exp1.csv
    spindlebench plot results/paper/exp1.csv -o docs/figures/exp1_overview.png \
        --title "Synthetic experiment 1: 4000 rpm, January ambient 5.3-10.4 °C"
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.transforms import offset_copy

from spindlebench.core.atomic import atomic_path
from spindlebench.core.errors import SpindlebenchError, columns_hint
from spindlebench.formats.recording import (
    AMBIENT_COLUMN,
    DRIFT_COLUMN,
    FEED_X_COLUMN,
    FEED_Y_COLUMN,
    SPEED_COLUMN,
    TIME_COLUMN,
    default_sensors,
    recording_name,
    true_column,
)
from spindlebench.testbench.sensor_parts import (
    AMBIENT_SENSOR,
    PARTS,
    part_colour,
    part_of,
    sensor_colours,
)

AMBIENT_DRIVER = AMBIENT_COLUMN
SPEED = SPEED_COLUMN
FEEDS = (FEED_X_COLUMN, FEED_Y_COLUMN)
PANEL_TITLES = {"spindle": "spindle and headstock", "axes": "feed axes and ambient air",
                "other": "sensors"}
LABEL_FONTSIZE = 6.5


@dataclass(frozen=True)
class _Panel:
    key: str
    sensors: tuple[str, ...]


def _temperature_panels(frames: Sequence[pd.DataFrame], target: str,
                        chosen: Sequence[Sequence[str]] | None = None) -> list[_Panel]:
    """The temperature panels every recording shares, in the order of the part table;
    ``chosen``: each frame's sensors (column roles), else ``default_sensors``."""
    sensors: list[str] = []
    for i, frame in enumerate(frames):
        for name in (default_sensors(frame, target) if chosen is None else chosen[i]):
            if name not in sensors:
                sensors.append(name)
    panels = []
    for key in ("spindle", "axes"):
        known = [s for part in PARTS if part.panel == key for s in part.sensors if s in sensors]
        if known:
            panels.append(_Panel(key, tuple(known)))
    other = tuple(s for s in sensors if part_of(s) is None)
    if other:
        panels.append(_Panel("other", other))
    return panels


def _first_finite(values: np.ndarray) -> float:
    finite = values[np.isfinite(values)]
    return float(finite[0]) if finite.size else float("nan")


def _colours(sensors: Sequence[str]) -> dict[str, tuple]:
    colours: dict[str, tuple] = {}
    for part in PARTS:
        colours.update(sensor_colours(part))
    unknown = [s for s in sensors if s not in colours]
    cmap = matplotlib.colormaps["viridis"]
    for i, name in enumerate(unknown):
        colours[name] = cmap(0.9 * i / max(len(unknown) - 1, 1))
    return colours


def recordings_figure(frames: Sequence[pd.DataFrame], titles: Sequence[str] | None = None, *,
                      rises: bool = False, target: str = DRIFT_COLUMN,
                      suptitle: str | None = None,
                      sensors: Sequence[Sequence[str]] | None = None) -> Figure:
    """Temperature panels by part, the thermal error ``target`` and the inputs, over hours.

    ``sensors`` gives each frame's temperature columns (``plot``'s column roles); without
    it, every column ``default_sensors`` counts.

    ``rises`` draws every temperature (and the ambient driver) as its change since the first
    sample, which shows the shapes that absolute values of different levels hide.
    """
    if not frames:
        raise SpindlebenchError("plot: no recording given")
    for frame in frames:
        if target not in frame.columns:
            raise SpindlebenchError(
                f"recording {recording_name(frame)}: no thermal-error column {target!r} "
                f"({columns_hint(list(map(str, frame.columns)), target)}; choose one with "
                "--target)")
    titles = list(titles) if titles is not None else [recording_name(f) for f in frames]
    panels = _temperature_panels(frames, target, sensors)
    has_inputs = any(SPEED in f or any(c in f for c in FEEDS) for f in frames)
    heights = [3.0] * len(panels) + [1.9] + ([1.4] if has_inputs else [])
    room = label_room_in([s for p in panels for s in p.sensors] + ["ambient air"])
    fig, axes = plt.subplots(len(heights), len(frames), squeeze=False, sharex="col",
                             sharey="row", figsize=(1.3 + (5.05 + room) * len(frames),
                                                    sum(heights) + 1),
                             gridspec_kw={"height_ratios": heights})
    try:
        colours = _colours([s for p in panels for s in p.sensors])
        # the input rows share their y axis: scale it to the fastest spindle of all columns
        speed_top = max([float(np.nanmax(f[SPEED])) for f in frames if SPEED in f] + [1.0])
        for column, (frame, title) in enumerate(zip(frames, titles, strict=True)):
            _draw_column(frame, axes[:, column], panels, colours, rises, target,
                         speed_top if has_inputs else None)
            # a line above the panel label (as a centre title it sat on the label's line)
            top = axes[0, column]
            top.text(0.5, 1.0, title, ha="center", va="bottom", fontsize=10,
                     transform=offset_copy(top.transAxes, fig=fig, y=17, units="points"))
        for row, panel in enumerate(panels):
            axes[row, 0].set_ylabel("rise since start (K)" if rises else "temperature (°C)")
            _part_legend(axes[row, 0], panel)
        axes[len(panels), 0].set_ylabel("drift (µm)" if target == DRIFT_COLUMN else
                                        f"{target.removesuffix('_um')} (µm)"
                                        if target.endswith("_um") else target)
        for ax in axes[-1, :]:
            ax.set_xlabel("time (h)")
        if suptitle:
            fig.suptitle(suptitle)
        fig.tight_layout()
        fit_label_room(fig, len(frames), room)
        for ax in axes[:len(panels), :].flat:
            label_line_ends(ax)
    except BaseException:
        plt.close(fig)
        raise
    return fig


#: Inches a line-end label's character takes at ``LABEL_FONTSIZE`` (DejaVu Sans averages
#: about 0.6 em), the leader before it, and the tick labels of the next column.
_CHAR_IN = 0.62 * LABEL_FONTSIZE / 72.0
_LEADER_IN = 0.2
_TICKS_IN = 0.5


def label_room_in(labels: Sequence[str]) -> float:
    """Inches right of a column its longest line-end label needs (``Spindle front [degC]``
    was clipped by the next column or the figure's edge: the room was a fixed 0.55 in)."""
    return _LEADER_IN + _CHAR_IN * max((len(str(label)) for label in labels), default=4)


def fit_label_room(fig: Figure, columns: int, room_in: float) -> None:
    """Leave ``room_in`` right of every column (and the next column's ticks after it)."""
    width_in = fig.get_figwidth()
    left = fig.subplotpars.left
    right = min(fig.subplotpars.right, 1 - room_in / width_in)
    gap_in = room_in + _TICKS_IN
    axes_in = ((right - left) * width_in - (columns - 1) * gap_in) / columns
    fig.subplots_adjust(right=right, wspace=gap_in / max(axes_in, 0.5) if columns > 1
                        else fig.subplotpars.wspace)


def _draw_column(frame: pd.DataFrame, axes: np.ndarray, panels: Sequence[_Panel],
                 colours: dict[str, tuple], rises: bool, target: str,
                 speed_top: float | None) -> None:
    """One recording's panels; ``speed_top`` is the input row's rpm scale (None: no row)."""
    hours = frame[TIME_COLUMN].to_numpy(float) / 3600.0

    def values(name: str) -> np.ndarray:
        data = frame[name].to_numpy(float)
        return data - _first_finite(data) if rises else data

    for ax, panel in zip(axes, panels, strict=False):
        ax.set_title(PANEL_TITLES[panel.key], fontsize=8, loc="left", color="0.3")
        if panel.key == "axes" and AMBIENT_DRIVER in frame:  # a wide grey band under T10
            ax.plot(hours, values(AMBIENT_DRIVER), color="0.6", lw=4, alpha=0.5, zorder=1,
                    gid=END_LABEL, label="ambient air")
        for i, name in enumerate(panel.sensors):
            if name not in frame:
                continue
            ambient = name == AMBIENT_SENSOR
            ax.plot(hours, values(name), color="black" if ambient else colours[name],
                    lw=1.1, ls="--" if ambient or i % 2 else "-", label=name, gid=END_LABEL)
        ax.grid(alpha=0.3)
    error = axes[len(panels)]
    error.plot(hours, frame[target], lw=1.2, color="tab:brown", label="measured")
    truth = true_column(DRIFT_COLUMN)
    if target == DRIFT_COLUMN and truth in frame:
        true = frame[truth] - frame[truth].iloc[0]
        error.plot(hours, true, "k--", lw=0.9, label="noise-free")
    error.set_title("thermal error: axial drift, tool towards table, since the start"
                    if target == DRIFT_COLUMN else f"thermal error {target}",
                    fontsize=8, loc="left", color="0.3")
    error.legend(fontsize=7, loc="upper left")
    error.grid(alpha=0.3)
    if speed_top is not None:
        _draw_inputs(axes[len(panels) + 1], frame, hours, speed_top)


def _draw_inputs(ax: Axes, frame: pd.DataFrame, hours: np.ndarray, speed_top: float) -> None:
    ax.set_title("inputs", fontsize=8, loc="left", color="0.3")
    handles = []
    if SPEED in frame:
        handles += ax.plot(hours, frame[SPEED], color="black", lw=1.1, label="spindle (rpm)")
    ax.set_ylabel("rpm")
    ax.set_ylim(0, speed_top * 1.15)
    ax.grid(alpha=0.3)
    feeds = [c for c in FEEDS if c in frame]
    if feeds:
        feed_ax = ax.twinx()
        for name, style in zip(feeds, ("-", ":"), strict=False):
            axis = name.split("_")[1].upper()
            handles += feed_ax.plot(hours, frame[name], color="tab:blue", lw=1, ls=style,
                                    label=f"{axis} feed (mm/min)")
        feed_ax.set_ylabel("mm/min", color="tab:blue")
        fastest = max(max(float(np.nanmax(frame[c])) for c in feeds), 1.0)
        feed_ax.set_ylim(0, fastest * 2.0)  # feeds at mid-height, apart from the speed
    ax.legend(handles=handles, fontsize=6.5, loc="lower right", ncol=len(handles))


def _part_legend(ax: Axes, panel: _Panel) -> None:
    """One entry per part in the panel: its colour family and its sensors."""
    handles = []
    for part in PARTS:
        shown = [s for s in part.sensors if s in panel.sensors]
        if shown:
            # the family's middle shade: the darkest reds and purples looked alike
            shade = "black" if part.sensors == (AMBIENT_SENSOR,) else part_colour(part)
            handles.append(Line2D([], [], color=shade, lw=2,
                                  label=f"{part.name}: {_span(shown)}"))
    if handles:
        ax.legend(handles=handles, fontsize=7, loc="upper left", framealpha=0.85)


def _span(sensors: Sequence[str]) -> str:
    numbers = [int(s[1:]) for s in sensors]
    if numbers == list(range(numbers[0], numbers[-1] + 1)) and len(numbers) > 2:
        return f"T{numbers[0]}–T{numbers[-1]}"
    return ", ".join(sensors)


def spread_labels(wanted: Sequence[float], gap: float, low: float, high: float) -> list[float]:
    """Label positions as close to ``wanted`` as possible, at least ``gap`` apart, kept in
    ``[low, high]`` where there is room: push up from the bottom, then down from the top."""
    order = np.argsort(wanted, kind="stable")
    placed = np.asarray(wanted, float)[order].copy()
    for i in range(len(placed)):
        floor = low if i == 0 else placed[i - 1] + gap
        placed[i] = max(placed[i], floor)
    for i in range(len(placed) - 1, -1, -1):
        ceiling = high if i == len(placed) - 1 else placed[i + 1] - gap
        placed[i] = min(placed[i], ceiling)
    result = np.empty_like(placed)
    result[order] = placed
    return result.tolist()


#: Lines drawn with this ``gid`` are named at their end by ``label_line_ends``.
END_LABEL = "end-label"


def label_line_ends(ax: Axes) -> None:
    """Name each line drawn with ``gid=END_LABEL`` just right of the axes, at the height
    where it ends, joined to its end by a thin leader; labels are spread so none overlap.
    Call it after the axes' limits and the figure layout are final."""
    lines = [line for line in ax.lines if line.get_gid() == END_LABEL]
    ends = []
    for line in lines:
        x, y = (np.asarray(v, float) for v in line.get_data())
        ok = np.isfinite(y)
        if ok.any():
            ends.append((line, float(x[ok][-1]), float(y[ok][-1])))
    if not ends:
        return
    low, high = ax.get_ylim()
    height_in = ax.get_window_extent().height / ax.figure.dpi
    gap = (high - low) * (LABEL_FONTSIZE * 1.25 / 72.0) / max(height_in, 0.1)
    placed = spread_labels([y for _, _, y in ends], gap, low, high)
    for (line, x_end, y_end), y_label in zip(ends, placed, strict=True):
        colour = line.get_color()
        ax.annotate(line.get_label(), xy=(x_end, y_end), xycoords="data",
                    xytext=(1.015, y_label), textcoords=("axes fraction", "data"),
                    fontsize=LABEL_FONTSIZE, color=colour, va="center", ha="left",
                    annotation_clip=False,
                    arrowprops={"arrowstyle": "-", "color": colour, "lw": 0.4,
                                "shrinkA": 0, "shrinkB": 0})


def overview_figure(frame: pd.DataFrame, title: str, *, rises: bool = False) -> Figure:
    """``recordings_figure`` of one recording, ``title`` above it."""
    return recordings_figure([frame], [title], rises=rises)


def save_figure(fig: Figure, out_png: str | os.PathLike[str]) -> None:
    """Write ``fig`` as PNG atomically and close it."""
    try:
        with atomic_path(out_png) as tmp:
            fig.savefig(tmp, format="png", dpi=110)
    finally:
        plt.close(fig)


def plot_recording(frame: pd.DataFrame, out_png: str | os.PathLike[str], title: str,
                   *, rises: bool = False) -> None:
    """Draw ``overview_figure`` into ``out_png`` atomically."""
    save_figure(overview_figure(frame, title, rises=rises), out_png)
