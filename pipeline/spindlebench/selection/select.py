"""Temperature-sensitive point selection, steps 2-5 of Xu et al. (2023) on an array.

similarity R (eq. 1) -> closure t(R) (eq. 2) -> cut into k clusters (eq. 3) -> in each cluster
the candidate with the largest |psi|, psi = Pearson correlation with the thermal error (eq. 4).

Constant candidates (zero variance, e.g. a sensor that never changed, or a difference of two
sensors with a constant offset) have no correlation: they are dropped with a
``SelectionWarning`` before R is built, so they never put NaN into the matrix.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from spindlebench.core.names import DEFAULT_SIMILARITY
from spindlebench.selection.closure import (
    SpanningTree,
    check_similarity,
    closure_from_tree,
    maximum_spanning_tree,
    transitive_closure,
)
from spindlebench.selection.cut import Cut, cut_tree_for_clusters
from spindlebench.selection.errors import (
    SelectionError,
    SelectionWarning,
    check_n_clusters,
    check_names,
    column_list,
)
from spindlebench.selection.similarity import (
    constant_columns,
    correlation_with,
    similarity_and_standardized,
)

#: R or t(R), or a function that forms it on request (the row-wise selection over sensors
#: and their differences never forms the n x n matrices unless asked).
MatrixSource = np.ndarray | Callable[[], np.ndarray]


@dataclass(frozen=True)
class Selection:
    """Everything steps 2-5 produce; indices refer to the columns of the input ``X``."""

    kept: np.ndarray  #: non-constant candidates, in input order (rows/cols of R and t(R))
    dropped: np.ndarray  #: constant candidates, removed with a warning
    similarity_source: MatrixSource = field(repr=False, compare=False)
    closure_source: MatrixSource = field(repr=False, compare=False)
    eta: float  #: threshold of the cut
    clusters: list[np.ndarray]  #: input column indices, ordered by first member
    psi: np.ndarray  #: correlation of every input column with the error (NaN if dropped)
    selected: np.ndarray  #: per cluster, the input column with the largest |psi|

    @property
    def similarity(self) -> np.ndarray:
        """R over ``kept`` (formed on request by the row-wise selection)."""
        source = self.similarity_source
        return source if isinstance(source, np.ndarray) else source()

    @property
    def closure(self) -> np.ndarray:
        """t(R) over ``kept`` (formed on request by the row-wise selection)."""
        source = self.closure_source
        return source if isinstance(source, np.ndarray) else source()

    @property
    def selected_psi(self) -> np.ndarray:
        """psi of the selected candidates, with sign."""
        return self.psi[self.selected]


def strongest_per_cluster(psi: np.ndarray, clusters: Sequence[np.ndarray]) -> np.ndarray:
    """Index of the largest |psi| in each cluster (the first one on exact ties)."""
    return np.array(
        [members[int(np.argmax(np.abs(psi[members])))] for members in clusters], dtype=np.intp
    )


def _check_inputs(X: np.ndarray, y: np.ndarray, n_clusters: int) -> tuple[np.ndarray, np.ndarray]:
    X = np.asarray(X, dtype=float)
    y = np.asarray(y, dtype=float).ravel()
    if X.ndim != 2:
        raise SelectionError(f"candidates must be a 2-D array, got shape {X.shape}")
    check_counts(X.shape[0], X.shape[1], y, n_clusters)
    if not (np.all(np.isfinite(X)) and np.all(np.isfinite(y))):
        raise SelectionError("candidates and target must be finite (no NaN or inf)")
    return X, y


def check_counts(n_samples: int, n_candidates: int, y: np.ndarray, n_clusters: int) -> None:
    """Samples, target length and the cluster count k, checked against each other."""
    if n_samples != y.shape[0]:
        raise SelectionError(f"{n_samples} candidate samples but {y.shape[0]} target samples")
    if n_samples < 2:
        raise SelectionError(f"selection needs at least 2 samples, got {n_samples} sample(s)")
    check_n_clusters(n_clusters, n_candidates, "feature(s)")


def split_constant(
    constant: np.ndarray, names: Sequence[str] | None, n_clusters: int,
    making: str | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(kept, dropped) candidate indices; dropping warns, too few kept is an error.

    ``making`` says what k counts in that error (default ``"{k} clusters"``); every method
    of the registry drops constant candidates through here, so all see the same ones."""
    kept = np.flatnonzero(~constant)
    dropped = np.flatnonzero(constant)
    if dropped.size:
        warnings.warn(
            f"dropping {dropped.size} constant candidate(s) (zero variance): "
            f"{column_list(dropped, names)}",
            SelectionWarning,
            stacklevel=3,
        )
    if n_clusters > kept.size:
        what = making or f"make {n_clusters} clusters"
        raise SelectionError(
            f"cannot {what}: only {kept.size} candidate(s) vary "
            f"({dropped.size} constant one(s) dropped)"
        )
    return kept, dropped


def assemble(
    kept: np.ndarray,
    dropped: np.ndarray,
    similarity: MatrixSource,
    closure: MatrixSource,
    cut: Cut,
    psi: np.ndarray,
) -> Selection:
    """The ``Selection`` of a cut over ``kept`` (cut indices are positions in ``kept``)."""
    clusters = [kept[members] for members in cut.clusters]
    return Selection(
        kept=kept,
        dropped=dropped,
        similarity_source=similarity,
        closure_source=closure,
        eta=cut.eta,
        clusters=clusters,
        psi=psi,
        selected=strongest_per_cluster(psi, clusters),
    )


