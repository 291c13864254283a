"""Study figures are legible: no label collisions, medians visible, no-k methods drawn once."""

from __future__ import annotations

from pathlib import Path

import matplotlib.colors as mcolors
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import LineCollection
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.studies.placement import schematic
from spindlebench.studies.placement.placement_file import fmu_nodes
from spindlebench.studies.placement.placements import Placement
from spindlebench.studies.sweep import sweep_plots as plots


@pytest.fixture
def kept(monkeypatch):
    """Figures the plotting functions make, kept open instead of saved and closed."""
    figures: list[plt.Figure] = []

    def keep(fig: plt.Figure, path: Path) -> Path:
        figures.append(fig)
        return path

    monkeypatch.setattr(plots, "_save", keep)
    monkeypatch.setattr(schematic, "_save", keep)
    yield figures
    for fig in figures:
        plt.close(fig)


def results() -> pd.DataFrame:
    rng = np.random.default_rng(0)
    rows = []
    for data in ("measured", "noise-free"):
        for method, ks in (("all_raw", [2, 3]), ("six_diff", [2, 3]), ("ridge", [None]),
                           ("oracle", [None])):
            for k in ks:
                for month in ("Jan", "Jul"):
                    for value in rng.uniform(1, 5, 6):
                        rows.append({"data": data, "method": method, "k": k,
                                     "rmse_um": value, "test_month": month,
                                     "noise": "lab", "fault": "none"})
    frame = pd.DataFrame(rows)
    frame["k"] = frame["k"].astype("Int64")
    return frame


def luminance(colour) -> float:
    r, g, b = mcolors.to_rgb(colour)
    return 0.2126 * r + 0.7152 * g + 0.0722 * b


def test_methods_without_k_get_one_panel_and_medians_contrast(kept, tmp_path):
    plots.by_method_and_k(results(), tmp_path / "m.png")
    (fig,) = kept
    titles = [ax.get_title() for ax in fig.axes]
    assert titles == ["k = 2", "k = 3", "no k: ridge, oracle"]
    ticks = [[t.get_text() for t in ax.get_xticklabels()] for ax in fig.axes]
    assert ticks[0] == ticks[1] == ["all_raw", "six_diff"]
    assert ticks[2] == ["ridge", "oracle"]
    assert fig.get_layout_engine() is not None  # titles are not cramped


def test_every_method_colour_shows_on_white_and_under_a_black_median(kept, tmp_path):
    assert mcolors.to_rgb(plots.MEDIAN["color"]) == (0, 0, 0)
    for method in plots.METHOD_ORDER:
        assert 0.25 < luminance(plots.COLOURS[method]) < 0.85, method
    plots.by_month(results(), tmp_path / "month.png")
    assert [ax.get_title() for ax in kept[0].axes] == [
        "k = 2, all held-out runs", "k = 3, all held-out runs"]  # one row per k
    medians = [segment for lines in kept[0].axes[0].collections
               if isinstance(lines, LineCollection) and lines.get_zorder() > 2
               and mcolors.to_rgb(lines.get_colors()[0]) == (0, 0, 0)
               and lines.get_linewidths()[0] == 1.5 for segment in lines.get_segments()]
    assert len(medians) == 4 * 2  # all_raw, six_diff, ridge, oracle in two months


def overlaps(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def test_node_map_labels_do_not_collide(kept, tmp_path):
    nodes = fmu_nodes(DEFAULT_FMU)
    schematic.nodes_figure(nodes, tmp_path / "nodes.png")
    (fig,) = kept
    fig.canvas.draw()  # runs the layout engine, as saving does
    renderer = fig.canvas.get_renderer()
    names = set(nodes) | {part[5] for part in schematic.PARTS.values()}
    texts = [t for t in fig.axes[0].texts if t.get_text() in names]
    assert {t.get_text() for t in texts} >= set(nodes) | {"headstock"}
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in texts]
    clashes = [(a, b) for i, (a, box_a) in enumerate(boxes) for b, box_b in boxes[i + 1:]
               if overlaps(box_a, box_b)]
    assert clashes == []


def test_placement_lists_stay_clear_of_the_next_row(kept, tmp_path):
    nodes = fmu_nodes(DEFAULT_FMU)
    variables = ("spindle_shaft_5-spindle_shaft_12", "housing_4-column_11", "bed_7",
                 "x_screw-y_bearing_seat", "floor_slab-housing_2", "table_9")
    chosen = [Placement(method, with_diff, 6, tuple(range(6)), variables, (), 0.0, 0.0)
              for method in ("fuzzy", "greedy") for with_diff in (False, True)]
    table = pd.DataFrame([{"label": p.label, "m": 6, "test_mean_rmse_um": 1.0}
                          for p in chosen])
    schematic.budget_figure(nodes, chosen, table, 6, tmp_path / "m6.png")
    (fig,) = kept
    fig.canvas.draw()  # runs the layout engine, as saving does
    renderer = fig.canvas.get_renderer()
    listings = [t for ax in fig.axes for t in ax.texts if t.get_text().startswith("1: ")]
    titles = [ax.title for ax in fig.axes if ax.get_title()]
    assert len(listings) == len(titles) == 4
    for listing in listings:
        for title in titles:
            assert not overlaps(listing.get_window_extent(renderer),
                                title.get_window_extent(renderer)), title.get_text()
    # No empty band: the first row's titles sit just under the suptitle.
    top_title = max(t.get_window_extent(renderer).y1 for t in titles)
    suptitle = fig._suptitle.get_window_extent(renderer)
    assert suptitle.y0 - top_title < 0.3 * fig.dpi
