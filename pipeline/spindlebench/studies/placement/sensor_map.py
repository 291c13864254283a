"""The sensor map: where the paper's T1–T20 sit on the machine, in a front and a side view.

The side view is the placement study's schematic (``schematic.draw_machine``, every node of
the temperature field as a grey dot); the front view is drawn here in the same coordinates
(X horizontal, Z up). Each sensor is a marker in its part's colour family
(``testbench.sensor_parts``) next to the model node its probe is connected to. Both views are
schematics, not to scale. ``docs/figures/sensor_map.png`` is drawn by::

    python -m spindlebench.studies.placement.sensor_map docs/figures/sensor_map.png
"""

from __future__ import annotations

import re
import sys
from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import FancyArrowPatch, Rectangle

from spindlebench.core.atomic import atomic_path
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import MODELS_DIR
from spindlebench.studies.placement.schematic import LUMPED, SEGMENTED, draw_machine
from spindlebench.testbench.sensor_parts import AMBIENT_SENSOR, LOCATIONS, PARTS, sensor_colours


def port_fractions(part: str, source: str | None = None) -> dict[str, float]:
    """Where the ports of a segmented part sit along its axis, read from the model source:
    ``port_a`` at 0, ``port_b`` at 1, ``port_k`` at the part's ``xk`` modifier (the default
    0.5 of ``SegmentedSolid`` where the model does not set it)."""
    if source is None:
        source = (MODELS_DIR / "SpindleBench.mo").read_text(encoding="utf-8")
    match = re.search(rf"SegmentedSolid\s+{part}\s*\((.*?)\)\s*\"", source, re.S)
    if match is None:
        raise SpindlebenchError(f"{MODELS_DIR / 'SpindleBench.mo'}: no SegmentedSolid {part}")
    fractions = {"port_a": 0.0, "port_b": 1.0}
    for k in (1, 2, 3):
        value = re.search(rf"\bx{k}\s*=\s*([0-9.eE+-]+)", match[1])
        fractions[f"port_{k}"] = float(value[1]) if value else 0.5
    return fractions

#: Offset (dy, dz) of each sensor marker from its node in the side view, so several probes on
#: one node (T1, T3, T5 on the front bearing) stay apart; T10 is in the air by the column.
SIDE_OFFSET = {
    "T1": (0.0, -0.16), "T3": (0.13, -0.06), "T5": (0.10, 0.10), "T2": (0.0, 0.0),
    "T4": (0.0, 0.0), "T6": (0.0, 0.0), "T9": (0.05, 0.0), "T7": (0.0, 0.0), "T8": (0.0, 0.0),
    "T11": (0.0, 0.0), "T12": (0.0, 0.09), "T14": (0.0, -0.09), "T13": (0.0, 0.09),
    "T15": (0.0, -0.09), "T16": (0.0, 0.07), "T17": (0.15, 0.0), "T18": (0.0, 0.08),
    "T19": (0.0, -0.08), "T20": (0.0, 0.0),
}
AMBIENT_SIDE = (2.35, 1.80)

#: Front view (X horizontal, Z up): part outlines (x0, z0, width, height, colour, label) …
FRONT_PARTS = (
    (-1.30, -0.40, 2.60, 0.30, "#d9d4c7", "floor slab"),
    (-1.20, 0.0, 2.40, 0.50, "#b8c4d6", "bed"),
    (-0.50, 0.50, 1.00, 2.15, "#b8c4d6", ""),
    (-0.45, 0.50, 0.90, 0.25, "#d6c4b8", ""),
    (-0.90, 0.75, 1.80, 0.30, "#d6c4b8", "saddle + table"),
    (-0.40, 1.40, 0.80, 1.00, "#c9d6b8", "headstock"),
    (0.12, 2.40, 0.36, 0.30, "#e3c08f", "spindle motor"),
    (-0.10, 2.40, 0.20, 0.18, "#e3c08f", "drawbar"),
    (0.95, 0.62, 0.22, 0.20, "#e3c08f", "X motor"),
    (-0.12, 0.30, 0.24, 0.20, "#e3c08f", "Y motor"),
)
#: … and sensor positions (x, z): Z as in the side view, X where the part is seen from the front.
FRONT = {
    "T1": (-0.17, 1.34), "T3": (0.17, 1.34), "T5": (0.15, 1.55), "T2": (-0.30, 1.47),
    "T4": (-0.40, 1.66), "T6": (0.40, 1.90), "T9": (-0.17, 1.85), "T7": (0.0, 2.49),
    "T8": (0.30, 2.55), "T10": (0.68, 1.80),
    "T11": (0.76, 0.72), "T12": (-0.10, 0.84), "T14": (0.10, 0.84), "T13": (1.06, 0.72),
    "T15": (0.92, 0.72), "T16": (-0.065, 0.39), "T17": (0.065, 0.39), "T18": (-0.45, 0.40),
    "T19": (-0.30, 0.40), "T20": (0.45, 0.40),
}


