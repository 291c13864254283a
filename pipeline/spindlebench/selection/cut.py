"""Lambda-cut of the fuzzy equivalence matrix into clusters (eq. 3 of Xu et al. 2023).

Candidates i and j share a cluster at threshold eta when t(R)_ij >= eta. Because t(R) is the
single-linkage closure, the clusters at eta are the connected components of the maximum
spanning tree's edges with similarity >= eta, and the distinct off-diagonal values of t(R) are
exactly the tree's edge similarities. So the number of clusters at eta is
1 + #(tree edges with similarity < eta), which lets ``cut_for_clusters`` pick eta without
scanning the matrix. It gives the same clusters whether it is handed R or t(R).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from spindlebench.selection.closure import (
    SpanningTree,
    check_similarity,
    maximum_spanning_tree,
)
from spindlebench.selection.errors import SelectionError, SelectionWarning, check_n_clusters


@dataclass(frozen=True)
class Cut:
    """Result of a cut: the threshold and the clusters (index arrays, each sorted, clusters
    ordered by their first member)."""

    eta: float
    clusters: list[np.ndarray]

    @property
    def labels(self) -> np.ndarray:
        """Cluster number of every candidate."""
        n = sum(len(members) for members in self.clusters)
        labels = np.empty(n, dtype=np.intp)
        for number, members in enumerate(self.clusters):
            labels[members] = number
        return labels


#: ``_components`` groups at most this many vertices by their roots in one Python pass
#: (the sweep's cuts have 6 to 21 candidates, where NumPy's unique, sorts and split took
#: most of a cut's time); more by sorting.
FEW_VERTICES = 256


def _components(n: int, child: np.ndarray, parent: np.ndarray) -> list[np.ndarray]:
    """Connected components of a forest cut from a spanning tree (edges child -> parent),
    ordered by first member.

    Each vertex points to its parent; pointer jumping (root = root[root]) finds every
    vertex's root in log2(depth) vectorised passes, without building a graph (SciPy's
    ``connected_components`` took ~1 s of imports on this machine, for a forest).
    """
    root = np.arange(n)
    root[child] = parent
    while True:
        jumped = root[root]
        if np.array_equal(jumped, root):
            break
        root = jumped
    if n <= FEW_VERTICES:  # one pass in vertex order: each cluster opens at its first member
        clusters: dict[int, list[int]] = {}
        for vertex, vertex_root in enumerate(root.tolist()):
            clusters.setdefault(vertex_root, []).append(vertex)
        return [np.array(members, dtype=np.intp) for members in clusters.values()]
    _, first_member, labels = np.unique(root, return_index=True, return_inverse=True)
    ranked = np.argsort(first_member, kind="stable")  # clusters by their first member
    rank = np.empty_like(ranked)
    rank[ranked] = np.arange(ranked.size)
    labels = rank[labels]
    members = np.argsort(labels, kind="stable")  # each cluster's members, ascending
    bounds = np.cumsum(np.bincount(labels, minlength=ranked.size))[:-1]
    return np.split(members, bounds)


def cut_at(T: np.ndarray, eta: float) -> Cut:
    """Clusters of the cut t(R) >= ``eta``; ``eta`` is a finite number in [0, 1] (NaN would
    cut every edge, 2.0 silently give singletons)."""
    T = check_similarity(T)
    if isinstance(eta, bool) or not isinstance(eta, (int, float, np.integer, np.floating)) \
            or not 0.0 <= float(eta) <= 1.0:
        raise SelectionError(f"the cut threshold eta must be a number in [0, 1], got {eta!r}")
    child, parent, weight = maximum_spanning_tree(T).edges()
    keep = weight >= eta
    return Cut(eta=float(eta), clusters=_components(T.shape[0], child[keep], parent[keep]))


def cut_for_clusters(T: np.ndarray, n_clusters: int) -> Cut:
    """The cut with the smallest eta among the distinct values of t(R) giving at least
    ``n_clusters`` clusters.

    When tied similarities make exactly ``n_clusters`` impossible, a ``SelectionWarning`` says
    so and the finer partition (more clusters) is returned.
    """
    T = check_similarity(T)
    check_n_clusters(n_clusters, T.shape[0])
    return cut_tree_for_clusters(maximum_spanning_tree(T), n_clusters)


def cut_tree_for_clusters(tree: SpanningTree, n_clusters: int) -> Cut:
    """``cut_for_clusters`` from a maximum spanning tree of R alone (no n x n matrix): the
    selection over sensors and all their differences builds the tree row by row."""
    n = tree.order.size
    check_n_clusters(n_clusters, n)
    child, parent, weight = tree.edges()
    sorted_weights = np.sort(weight)
    # distinct values of t(R), ascending: np.unique's result without its import of numpy.ma
    # (~30 ms of the start-up of ``spindlebench evaluate``)
    levels = np.sort(np.append(weight, 1.0))
    levels = levels[np.append(True, levels[1:] != levels[:-1])]
    counts = 1 + np.searchsorted(sorted_weights, levels, side="left")
    reachable = np.flatnonzero(counts >= n_clusters)
    if reachable.size == 0:
        raise SelectionError(
            f"cannot make {n_clusters} clusters: at most {counts[-1]} candidates are "
            f"distinguishable (the others have similarity 1 with each other)"
        )
    eta = float(levels[reachable[0]])
    keep = weight >= eta
    clusters = _components(n, child[keep], parent[keep])
    if len(clusters) != n_clusters:
        warnings.warn(
            f"tied similarities: no threshold gives exactly {n_clusters} clusters; "
            f"using eta={eta:.6g} with {len(clusters)} clusters",
            SelectionWarning,
            stacklevel=3,
        )
    return Cut(eta=eta, clusters=clusters)
