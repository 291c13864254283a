"""Lambda-cut (eq. 3): cluster counts per threshold, choice of eta, ties, bad k."""

import warnings

import numpy as np
import pytest
from scipy.cluster.hierarchy import fcluster
from selection_data import HAND_R, HAND_T, random_similarity
from spindlebench.selection import (
    SelectionError,
    SelectionWarning,
    closure_minimax,
    cut_at,
    cut_for_clusters,
    linkage_from_similarity,
)


def members(cut):
    return [m.tolist() for m in cut.clusters]


@pytest.mark.parametrize(("k", "eta", "clusters"), [
    (1, 0.3, [[0, 1, 2, 3]]),
    (2, 0.6, [[0, 2, 3], [1]]),
    (3, 0.8, [[0, 2], [1], [3]]),
    (4, 1.0, [[0], [1], [2], [3]]),
])
def test_hand_example_cuts(k, eta, clusters):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no tie warning here
        cut = cut_for_clusters(HAND_T, k)
    assert cut.eta == eta
    assert members(cut) == clusters
    assert members(cut_for_clusters(HAND_R, k)) == clusters  # R gives the same cut


def test_cut_at_matches_boolean_equivalence_classes():
    tr = closure_minimax(random_similarity(30, 5))
    for eta in np.unique(tr)[::3]:
        cut = cut_at(tr, eta)
        for cluster in cut.clusters:
            block = tr[np.ix_(cluster, cluster)] >= eta
            assert block.all()
        labels = cut.labels
        assert np.all((tr >= eta) == (labels[:, None] == labels[None, :]))


def test_eta_is_smallest_distinct_value_reaching_k():
    tr = closure_minimax(random_similarity(25, 8))
    for k in range(1, 26):
        cut = cut_for_clusters(tr, k)
        assert len(cut.clusters) == k  # no ties in continuous random data
        assert cut.eta in tr
        smaller = np.unique(tr[tr < cut.eta])
        if smaller.size:
            assert len(cut_at(tr, smaller[-1]).clusters) < k


def test_ties_warn_and_return_finer_partition():
    R = np.full((3, 3), 0.5)
    np.fill_diagonal(R, 1.0)
    with pytest.warns(SelectionWarning, match="no threshold gives exactly 2 clusters"):
        cut = cut_for_clusters(R, 2)
    assert len(cut.clusters) == 3 and cut.eta == 1.0


@pytest.mark.parametrize(("k", "message"), [(0, "at least 1"), (-2, "at least 1"),
                                            (5, "larger than the number of candidates"),
                                            (2.5, "integer")])
def test_bad_k(k, message):
    with pytest.raises(SelectionError, match=message):
        cut_for_clusters(HAND_T, k)


def test_identical_candidates_cannot_be_separated():
    R = np.ones((3, 3))
    with pytest.raises(SelectionError, match="at most 1 candidates are distinguishable"):
        cut_for_clusters(R, 2)


def test_linkage_gives_the_same_clusters_as_the_cut():
    R = random_similarity(20, 9)
    Z = linkage_from_similarity(R)
    assert np.all(np.diff(Z[:, 2]) >= 0) and Z[-1, 3] == 20
    for k in (2, 3, 5, 8):
        cut = cut_for_clusters(closure_minimax(R), k)
        labels = fcluster(Z, k, criterion="maxclust")
        ours = cut.labels
        assert np.all((labels[:, None] == labels[None, :]) == (ours[:, None] == ours[None, :]))


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("n", [21, 300])
def test_forest_components_are_scipys_connected_components(seed, n, monkeypatch):
    """The cut's own component search (pointer jumping on the tree) against SciPy's graph
    search, on random spanning trees with random edges removed: same partition, same order,
    by the one-pass grouping of a few vertices and by sorting."""
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import connected_components
    from spindlebench.selection import cut
    from spindlebench.selection.cut import _components

    rng = np.random.default_rng(seed)
    order = rng.permutation(n)
    child = order[1:]
    parent = np.array([order[rng.integers(0, i)] for i in range(1, n)])
    keep = rng.random(n - 1) < 0.75
    ours = _components(n, child[keep], parent[keep])
    monkeypatch.setattr(cut, "FEW_VERTICES", 0)
    sorted_way = _components(n, child[keep], parent[keep])
    assert [c.tolist() for c in ours] == [c.tolist() for c in sorted_way]
    assert all(c.dtype == np.intp for c in ours + sorted_way)
    graph = coo_array((np.ones(keep.sum()), (child[keep], parent[keep])), shape=(n, n))
    count, labels = connected_components(graph, directed=False)
    first = [np.flatnonzero(labels == label)[0] for label in range(count)]
    theirs = [np.flatnonzero(labels == label) for label in np.argsort(first)]
    assert len(ours) == count > 1
    assert [c.tolist() for c in ours] == [c.tolist() for c in theirs]
