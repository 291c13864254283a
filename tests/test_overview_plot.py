"""The recording overview figure used by `spindlebench demo` and the README."""

import numpy as np
import pandas as pd
import pytest
from spindlebench.testbench.overview import plot_recording


def test_overview_writes_a_png(tmp_path):
    t = np.arange(0, 3600, 60.0)
    frame = pd.DataFrame({"time_s": t, "drift_um": t / 100, "true_drift_um": t / 100 + 3,
                          "ambient_C": 20 + 0 * t})
    for i in range(1, 21):
        frame[f"T{i}"] = 20 + i * t / 3600
    out = tmp_path / "overview.png"
    plot_recording(frame, out, "test")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert out.stat().st_size > 10_000


def test_overview_without_drift_fails_and_leaves_nothing(tmp_path):
    frame = pd.DataFrame({"time_s": [0.0, 60.0], "T1": [20.0, 21.0]})
    with pytest.raises(KeyError):
        plot_recording(frame, tmp_path / "o.png", "test")
    assert list(tmp_path.iterdir()) == []
