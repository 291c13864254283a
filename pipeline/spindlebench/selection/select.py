"""Temperature-sensitive point selection, steps 2-5 of Xu et al. (2023) on an array.

similarity R (eq. 1) -> closure t(R) (eq. 2) -> cut into k clusters (eq. 3) -> in each cluster
the candidate with the largest |psi|, psi = Pearson correlation with the thermal error (eq. 4).

Constant candidates (zero variance, e.g. a sensor that never changed, or a difference of two
sensors with a constant offset) have no correlation: they are dropped with a
``SelectionWarning`` before R is built, so they never put NaN into the matrix.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from spindlebench.names import DEFAULT_SIMILARITY
from spindlebench.selection.closure import transitive_closure
from spindlebench.selection.cut import cut_for_clusters
from spindlebench.selection.errors import SelectionError, SelectionWarning, check_names
from spindlebench.selection.similarity import (
    constant_columns,
    correlation_with,
    similarity_matrix,
)


@dataclass(frozen=True)
class Selection:
    """Everything steps 2-5 produce; indices refer to the columns of the input ``X``."""

    kept: np.ndarray  #: non-constant candidates, in input order (rows/cols of R and t(R))
    dropped: np.ndarray  #: constant candidates, removed with a warning
    similarity: np.ndarray  #: R over ``kept``
    closure: np.ndarray  #: t(R) over ``kept``
    eta: float  #: threshold of the cut
    clusters: list[np.ndarray]  #: input column indices, ordered by first member
    psi: np.ndarray  #: correlation of every input column with the error (NaN if dropped)
    selected: np.ndarray  #: per cluster, the input column with the largest |psi|

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
    if X.shape[0] != y.shape[0]:
        raise SelectionError(f"{X.shape[0]} candidate samples but {y.shape[0]} target samples")
    if X.shape[0] < 2:
        raise SelectionError(f"selection needs at least 2 samples, got {X.shape[0]} sample(s)")
    if not (np.all(np.isfinite(X)) and np.all(np.isfinite(y))):
        raise SelectionError("candidates and target must be finite (no NaN or inf)")
    if isinstance(n_clusters, bool) or not isinstance(n_clusters, (int, np.integer)):
        raise SelectionError(f"the number of clusters must be an integer, got {n_clusters!r}")
    if n_clusters < 1:
        raise SelectionError(f"the number of clusters must be at least 1, got {n_clusters}")
    if n_clusters > X.shape[1]:
        raise SelectionError(
            f"cannot make {n_clusters} clusters from {X.shape[1]} feature(s): "
            f"n_clusters is larger than the number of candidates"
        )
    return X, y


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
    """
    X, y = _check_inputs(X, y, n_clusters)
    if names is not None:
        names = [str(name) for name in names]
        check_names(names, X.shape[1])
    constant = constant_columns(X)
    kept = np.flatnonzero(~constant)
    dropped = np.flatnonzero(constant)
    if dropped.size:
        labels = [str(names[i]) if names is not None else f"column {i}" for i in dropped]
        shown = ", ".join(labels[:10])
        if len(labels) > 10:
            shown += f" and {len(labels) - 10} more"
        warnings.warn(
            f"dropping {len(labels)} constant candidate(s) (zero variance): {shown}",
            SelectionWarning,
            stacklevel=2,
        )
    if n_clusters > kept.size:
        raise SelectionError(
            f"cannot make {n_clusters} clusters: only {kept.size} candidate(s) vary "
            f"({dropped.size} constant one(s) dropped)"
        )
    kept_names = None if names is None else [names[i] for i in kept]
    R = similarity_matrix(X[:, kept], similarity, kept_names)
    T = transitive_closure(R, closure)
    cut = cut_for_clusters(T, n_clusters)
    psi = np.full(X.shape[1], np.nan)
    psi[kept] = correlation_with(X[:, kept], y, kept_names)
    clusters = [kept[members] for members in cut.clusters]
    return Selection(
        kept=kept,
        dropped=dropped,
        similarity=R,
        closure=T,
        eta=cut.eta,
        clusters=clusters,
        psi=psi,
        selected=strongest_per_cluster(psi, clusters),
    )
