"""The recording figure (``spindlebench plot``, ``simulate --plot``, the README hero figure)."""

import re

import numpy as np
import pandas as pd
import pytest
from matplotlib.colors import to_rgba
from spindlebench.commands import main as cli
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import MODELS_DIR, SCENARIOS_DIR
from spindlebench.testbench.overview import (
    overview_figure,
    plot_recording,
    recordings_figure,
    spread_labels,
)
from spindlebench.testbench.sensor_parts import LOCATIONS, PARTS, part_of


def full_frame(hours: float = 1.0) -> pd.DataFrame:
    t = np.arange(0, hours * 3600, 60.0)
    frame = pd.DataFrame({"time_s": t, "drift_um": t / 100, "true_drift_um": t / 100 + 3,
                          "ambient_C": 20 + 0 * t, "spindle_speed_rpm": 4000 + 0 * t,
                          "feed_x_mm_per_min": 1500 + 0 * t, "feed_y_mm_per_min": 0 * t})
    for i in range(1, 21):
        frame[f"T{i}"] = 20 + i * t / 3600
    return frame


def end_labels(ax) -> dict[str, tuple]:
    """Line-end label text → (label height in data units, colour)."""
    return {a.get_text(): (a.xyann[1], to_rgba(a.get_color()))
            for a in ax.texts if hasattr(a, "xyann")}


def test_overview_writes_a_png(tmp_path):
    out = tmp_path / "overview.png"
    plot_recording(full_frame(), out, "test")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert out.stat().st_size > 10_000


def test_a_recording_without_the_error_column_is_one_line_and_leaves_nothing(tmp_path):
    frame = pd.DataFrame({"time_s": [0.0, 60.0], "T1": [20.0, 21.0]})
    with pytest.raises(SpindlebenchError, match="no thermal-error column 'drift_um'"):
        plot_recording(frame, tmp_path / "o.png", "test")
    assert list(tmp_path.iterdir()) == []


def test_twenty_sensors_are_grouped_by_part_and_named_at_their_line_ends():
    import matplotlib.pyplot as plt

    fig = overview_figure(full_frame(), "test")
    try:
        spindle, axes_panel, drift, inputs = fig.axes[:4]
        assert [ax.get_title(loc="left") for ax in fig.axes[:4]] == [
            "spindle and headstock", "feed axes and ambient air",
            "thermal error: axial drift, tool towards table, since the start", "inputs"]
        labels = {**end_labels(spindle), **end_labels(axes_panel)}
        assert {f"T{i}" for i in range(1, 21)} <= set(labels)  # every sensor named once
        assert "ambient air" in labels
        for ax in (spindle, axes_panel):  # labels of a panel never overlap
            heights = sorted(y for y, _ in end_labels(ax).values())
            assert min(np.diff(heights)) > 0
        # one colour family per part: the parts' shades are disjoint, T10 is black
        for part in PARTS:
            shades = {labels[s][1] for s in part.sensors}
            assert len(shades) == len(part.sensors)
            others = {labels[s][1] for s in LOCATIONS if s not in part.sensors}
            assert not shades & others
        assert labels["T10"][1] == to_rgba("black")
        assert drift.get_ylabel() == "drift (µm)"
        assert inputs.get_xlabel() == "time (h)"
    finally:
        plt.close(fig)


def test_rises_start_at_zero_and_absolute_values_do_not():
    import matplotlib.pyplot as plt

    for rises, first in ((True, 0.0), (False, 20.0)):
        fig = recordings_figure([full_frame()], ["r"], rises=rises)
        try:
            (t1,) = [line for line in fig.axes[0].lines if line.get_label() == "T1"]
            assert t1.get_ydata()[0] == pytest.approx(first)
        finally:
            plt.close(fig)


def test_several_recordings_are_columns_and_unknown_sensors_get_their_own_panel():
    import matplotlib.pyplot as plt

    real = pd.DataFrame({"time_s": [0.0, 60, 120], "t1_C": [20.0, 21, 22],
                         "t2_C": [20.0, 20.5, 21], "ch3_um": [0.0, 1, 2],
                         "spindle_speed_rpm": [5000.0] * 3})
    fig = recordings_figure([real, real], ["a", "b"], target="ch3_um")
    try:
        grid = fig.axes[0].get_subplotspec().get_gridspec()
        assert (grid.nrows, grid.ncols) == (3, 2)  # sensors, error, inputs × two recordings
        assert fig.axes[0].get_title(loc="left") == "sensors"
        assert set(end_labels(fig.axes[0])) == {"t1_C", "t2_C"}
    finally:
        plt.close(fig)


def test_spread_labels_keeps_order_and_gap_and_moves_as_little_as_needed():
    placed = spread_labels([5.0, 5.0, 5.1, 9.0], gap=0.5, low=0.0, high=10.0)
    assert placed[3] == 9.0
    assert np.diff(sorted(placed[:3])).min() == pytest.approx(0.5)
    assert spread_labels([9.9, 10.0], gap=0.5, low=0.0, high=10.0) == [9.5, 10.0]


