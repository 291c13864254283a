"""Deng's grey relational grade of every candidate with the thermal error.

An alternative to |psi| for the choice inside a cluster (Deng 1982; the grey relational
analysis the open temperature-sensitive-point tools offer). For reference series x0 (the
error) and candidates xi, all normalised first:

    Delta_i(k) = |x0(k) - xi(k)|
    xi_i(k)    = (Delta_min + rho Delta_max) / (Delta_i(k) + rho Delta_max)
    grade_i    = mean over k of xi_i(k)

with Delta_min and Delta_max the smallest and largest Delta over *all* candidates and samples
(so grades of different candidates are comparable) and the distinguishing coefficient rho
(0.5 by default). Normalisations:

- ``interval``: (x - min) / (max - min), every series onto [0, 1]. For rises that start at 0
  and grow this is division by the maximum.
- ``mean``: x / mean(x). A series whose mean is 0 (a rise that returns to its start, a
  difference of two equal rises) has no mean normalisation: it is an error naming it.

Unlike the correlation, the grade is not symmetric in sign: a candidate that falls while the
error rises is far from it after normalisation and gets a low grade. That is the method.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from spindlebench.selection.errors import SelectionError, check_names, column_list
from spindlebench.selection.similarity import constant_by_range

NORMALISATIONS: tuple[str, ...] = ("interval", "mean")
#: Deng's usual distinguishing coefficient.
DEFAULT_RHO = 0.5


def normalised(X: np.ndarray, normalisation: str = "interval",
               names: Sequence[str] | None = None) -> np.ndarray:
    """Columns of ``X`` normalised by ``interval`` or ``mean`` (see the module docstring)."""
    X = np.asarray(X, dtype=float)
    if normalisation == "interval":
        low, high = X.min(axis=0), X.max(axis=0)
        # constant_columns' rule from these two reductions (its own two, not repeated)
        flat = np.flatnonzero(constant_by_range(high - low,
                                                np.maximum(np.abs(high), np.abs(low))))
        if flat.size:
            raise SelectionError(
                f"grey grade: interval normalisation needs non-constant series; constant: "
                f"{column_list(flat, names)}")
        out = np.subtract(X, low)
        np.divide(out, high - low, out=out)
        return out
    if normalisation == "mean":
        mean = X.mean(axis=0)
        scale = np.max(np.abs(X), axis=0)
        zero = np.flatnonzero(np.abs(mean) <= 1e-12 * np.where(scale > 0, scale, 1.0))
        if zero.size:
            raise SelectionError(
                f"grey grade: mean normalisation needs series with a non-zero mean; mean 0 "
                f"in {column_list(zero, names)}")
        return X / mean
    raise SelectionError(
        f"unknown grey normalisation {normalisation!r}; choose one of {', '.join(NORMALISATIONS)}")


def grey_relational_grade(X: np.ndarray, y: np.ndarray, normalisation: str = "interval",
                          rho: float = DEFAULT_RHO,
                          names: Sequence[str] | None = None) -> np.ndarray:
    """Grade (in (0, 1]) of every column of ``X`` with the reference series ``y``.

    ``names`` (one per column) only serve the messages.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.array([0.0, 1.0, 2.0])
    >>> X = np.column_stack([y, [0.0, 2.0, 2.0]])
    >>> grey_relational_grade(X, y).round(4)
    array([1.    , 0.7778])
    """
    X = np.asarray(X, dtype=float)
    y = np.asarray(y, dtype=float).ravel()
    if X.ndim != 2 or X.shape[0] != y.shape[0] or X.shape[0] < 2:
        raise SelectionError(f"grey grade needs X (n x p, n >= 2) and y (n); got {X.shape}, "
                             f"{y.shape}")
    check_names(names, X.shape[1])
    if not (np.isfinite(X).all() and np.isfinite(y).all()):
        raise SelectionError("grey grade: candidates and target must be finite (no NaN or inf)")
    if isinstance(rho, bool) or not isinstance(rho, (int, float, np.floating)) \
            or not 0.0 < float(rho) <= 1.0:
        raise SelectionError(f"grey grade: rho must be a number in (0, 1], got {rho!r}")
    x0 = normalised(y[:, None], normalisation, ["the target"])[:, 0]
    # in place on the normalised copy (the same operations in the same layout, so the same
    # bits, without four more temporaries of the candidates' size)
    delta = normalised(X, normalisation, names)
    np.subtract(delta, x0[:, None], out=delta)
    np.abs(delta, out=delta)
    low, high = float(delta.min()), float(delta.max())
    if high == 0.0:  # every candidate equals the reference after normalisation
        return np.ones(X.shape[1])
    np.add(delta, rho * high, out=delta)
    np.divide(low + rho * high, delta, out=delta)
    return delta.mean(axis=0)
