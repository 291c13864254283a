"""Clustering of the candidates: the paper's closure and the variants practitioners use.

Every variant partitions the (non-constant) candidate columns of ``X`` into ``n_clusters``
clusters; the choice of one candidate per cluster is separate (|psi| or the grey grade).

- ``closure``: the paper's fuzzy equivalence closure t(R) of the similarity R, cut at the
  threshold giving k clusters (``similarity``, ``closure``, ``cut``; single linkage on 1 - R).
- ``fcm``: fuzzy c-means (scikit-fuzzy ``cmeans``, fuzzifier m = 2) with the standardised
  candidate series as points; each candidate goes to the cluster of its largest membership.
- ``kmeans``: scikit-learn ``KMeans`` (10 starts) on the same standardised series.
- ``average``, ``complete``: SciPy hierarchical clustering on the distance 1 - R, the same
  distance whose single linkage the closure is, so only the linkage differs.
- ``ward``: SciPy Ward linkage on the standardised series as points (Ward's criterion is
  defined for Euclidean distances, which 1 - R is not).

Standardised series are centred and scaled to unit norm (``similarity.standardized``), so the
squared Euclidean distance of two of them is 2 (1 - r): points close together co-vary. Note
that this keeps the sign: an anti-correlated pair is far apart for ``fcm``, ``kmeans`` and
``ward``, while R = |r| puts it close for ``closure``, ``average`` and ``complete``.

Seeded variants (``fcm``, ``kmeans``) take ``random_state`` (None, an int as recorded by the
callers, or a ``Generator``: ``selection.randomness``).
A variant that cannot give exactly k non-empty clusters (ties in a linkage, an fcm cluster
that is nobody's largest membership) warns and returns the clusters it has.
Clusters are index arrays (sorted), ordered by their first member, as ``cut.Cut`` orders them.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np
from scipy.cluster.hierarchy import fcluster, linkage
from scipy.spatial.distance import squareform

from spindlebench.core.names import DEFAULT_SIMILARITY
from spindlebench.selection.closure import transitive_closure
from spindlebench.selection.cut import cut_for_clusters
from spindlebench.selection.errors import SelectionError, SelectionWarning
from spindlebench.selection.method_registry import method_names
from spindlebench.selection.randomness import fcm_init, int_seed
from spindlebench.selection.similarity import constant_columns, similarity_matrix, standardized

#: The clusterings ``cluster_candidates`` implements: the built-in clustered methods of the
#: registry (``method_registry``), read when this module is imported.
CLUSTERINGS: tuple[str, ...] = method_names(clustered=True)
#: The clusterings that form an n x n matrix over the n candidates (R, or SciPy's condensed
#: distances for ward); fcm and k-means work on the n candidate columns as points.
PAIRWISE_CLUSTERINGS: tuple[str, ...] = method_names(clustered=True, pairwise=True)
#: The fuzzifier of fuzzy c-means (the usual value, and the issue's).
FCM_FUZZIFIER = 2.0
FCM_TOLERANCE = 1e-6
FCM_MAX_ITERATIONS = 1000
KMEANS_STARTS = 10
#: scikit-learn's ``KMeans`` default ``tol`` (relative to the mean variance per coordinate).
KMEANS_DEFAULT_TOL = 1e-4


def clusters_from_labels(labels: np.ndarray) -> list[np.ndarray]:
    """Index arrays of equal labels, ordered by first member."""
    labels = np.asarray(labels)
    first_seen: dict = {}
    for index, label in enumerate(labels.tolist()):
        first_seen.setdefault(label, index)
    ordered = sorted(first_seen, key=first_seen.__getitem__)
    return [np.flatnonzero(labels == label) for label in ordered]


def _warn_count(found: int, wanted: int, clustering: str) -> None:
    if found != wanted:
        warnings.warn(f"{clustering}: {found} non-empty cluster(s) instead of {wanted}",
                      SelectionWarning, stacklevel=3)


def hierarchical_labels(distances: np.ndarray, n_clusters: int, linkage_method: str) -> np.ndarray:
    """Cluster labels of a SciPy hierarchy (``linkage_method``) on a square distance matrix,
    cut into at most ``n_clusters`` clusters."""
    condensed = squareform(np.asarray(distances, dtype=float), checks=False)
    tree = linkage(condensed, method=linkage_method)
    return fcluster(tree, n_clusters, criterion="maxclust")


def fcm_memberships(points: np.ndarray, n_clusters: int, random_state) -> np.ndarray:
    """Fuzzy c-means memberships (n_clusters x n_points) of the rows of ``points``.

    The start is ``randomness.fcm_init`` (what ``cmeans(seed=...)`` draws, without its
    ``np.random.seed``: NumPy's global generator is never reseeded)."""
    from skfuzzy.cluster import cmeans

    init = fcm_init(n_clusters, points.shape[0], random_state)
    _, u, *_ = cmeans(points.T, n_clusters, FCM_FUZZIFIER, error=FCM_TOLERANCE,
                      maxiter=FCM_MAX_ITERATIONS, init=init)
    return u


def pair_coordinates(raw: np.ndarray) -> np.ndarray:
    """The standardised candidates of raw sensors ``raw`` (samples x m) and all their
    differences (``pairs.PairCandidates`` order) as points, one row each, in the
    orthonormal basis of the centred raw rises' QR factorisation (``pairs.PairGeometry``:
    candidate (i, k) is G (e_i - e_k) / |G (e_i - e_k)|): m coordinates instead of one per
    sample, the same distances to rounding."""
    from spindlebench.selection.pairs import PairCandidates, PairGeometry, standardized_centre

    geometry = PairGeometry.of(PairCandidates(raw), standardized_centre(raw))
    factor = np.hstack([geometry.factor, np.zeros((geometry.factor.shape[0], 1))])
    vectors = factor[:, geometry.first] - factor[:, geometry.second]
    return np.ascontiguousarray((vectors * geometry.inverse_norm).T)


def kmeans_labels(X: np.ndarray, n_clusters: int, random_state,
                  names: Sequence[str] | None = None) -> np.ndarray:
    """scikit-learn ``KMeans`` (``KMEANS_STARTS`` starts) labels of the standardised columns
    of ``X`` as points (``similarity.standardized``, one row each).

    Where ``X`` is m raw sensors followed by all their differences
    (``pairs.sensors_with_differences``) and m is below the samples, every point lies in the
    m-dimensional span of the centred raw sensors: k-means runs on the points' coordinates
    in an orthonormal basis of that span (``pair_coordinates``), with ``tol`` scaled by
    m / samples so that scikit-learn's tolerance (``tol`` times the mean variance per
    coordinate) is the same. Distances, the k-means++ draws' weights, inertias and centre
    shifts are the same to rounding and each Lloyd pass costs m / samples of the work (81
    sensors on 361 samples: 4.5x less). Not bit for bit: a point within rounding of two
    centres could change cluster; checked identical on ``bench_placement.py``'s field and
    the tests' (issue 26).
    """
    from sklearn.cluster import KMeans

    from spindlebench.selection.pairs import sensors_with_differences

    tol, points = KMEANS_DEFAULT_TOL, None
    m = sensors_with_differences(X)
    if m is not None and m < X.shape[0] and not constant_columns(X).any():
        coordinates = pair_coordinates(X[:, :m])
        if np.isfinite(coordinates).all():  # else ``standardized`` names the overflow
            points, tol = coordinates, tol * m / X.shape[0]
    if points is None:
        points = standardized(X, names).T
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # duplicate points: fewer distinct clusters
        return KMeans(n_clusters, n_init=KMEANS_STARTS, tol=tol,
                      random_state=int_seed(random_state)).fit(points).labels_


def cluster_candidates(X: np.ndarray, n_clusters: int, clustering: str = "closure",
                       similarity: str = DEFAULT_SIMILARITY, closure: str = "fast",
                       random_state=0,
                       names: Sequence[str] | None = None) -> list[np.ndarray]:
    """Partition the columns of ``X`` (non-constant candidates) into ``n_clusters`` clusters.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 50)
    >>> X = np.column_stack([t, t + 0.01 * t**2, np.sin(9 * t), np.sin(9 * t) + 0.01 * t])
    >>> [c.tolist() for c in cluster_candidates(X, 2, "kmeans")]
    [[0, 1], [2, 3]]
    """
    if clustering not in CLUSTERINGS:
        raise SelectionError(
            f"unknown clustering {clustering!r}; choose one of {', '.join(CLUSTERINGS)}")
    X = np.asarray(X, dtype=float)
    n = X.shape[1]
    if isinstance(n_clusters, bool) or not isinstance(n_clusters, (int, np.integer)) \
            or not 1 <= n_clusters <= n:
        raise SelectionError(f"cannot make {n_clusters!r} clusters from {n} feature(s)")
    if clustering == "closure":
        R = similarity_matrix(X, similarity, names)
        return cut_for_clusters(transitive_closure(R, closure), n_clusters).clusters
    if n_clusters == 1:
        return [np.arange(n)]
    if clustering in ("average", "complete"):
        R = similarity_matrix(X, similarity, names)
        labels = hierarchical_labels(1.0 - R, n_clusters, clustering)
    elif clustering == "kmeans":
        labels = kmeans_labels(X, n_clusters, random_state, names)
    else:
        points = standardized(X, names).T  # one row per candidate
        if clustering == "ward":
            labels = fcluster(linkage(points, method="ward"), n_clusters, criterion="maxclust")
        else:
            labels = np.argmax(fcm_memberships(points, n_clusters, random_state), axis=0)
    clusters = clusters_from_labels(labels)
    _warn_count(len(clusters), n_clusters, clustering)
    return clusters
