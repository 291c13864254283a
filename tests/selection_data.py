"""Shared test data for the selection tests: the real recording and a synthetic experiment."""

from __future__ import annotations

import numpy as np
import pandas as pd
from conftest import REAL_RECORDING, REPO

__all__ = ["HAND_R", "HAND_T", "REAL_RECORDING", "REPO", "random_similarity", "real_temperatures",
           "synthetic_experiment"]


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


#: A hand-checked similarity matrix and its transitive closure (closure and cut tests).
HAND_R = np.array([
    [1.0, 0.1, 0.8, 0.5],
    [0.1, 1.0, 0.2, 0.3],
    [0.8, 0.2, 1.0, 0.6],
    [0.5, 0.3, 0.6, 1.0],
])
# by hand: 0-2 (0.8), 2-3 (0.6) and 1-3 (0.3) are the strongest links; every other pair is
# linked best through them: t(0,3) = min(0.8, 0.6), t(1, .) = 0.3.
HAND_T = np.array([
    [1.0, 0.3, 0.8, 0.6],
    [0.3, 1.0, 0.3, 0.3],
    [0.8, 0.3, 1.0, 0.6],
    [0.6, 0.3, 0.6, 1.0],
])


def experiment_files(folder, count: int = 3) -> list:
    """``exp1.csv`` ... in ``folder``: ``synthetic_experiment`` at rising speeds, the
    recordings the evaluate command and the method registry are run on."""
    paths = []
    for seed in range(count):
        path = folder / f"exp{seed + 1}.csv"
        synthetic_experiment(seed, speed=0.5 + 0.4 * seed).to_csv(path, index=False)
        paths.append(path)
    return paths


def random_similarity(n: int, seed: int, levels: int | None = None) -> np.ndarray:
    rng = np.random.default_rng(seed)
    R = rng.random((n, n))
    if levels:  # few distinct values: many ties
        R = np.round(R * levels) / levels
    R = np.triu(R, 1)
    R = R + R.T
    np.fill_diagonal(R, 1.0)
    return R

