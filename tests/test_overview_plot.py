"""The recording overview figure used by `spindlebench demo` and the README."""

import numpy as np
import pandas as pd
import pytest
from matplotlib.colors import to_rgba
from spindlebench.testbench.overview import overview_figure, plot_recording


def full_frame() -> pd.DataFrame:
    t = np.arange(0, 3600, 60.0)
    frame = pd.DataFrame({"time_s": t, "drift_um": t / 100, "true_drift_um": t / 100 + 3,
                          "ambient_C": 20 + 0 * t})
    for i in range(1, 21):
        frame[f"T{i}"] = 20 + i * t / 3600
    return frame


def test_overview_writes_a_png(tmp_path):
    frame = full_frame()
    out = tmp_path / "overview.png"
    plot_recording(frame, out, "test")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert out.stat().st_size > 10_000


def test_overview_without_drift_fails_and_leaves_nothing(tmp_path):
    frame = pd.DataFrame({"time_s": [0.0, 60.0], "T1": [20.0, 21.0]})
    with pytest.raises(KeyError):
        plot_recording(frame, tmp_path / "o.png", "test")
    assert list(tmp_path.iterdir()) == []


def test_every_sensor_of_a_panel_has_its_own_colour_and_t10_stands_apart():
    """Twelve sensors on a ten-colour cycle gave T19 the colour of T6 and T20 that of T10."""
    import matplotlib.pyplot as plt

    fig = overview_figure(full_frame(), "test")
    try:
        near, far, drift = fig.axes
        for ax in (near, far):
            sensors = [line for line in ax.lines if line.get_label().startswith("T")]
            machine = [line for line in sensors if not line.get_label().startswith("T10")]
            colours = {to_rgba(line.get_color()) for line in machine}
            assert len(colours) == len(machine)
            assert to_rgba("black") not in colours
        assert len([line for line in far.lines if line.get_label().startswith("T")]) == 12
        (probe,) = [line for line in far.lines if line.get_label().startswith("T10")]
        assert to_rgba(probe.get_color()) == to_rgba("black")
        assert probe.get_linestyle() == "--"
        assert [ax.get_ylabel() for ax in fig.axes] == ["temperature (°C)", "temperature (°C)",
                                                         "drift (µm)"]
        assert drift.get_xlabel() == "time (h)"
    finally:
        plt.close(fig)


def test_overview_command_line_draws_a_recording(tmp_path, capsys):
    from spindlebench.testbench.overview import main

    frame = full_frame()
    frame[["time_s", *[f"T{i}" for i in range(1, 21)], "drift_um"]].to_csv(
        tmp_path / "run.csv", index=False)
    out = tmp_path / "run.png"
    assert main([str(tmp_path / "run.csv"), str(out)]) == 0
    assert out.read_bytes()[:4] == b"\x89PNG"
    assert main([]) == 2
