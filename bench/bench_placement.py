"""Benchmark: placement searches on a 100-node field with its 4 950 differences.

Synthetic test data (not the FMU): 100 node temperatures of 9 runs (1 training, 8
validation), warm-up curves with node-specific time constants, ambient wander, noise and the
logger's 0.1 K quantisation. Times, each against a naive baseline in the same process with
the same result checked:

- fuzzy selection (similarity, closure, cut, psi; ``select_sensitive_points``) on all 5 050
  candidates with the fast closure; the repeated-squaring closure as baseline on a 40-node
  field (820 candidates), where it still finishes;
- greedy forward selection to m = 6 (incremental Gram-Schmidt, all candidates scored per step)
  vs refitting ``numpy.linalg.lstsq`` for every candidate at every step;
- exhaustive search over the 100 nodes, m = 2 and 3 (batched Gram matrices) vs one lstsq per
  subset (m = 2 only for the baseline).

Run: .venv/bin/python bench/bench_placement.py
"""

from __future__ import annotations

import itertools
import time
import warnings

import numpy as np
from spindlebench.selection import SelectionWarning, select_sensitive_points
from spindlebench.selection.differences import pairwise_differences
from spindlebench.studies.placement.search import Block, exhaustive_search, greedy_forward

N_NODES, N_SAMPLES, N_VALID = 100, 361, 8


def field(n_nodes: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """One run: node rises (samples x nodes) and a drift that depends on a few of them."""
    t = np.linspace(0.0, 1.0, N_SAMPLES)[:, None]
    tau = rng.uniform(0.05, 1.5, n_nodes)
    gain = rng.uniform(0.2, 8.0, n_nodes) * rng.uniform(0.6, 1.4)
    ambient = np.cumsum(rng.normal(0, 0.03, N_SAMPLES))[:, None]
    T = 20.0 + ambient + gain * (1 - np.exp(-t / tau)) + rng.normal(0, 0.05, (N_SAMPLES, n_nodes))
    T = np.round(T / 0.1) * 0.1
    a, b, c, d = (int(f * n_nodes) for f in (0.03, 0.4, 0.7, 0.1))
    drift = 4.0 * T[:, a] - 2.5 * T[:, b] + 1.5 * (T[:, c] - T[:, d])
    drift += rng.normal(0, 0.3, N_SAMPLES)
    return T - T[0], drift - drift[0]


def blocks(n_nodes: int, differences: bool, seed: int = 0) -> tuple[Block, Block]:
    rng = np.random.default_rng(seed)
    runs = [field(n_nodes, rng) for _ in range(1 + N_VALID)]
    X = [np.hstack([T, pairwise_differences(T)]) if differences else T for T, _ in runs]
    y = [d for _, d in runs]
    train = Block(X[0], y[0], np.array([0]))
    valid = Block(np.vstack(X[1:]), np.concatenate(y[1:]), np.arange(N_VALID) * N_SAMPLES)
    return train, valid


def lstsq_score(train: Block, valid: Block, columns) -> float:
    columns = list(columns)
    A = np.column_stack([np.ones(train.X.shape[0]), train.X[:, columns]])
    coef, *_ = np.linalg.lstsq(A, train.y, rcond=None)
    residual = valid.y - coef[0] - valid.X[:, columns] @ coef[1:]
    runs = np.split(residual, valid.starts[1:])
    return float(np.mean([np.sqrt(np.mean(r**2)) for r in runs]))


def naive_greedy(train: Block, valid: Block, size: int) -> list[int]:
    chosen: list[int] = []
    for _ in range(size):
        scores = [np.inf if j in chosen else lstsq_score(train, valid, [*chosen, j])
                  for j in range(train.X.shape[1])]
        chosen.append(int(np.argmin(scores)))
    return chosen


def timed(function, *args):
    start = time.perf_counter()
    result = function(*args)
    return time.perf_counter() - start, result


def fuzzy(train: Block, k: int, closure: str):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SelectionWarning)
        return select_sensitive_points(train.X, train.y, k, closure=closure).selected


def main() -> None:
    print(f"synthetic field: {N_NODES} nodes, {N_SAMPLES} samples per run, 1 training + "
          f"{N_VALID} validation runs")
    train, valid = blocks(N_NODES, differences=True)
    print(f"\n[fuzzy selection, k = 6] {train.X.shape[1]} candidates")
    t_fast, picked = timed(fuzzy, train, 6, "fast")
    print(f"  fast closure (spanning tree)           {t_fast:8.2f} s   "
          f"picks {[int(i) for i in picked]}")
    small, _ = blocks(40, differences=True, seed=1)
    t_small, fast_small = timed(fuzzy, small, 6, "fast")
    t_square, square_small = timed(fuzzy, small, 6, "squaring")
    assert list(fast_small) == list(square_small)
    print(f"  {small.X.shape[1]} candidates: fast {t_small:.3f} s, repeated squaring "
          f"{t_square:.2f} s -> ratio {t_square / t_small:6.0f}x (same picks)")

    print(f"\n[greedy forward selection to m = 6] {train.X.shape[1]} candidates")
    t_greedy, path = timed(greedy_forward, train, valid, 6)
    t_naive, naive = timed(naive_greedy, train, valid, 6)
    assert path.chosen == naive, (path.chosen, naive)
    print(f"  incremental (Gram-Schmidt, vectorised) {t_greedy:8.2f} s")
    print(f"  naive (one lstsq per candidate/step)   {t_naive:8.2f} s   "
          f"ratio {t_naive / t_greedy:6.1f}x (same path)")

    nodes_train, nodes_valid = blocks(N_NODES, differences=False)
    print(f"\n[exhaustive search] {N_NODES} nodes")
    t_ex2, ex2 = timed(exhaustive_search, nodes_train, nodes_valid, 2)
    pairs = list(itertools.combinations(range(N_NODES), 2))
    t_naive2, best = timed(lambda: min(pairs, key=lambda c: lstsq_score(nodes_train,
                                                                         nodes_valid, c)))
    assert tuple(ex2.chosen) == best
    print(f"  m = 2: batched Gram {t_ex2:6.2f} s, naive lstsq {t_naive2:6.2f} s   "
          f"ratio {t_naive2 / t_ex2:6.1f}x ({ex2.evaluated:,} subsets, same optimum)")
    t_ex3, ex3 = timed(exhaustive_search, nodes_train, nodes_valid, 3)
    print(f"  m = 3: batched Gram {t_ex3:6.2f} s ({ex3.evaluated:,} subsets, "
          f"{ex3.evaluated / t_ex3:,.0f} per s; naive would take ~"
          f"{t_naive2 / len(pairs) * ex3.evaluated:,.0f} s)")


if __name__ == "__main__":
    main()
