"""Fuzzy similarity matrix R between candidate variables (eq. 1 of Xu et al. 2023).

Two readings of eq. 1:

- ``abs-pearson`` (default): |Pearson r|, the usual reading.
- ``literal``: the formula as printed, sum |a-mean(a)| |b-mean(b)| / (norm(a-mean) norm(b-mean)),
  which by Cauchy-Schwarz also lies in [0, 1] and is 1 on the diagonal; it ignores the sign of
  co-variation, so it is never smaller than |Pearson r|.

Columns are centred twice (the second pass removes the rounding left by the first, which
matters for temperatures of ~25 degC varying by hundredths) and scaled to unit norm before the
product, so R is exactly symmetric, exactly 1 on the diagonal and clipped into [0, 1].
Constant columns have no correlation; they must be removed first (see ``constant_columns``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from threadpoolctl import threadpool_limits

from spindlebench.core.names import DEFAULT_SIMILARITY, SIMILARITIES
from spindlebench.selection.errors import (
    SelectionError,
    SelectionOverflowError,
    check_names,
    column_list,
)

#: A column is constant when its peak-to-peak range is below this fraction of the data's
#: scale: differences of two sensors with a constant offset vary only by rounding.
CONSTANT_RTOL = 1e-12
#: The ``literal`` reading is not linear in the data (|a - mean(a)| |b - mean(b)|), so it
#: needs the n x n matrix (several 8 n^2-byte arrays while it is formed, ~1.2 GB here).
LITERAL_MAX_CANDIDATES = 6000
#: Threaded OpenBLAS has crashed (SIGSEGV) on ``Z.T @ Z`` with ~15 500 columns and more;
#: above this many the product runs single-threaded.
SINGLE_THREAD_ABOVE = 8000


def constant_columns(X: np.ndarray) -> np.ndarray:
    """Boolean mask of columns that are constant up to floating-point rounding.

    The scale of a column is the larger of its own magnitude and the median range of all
    columns, so a rounding-noise column of rises (values ~1e-15 around 0, from two sensors with
    a constant offset) counts as constant next to rises of a few kelvin. The median, not the
    largest range: one outlier cell (a logger's 9.9e37 sentinel) in one column must not make
    every other column look constant.
    """
    X = np.asarray(X, dtype=float)
    if X.shape[0] == 0:
        return np.ones(X.shape[1], dtype=bool)
    # two reductions instead of np.ptp's two and a third over |X|: the range is max - min
    # as np.ptp computes it, and max |x| is the larger of |max| and |min| (exact; NaN stays
    # NaN), so the same mask
    high, low = X.max(axis=0), X.min(axis=0)
    return constant_by_range(high - low, np.maximum(np.abs(high), np.abs(low)))


def constant_by_range(spread: np.ndarray, magnitude: np.ndarray) -> np.ndarray:
    """``constant_columns``' rule from each column's range (max - min) and largest |value|,
    for callers that gather those a block of columns at a time and never form the matrix
    (``pairs.check_candidates``): the same mask, bit for bit."""
    typical = _median(spread) if spread.size else 0.0
    scale = np.maximum(magnitude, typical)
    return spread <= CONSTANT_RTOL * scale


def _median(values: np.ndarray) -> float:
    """``np.median`` of a non-empty 1-D array, the same bits (the middle value, or the mean
    of the two middle values; NaN if any is NaN), without the import of ``numpy.ma`` that
    ``np.median`` triggers (~50 ms of a short command's start-up)."""
    if np.isnan(values).any():
        return float("nan")
    ordered = np.sort(values)
    middle = ordered.size // 2
    start = middle if ordered.size % 2 else middle - 1
    return float(np.mean(ordered[start:middle + 1]))  # as np.median does (-0.0 becomes 0.0)


def standardized(X: np.ndarray, names: Sequence[str] | None = None) -> np.ndarray:
    """Columns centred (two passes) and scaled to unit Euclidean norm.

    A column of finite values whose sum of squares overflows (|values| ~ 1e154 and up) raises
    ``SelectionOverflowError`` naming it (``names`` or "column i"): its norm would be inf and
    its correlations silently 0. Columns with NaN or inf stay NaN (callers that must not see
    them check first).
    """
    X = np.asarray(X, dtype=float)
    with np.errstate(over="ignore", invalid="ignore"):
        centred = X - X.mean(axis=0)
        centred -= centred.mean(axis=0)
        norms = np.sqrt(np.einsum("ij,ij->j", centred, centred))
    # finite values with a norm that is not: only the columns whose norm is not finite are
    # looked at (the same columns as checking every one)
    suspect = np.flatnonzero(~np.isfinite(norms))
    overflow = suspect[np.isfinite(X[:, suspect]).all(axis=0)]
    if overflow.size:
        raise SelectionOverflowError(
            f"values too large to correlate (overflow) in {column_list(overflow, names)}"
        )
    if np.any(norms == 0) or np.any(constant_columns(X)):
        raise SelectionError("similarity needs non-constant columns; drop constant ones first")
    centred /= norms  # in place: the same quotients, one temporary fewer
    return centred


def _symmetric_unit(matrix: np.ndarray) -> np.ndarray:
    """Mirror the upper triangle, clip into [0, 1] and put exact ones on the diagonal."""
    upper = np.triu(matrix, k=1)
    out = upper + upper.T
    np.clip(out, 0.0, 1.0, out=out)
    np.fill_diagonal(out, 1.0)
    return out


def similarity_matrix(
    X: np.ndarray, method: str = DEFAULT_SIMILARITY, names: Sequence[str] | None = None
) -> np.ndarray:
    """Fuzzy similarity R (n_candidates x n_candidates) of the columns of ``X``.

    NaN or inf anywhere is an error (it would make R, and every cluster, NaN); ``names``
    (one per column) only serve the messages.
    """
    return similarity_and_standardized(X, method, names)[0]


def similarity_and_standardized(
    X: np.ndarray, method: str = DEFAULT_SIMILARITY, names: Sequence[str] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """``similarity_matrix(X, method, names)`` and the ``standardized(X, names)`` it was
    made of (read-only use), which ``correlation_with`` of the same ``X`` makes too: a
    selection correlating the candidates it clusters standardises them once (a third of
    the similarity's and the correlation's time)."""
    if method not in SIMILARITIES:
        raise SelectionError(
            f"unknown similarity {method!r}; choose one of {', '.join(SIMILARITIES)}"
        )
    X = np.asarray(X, dtype=float)
    if X.ndim != 2 or X.shape[0] < 2:
        raise SelectionError(f"similarity needs at least 2 samples, got shape {X.shape}")
    check_names(names, X.shape[1])
    bad = np.flatnonzero(~np.isfinite(X).all(axis=0))
    if bad.size:
        raise SelectionError(
            f"similarity needs finite values; NaN or inf in {column_list(bad, names)}"
        )
    if method == "literal" and X.shape[1] > LITERAL_MAX_CANDIDATES:
        raise SelectionError(
            f"the literal similarity needs the n x n matrix: at most "
            f"{LITERAL_MAX_CANDIDATES} candidates, got {X.shape[1]}; use abs-pearson (which "
            f"runs row-wise for sensors plus differences) or fewer sensors"
        )
    standard = standardized(X, names)
    Z = np.abs(standard) if method == "literal" else standard
    if Z.shape[1] > SINGLE_THREAD_ABOVE:
        with threadpool_limits(limits=1, user_api="blas"):
            product = Z.T @ Z
    else:
        product = Z.T @ Z
    return _symmetric_unit(product if method == "literal" else np.abs(product)), standard


def correlation_with(
    X: np.ndarray, y: np.ndarray, names: Sequence[str] | None = None,
    standardized_X: np.ndarray | None = None,
) -> np.ndarray:
    """Pearson correlation of every column of ``X`` with ``y`` (eq. 4), sign kept.

    A column holding NaN or inf gets NaN (the studies rank such a dropped-out sensor last);
    values whose squares overflow are an error naming the column (``names``) or the target.
    ``standardized_X``: ``standardized(X, names)`` made already
    (``similarity_and_standardized``).
    """
    y = np.asarray(y, dtype=float).ravel()
    X = np.asarray(X, dtype=float)
    if X.shape[0] != y.shape[0]:
        raise SelectionError(f"X has {X.shape[0]} samples but the target has {y.shape[0]}")
    check_names(names, X.shape[1])
    if constant_columns(y[:, None])[0]:
        raise SelectionError("the target (thermal error) is constant; no correlation exists")
    zy = standardized(y[:, None], ["the target"])[:, 0]
    Z = standardized(X, names) if standardized_X is None else standardized_X
    return np.clip(Z.T @ zy, -1.0, 1.0)