def side_positions() -> dict[str, tuple[float, float]]:
    """Side-view position of every sensor: its model node's place on the schematic, nudged."""
    positions = {}
    fractions: dict[str, dict[str, float]] = {}
    for sensor, (node, _) in LOCATIONS.items():
        if sensor == AMBIENT_SENSOR:
            positions[sensor] = AMBIENT_SIDE
            continue
        part, _, port = node.partition(".")
        if port:
            (y0, z0), (y1, z1) = SEGMENTED[part]
            f = fractions.setdefault(part, port_fractions(part))[port]
            y, z = y0 + f * (y1 - y0), z0 + f * (z1 - z0)
        else:
            y, z = LUMPED[part]
        dy, dz = SIDE_OFFSET.get(sensor, (0.0, 0.0))
        positions[sensor] = (y + dy, z + dz)
    return positions


def _colours() -> dict[str, tuple]:
    colours: dict[str, tuple] = {}
    for part in PARTS:
        colours.update(sensor_colours(part))
    colours[AMBIENT_SENSOR] = (0.15, 0.15, 0.15, 1.0)
    return colours


def _markers(ax: Axes, positions: Mapping[str, tuple[float, float]]) -> None:
    colours = _colours()
    for sensor, (u, z) in positions.items():
        ax.scatter([u], [z], s=150, color=colours[sensor], edgecolor="black", lw=0.6,
                   zorder=6)
        ax.text(u, z, sensor[1:], fontsize=6, ha="center", va="center", color="white",
                fontweight="bold", zorder=7)


def draw_front(ax: Axes) -> None:
    """The machine seen by the operator: X horizontal, Z up, the column behind."""
    for x, z, w, h, colour, label in FRONT_PARTS:
        ax.add_patch(Rectangle((x, z), w, h, facecolor=colour, edgecolor="#555555", lw=0.8,
                               alpha=0.7, zorder=1))
        if label:
            above = label in ("spindle motor", "drawbar", "X motor", "Y motor")
            ax.text(x + 0.02, z + h + 0.02 if above else z + h - 0.02, label, fontsize=6,
                    va="bottom" if above else "top", color="#333333", zorder=2)
    ax.add_patch(Rectangle((-0.10, 1.22), 0.20, 1.18, facecolor="#9fb0c0", edgecolor="#555555",
                           lw=0.6, zorder=1.5))  # spindle
    ax.plot([0.0, 0.0], [1.22, 1.10], color="#333333", lw=2.5, zorder=2)  # tool
    ax.text(-0.48, 1.16, "column (behind)", fontsize=6, va="center", color="#333333", zorder=2)
    ax.plot([-0.85, 0.95], [0.72, 0.72], color="#777777", lw=1.0, ls="--", zorder=1.5)
    ax.text(-0.85, 0.66, "X screw", fontsize=5.5, color="#555555", va="top", zorder=2)
    ax.text(-0.62, 0.30, "Y screw (into the page)", fontsize=5.5, color="#555555", zorder=2)
    for start, end, text in (((-1.15, 1.55), (-0.75, 1.55), "X"), ((-1.15, 1.55),
                                                                   (-1.15, 1.95), "Z")):
        ax.add_patch(FancyArrowPatch(start, end, arrowstyle="-|>", mutation_scale=10,
                                     color="black", zorder=3))
        ax.text(end[0] + 0.03, end[1] + 0.03, text, fontsize=8, zorder=3)
    ax.set_xlim(-1.35, 1.35)
    ax.set_ylim(-0.45, 2.85)
    ax.set_aspect("equal")
    ax.axis("off")


def sensor_map_figure(nodes: list[str]) -> Figure:
    """Front view, side view with the model's nodes, and the list of sensors by part."""
    fig = plt.figure(figsize=(12, 6.6), layout="constrained")
    grid = fig.add_gridspec(2, 2, height_ratios=[5.0, 1.25], width_ratios=[1.0, 1.15])
    front, side = fig.add_subplot(grid[0, 0]), fig.add_subplot(grid[0, 1])
    draw_front(front)
    _markers(front, FRONT)
    front.set_title("front view (operator's side)", fontsize=9)
    draw_machine(side, nodes)
    _markers(side, side_positions())
    side.set_title("side view: grey dots are the model's temperature nodes", fontsize=9)
    listing = fig.add_subplot(grid[1, :])
    listing.axis("off")
    colours = _colours()
    for column, part in enumerate(PARTS):
        listing.text(column / len(PARTS), 1.0, part.name, fontsize=8, fontweight="bold",
                     color=colours[part.sensors[-1]], va="top", transform=listing.transAxes)
        for row, sensor in enumerate(part.sensors, start=1):
            listing.text(column / len(PARTS), 1.0 - 0.17 * row,
                         f"{sensor}: {LOCATIONS[sensor][1]}", fontsize=6.5, va="top",
                         color="#222222", transform=listing.transAxes)
    fig.suptitle("Where the paper's 20 temperature sensors sit on the synthetic machine "
                 "(schematic, not to scale)", fontsize=10)
    return fig


def write_sensor_map(path: str | Path, nodes: list[str] | None = None) -> Path:
    """Draw the sensor map into ``path`` atomically; ``nodes`` default to the FMU's."""
    if nodes is None:
        from spindlebench.core.paths import DEFAULT_FMU
        from spindlebench.studies.placement.placement_file import fmu_nodes

        nodes = fmu_nodes(DEFAULT_FMU)
    fig = sensor_map_figure(nodes)
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=130, format="png")
    finally:
        plt.close(fig)
    return Path(path)


if __name__ == "__main__":
    target = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("docs/figures/sensor_map.png")
    print(write_sensor_map(target))
