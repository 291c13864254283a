"""Actively constructed temperature differences (Xu et al. 2023, section 1.2).

Every pair of raw sensors (A, B), A before B in the given order, gives the candidate ``A-B``:
6 sensors give 15 differences, 20 give 190. Pairs follow ``numpy.triu_indices`` order, i.e.
T1-T2, T1-T3, ..., T1-Tn, T2-T3, ... as in the paper.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from spindlebench.selection.errors import SelectionError

if TYPE_CHECKING:
    import pandas as pd


@functools.lru_cache(maxsize=32)
def pair_indices(n_sensors: int) -> tuple[np.ndarray, np.ndarray]:
    """Indices (first, second) of every pair, first before second (read-only arrays, made
    once per size: a study asks for them thousands of times)."""
    first, second = np.triu_indices(n_sensors, k=1)
    first.flags.writeable = False
    second.flags.writeable = False
    return first, second


def difference_names(names: Sequence[str]) -> list[str]:
    """``A-B`` names of every pair, in pair order."""
    names = [str(name) for name in names]
    if len(set(names)) != len(names):
        duplicates = sorted({name for name in names if names.count(name) > 1})
        raise SelectionError(f"sensor names must be unique; repeated: {', '.join(duplicates)}")
    first, second = pair_indices(len(names))
    return [f"{names[i]}-{names[j]}" for i, j in zip(first, second, strict=True)]


@functools.lru_cache(maxsize=8)
def with_differences_matrix(n_sensors: int) -> np.ndarray:
    """The (n, n + n(n-1)/2) matrix ``M`` with ``X @ M`` = X's columns followed by their
    pairwise differences (read-only; made once per size): the raw-plus-differences
    candidates as a product, for algebra that wants their low rank."""
    first, second = pair_indices(n_sensors)
    pairs = np.zeros((n_sensors, first.size))
    pairs[first, np.arange(first.size)] = 1.0
    pairs[second, np.arange(first.size)] = -1.0
    matrix = np.hstack([np.eye(n_sensors), pairs])
    matrix.flags.writeable = False
    return matrix


def pairwise_differences(X: np.ndarray) -> np.ndarray:
    """Columns ``X[:, i] - X[:, j]`` for every pair i < j (n_samples x n(n-1)/2)."""
    X = np.asarray(X, dtype=float)
    if X.ndim != 2:
        raise SelectionError(f"expected a 2-D array of sensors, got shape {X.shape}")
    first, second = pair_indices(X.shape[1])
    return X[:, first] - X[:, second]


def with_differences(frame: pd.DataFrame, sensors: Sequence[str]) -> pd.DataFrame:
    """The raw ``sensors`` of ``frame`` followed by all their pairwise differences."""
    import pandas as pd

    sensors = list(sensors)
    raw = frame.loc[:, sensors].to_numpy(dtype=float)
    diffs = pd.DataFrame(
        pairwise_differences(raw), columns=difference_names(sensors), index=frame.index
    )
    return pd.concat([frame.loc[:, sensors].astype(float), diffs], axis=1)
