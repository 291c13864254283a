"""Exhaustive search: every k-subset of the candidates, scored by validation RMSE.

The objective is ``forward.validation_score``'s (OLS on the training rises of the subset,
mean over validation runs of each run's RMSE), the one greedy forward selection climbs; the
search here scores *every* subset instead of growing one, so it finds the best set where
greedy can miss it (two candidates that only together explain the error). It serves both
the selection method ``exhaustive`` (``selectors.ExhaustiveSelector``: training part and
validation part of one run, or experiments given as ``groups``) and the placement study's
exhaustive search (``studies.placement``), so they are the same numbers.

:func:`exhaustive_search` scores every m-subset from Gram matrices (training X'X, X'y and
per-run validation X'X, X'e), batched: one m x m solve per subset, no pass over the samples.
It only ranks sets; a caller that reports the winner's score re-scores it with
``validation_score``, one plain least-squares fit.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from spindlebench.selection.forward import Block, usable_candidates

#: Subsets scored per batch in the exhaustive search (bounds memory to a few tens of MB).
EXHAUSTIVE_CHUNK = 4096


def n_subsets(n_candidates: int, size: int) -> int:
    return math.comb(n_candidates, size)


@dataclass(frozen=True)
class ExhaustiveResult:
    """The best m-subset, its score and how many subsets were scored."""

    chosen: list[int]
    score: float
    evaluated: int


def subset_batches(n: int, size: int, chunk: int = EXHAUSTIVE_CHUNK) -> Iterator[np.ndarray]:
    """Every ``size``-subset of ``range(n)`` in lexicographic order, as index arrays of about
    ``chunk`` rows: all but the last two members come from ``itertools``, the last two from
    ``numpy.triu_indices``, so Python loops once per prefix, not once per subset."""
    if size == 1:
        for start in range(0, n, chunk):
            yield np.arange(start, min(n, start + chunk), dtype=np.intp)[:, None]
        return
    pending: list[np.ndarray] = []
    count = 0
    for prefix in itertools.combinations(range(n), size - 2):
        low = prefix[-1] + 1 if prefix else 0
        first, second = np.triu_indices(n - low, k=1)
        if first.size == 0:
            continue
        tail = np.column_stack([first + low, second + low]).astype(np.intp)
        head = np.broadcast_to(np.asarray(prefix, dtype=np.intp), (tail.shape[0], size - 2))
        rows = np.hstack([head, tail])
        for start in range(0, rows.shape[0], chunk):
            part = rows[start:start + chunk]
            pending.append(part)
            count += part.shape[0]
            if count >= chunk:
                yield np.vstack(pending)
                pending, count = [], 0
    if pending:
        yield np.vstack(pending)


def _gram_data(train: Block, valid: Block, pool: np.ndarray):
    """Training and per-run validation Gram matrices of the (scaled, centred) pool columns.

    The per-run matrices are stored run-last (p x p x runs) so that gathering a subset's
    entries reads contiguous vectors.
    """
    x_mean = train.X[:, pool].mean(axis=0)
    Xc = train.X[:, pool] - x_mean
    scale = np.sqrt(np.einsum("ij,ij->j", Xc, Xc))
    Xc /= scale
    yc = train.y - train.y.mean()
    Xv = (valid.X[:, pool] - x_mean) / scale
    e0 = valid.y - train.y.mean()
    runs = np.split(np.arange(valid.X.shape[0]), valid.starts[1:])
    H = np.stack([Xv[rows].T @ Xv[rows] for rows in runs], axis=-1)  # p x p x runs
    u = np.stack([Xv[rows].T @ e0[rows] for rows in runs], axis=-1)  # p x runs
    E = np.array([e0[rows] @ e0[rows] for rows in runs])
    return Xc.T @ Xc, Xc.T @ yc, H, u, E, valid.lengths.astype(float)


def _solve_batch(G: np.ndarray, b: np.ndarray) -> np.ndarray:
    try:
        return np.linalg.solve(G, b[..., None])[..., 0]
    except np.linalg.LinAlgError:  # a singular subset: minimum-norm solution, as lstsq gives
        return (np.linalg.pinv(G, hermitian=True) @ b[..., None])[..., 0]


def exhaustive_search(train: Block, valid: Block, size: int,
                      pool: Sequence[int] | None = None,
                      chunk: int = EXHAUSTIVE_CHUNK) -> ExhaustiveResult:
    """Score every ``size``-subset of ``pool`` and return the best (first on ties)."""
    pool = usable_candidates(train) if pool is None else np.asarray(pool, dtype=np.intp)
    if size > pool.size:
        raise ValueError(f"cannot choose {size} of {pool.size} candidates")
    G, b, H, u, E, lengths = _gram_data(train, valid, pool)
    best_score, best_subset, evaluated = np.inf, None, 0
    for idx in subset_batches(pool.size, size, chunk):
        c = idx.shape[0]
        rows, cols = idx[:, :, None], idx[:, None, :]
        beta = _solve_batch(G[rows, cols], b[idx])  # c x m
        outer = (beta[:, :, None] * beta[:, None, :]).reshape(c, 1, size * size)
        quad = (outer @ H[rows, cols].reshape(c, size * size, -1))[:, 0, :]  # c x runs
        cross = np.einsum("cmr,cm->cr", u[idx], beta)
        sse = np.maximum(E - 2.0 * cross + quad, 0.0)
        score = np.sqrt(sse / lengths).mean(axis=1)
        score[~np.isfinite(score)] = np.inf
        at = int(np.argmin(score))
        if score[at] < best_score:
            best_score, best_subset = float(score[at]), idx[at]
        evaluated += c
    assert best_subset is not None
    return ExhaustiveResult([int(pool[i]) for i in best_subset], best_score, evaluated)
