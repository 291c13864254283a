"""Selection over raw sensors and all their pairwise differences, without the n x n matrix.

With m raw sensors the paper's candidate set has n = m + m(m-1)/2 members (500 sensors:
125 250), and R alone would take 8 n^2 bytes (125 GB). But every candidate is linear in the
raw rises: after centring, candidate b = (i, k) is the column Xc (e_i - e_k) (a raw sensor is
(i, none)). With the QR factorisation Xc = Q G (G is m x m), that column is s_b = G (e_i - e_k)
in an orthonormal basis, so

    corr(a, b) = (s_a / |s_a|) . s_b / |s_b| = (u_i - u_k) / |s_b|,   u = G^T s_a / |s_a|,

and the row of R for candidate a costs one m x m product plus O(n). Prim's algorithm on the
complete graph asks for each row once, so the maximum spanning tree (which is all the closure
and the cut need, see ``closure`` and ``cut``) takes O(n^2 + n m^2) time and O(n) memory.

Precision: a difference of coefficient columns loses eps |x_i| / |x_i - x_k| like the explicit
difference of two data columns does; forming the m x m covariance instead would square that
factor. The values of R differ from the matrix path's only by rounding (~1e-15).

Constant candidates and overflowing differences are found from the candidate columns
themselves, one sensor's differences at a time, with the matrix path's rule, so the same ones
are dropped or refused.
psi follows from the raw sensors' covariances with the target like R's rows do.

Above ``COMPILED_ABOVE`` candidates Prim's loop is compiled with Numba (``prim_kernel``): a
symmetric similarity (the unit vectors' dot product in a fixed order), a vectorised screen
through the Gram matrix per block of candidates and lazy links; the same clusters as the
NumPy rows to rounding (on exact ties it may build another maximum spanning tree of R, with
the same weights and cuts to rounding). Below, the m x m product of each row is BLAS, kept
single-threaded (a product per row gains nothing from threads on a shared machine).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from threadpoolctl import threadpool_limits

from spindlebench.selection.closure import SpanningTree, closure_from_tree, prim_tree
from spindlebench.selection.cut import cut_tree_for_clusters
from spindlebench.selection.differences import pair_indices
from spindlebench.selection.errors import (
    SelectionError,
    SelectionOverflowError,
    check_n_clusters,
    check_names,
    column_list,
)
from spindlebench.selection.select import Selection, assemble, check_counts, split_constant
from spindlebench.selection.similarity import (
    constant_by_range,
    constant_columns,
    standardized,
)

#: ``evaluate``, ``select_sensitive_points`` (and so ``FuzzyClusterSelector`` and the
#: placement study) select row-wise above this many candidates (R would take over 32 MB) and
#: form R below, where the matrix path's results stay exactly as they were.
ROW_WISE_ABOVE = 2000
#: R and t(R) of the row-wise selection are formed on request only up to this many
#: candidates (two 8 n^2-byte matrices).
MAX_FORMED_CANDIDATES = 6000


@dataclass(frozen=True)
class PairCandidates:
    """Raw rises (n_samples x m) and, implicitly, the candidates made of them: the raw
    columns (if ``include_raw``) followed by every difference A-B in ``pair_indices`` order,
    exactly the columns ``CandidateSet.matrix`` and ``PairwiseDifferences`` form."""

    raw: np.ndarray
    include_raw: bool = True

    @cached_property
    def _pairs(self) -> tuple[np.ndarray, np.ndarray]:
        """(first, second) sensor of every candidate; second == m for a raw sensor."""
        m = self.raw.shape[1]
        first, second = pair_indices(m)
        if not self.include_raw:
            return first, second
        return np.concatenate([np.arange(m), first]), np.concatenate([np.full(m, m), second])

    @property
    def n_sensors(self) -> int:
        return self.raw.shape[1]

    @property
    def n_candidates(self) -> int:
        return self._pairs[0].size

    def columns(self, index: np.ndarray) -> np.ndarray:
        """Values of candidates ``index`` as C-ordered columns (n_samples x len(index)), the
        matrix ``CandidateSet.matrix`` forms (same subtraction, same bits), for the methods
        that need it formed."""
        first, second = self._pairs
        padded = np.hstack([self.raw, np.zeros((self.raw.shape[0], 1))])  # x - 0.0 is x
        # ``take`` along the columns writes C order (``padded[:, index]`` gives a transposed
        # layout that needed a second copy): one gather, one in-place subtraction, 3.6x faster
        # on 2 888 x 3 321 (bench_placement's greedy+diff), the same bits.
        out = np.take(padded, first[index], axis=1)
        out -= np.take(padded, second[index], axis=1)
        return out

    def blocks(self, columns: np.ndarray) -> Iterator[tuple[slice, np.ndarray]]:
        """The candidates built from ``columns`` (one per raw sensor, any leading shape) in
        contiguous pieces: (candidate slice, values with the candidates on the last axis).

        First the raw sensors (all of them, if included), then for each sensor i its
        differences with every later sensor, ``columns[..., i] - columns[..., i+1:]``
        (``pair_indices`` order), so no index array is gathered."""
        m = self.n_sensors
        start = 0
        if self.include_raw:
            yield slice(0, m), columns
            start = m
        for i in range(m - 1):
            stop = start + m - 1 - i
            yield slice(start, stop), columns[..., i:i + 1] - columns[..., i + 1:]
            start = stop


def sensors_with_differences(X: np.ndarray) -> int | None:
    """m if the columns of ``X`` are m raw sensors followed by every difference of them in
    ``pair_indices`` order, bit for bit as ``PairwiseDifferences`` and ``CandidateSet`` form
    them; otherwise None. Checked one sensor's differences at a time (no copy of ``X``); a
    matrix of another shape or content fails at its first block."""
    n = X.shape[1]
    m = (math.isqrt(8 * n + 1) - 1) // 2
    if m < 2 or m * (m + 1) // 2 != n:
        return None
    candidates = PairCandidates(X[:, :m])
    for where, values in candidates.blocks(X[:, :m]):
        if where.start >= m and not np.array_equal(X[:, where], values):
            return None
    return m


def check_candidates(candidates: PairCandidates, names: Sequence[str] | None) -> np.ndarray:
    """The constant candidates (``similarity.constant_columns``' rule, ``constant_by_range``:
    the same mask as on the formed matrix), in one pass that also refuses, naming them,
    candidates where two finite values subtract to inf."""
    spread = np.empty(candidates.n_candidates)
    magnitude = np.empty(candidates.n_candidates)
    with np.errstate(over="ignore", invalid="ignore"):
        for where, values in candidates.blocks(np.ascontiguousarray(candidates.raw.T).T):
            high, low = values.max(axis=0), values.min(axis=0)
            finite = np.isfinite(high) & np.isfinite(low)  # a NaN or inf reaches both
            if not finite.all():
                raise SelectionOverflowError(
                    "values too large for rises and differences (overflow) in "
                    f"{column_list(np.arange(where.start, where.stop)[~finite], names)}"
                )
            spread[where] = high - low
            magnitude[where] = np.maximum(np.abs(high), np.abs(low))
    return constant_by_range(spread, magnitude)


@dataclass(frozen=True)
class PairGeometry:
    """The candidates as vectors in an orthonormal basis of the centred raw rises."""

    factor: np.ndarray  #: G of Xc = Q G (r x m), r = min(n_samples, m)
    first: np.ndarray  #: per candidate, its first sensor
    second: np.ndarray  #: per candidate, its second sensor (m: none, a raw sensor)
    inverse_norm: np.ndarray  #: 1 / |s_b| per candidate

    @classmethod
    def of(cls, candidates: PairCandidates, centred: np.ndarray) -> PairGeometry:
        """G from the raw rises ``centred`` (``standardized_centre``), and the norms."""
        with threadpool_limits(limits=1, user_api="blas"), np.errstate(all="ignore"):
            factor = np.linalg.qr(centred, mode="r")
        first, second = candidates._pairs
        norms = np.empty(first.size)
        for where, vectors in candidates.blocks(factor):
            norms[where] = np.sqrt(np.einsum("ij,ij->j", vectors, vectors))
        with np.errstate(divide="ignore", invalid="ignore"):
            inverse = 1.0 / norms
        return cls(factor, first, second, inverse)

    def correlations(self, centred: np.ndarray, kept: np.ndarray, y: np.ndarray) -> np.ndarray:
        """psi of every candidate (NaN where not ``kept``): the correlation of a difference
        is the difference of the raw sensors' covariances with the unit-norm target, over
        the candidate's norm; the same as ``correlation_with`` on the column, to rounding."""
        if constant_columns(y[:, None])[0]:
            raise SelectionError("the target (thermal error) is constant; no correlation exists")
        zy = standardized(y[:, None], ["the target"])[:, 0]
        covariance = np.append(centred.T @ zy, 0.0)
        psi = np.full(self.first.size, np.nan)
        psi[kept] = np.clip((covariance[self.first[kept]] - covariance[self.second[kept]])
                            * self.inverse_norm[kept], -1.0, 1.0)
        return psi

    def check_finite(self, kept: np.ndarray, names: Sequence[str] | None) -> None:
        """Overflow error naming the candidates whose sum of squares is not finite (their
        correlations would be silently 0), as ``standardized`` refuses them."""
        norms_bad = ~(np.isfinite(self.inverse_norm[kept]) & (self.inverse_norm[kept] > 0))
        if norms_bad.any():
            raise SelectionOverflowError(
                f"values too large to correlate (overflow) in "
                f"{column_list(kept[norms_bad], names)}"
            )

    def rows_of(self, kept: np.ndarray) -> Callable[[int, np.ndarray], np.ndarray]:
        """The row of R over ``kept`` for the v-th of them, at the positions ``outside`` of
        ``kept`` (``closure.prim_tree``'s ``row``): the same arithmetic as the compiled
        kernel's rows. What depends on ``outside`` alone is kept until it changes; every
        candidate's unit direction (s_b / |s_b|, r numbers) is made at once (elementwise, the
        same bits as one at a time; 8 n r bytes, at most 11 MB below ``COMPILED_ABOVE``)."""
        first, second = self.first[kept], self.second[kept]
        inverse = self.inverse_norm[kept]
        factor_rows = np.vstack([self.factor.T, np.zeros((1, self.factor.shape[0]))])
        directions = factor_rows[first] - factor_rows[second]
        directions *= inverse[:, None]
        factor_t = self.factor.T
        u = np.zeros(self.factor.shape[1] + 1)
        projected = u[:-1]
        cached: list = [None, first, second, inverse]

        def row(vertex: int, outside: np.ndarray) -> np.ndarray:
            if cached[0] is not outside:
                cached[:] = [outside, first[outside], second[outside], inverse[outside]]
            _, ahead, behind, scale = cached
            np.matmul(factor_t, directions[vertex], out=projected)
            values = u[ahead]
            values -= u[behind]
            np.abs(values, out=values)
            values *= scale
            return np.minimum(values, 1.0, out=values)

        return row

    def similarity(self, kept: np.ndarray) -> np.ndarray:
        """R over ``kept`` formed from the vectors (only for small candidate sets)."""
        if kept.size > MAX_FORMED_CANDIDATES:
            raise SelectionError(
                f"R of {kept.size} candidates is not formed by the row-wise selection "
                f"(at most {MAX_FORMED_CANDIDATES}, 8 n^2 bytes each); its tree, clusters and "
                f"psi are available"
            )
        padded = np.hstack([self.factor, np.zeros((self.factor.shape[0], 1))])
        vectors = (padded[:, self.first[kept]] - padded[:, self.second[kept]])
        vectors *= self.inverse_norm[kept]
        R = np.abs(vectors.T @ vectors)
        upper = np.triu(R, k=1)
        R = upper + upper.T
        np.clip(R, 0.0, 1.0, out=R)
        np.fill_diagonal(R, 1.0)
        return R


