"""Shared test data for the selection tests: the real recording and a synthetic experiment."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

REPO = Path(__file__).resolve().parents[1]
REAL_RECORDING = REPO / ".." / "shared" / "recordings" / "caiviac-fl-thermal" / "data.csv"


def real_temperatures(rows: slice = slice(31, 1951)) -> pd.DataFrame:
    """One heating/cooling cycle of the real recording (1250 rpm), all columns."""
    return pd.read_csv(REAL_RECORDING).iloc[rows].reset_index(drop=True)


def synthetic_experiment(seed: int, n: int = 240, speed: float = 1.0) -> pd.DataFrame:
    """A small warm-up experiment: six sensors with exponential rises and a drift that is
    linear in two of them (T1 rises, T10 is ambient), plus measurement noise."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 4 * 3600.0, n)
    ambient = 20.0 + 1.5 * np.sin(t / 9000.0 + seed)
    warm = 1 - np.exp(-t / 3000.0)
    slow = 1 - np.exp(-t / 9000.0)
    temps = {
        "T1": ambient + 12 * speed * warm,
        "T6": ambient + 6 * speed * slow,
        "T8": ambient + 9 * speed * warm + 0.5 * slow,
        "T10": ambient,
        "T13": ambient + 3 * slow,
        "T16": ambient + 2.5 * slow + 0.3 * warm,
    }
    frame = pd.DataFrame({"time_s": t})
    for name, values in temps.items():
        frame[name] = values + rng.normal(0, 0.02, n)
    drift = 4.0 * (frame["T1"] - frame["T10"]) - 2.0 * (frame["T13"] - frame["T16"])
    frame["drift_um"] = drift - drift.iloc[0] + rng.normal(0, 0.3, n)
    frame["spindle_speed_rpm"] = 4000.0 * speed
    frame["true_drift_um"] = drift - drift.iloc[0]
    return frame
