"""Max-min transitive closure t(R) of a fuzzy similarity matrix (eq. 2 of Xu et al. 2023).

Two implementations with identical results (only min and max of entries of R are taken, so
the agreement is exact, not approximate):

- ``closure_by_squaring``: the paper's R -> R^2 -> R^4 ... with the max-min product, until a
  squaring changes nothing. O(n^3 log n); vectorised and chunked so it is a fair baseline.
- ``closure_minimax``: t(R)_ij is the largest "bottleneck" similarity over all paths from i to
  j, which is attained on the path through a maximum spanning tree (single linkage). Prim's
  algorithm on the dense matrix and one pass over the tree give it in O(n^2).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from spindlebench.selection.errors import SelectionError

CLOSURES: tuple[str, ...] = ("fast", "squaring")

#: Memory per chunk of the max-min product (bytes).
CHUNK_BYTES = 64 * 2**20


def check_similarity(R: np.ndarray) -> np.ndarray:
    """``R`` as a float array, checked to be a square, symmetric, reflexive matrix in [0, 1]."""
    R = np.asarray(R, dtype=float)
    if R.ndim != 2 or R.shape[0] != R.shape[1] or R.shape[0] == 0:
        raise SelectionError(f"a similarity matrix must be square and non-empty, got {R.shape}")
    if not np.all(np.isfinite(R)) or R.min() < 0.0 or R.max() > 1.0:
        raise SelectionError("a similarity matrix must hold finite values in [0, 1]")
    if not np.array_equal(R, R.T):
        raise SelectionError("a similarity matrix must be exactly symmetric")
    if not np.all(np.diagonal(R) == 1.0):
        raise SelectionError("a similarity matrix must have ones on the diagonal")
    return R


def maxmin_product(A: np.ndarray, B: np.ndarray, chunk_bytes: int = CHUNK_BYTES) -> np.ndarray:
    """Max-min composition (A o B)_ij = max_k min(A_ik, B_kj), in row chunks."""
    n, m = A.shape
    p = B.shape[1]
    rows = max(1, chunk_bytes // (8 * m * p))
    out = np.empty((n, p))
    for start in range(0, n, rows):
        stop = min(n, start + rows)
        out[start:stop] = np.minimum(A[start:stop, :, None], B[None, :, :]).max(axis=1)
    return out


def closure_by_squaring(R: np.ndarray, chunk_bytes: int = CHUNK_BYTES) -> np.ndarray:
    """Reference t(R): repeated max-min squaring until stable (the paper's eq. 2)."""
    current = check_similarity(R).copy()
    while True:
        squared = maxmin_product(current, current, chunk_bytes)
        if np.array_equal(squared, current):
            return current
        current = squared


@dataclass(frozen=True)
class SpanningTree:
    """A maximum spanning tree in Prim order: ``order[0]`` is the root; for every later vertex
    ``order[i]``, ``parent[order[i]]`` joined the tree before it by an edge of similarity
    ``weight[order[i]]`` (the root has parent -1 and weight 1)."""

    order: np.ndarray
    parent: np.ndarray
    weight: np.ndarray

    def edges(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(child, parent, similarity) of the n - 1 tree edges, in Prim order."""
        children = self.order[1:]
        return children, self.parent[children], self.weight[children]


def maximum_spanning_tree(R: np.ndarray) -> SpanningTree:
    """Prim's algorithm on the dense similarity matrix, O(n^2) with vectorised rows."""
    # a row of R is a view: gathering the outside vertices' entries would cost more than
    # comparing all of them
    return prim_tree(R.shape[0], lambda vertex, outside: R[vertex], compact_every=0)


#: Prim's loop drops the vertices that joined the tree from its working arrays every this
#: many steps, so each row is asked only for the vertices still outside (half of them on
#: average): fewer similarities computed and compared, the same tree. For rows computed
#: on demand (``pairs``); 0: never (all vertices, every row).
COMPACT_EVERY = 32


def prim_tree(n: int, row: Callable[[int, np.ndarray], np.ndarray],
              compact_every: int = COMPACT_EVERY) -> SpanningTree:
    """Prim's algorithm on the complete graph of ``n`` vertices: start at vertex 0, take the
    largest link, the first one (lowest index) on ties; a parent changes only on a strictly
    larger similarity.

    ``row(v, outside)`` gives the similarities from vertex ``v`` to the vertices ``outside``
    (increasing indices; it may hold some that joined the tree already, which are ignored;
    the same array object until it is compacted, every ``compact_every`` steps, so ``row``
    can keep what it derives from it). It is asked once per vertex but the last.
    """
    parent = np.full(n, -1, dtype=np.intp)
    weight = np.ones(n)
    order = np.empty(n, dtype=np.intp)
    # per entry of ``outside``: its best link to the tree so far and from which vertex;
    # ``guard`` is the same, +inf once it joined (no row raises it), ``best`` then -inf
    outside = np.arange(n)
    best = np.full(n, -np.inf)
    guard = best.copy()
    link = np.full(n, -1, dtype=np.intp)
    improves = np.empty(n, dtype=bool)
    entry = 0
    for position in range(n):
        if position > 0:
            entry = int(best.argmax())  # entries in the tree hold -inf
        vertex = int(outside[entry])
        order[position] = vertex
        if position > 0:
            weight[vertex], parent[vertex] = best[entry], link[entry]
        if position == n - 1:
            break
        best[entry], guard[entry] = -np.inf, np.inf
        if compact_every and position % compact_every == compact_every - 1:
            still = np.flatnonzero(guard != np.inf)
            outside, best, guard, link = outside[still], best[still], guard[still], link[still]
            improves = improves[:still.size]
        similarities = row(vertex, outside)
        np.greater(similarities, guard, out=improves)
        np.copyto(best, similarities, where=improves)
        np.copyto(guard, similarities, where=improves)
        np.copyto(link, vertex, where=improves)
    return SpanningTree(order=order, parent=parent, weight=weight)


def closure_minimax(R: np.ndarray) -> np.ndarray:
    """Fast t(R): minimax-path (bottleneck) similarity over a maximum spanning tree."""
    return closure_from_tree(maximum_spanning_tree(check_similarity(R)))


def closure_from_tree(tree: SpanningTree) -> np.ndarray:
    """t(R) from a maximum spanning tree of R alone (R itself is not needed).

    Vertices are visited in Prim order; each new vertex is a leaf hanging from its parent, so
    its closure with every earlier vertex u is min(edge similarity, t(parent, u)).
    """
    n = tree.order.size
    position = np.empty(n, dtype=np.intp)
    position[tree.order] = np.arange(n)
    ordered = np.empty((n, n))  # closure in Prim order, kept symmetric as it grows
    ordered[0, 0] = 1.0
    for i in range(1, n):
        vertex = tree.order[i]
        row = np.minimum(ordered[position[tree.parent[vertex]], :i], tree.weight[vertex])
        ordered[i, :i] = row
        ordered[:i, i] = row
        ordered[i, i] = 1.0
    return ordered[np.ix_(position, position)]


def transitive_closure(R: np.ndarray, method: str = "fast") -> np.ndarray:
    """t(R) by ``method``: ``fast`` (spanning tree) or ``squaring`` (the paper's reference)."""
    if method == "fast":
        return closure_minimax(R)
    if method == "squaring":
        return closure_by_squaring(R)
    raise SelectionError(f"unknown closure method {method!r}; choose one of {', '.join(CLOSURES)}")
