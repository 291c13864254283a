"""Greedy forward selection by validation RMSE: add the candidate that helps most, repeat.

The objective of a candidate set S (the placement study's, and ``GreedyForwardSelector``'s):
fit the rise model (OLS with intercept, ``regression.fit_ols``) on the training runs, predict
every validation run, and take the mean over runs of the per-run RMSE (um), as the paper
averages its Table 6. :func:`validation_score` computes it directly (the reference);
:func:`greedy_forward` computes the same number for every candidate at once.

:func:`greedy_forward` keeps the training design orthogonalised (modified Gram-Schmidt with
explicit residual columns, re-orthogonalised once), so adding candidate j is a rank-one update:
by Frisch-Waugh its coefficient is <r_j, r_y> / <r_j, r_j> on the residuals r of the current
set, and the validation residual moves along the same combination of columns applied to the
validation rows. Every step scores *all* candidates in O((n_train + n_valid) p) with a handful
of vectorised passes, instead of p separate least-squares fits.

It lives here, in the selection package, because it is one of the selection methods; the
placement study (``studies.placement.search``) adds the exhaustive search next to it.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from spindlebench.selection.regression import fit_ols
from spindlebench.selection.similarity import constant_columns

#: A candidate whose training residual keeps less than this fraction of its own squared norm
#: lies in the span of the chosen set (e.g. T_a - T_b once T_a and T_b are chosen): skipped.
COLLINEAR_RTOL = 1e-9
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
        self.X = _pool_columns(valid.X, pool)
        self.x_mean = x_mean
        self.e = e.copy()
        self.bounds = list(itertools.pairwise(np.append(valid.starts, valid.X.shape[0])))
        self.lengths = valid.lengths.astype(float)
        self.xx = np.empty((len(self.bounds), pool.size))  # |x_j|^2 per run
        self.ex = np.empty((len(self.bounds), pool.size))  # e'x_j per run
        longest = max((hi - lo for lo, hi in self.bounds), default=0)
        buffer = np.empty((longest, pool.size))  # one run's centred block, reused
        for g, (lo, hi) in enumerate(self.bounds):
            block = np.subtract(self.X[lo:hi], x_mean, out=buffer[:hi - lo])
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


def _pool_columns(X: np.ndarray, pool: np.ndarray) -> np.ndarray:
    """The ``pool`` columns of the validation block, as before: ``X`` itself when the pool
    is every column (its layout decides the bits of the sums; the training side keeps its
    ``X[:, pool]`` gather, whose layout its sums were computed in)."""
    return X[:, pool] if pool.size < X.shape[1] else X


def _subtract_outer(M: np.ndarray, u: np.ndarray, v: np.ndarray, rows: int = 1024) -> None:
    """``M -= outer(u, v)`` in place, a block of rows at a time (bounded temporaries)."""
    for lo in range(0, M.shape[0], rows):
        M[lo:lo + rows] -= u[lo:lo + rows, None] * v
