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
from collections.abc import Iterator, Sequence
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

    The training residual columns ``Rt`` are kept explicitly (modified Gram-Schmidt, two
    passes). Their validation counterparts ``Rv_j = x_j - sum_k z_k a_kj`` are never formed:
    per run only the sums the score needs are updated (``e'Rv_j`` and ``|Rv_j|^2`` from
    ``z_k'x_j``, ``z_k'z_l`` and the coefficients ``a_kj``), so each step reads the
    validation block once and writes nothing of its size.
    """
    pool = usable_candidates(train) if pool is None else np.asarray(pool, dtype=np.intp)
    x_mean = train.X[:, pool].mean(axis=0)
    y_mean = float(train.y.mean())
    Rt = train.X[:, pool] - x_mean  # training residual columns (centred, then orthogonalised)
    r_y = train.y - y_mean  # training residual of the target
    runs = _ValidationRuns(valid, pool, x_mean, valid.y - y_mean)
    original = np.einsum("ij,ij->j", Rt, Rt)
    alive = original > 0
    size = min(max_size, pool.size)
    A = np.zeros((size, pool.size))  # a_kj: coefficient of basis vector k in column j
    chosen: list[int] = []
    scores: list[float] = []
    for step in range(size):
        norm2 = np.einsum("ij,ij->j", Rt, Rt)
        alive &= norm2 > COLLINEAR_RTOL * original
        if not alive.any():
            break
        safe = np.where(alive, norm2, 1.0)
        t = (r_y @ Rt) / safe  # coefficient of each candidate's residual (Frisch-Waugh)
        E, P, W = runs.sums(A[:step])
        sse = np.maximum(E[:, None] - 2.0 * t * P + t**2 * W, 0.0)
        score = np.sqrt(sse / runs.lengths[:, None]).mean(axis=0)
        score[~alive] = np.inf
        best = int(np.argmin(score))
        chosen.append(int(pool[best]))
        scores.append(float(score[best]))
        norm = math.sqrt(norm2[best])
        runs.add_direction(best, A[:step, best], norm, t[best] * norm)
        r_y = r_y - t[best] * Rt[:, best]
        q = Rt[:, best] / norm
        for _pass in range(2):  # "twice is enough" (Kahan/Parlett) against lost orthogonality
            a = q @ Rt
            _subtract_outer(Rt, q, a)
            A[step] += a
        alive[best] = False
    return GreedyPath(chosen, scores)


class _ValidationRuns:
    """Per-run sums over the validation block for the greedy score, updated per direction.

    With ``x`` the validation columns centred by the training means, the residual columns
    are ``Rv_j = x_j - sum_k z_k a_kj`` and the residual of the target is ``e``; per run g:
    ``e'Rv_j = e'x_j - sum_k (e'z_k) a_kj`` and
    ``|Rv_j|^2 = |x_j|^2 - 2 sum_k a_kj z_k'x_j + sum_kl a_kj a_lj z_k'z_l``.
    """

    def __init__(self, valid: Block, pool: np.ndarray, x_mean: np.ndarray,
                 e: np.ndarray) -> None:
        self.X = valid.X[:, pool] if pool.size < valid.X.shape[1] else valid.X
        self.x_mean = x_mean
        self.e = e.copy()
        self.bounds = list(itertools.pairwise(np.append(valid.starts, valid.X.shape[0])))
        self.lengths = valid.lengths.astype(float)
        self.xx = np.empty((len(self.bounds), pool.size))  # |x_j|^2 per run
        self.ex = np.empty((len(self.bounds), pool.size))  # e'x_j per run
        for g, (lo, hi) in enumerate(self.bounds):
            block = self.X[lo:hi] - x_mean
            self.xx[g] = np.einsum("ij,ij->j", block, block)
            self.ex[g] = self.e[lo:hi] @ block
        self.Z: list[np.ndarray] = []  # validation counterparts of the basis vectors
        self.B: list[np.ndarray] = []  # per direction k: z_k'x_j per run (runs x p)

    def _zx(self, z: np.ndarray) -> np.ndarray:
        """z'x_j per run, for every pool column (one read of the validation block)."""
        out = np.empty((len(self.bounds), self.X.shape[1]))
        for g, (lo, hi) in enumerate(self.bounds):
            out[g] = z[lo:hi] @ self.X[lo:hi] - z[lo:hi].sum() * self.x_mean
        return out

    def _per_run(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.array([a[lo:hi] @ b[lo:hi] for lo, hi in self.bounds])

    def sums(self, A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per run: e'e, e'Rv_j and |Rv_j|^2 for every column j (A: coefficients so far)."""
        E = self._per_run(self.e, self.e)
        if not self.Z:
            return E, self.ex.copy(), self.xx.copy()
        ez = np.stack([self._per_run(self.e, z) for z in self.Z], axis=1)  # runs x k
        P = self.ex - ez @ A
        B = np.stack(self.B, axis=1)  # runs x k x p
        ZZ = np.array([[self._per_run(zk, zl) for zl in self.Z] for zk in self.Z])
        ZZ = ZZ.transpose(2, 0, 1)  # runs x k x l
        W = self.xx - 2.0 * np.einsum("kj,gkj->gj", A, B) + \
            np.einsum("kj,gkj->gj", A, ZZ @ A)
        return E, P, W

    def add_direction(self, column: int, a: np.ndarray, norm: float, step: float) -> None:
        """Basis vector of pool column ``column`` (coefficients ``a`` on the earlier ones);
        the target residual moves by ``step`` times it."""
        z = self.X[:, column] - self.x_mean[column]
        for ak, zk in zip(a, self.Z, strict=True):
            z = z - ak * zk
        z /= norm
        b = self._zx(z)
        self.e -= step * z
        self.ex -= step * b
        self.Z.append(z)
        self.B.append(b)


def _subtract_outer(M: np.ndarray, u: np.ndarray, v: np.ndarray, rows: int = 1024) -> None:
    """``M -= outer(u, v)`` in place, a block of rows at a time (bounded temporaries)."""
    for lo in range(0, M.shape[0], rows):
        M[lo:lo + rows] -= u[lo:lo + rows, None] * v


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
