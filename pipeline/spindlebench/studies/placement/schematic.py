"""A side view of the vertical machining centre with its temperature-field nodes.

The drawing is a schematic, not to scale: Y runs horizontally (operator at the left, column at
the rear), Z vertically, X points out of the page. Each node of the model is put on the part
its name says (``docs/contracts.md``: ``node_<part>_C``; a discretised part's nodes are
``<part>_1`` … ``<part>_n`` along the axis the model documents, e.g. ``spindle_shaft_1`` at the
nose, ``column_1`` at the bed face). Nodes the drawing does not know are listed in a strip
beneath it, so a model with new parts still gets a complete drawing.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.patches import FancyArrowPatch, Rectangle

from spindlebench.core.atomic import atomic_path
from spindlebench.studies.placement.placement_file import PlacementStudy
from spindlebench.studies.placement.placements import Placement

#: Outline of each part: (y0, z0, width, height, colour, label, label above the box?).
PARTS = {
    "floor_slab": (-0.35, -0.40, 2.90, 0.30, "#d9d4c7", "floor slab", False),
    "bed": (-0.05, 0.0, 2.25, 0.50, "#b8c4d6", "bed", False),
    "column": (1.62, 0.50, 0.55, 2.15, "#b8c4d6", "column", False),
    "housing": (0.58, 1.40, 1.04, 1.00, "#c9d6b8", "headstock", False),
    "table": (0.20, 0.50, 1.20, 0.55, "#d6c4b8", "saddle + table", False),
    "spindle_motor": (1.18, 2.40, 0.36, 0.30, "#e3c08f", "spindle motor", True),
    "drawbar_cylinder": (0.75, 2.40, 0.20, 0.18, "#e3c08f", "drawbar cyl.", True),
    "x_motor": (-0.02, 0.62, 0.20, 0.20, "#e3c08f", "X motor", True),
    "y_motor": (-0.32, 0.30, 0.22, 0.20, "#e3c08f", "Y motor", True),
}

#: Axis of each discretised part: node 1 at ``start``, node n at ``end`` (y, z).
SEGMENTED = {
    "spindle_shaft": ((0.85, 1.22), (0.85, 2.34)),  # nose -> drawbar end
    "housing": ((1.50, 1.47), (1.50, 2.33)),  # front bearing seat -> top
    "column": ((1.90, 0.62), (1.90, 2.55)),  # bed face -> top
    "bed": ((0.05, 0.22), (2.08, 0.22)),  # front -> rear under the column
    "table": ((0.80, 0.55), (1.36, 1.00)),  # saddle underside -> table top (drawn slanted)
}

#: Lumped nodes: (y, z).
LUMPED = {
    "front_bearing": (0.98, 1.50),
    "front_cap": (1.08, 1.43),
    "tool": (0.85, 1.13),
    "fixture": (0.85, 1.01),
    "z_nut": (1.66, 1.75),
    "z_screw": (1.72, 2.05),
    "z_bearing_seat": (1.72, 2.50),
    "z_motor": (1.82, 2.60),
    "rear_bearing": (0.98, 2.15),
    "inner_cavity": (1.15, 1.85),
    "drawbar_cylinder": (0.85, 2.49),
    "spindle_motor": (1.36, 2.55),
    "x_motor": (0.08, 0.72),
    "x_bearing_seat": (0.28, 0.72),
    "x_screw": (0.48, 0.72),
    "x_nut": (0.68, 0.72),
    "y_motor": (-0.21, 0.40),
    "y_screw": (0.55, 0.42),
    "y_nut": (0.90, 0.45),
    "y_bearing_seat": (1.45, 0.42),
    "floor_slab": (1.10, -0.25),
}

#: Parts whose node labels go to the left of the dot (the right side is crowded).
LABEL_LEFT = ("spindle_shaft",)
#: Node labels nudged off their default spot (dy, dz from the dot, text to the right): the X
#: drive's four nodes sit 0.2 apart, closer than their names are long, so they alternate
#: above and below; the labels of the Y screw nodes sit above its dashed line; the Y motor's
#: stays inside its box.
LABEL_NUDGE = {"x_motor": (-0.01, 0.05), "x_bearing_seat": (0.0, -0.05),
               "x_screw": (0.0, 0.05), "x_nut": (0.0, -0.05),
               "y_screw": (0.0, 0.045), "y_bearing_seat": (0.0, 0.045),
               "y_motor": (-0.075, -0.05), "z_nut": (0.10, -0.02)}
#: Part labels moved off the top-left corner where something is drawn over them (the
#: spindle and its node labels cover the headstock's corner): (y, z) of the label.
PART_LABEL_AT = {"housing": (0.97, 2.38)}

_INDEXED = re.compile(r"^(?P<part>.+)_(?P<index>\d+)$")
METHOD_COLOURS = {"fuzzy": "#d9622b", "greedy": "#2b7bd9", "exhaustive": "#2a9d52"}
#: Colours of the other methods (``kmeans+grey``, ``lasso``, ...), in the study's order,
#: each apart from the three above and from each other (every such method was "purple": two
#: identical purples in one legend).
OTHER_COLOURS = ("#7b3fa0", "#b8860b", "#17a2b8", "#d63384", "#6c757d", "#8c564b",
                 "#9acd32", "#000000")


def method_colour(method: str, methods: Sequence[str]) -> str:
    """The colour of ``method`` among the study's ``methods`` (one home for both figures)."""
    if method in METHOD_COLOURS:
        return METHOD_COLOURS[method]
    others = [m for m in dict.fromkeys(methods) if m not in METHOD_COLOURS]
    index = others.index(method) if method in others else len(others)
    return OTHER_COLOURS[index % len(OTHER_COLOURS)]