def test_the_part_table_matches_the_models_sensor_connections():
    source = (MODELS_DIR / "SpindleBench.mo").read_text(encoding="utf-8")

    def inside(port: str) -> str:
        """``spindle_unit.cap`` → ``front_cap.port``: the node an assembly's port is joined to."""
        instance, name = port.split(".")
        kind = re.search(rf"^\s+(\w+) {instance}\(", source, re.M)
        if kind is None:  # a component of the machine itself (ambient)
            return port
        body = re.search(rf"model {kind[1]} .*?end {kind[1]};", source, re.S)[0]
        return re.search(rf"connect\(([\w.]+), {name}\);", body)[1]

    connected = {m[1]: inside(m[2]).removesuffix(".port")
                 for m in re.finditer(r"connect\(sensor_(T\d+)\.port,\s*([\w.]+)\)", source)}
    assert connected == {s: node for s, (node, _) in LOCATIONS.items()} | {"T10": "ambient"}
    assert sorted(s for part in PARTS for s in part.sensors) == sorted(LOCATIONS)
    assert part_of("t1_C") is None


def test_plot_command_draws_one_or_several_recordings(tmp_path, capsys):
    for name in ("a", "b"):
        full_frame().to_csv(tmp_path / f"{name}.csv", index=False)
    assert cli.main(["plot", str(tmp_path / "a.csv")]) == 0
    assert (tmp_path / "a.png").read_bytes()[:4] == b"\x89PNG"
    out = tmp_path / "both.png"
    assert cli.main(["plot", str(tmp_path / "a.csv"), str(tmp_path / "b.csv"), "-o", str(out),
                     "--rises", "--title", "two"]) == 0
    assert out.stat().st_size > 10_000


@pytest.mark.parametrize(("extra", "message"), [
    (["-o", "x.pdf"], "x.pdf: the figure is written as PNG"),
    (["--target", "ch3_um"], "target column 'ch3_um' not found"),
    (["SECOND"], "2 recordings go into one figure; name it with -o FIG.png"),
])
def test_plot_command_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, extra,
                                                               message):
    full_frame().to_csv(tmp_path / "a.csv", index=False)
    extra = [str(tmp_path / "a.csv") if e == "SECOND" else e for e in extra]
    before = set(tmp_path.iterdir())
    assert cli.main(["plot", str(tmp_path / "a.csv"), *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert set(tmp_path.iterdir()) == before


def test_simulate_plot_writes_the_figure_beside_the_recording(tmp_path, capsys):
    out = tmp_path / "quick.csv"
    assert cli.main(["simulate", str(SCENARIOS_DIR / "examples/quick.toml"), "-o", str(out),
                     "--plot"]) == 0
    assert "quick.png" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["quick.csv", "quick.json",
                                                          "quick.png"]


def test_the_shared_speed_axis_shows_the_fastest_recording():
    """Each column set its own rpm limit on a shared axis: the last (1250 rpm) one hid 5000."""
    import matplotlib.pyplot as plt

    fast, slow = full_frame(), full_frame()
    slow["spindle_speed_rpm"] = 1250.0
    fig = recordings_figure([fast, slow], ["fast", "slow"])
    try:
        inputs = [ax for ax in fig.axes if ax.get_title(loc="left") == "inputs"]
        assert all(ax.get_ylim()[1] > 4000 for ax in inputs)
    finally:
        plt.close(fig)


def long_named(n: int = 40) -> pd.DataFrame:
    """Another logger's names: longer line-end labels than T1 … T20."""
    t = np.arange(n) * 300.0
    return pd.DataFrame({"time_s": t, "Spindle front [degC]": 20 + t / 3600,
                         "Headstock side [degC]": 20 + t / 7200, "dz [um]": t / 600})


def test_long_line_end_labels_stay_inside_the_figure_and_clear_of_the_next_column():
    """Issue 25: the labels had a fixed 0.55 in: ``Spindle front [degC]`` was clipped."""
    import matplotlib.pyplot as plt

    fig = recordings_figure([long_named(), long_named()], ["a", "b"], target="dz [um]")
    try:
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        width = fig.bbox.width
        left_panel, right_panel = fig.axes[0], fig.axes[1]  # row-major: the top row
        assert right_panel.get_position().x0 > left_panel.get_position().x1
        for ax in (left_panel, right_panel):
            for text in ax.texts:
                if not hasattr(text, "xyann"):
                    continue
                box = text.get_window_extent(renderer)
                assert box.x1 <= width, (text.get_text(), box.x1, width)
                if ax is left_panel:  # left of the next column's tick labels
                    ticks = right_panel.get_tightbbox(renderer)
                    assert box.x1 < ticks.x0, text.get_text()
    finally:
        plt.close(fig)


def test_the_recording_title_is_above_the_panel_label_and_the_part_legend_colours_differ():
    """Issue 25: in exp1_overview.png the title sat on the panel label's line, and the
    legend's darkest red (spindle front) and darkest purple (headstock) looked alike."""
    import matplotlib.pyplot as plt

    fig = recordings_figure([full_frame()], ["exp1"])
    try:
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        top = fig.axes[0]
        (title,) = [t for t in top.texts if t.get_text() == "exp1"]
        label = top.title if top.get_title() else top._left_title
        assert title.get_window_extent(renderer).y0 >= \
            top._left_title.get_window_extent(renderer).y1 - 0.5, label
        colours = [np.array(to_rgba(h.get_color())[:3]) for h in
                   top.get_legend().get_lines()]
        assert len(colours) == 2 and np.abs(colours[0] - colours[1]).max() > 0.3
    finally:
        plt.close(fig)


def test_every_placement_method_has_its_own_colour():
    from spindlebench.studies.placement.schematic import method_colour

    methods = ["fuzzy", "greedy", "exhaustive", "kmeans+grey", "lasso", "ward", "fcm+grey"]
    colours = [method_colour(m, methods) for m in methods]
    assert len(set(colours)) == len(methods)  # "kmeans+grey" and "lasso" were both purple