def select_sensitive_points(
    X: np.ndarray,
    y: np.ndarray,
    n_clusters: int,
    similarity: str = DEFAULT_SIMILARITY,
    closure: str = "fast",
    names: Sequence[str] | None = None,
) -> Selection:
    """Steps 2-5 on candidates ``X`` (n_samples x n_candidates) and thermal error ``y``.

    ``names`` (one per column of ``X``) only serve messages: the warning about dropped
    constant candidates and the error about values too large to correlate.

    When ``X`` is raw sensors followed by all their pairwise differences (as
    ``PairwiseDifferences`` and ``CandidateSet`` form them) and has more than
    ``pairs.ROW_WISE_ABOVE`` columns, with |Pearson r| and the fast closure, the selection
    runs row-wise (``pairs.select_among_pairs``): the same clusters and psi, eta to rounding,
    without the n x n matrices (formed on request up to ``pairs.MAX_FORMED_CANDIDATES``).
    """
    return SensitivePoints(X, y, similarity, closure, names).select(n_clusters)


class SensitivePoints:
    """``select_sensitive_points`` on one ``X`` and ``y`` for any number of k: every step
    that does not depend on k (the constant candidates, R, psi and the maximum spanning
    tree the cut reads; t(R) when asked for) is done once, at the first ``select``.

    Why: a study selects k = 2, 3, 4 from the same candidates of the same training run;
    those steps were done again for each k. Each ``select(k)`` checks its inputs, warns and
    raises as ``select_sensitive_points(X, y, k, ...)`` does, in the same order, and gives
    the same selection (the shared arrays are read-only: do not modify them).
    """

    def __init__(self, X: np.ndarray, y: np.ndarray, similarity: str = DEFAULT_SIMILARITY,
                 closure: str = "fast", names: Sequence[str] | None = None) -> None:
        self.X, self.y = X, y
        self.similarity, self.closure, self.names = similarity, closure, names
        self._constant: np.ndarray | None = None
        self._prepared: tuple[np.ndarray, MatrixSource, np.ndarray, SpanningTree] | None = None

    def select(self, n_clusters: int) -> Selection:
        """``select_sensitive_points(X, y, n_clusters, similarity, closure, names)``."""
        X, y = _check_inputs(self.X, self.y, n_clusters)
        names = self.names
        if names is not None:
            names = [str(name) for name in names]
            check_names(names, X.shape[1])
        from spindlebench.selection import pairs  # (pairs builds on this module)

        if (self.closure == "fast" and self.similarity == DEFAULT_SIMILARITY
                and X.shape[1] > pairs.ROW_WISE_ABOVE):
            m = pairs.sensors_with_differences(X)
            if m is not None:
                return pairs.select_among_pairs(X[:, :m], y, n_clusters, names=names)
        if self._constant is None:
            self._constant = constant_columns(X)
        kept, dropped = split_constant(self._constant, names, n_clusters)
        if self._prepared is None:  # a step that raises raises again at the next k
            kept_names = None if names is None else [names[i] for i in kept]
            varying = X[:, kept]
            R, Z = similarity_and_standardized(varying, self.similarity, kept_names)
            T, tree = _closure_and_tree(R, self.closure)
            psi = np.full(X.shape[1], np.nan)
            psi[kept] = correlation_with(varying, y, kept_names, standardized_X=Z)
            self._prepared = (R, T, psi, tree)
        R, T, psi, tree = self._prepared
        # cut_for_clusters(T, n_clusters), its tree made once
        check_n_clusters(n_clusters, tree.order.size)
        return assemble(kept, dropped, R, T, cut_tree_for_clusters(tree, n_clusters), psi)


def _closure_and_tree(R: np.ndarray, closure: str) -> tuple[MatrixSource, SpanningTree]:
    """t(R) (or the function that forms it, once, on request) and the maximum spanning tree
    the cut reads, raising what ``transitive_closure(R, closure)`` raises.

    Why: with the fast closure, t(R) is made from a maximum spanning tree of R, and a cut of
    t(R) reads the same clusters and eta off that tree as off one of t(R) (every maximum
    spanning tree of a graph has the same edge similarities, and these are exact minima and
    maxima of R's entries; the clusters at eta are the graph's components at eta, whichever
    tree spans it). So the tree of R serves the cut, and t(R) is formed only when a caller
    reads ``Selection.closure`` (the evaluations of a sweep never do): neither t(R) nor a
    second tree is made per training run and group."""
    if closure != "fast":
        T = transitive_closure(R, closure)
        return T, maximum_spanning_tree(check_similarity(T))
    tree = maximum_spanning_tree(check_similarity(R))
    return _ClosureOfTree(tree), tree


class _ClosureOfTree:
    """``closure_from_tree(tree)``, formed at the first call and then kept: a
    ``Selection``'s closure source that pickles (a fitted selector holding its selection
    does), unlike a function made inside another."""

    def __init__(self, tree: SpanningTree) -> None:
        self.tree = tree
        self._matrix: np.ndarray | None = None

    def __call__(self) -> np.ndarray:
        if self._matrix is None:
            self._matrix = closure_from_tree(self.tree)
        return self._matrix