def standardized_centre(X: np.ndarray) -> np.ndarray:
    """Columns centred twice, the centring ``standardized`` applies before scaling."""
    centred = X - X.mean(axis=0)
    centred -= centred.mean(axis=0)
    return centred


#: Vertices per compiled call: between calls Python can act on Ctrl-C.
PRIM_BATCH = 512
#: [visits, screened passes, exact similarities formed, links replaced] of the compiled
#: Prim loops in this process (for the bench; they only grow).
PRIM_COUNTS = np.zeros(4, dtype=np.int64)
#: Above this many candidates Prim's loop runs compiled (``prim_kernel``); below, NumPy rows
#: (``closure.prim_tree``) cost less than importing Numba and loading its code (~1 s of CPU
#: here; NumPy took 0.33 s for the 5 050 candidates of 100 sensors).
COMPILED_ABOVE = 10000


def maximum_spanning_tree_of_pairs(
    geometry: PairGeometry, kept: np.ndarray, screen: bool = True
) -> SpanningTree:
    """Prim's algorithm over the ``kept`` candidates, one row of R at a time.

    The same rules as ``closure.maximum_spanning_tree`` on the matrix (start at the first
    candidate, take the largest link, the first one on ties, and a parent only changes on a
    strictly larger similarity). The NumPy rows build the matrix path's tree on exact ties;
    the compiled loop's similarity differs from theirs in the last bits, so on ties it may
    build another maximum spanning tree (weights equal to rounding; the same clusters at
    every cut unless two similarities within rounding of each other straddle it).
    ``screen=False``: the compiled loop forms every similarity exactly (the tests'
    reference for the screen, far slower).
    """
    kept = np.asarray(kept, dtype=np.int64)
    if not np.all(np.isfinite(geometry.inverse_norm[kept])):
        raise SelectionError("a spanning tree needs non-constant candidates (a finite, "
                             "nonzero norm); drop the constant ones first (check_candidates)")
    if kept.size <= COMPILED_ABOVE:
        with threadpool_limits(limits=1, user_api="blas"):
            return prim_tree(kept.size, geometry.rows_of(kept))
    from spindlebench.selection.prim_kernel import block_top, prim_blocks

    factor = np.ascontiguousarray(geometry.factor)
    r, m = factor.shape
    first, second = geometry.first, geometry.second
    n_all = first.size
    lengths = np.minimum(np.where(second == m, first, second) + 1, r).astype(np.int64)
    blocks = candidate_blocks(m, include_raw=bool(n_all and second[0] == m))
    block_of = np.repeat(np.arange(blocks.shape[0]), blocks[:, 3])
    active = np.zeros(n_all, dtype=bool)
    active[kept] = True
    low = np.full(n_all, -np.inf)  # each link's interval; -inf: none yet (exactly)
    high = low.copy()
    exact = np.ones(n_all, dtype=np.bool_)
    parent = np.full(n_all, -1, dtype=np.int64)
    threshold = np.where(active, -np.inf, np.inf).astype(np.float32)
    block_alive = np.bincount(block_of[kept], minlength=blocks.shape[0]).astype(np.int64)
    tops = np.array([block_top(high, active, offset, count) for offset, count in blocks[:, 2:]],
                    dtype=np.int64)
    order = np.empty(kept.size, dtype=np.int64)
    weight = np.ones(n_all)
    tree_parent = np.full(n_all, -1, dtype=np.int64)
    # C order: each candidate's unit vector reads one row (vstack of a transposed array
    # keeps its Fortran order, and a row was then r cache lines apart: ~12 % of the loop
    # at 1 000 sensors went to forming unit vectors); the same numbers, the same bits.
    factor_rows = np.ascontiguousarray(np.vstack([factor.T, np.zeros((1, r))]))
    norms = np.append(np.sqrt(np.einsum("ij,ij->j", factor, factor)), 0.0)
    with threadpool_limits(limits=1, user_api="blas"):
        gram = np.zeros((m + 1, m + 1))
        for block in range(0, m, 256):  # small blocks: one BLAS thread, little memory
            gram[block:min(block + 256, m), :m] = factor[:, block:block + 256].T @ factor
    for start in range(0, kept.size, PRIM_BATCH):
        prim_blocks(factor_rows, gram, norms, first, second, geometry.inverse_norm, lengths,
                    blocks, block_alive, block_of, tops, active, low, high, exact, parent,
                    threshold, order, weight, tree_parent, start,
                    min(start + PRIM_BATCH, kept.size),
                    screen, PRIM_COUNTS)
    local = np.full(n_all, -1, dtype=np.intp)
    local[kept] = np.arange(kept.size)
    parents = np.full(kept.size, -1, dtype=np.intp)
    parents[local[order[1:]]] = local[tree_parent[order[1:]]]
    return SpanningTree(order=local[order], parent=parents, weight=weight[kept])


