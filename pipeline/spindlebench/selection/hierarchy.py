"""The fuzzy equivalence hierarchy as a SciPy linkage matrix, for dendrograms.

t(R) is an ultrametric similarity: cutting it at every eta gives nested partitions. The same
hierarchy is single linkage on the distance 1 - similarity, so it can be drawn with
``scipy.cluster.hierarchy.dendrogram(linkage_from_similarity(R))``; the cut at eta is a
horizontal line at height 1 - eta.
"""

from __future__ import annotations

import numpy as np

from spindlebench.selection.closure import check_similarity, maximum_spanning_tree


def linkage_from_similarity(R: np.ndarray) -> np.ndarray:
    """SciPy linkage matrix (n-1 x 4) of the single-linkage hierarchy of R (or of t(R)).

    Heights are distances 1 - similarity, non-decreasing; ties merge in tree order.
    """
    R = check_similarity(R)
    n = R.shape[0]
    child, parent, weight = maximum_spanning_tree(R).edges()
    order = np.argsort(-weight, kind="stable")
    cluster_of = np.arange(n)  # union-find over leaves -> current scipy cluster id
    root = np.arange(n)
    size = {i: 1 for i in range(n)}

    def find(i: int) -> int:
        while root[i] != i:
            root[i] = root[root[i]]
            i = root[i]
        return i

    Z = np.empty((n - 1, 4))
    for step, edge in enumerate(order):
        a, b = find(int(child[edge])), find(int(parent[edge]))
        ida, idb = cluster_of[a], cluster_of[b]
        new_id = n + step
        Z[step] = [min(ida, idb), max(ida, idb), 1.0 - weight[edge], size[ida] + size[idb]]
        size[new_id] = size.pop(ida) + size.pop(idb)
        root[b] = a
        cluster_of[a] = new_id
    return Z