def node_positions(nodes: Sequence[str]) -> tuple[dict[str, tuple[float, float]], list[str]]:
    """Drawing position of every known node, and the nodes the drawing does not know."""
    counts: dict[str, int] = {}
    for node in nodes:
        match = _INDEXED.match(node)
        if match and match["part"] in SEGMENTED:
            counts[match["part"]] = max(counts.get(match["part"], 0), int(match["index"]))
    positions: dict[str, tuple[float, float]] = {}
    unknown: list[str] = []
    for node in nodes:
        match = _INDEXED.match(node)
        if match and match["part"] in SEGMENTED:
            (y0, z0), (y1, z1) = SEGMENTED[match["part"]]
            n = counts[match["part"]]
            f = (int(match["index"]) - 1) / (n - 1) if n > 1 else 0.5
            positions[node] = (y0 + f * (y1 - y0), z0 + f * (z1 - z0))
        elif node in LUMPED:
            positions[node] = LUMPED[node]
        else:
            unknown.append(node)
    for i, node in enumerate(unknown):  # a strip beneath the floor
        positions[node] = (-0.2 + 0.35 * (i % 8), -0.65 - 0.18 * (i // 8))
    return positions, unknown


def draw_machine(ax: plt.Axes, nodes: Sequence[str], labels: bool = False) -> dict[str, tuple]:
    """The machine outline, axes and every node as a grey dot; returns the node positions."""
    for part, (y, z, w, h, colour, label, above) in PARTS.items():
        ax.add_patch(Rectangle((y, z), w, h, facecolor=colour, edgecolor="#555555", lw=0.8,
                               alpha=0.7, zorder=1))
        if above:
            ax.text(y, z + h + 0.02, label, fontsize=6, va="bottom", color="#333333", zorder=2)
        else:
            at = PART_LABEL_AT.get(part, (y + 0.02, z + h - 0.02))
            ax.text(*at, label, fontsize=6, va="top", color="#333333", zorder=2)
    ax.add_patch(Rectangle((0.75, 1.22), 0.20, 1.18, facecolor="#9fb0c0", edgecolor="#555555",
                           lw=0.6, zorder=1.5))  # spindle in the headstock
    ax.plot([0.85, 0.85], [1.22, 1.10], color="#333333", lw=2.5, zorder=2)  # tool
    ax.add_patch(Rectangle((0.60, 1.05), 0.50, 0.05, facecolor="#8f8f8f", zorder=1.5))
    ax.plot([-0.05, 1.45], [0.42, 0.42], color="#777777", lw=1.0, ls="--", zorder=1.5)
    ax.plot([0.08, 0.68], [0.72, 0.72], color="#777777", lw=1.0, ls="--", zorder=1.5)
    for start, end, text in (((-0.25, 1.55), (0.15, 1.55), "Y"), ((-0.25, 1.55),
                                                                   (-0.25, 1.95), "Z")):
        ax.add_patch(FancyArrowPatch(start, end, arrowstyle="-|>", mutation_scale=10,
                                     color="black", zorder=3))
        ax.text(end[0] + 0.03, end[1] + 0.03, text, fontsize=8, zorder=3)
    ax.plot([-0.25], [1.55], marker="o", mfc="white", mec="black", ms=7, zorder=4)
    ax.plot([-0.25], [1.55], marker=".", color="black", ms=4, zorder=5)
    ax.text(-0.21, 1.45, "X (out of page)", fontsize=6, zorder=3)
    # an arrow between fixed points, not ax.annotate's: the annotation's arrow (clipped at
    # its text's box) came out one or two pixels apart from one process to the next
    ax.add_patch(FancyArrowPatch((0.53, 1.14), (0.85, 1.10), arrowstyle="->",
                                 mutation_scale=6, lw=0.6, color="black", zorder=3))
    ax.text(0.35, 1.13, "drift", fontsize=6, zorder=3)
    positions, _ = node_positions(nodes)
    pts = np.array([positions[n] for n in nodes])
    ax.scatter(pts[:, 0], pts[:, 1], s=7, color="#555555", zorder=4, lw=0)
    if labels:
        for node in nodes:
            y, z = positions[node]
            left = any(node.startswith(f"{part}_") for part in LABEL_LEFT)
            if node in LABEL_NUDGE:
                dy, dz = LABEL_NUDGE[node]
                ax.text(y + dy, z + dz, node, fontsize=4.5, va="center", ha="left", zorder=5)
            else:
                ax.text(y - 0.025 if left else y + 0.025, z, node, fontsize=4.5,
                        va="center", ha="right" if left else "left", zorder=5)
    low = min(-0.45, float(pts[:, 1].min()) - 0.1)
    ax.set_xlim(-0.45, 2.65)
    ax.set_ylim(low, 2.85)
    ax.set_aspect("equal")
    ax.axis("off")
    return positions


#: Markers closer than this (drawing units) are spread around their centre so none hides
#: another; the spread puts each at ``MARKER_SPREAD`` from the centre.
MARKER_CLEARANCE = 0.09
MARKER_SPREAD = 0.075


def spread_markers(points: Sequence[tuple[float, float]],
                   clearance: float = MARKER_CLEARANCE,
                   radius: float = MARKER_SPREAD) -> list[tuple[float, float]]:
    """Marker positions where points closer than ``clearance`` (chained) are put on a small
    circle around their common centre, in input order; lone points stay where they are."""
    pts = np.asarray(points, float).reshape(-1, 2)
    group = list(range(len(pts)))

    def root(i: int) -> int:
        while group[i] != i:
            i = group[i]
        return i

    for i in range(len(pts)):
        for j in range(i):
            if np.hypot(*(pts[i] - pts[j])) < clearance:
                group[root(i)] = root(j)
    placed = pts.copy()
    for r in {root(i) for i in range(len(pts))}:
        members = [i for i in range(len(pts)) if root(i) == r]
        if len(members) < 2:
            continue
        centre = pts[members].mean(axis=0)
        for k, i in enumerate(members):
            angle = np.pi / 2 + 2 * np.pi * k / len(members)
            placed[i] = centre + radius * np.array([np.cos(angle), np.sin(angle)])
    return [tuple(p) for p in placed]


def draw_placement(ax: plt.Axes, nodes: Sequence[str], placement: Placement,
                   colour: str) -> None:
    """Chosen sensors as numbered markers: a node filled, a difference A-B as ``n+`` at A
    (filled) and ``n−`` at B (hollow). No line joins the two ends of a difference: across
    the machine it crossed every other marker. Markers that would overlap are spread."""
    positions = draw_machine(ax, nodes)
    markers: list[tuple[tuple[float, float], str, bool]] = []  # (node position, text, filled)
    for number, variable in enumerate(placement.variables, start=1):
        if variable in positions:
            markers.append((positions[variable], str(number), True))
        else:
            first, second = variable.split("-")
            markers.append((positions[first], f"{number}+", True))
            markers.append((positions[second], f"{number}−", False))
    spread = spread_markers([at for at, _, _ in markers])
    for (node_at, text, filled), (y, z) in zip(markers, spread, strict=True):
        if (y, z) != tuple(node_at):  # a thin tick from the marker to its node
            ax.plot([node_at[0], y], [node_at[1], z], color="#333333", lw=0.5, zorder=5)
        ax.scatter([y], [z], s=95, color=colour if filled else "white", edgecolor=colour
                   if not filled else "black", lw=1.4 if not filled else 0.6, zorder=6)
        ax.text(y, z, text, fontsize=5.5, ha="center", va="center", fontweight="bold",
                color="white" if filled else colour, zorder=7)


def placement_legend(fig: plt.Figure, methods: Sequence[str]) -> None:
    """What the colours and markers mean, once for the whole figure."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], ls="", marker="o", ms=8, color=method_colour(m, methods),
                      mec="black", label=m) for m in dict.fromkeys(methods)]
    grey = "#555555"
    handles += [
        Line2D([], [], ls="", marker="o", ms=8, color=grey, mec="black",
               label="n: the n-th chosen node"),
        Line2D([], [], ls="", marker="o", ms=8, color="white", mec=grey, mew=1.4,
               label="n+ / n−: a difference, node n+ minus node n−"),
        Line2D([], [], ls="", marker="o", ms=3, color=grey, label="model node (candidate)"),
    ]
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles), fontsize=7,
               frameon=False)


def _save(fig: plt.Figure, path: Path) -> Path:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=130, bbox_inches="tight", format="png")
    plt.close(fig)
    return path


def nodes_figure(nodes: Sequence[str], path: Path) -> Path:
    """Every candidate node, labelled: the map the placement figures refer to."""
    fig, ax = plt.subplots(figsize=(9, 7.5))
    draw_machine(ax, nodes, labels=True)
    ax.set_title(f"Candidate sensor locations: the model's {len(nodes)} temperature nodes "
                 "(side view, schematic)", fontsize=9)
    return _save(fig, path)


def budget_figure(nodes: Sequence[str], placements: Sequence[Placement], table: pd.DataFrame,
                  budget: int, path: Path) -> Path | None:
    """One panel per method (and candidate set) for budget ``budget``.

    Each panel is a drawing with its variable list in a strip of its own beneath it, so the
    list cannot run into the next row's title; the figure is sized to the drawing's aspect,
    so no empty band is left around the equal-aspect drawings.
    """
    chosen = [p for p in placements if p.budget == budget and p.found]
    if not chosen:
        return None
    cols = min(3, len(chosen))
    rows = -(-len(chosen) // cols)
    lines = max(len(p.variables) for p in chosen)
    drawing_h, listing_h, width = 4.5, 0.16 + 0.105 * lines, 4.2
    fig = plt.figure(figsize=(width * cols, rows * (drawing_h + listing_h) + 0.35),
                     layout="constrained")
    grid = fig.add_gridspec(2 * rows, cols,
                            height_ratios=[drawing_h, listing_h] * rows)
    for i, placement in enumerate(chosen):
        row, col = divmod(i, cols)
        ax = fig.add_subplot(grid[2 * row, col])
        draw_placement(ax, nodes, placement,
                       method_colour(placement.method, [p.method for p in placements]))
        found = table[(table["label"] == placement.label) & (table["m"] == budget)]
        rmse = found["test_mean_rmse_um"].iloc[0] if len(found) else float("nan")
        ax.set_title(f"{placement.label}, m = {budget}: test RMSE {rmse:.2f} µm", fontsize=8)
        strip = fig.add_subplot(grid[2 * row + 1, col])
        strip.axis("off")
        listing = "\n".join(f"{n}: {v.replace('-', ' − ')}" for n, v in
                            enumerate(placement.variables, start=1))
        strip.text(0.02, 1.0, listing, fontsize=6, ha="left", va="top", family="monospace",
                   transform=strip.transAxes)
    fig.suptitle(f"Sensor placements for a budget of m = {budget} (colour: method; number: "
                 "order in the model; test RMSE on the held-out days)", fontsize=9)
    placement_legend(fig, [p.method for p in chosen])
    return _save(fig, path)


def placement_figures(study: PlacementStudy, placements: Sequence[Placement],
                      table: pd.DataFrame, folder: Path) -> dict[str, Path]:
    """The node map and one figure per budget; name → path of each written figure."""
    figures = {"nodes": nodes_figure(study.nodes, folder / "nodes.png")}
    for budget in study.budgets:
        path = budget_figure(study.nodes, placements, table, budget,
                             folder / f"placement_m{budget}.png")
        if path is not None:
            figures[f"m{budget}"] = path
    return figures
