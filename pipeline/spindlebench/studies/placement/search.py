"""Searching sensor sets: greedy forward selection and exhaustive search, by validation RMSE.

The objective of a candidate set S is the one the placement study reports: fit the rise model
(OLS with intercept, ``selection.fit_ols``) on the training runs, predict every validation run,
and take the mean over runs of the per-run RMSE (um), as the paper averages its Table 6.
:func:`validation_score` computes it directly (the reference); the searches compute the same
number for thousands of sets at once:

- :func:`greedy_forward` keeps the training design orthogonalised (modified Gram-Schmidt with
  explicit residual columns, re-orthogonalised once), so adding candidate j is a rank-one
  update: by Frisch-Waugh its coefficient is <r_j, r_y> / <r_j, r_j> on the residuals r of
  the current set, and the validation residual moves along the same combination of columns
  applied to the validation rows. Every step scores *all* candidates in O((n_train +
  n_valid) p) with a handful of vectorised passes, instead of p separate least-squares fits.
- :func:`exhaustive_search` scores every m-subset from Gram matrices (training X'X, X'y and
  per-run validation X'X, X'e), batched: one m x m solve per subset, no pass over the samples.

Both only rank sets: the study re-scores the winners with :func:`validation_score`, so every
reported number comes from one plain least-squares fit.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from spindlebench.selection import fit_ols
from spindlebench.selection.similarity import constant_columns

#: A candidate whose training residual keeps less than this fraction of its own squared norm
#: lies in the span of the chosen set (e.g. T_a - T_b once T_a and T_b are chosen): skipped.
COLLINEAR_RTOL = 1e-9
#: Subsets scored per batch in the exhaustive search (bounds memory to a few tens of MB).
EXHAUSTIVE_CHUNK = 4096


@dataclass(frozen=True)
class Block:
    """Rises of every candidate (rows: samples of one or more runs, stacked run by run).

    ``starts`` holds the first row of each run (ascending, starting at 0), so per-run sums are
    ``np.add.reduceat(values, starts)``.
    """

    X: np.ndarray
    y: np.ndarray
    starts: np.ndarray

    @property
    def lengths(self) -> np.ndarray:
        return np.diff(np.append(self.starts, self.X.shape[0]))


def mean_run_rmse(residual: np.ndarray, starts: np.ndarray) -> float:
    """Mean over runs of each run's RMSE (``residual`` stacked run by run)."""
    lengths = np.diff(np.append(starts, residual.shape[0]))
    sse = np.add.reduceat(residual**2, starts)
    return float(np.mean(np.sqrt(sse / lengths)))


def validation_score(train: Block, valid: Block, columns: Sequence[int]) -> float:
    """Reference objective: OLS on the training rises of ``columns``, mean validation RMSE."""
    columns = list(columns)
    fit = fit_ols(train.X[:, columns], train.y)
    return mean_run_rmse(valid.y - fit.predict(valid.X[:, columns]), valid.starts)


def usable_candidates(train: Block) -> np.ndarray:
    """Candidates that vary on the training runs (a constant one cannot enter a fit)."""
    return np.flatnonzero(~constant_columns(train.X))


@dataclass(frozen=True)
class GreedyPath:
    """The greedy order: ``chosen[:m]`` is the set of size m, scored ``scores[m - 1]``."""

    chosen: list[int]
    scores: list[float]


def greedy_forward(train: Block, valid: Block, max_size: int,
                   pool: Sequence[int] | None = None) -> GreedyPath:
    """Add, one at a time, the candidate that lowers the mean validation RMSE most.

    ``pool``: the candidate columns allowed (default: all that vary on the training runs).
    Ties go to the lowest column index. Stops early if no candidate adds a new direction.
    """
    pool = usable_candidates(train) if pool is None else np.asarray(pool, dtype=np.intp)
    x_mean = train.X[:, pool].mean(axis=0)
    y_mean = float(train.y.mean())
    Rt = train.X[:, pool] - x_mean  # training residual columns (centred, then orthogonalised)
    Rv = valid.X[:, pool] - x_mean  # the same linear combinations on the validation rows
    r_y = train.y - y_mean  # training residual of the target
    e = valid.y - y_mean  # validation residual of the current model
    original = np.einsum("ij,ij->j", Rt, Rt)
    alive = original > 0
    starts, lengths = valid.starts, valid.lengths
    chosen: list[int] = []
    scores: list[float] = []
    for _ in range(min(max_size, pool.size)):
        norm2 = np.einsum("ij,ij->j", Rt, Rt)
        alive &= norm2 > COLLINEAR_RTOL * original
        if not alive.any():
            break
        safe = np.where(alive, norm2, 1.0)
        t = (r_y @ Rt) / safe  # coefficient of each candidate's residual (Frisch-Waugh)
        E = np.add.reduceat(e**2, starts)  # per run: sum e^2, sum e r_v, sum r_v^2
        P = np.add.reduceat(e[:, None] * Rv, starts, axis=0)
        W = np.add.reduceat(Rv**2, starts, axis=0)
        sse = np.maximum(E[:, None] - 2.0 * t * P + t**2 * W, 0.0)
        score = np.sqrt(sse / lengths[:, None]).mean(axis=0)
        score[~alive] = np.inf
        best = int(np.argmin(score))
        chosen.append(int(pool[best]))
        scores.append(float(score[best]))
        # Move the target residuals, then orthogonalise every column against the new one.
        e = e - t[best] * Rv[:, best]
        r_y = r_y - t[best] * Rt[:, best]
        norm = math.sqrt(norm2[best])
        q, z = Rt[:, best] / norm, Rv[:, best] / norm
        for _pass in range(2):  # "twice is enough" (Kahan/Parlett) against lost orthogonality
            a = q @ Rt
            Rt -= np.outer(q, a)
            Rv -= np.outer(z, a)
        alive[best] = False
    return GreedyPath(chosen, scores)


def n_subsets(n_candidates: int, size: int) -> int:
    return math.comb(n_candidates, size)


@dataclass(frozen=True)
class ExhaustiveResult:
    """The best m-subset, its score and how many subsets were scored."""

    chosen: list[int]
    score: float
    evaluated: int


def subset_batches(n: int, size: int, chunk: int = EXHAUSTIVE_CHUNK):
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
