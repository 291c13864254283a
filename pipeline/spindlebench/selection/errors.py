"""Error and warning types of the selection pipeline.

``SelectionError`` is both a ``SpindlebenchError`` (the CLI prints it as one line) and a
``ValueError`` (scikit-learn's estimator checks expect bad input to raise ``ValueError``).
It also phrases the column lists and name checks those one-line messages share.
"""

from collections.abc import Sequence

import numpy as np

from spindlebench.core.errors import SpindlebenchError


class SelectionError(SpindlebenchError, ValueError):
    """Input the selection method cannot work with, phrased as one line."""


class SelectionWarning(UserWarning):
    """Input the method handles in a documented way that changes the result (e.g. a
    constant sensor dropped, or ties making the requested cluster count impossible)."""


class SelectionOverflowError(SelectionError):
    """Finite input so large that a sum of squares or a product overflows float64: the
    result would be inf or NaN (or, worse, silently zero correlations), so it is refused.
    ``evaluate`` adds the recording's name."""


def check_names(names: Sequence[str] | None, n_columns: int) -> None:
    """Refuse a list of column names (used only in messages) of the wrong length."""
    if names is not None and len(names) != n_columns:
        raise SelectionError(f"{len(names)} name(s) given for {n_columns} column(s)")


def column_list(indices: Sequence[int], names: Sequence[str] | None) -> str:
    """``T1, T6`` (or ``column 0, column 5``), the first 10 and a count of the rest."""
    labels = [str(names[i]) if names is not None else f"column {i}" for i in indices]
    shown = ", ".join(labels[:10])
    return shown + (f" and {len(labels) - 10} more" if len(labels) > 10 else "")


def check_n_clusters(n_clusters: int, n: int, what: str = "candidate(s)") -> None:
    """The one check of a cluster count k against the ``n`` things to cluster."""
    if isinstance(n_clusters, bool) or not isinstance(n_clusters, (int, np.integer)):
        raise SelectionError(f"the number of clusters must be an integer, got {n_clusters!r}")
    if n_clusters < 1:
        raise SelectionError(f"the number of clusters must be at least 1, got {n_clusters}")
    if n_clusters > n:
        raise SelectionError(
            f"cannot make {n_clusters} clusters from {n} {what}: "
            f"n_clusters is larger than the number of candidates"
        )
