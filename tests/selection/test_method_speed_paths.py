"""The faster paths of the placement methods (issue 26) give the selections of before.

- ``selection.pairs.PairCandidates.columns`` (one ``take`` and an in-place subtraction) forms
  the bits of the old gather-and-subtract;
- the LASSO path cut at its first kink with k active (``selectors._lars_prefix``) is the
  whole path's prefix, bit for bit, also where candidates drop out of it;
- k-means of sensors + all differences on their coordinates in the raw sensors' basis
  (``clustering.kmeans_labels``) gives scikit-learn's labels on the standardised series;
- the selections of ``kmeans``, ``kmeans+grey`` and ``lasso`` on a small field are those the
  code gave before these changes (recorded from it, commit 0ff6633).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from sklearn.cluster import KMeans
from sklearn.linear_model import lars_path
from spindlebench.selection import SelectionWarning
from spindlebench.selection.clustering import KMEANS_STARTS, kmeans_labels
from spindlebench.selection.differences import pairwise_differences
from spindlebench.selection.pairs import PairCandidates
from spindlebench.selection.registry import parse_method, select_with
from spindlebench.selection.selectors import LARS_MAX_ITER, _lars_prefix
from spindlebench.selection.similarity import standardized


def field(n_nodes: int, samples: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Warm-up rises of ``n_nodes`` nodes (noise, 0.1 K steps), all their differences, and
    a drift made of a few of them."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, samples)[:, None]
    tau = rng.uniform(0.05, 1.5, n_nodes)
    gain = rng.uniform(0.2, 8.0, n_nodes)
    T = gain * (1 - np.exp(-t / tau)) + rng.normal(0, 0.05, (samples, n_nodes))
    T = np.round(T / 0.1) * 0.1
    T = T - T[0]
    y = 4.0 * T[:, 1] - 2.5 * T[:, n_nodes // 2] + 1.5 * (T[:, -1] - T[:, 2])
    y = y + rng.normal(0, 0.3, samples)
    return np.hstack([T, pairwise_differences(T)]), y - y[0]


@pytest.fixture(scope="module")
def small_field() -> tuple[np.ndarray, np.ndarray]:
    return field(14, 60, 0)  # 14 nodes + 91 differences; 14 < 60 samples: the basis path


def test_pair_columns_are_the_old_bits():
    rng = np.random.default_rng(3)
    raw = np.round(rng.normal(size=(50, 9)).cumsum(axis=0) / 0.1) * 0.1
    raw[:, 4] = -0.0  # signed zeros and a constant sensor survive unchanged
    candidates = PairCandidates(raw)
    index = rng.permutation(candidates.n_candidates)[:30]
    first, second = candidates._pairs
    padded = np.hstack([raw, np.zeros((raw.shape[0], 1))])
    old = np.ascontiguousarray(padded[:, first[index]] - padded[:, second[index]])
    new = candidates.columns(index)
    assert new.flags.c_contiguous
    assert new.view(np.int64).tolist() == old.view(np.int64).tolist()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_lars_prefix_is_the_whole_paths_prefix(seed):
    rng = np.random.default_rng(seed)
    Z = rng.normal(size=(40, 60))
    Z[:, 1] = Z[:, 0] + 0.05 * rng.normal(size=40)  # near-collinear: candidates drop out
    y = Z[:, 0] - 0.8 * Z[:, 1] + Z[:, 5] + 0.1 * rng.normal(size=40)
    y = y - y.mean()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, _, whole = lars_path(Z, y, method="lasso", max_iter=LARS_MAX_ITER)
        for k in (1, 3, 8, 20):
            prefix = _lars_prefix(Z, y, k)
            kinks = prefix.shape[1]
            assert ((prefix != 0).sum(axis=0) >= k).any()
            assert prefix.view(np.int64).tolist() == whole[:, :kinks].view(np.int64).tolist()


def test_kmeans_on_basis_coordinates_gives_sklearns_labels(small_field):
    X, _ = small_field
    points = standardized(X).T
    for k in (2, 4):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            expected = KMeans(k, n_init=KMEANS_STARTS, random_state=0).fit(points).labels_
        assert kmeans_labels(X, k, 0).tolist() == expected.tolist()


#: ``select_with`` on ``field(14, 60, 0)`` before issue 26's changes: (selected, cluster sizes)
BEFORE = {
    ("kmeans", 2): ([32, 59], [53, 52]),
    ("kmeans", 3): ([32, 59, 84], [46, 25, 34]),
    ("kmeans", 5): ([32, 39, 59, 84, 44], [30, 16, 22, 29, 8]),
    ("kmeans+grey", 2): ([32, 30], [53, 52]),
    ("kmeans+grey", 3): ([32, 99, 55], [46, 25, 34]),
    ("kmeans+grey", 5): ([32, 39, 21, 30, 51], [30, 16, 22, 29, 8]),
    ("lasso", 2): ([32, 31], [1, 1]),
    ("lasso", 3): ([32, 31, 59], [1, 1, 1]),
    ("lasso", 5): ([32, 31, 59, 103, 1], [1, 1, 1, 1, 1]),
    ("elastic-net", 5): ([32, 31, 1, 39, 47], [1, 1, 1, 1, 1]),
}


@pytest.mark.parametrize(("label", "k"), list(BEFORE))
def test_selections_are_those_of_before(small_field, label, k):
    X, y = small_field
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SelectionWarning)
        selection = select_with(parse_method(label), X, y, k)
    got = ([int(i) for i in selection.selected], [len(c) for c in selection.clusters])
    assert got == BEFORE[(label, k)]
