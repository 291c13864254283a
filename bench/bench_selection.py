"""Benchmark: selection steps (similarity, closure, cut, psi) on synthetic candidate sets.

Sizes from issue 3: 20 raw sensors + 190 differences on 360 samples, and 100 raw + 4 950
differences on 1 440 samples. The fast closure (maximum spanning tree, O(n^2)) is timed against
the paper's repeated max-min squaring (vectorised, chunked numpy, O(n^3 log n)) in the same
process, on the sizes where the reference finishes in reasonable time; both results are
checked to be identical.

Run: .venv/bin/python bench/bench_selection.py
"""

from __future__ import annotations

import time

import numpy as np
from spindlebench.selection.closure import closure_by_squaring, closure_minimax
from spindlebench.selection.cut import cut_for_clusters
from spindlebench.selection.differences import pairwise_differences
from spindlebench.selection.similarity import correlation_with, similarity_matrix

SIZES = [  # (raw sensors, samples, run the squaring reference?)
    (20, 360, True),
    (40, 720, True),
    (100, 1440, False),
]


def synthetic_temperatures(n_sensors: int, n_samples: int, seed: int = 0) -> np.ndarray:
    """Warm-up curves with sensor-specific time constants and gains, ambient wander, noise."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, n_samples)[:, None]
    tau = rng.uniform(0.05, 0.8, n_sensors)
    gain = rng.uniform(0.5, 15.0, n_sensors)
    ambient = 20.0 + np.cumsum(rng.normal(0, 0.02, n_samples))[:, None]
    return ambient + gain * (1 - np.exp(-t / tau)) + rng.normal(0, 0.03, (n_samples, n_sensors))


def timed(function, *args, repeat: int = 1):
    """(best wall time in s, result) over ``repeat`` runs."""
    best, result = np.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        result = function(*args)
        best = min(best, time.perf_counter() - start)
    return best, result


def main() -> None:
    print(f"{'candidates':>16} {'samples':>7} {'similarity':>10} {'closure':>9} {'cut':>7} "
          f"{'psi':>7} {'squaring':>9} {'ratio':>7}")
    for n_sensors, n_samples, with_reference in SIZES:
        raw = synthetic_temperatures(n_sensors, n_samples)
        X = np.hstack([raw, pairwise_differences(raw)])
        y = 3.0 * (raw[:, 0] - raw[:, -1]) + np.random.default_rng(1).normal(0, 0.3, n_samples)
        repeat = 3 if X.shape[1] < 1000 else 1
        t_sim, R = timed(similarity_matrix, X, repeat=repeat)
        t_fast, T = timed(closure_minimax, R, repeat=repeat)
        t_cut, _ = timed(cut_for_clusters, T, 4, repeat=repeat)
        t_psi, _ = timed(correlation_with, X, y, repeat=repeat)
        reference = ratio = "-"
        if with_reference:
            t_ref, T_ref = timed(closure_by_squaring, R)
            if not np.array_equal(T_ref, T):
                raise SystemExit("fast closure differs from the squaring reference")
            reference, ratio = f"{t_ref:8.3f}s", f"{t_ref / t_fast:6.0f}x"
        label = f"{n_sensors}+{X.shape[1] - n_sensors}"
        print(f"{label:>16} {n_samples:>7} {t_sim:9.3f}s {t_fast:8.3f}s {t_cut:6.3f}s "
              f"{t_psi:6.3f}s {reference:>9} {ratio:>7}", flush=True)
    print("ratio = squaring reference time / fast closure time (identical results checked)")


if __name__ == "__main__":
    main()