def candidate_blocks(m: int, include_raw: bool) -> np.ndarray:
    """(fixed sensor, first k, offset, length) of each contiguous block of candidates in
    ``PairCandidates`` order: the raw sensors (k = 0..m-1 against the zero row m), then the
    differences (i, k), k = i+1..m-1, of each sensor i (empty blocks left out)."""
    rows = [(m, 0, 0, m)] if include_raw else []
    offset = m if include_raw else 0
    for i in range(m - 1):
        rows.append((i, i + 1, offset, m - 1 - i))
        offset += m - 1 - i
    return np.array(rows, dtype=np.int64).reshape(-1, 4)


class PairSelection:
    """``select_among_pairs`` for several k on one candidate set and target: the checks, the
    constant candidates, the geometry, psi and Prim's tree (which do not depend on k, and
    take nearly all the time) are done once, then :meth:`select` cuts the tree for each k.

    A placement study asks for k = m clusters for every budget m: with 500 nodes and all
    their differences one tree takes seconds (minutes at 1 000), so building it once per
    budget would multiply that by the number of budgets for the same result.

    ``n_clusters`` is the largest k that will be asked for: the counts are checked against
    it (and constant candidates dropped, with their warning) here, as
    ``select_among_pairs`` does for its one k.
    """

    def __init__(self, raw: np.ndarray, y: np.ndarray, n_clusters: int,
                 include_raw: bool = True, names: Sequence[str] | None = None) -> None:
        raw = np.asarray(raw, dtype=float)
        y = np.asarray(y, dtype=float).ravel()
        if raw.ndim != 2:
            raise SelectionError(f"raw sensors must be a 2-D array, got shape {raw.shape}")
        candidates = PairCandidates(raw, include_raw)
        check_counts(raw.shape[0], candidates.n_candidates, y, n_clusters)
        if not (np.all(np.isfinite(raw)) and np.all(np.isfinite(y))):
            raise SelectionError("candidates and target must be finite (no NaN or inf)")
        if names is not None:
            names = [str(name) for name in names]
            check_names(names, candidates.n_candidates)
        self.n_clusters = n_clusters
        self.kept, self.dropped = split_constant(check_candidates(candidates, names), names,
                                                 n_clusters)
        centred = standardized_centre(raw)
        self.geometry = PairGeometry.of(candidates, centred)
        self.geometry.check_finite(self.kept, names)
        self.psi = self.geometry.correlations(centred, self.kept, y)
        self.tree = maximum_spanning_tree_of_pairs(self.geometry, self.kept)

    def select(self, n_clusters: int) -> Selection:
        """The selection with ``n_clusters`` clusters (at most the ``n_clusters`` given)."""
        if n_clusters > self.n_clusters:
            raise SelectionError(f"{n_clusters} clusters asked of a pair selection prepared "
                                 f"for at most {self.n_clusters}")
        check_n_clusters(n_clusters, self.psi.size, "feature(s)")
        kept, geometry, tree = self.kept, self.geometry, self.tree
        cut = cut_tree_for_clusters(tree, n_clusters)

        def similarity() -> np.ndarray:
            return geometry.similarity(kept)

        def closure() -> np.ndarray:
            if kept.size > MAX_FORMED_CANDIDATES:
                geometry.similarity(kept)  # the same size error
            return closure_from_tree(tree)

        return assemble(kept, self.dropped, similarity, closure, cut, self.psi)


def select_among_pairs(
    raw: np.ndarray,
    y: np.ndarray,
    n_clusters: int,
    include_raw: bool = True,
    names: Sequence[str] | None = None,
) -> Selection:
    """``select_sensitive_points`` (abs-pearson, fast closure) on the raw sensors ``raw``
    (rises, n_samples x m) plus all their pairwise differences, without forming the
    candidate matrix or R: the same clusters, eta (to rounding) and psi.

    ``names`` name the candidates (``CandidateSet.names`` order) for the messages.
    """
    return PairSelection(raw, y, n_clusters, include_raw, names).select(n_clusters)
