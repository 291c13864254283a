"""Step 6: multiple linear regression of the thermal error on temperature rises.

Rises are relative to the first sample of each experiment (the paper's Delta T). The fit is
ordinary least squares with an intercept, solved on centred data with ``numpy.linalg.lstsq``
(the intercept then follows from the means), which is better conditioned than appending a
column of ones to temperatures that sit far from zero.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from spindlebench.selection.errors import SelectionError


def rises(X: np.ndarray, groups: np.ndarray | None = None) -> np.ndarray:
    """``X`` minus the first row of its experiment (``groups`` labels rows; None = one)."""
    X = np.asarray(X, dtype=float)
    if X.ndim != 2 or X.shape[0] == 0:
        raise SelectionError(f"rises need a non-empty 2-D array, got shape {X.shape}")
    if groups is None:
        return X - X[0]
    groups = np.asarray(groups)
    if groups.shape != (X.shape[0],):
        raise SelectionError(f"groups must label each of the {X.shape[0]} rows")
    out = np.empty_like(X)
    for label in _unique_in_order(groups):
        rows = np.flatnonzero(groups == label)
        out[rows] = X[rows] - X[rows[0]]
    return out


def _unique_in_order(values: np.ndarray) -> list:
    seen: dict = {}
    for value in values.tolist():
        seen.setdefault(value, None)
    return list(seen)


def r2_score(y: np.ndarray, predicted: np.ndarray) -> float:
    """Coefficient of determination 1 - SS_res / SS_tot (NaN for a constant target)."""
    y = np.asarray(y, dtype=float)
    residual = y - np.asarray(predicted, dtype=float)
    total = y - y.mean()
    if total @ total == 0:
        return float("nan")  # undefined for a constant target
    return float(1.0 - residual @ residual / (total @ total))


def rmse(y: np.ndarray, predicted: np.ndarray) -> float:
    """Root-mean-square error, in the unit of ``y``."""
    residual = np.asarray(y, dtype=float) - np.asarray(predicted, dtype=float)
    return float(np.sqrt(np.mean(residual**2)))


@dataclass(frozen=True)
class LinearFit:
    """y ~ intercept + X @ coefficients, with its training R^2."""

    intercept: float
    coefficients: np.ndarray
    r2: float

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Predicted error for candidate values (rises) ``X``."""
        return self.intercept + np.asarray(X, dtype=float) @ self.coefficients


def fit_ols(X: np.ndarray, y: np.ndarray) -> LinearFit:
    """Ordinary least squares with intercept (minimum-norm if the design is rank deficient)."""
    X = np.asarray(X, dtype=float)
    y = np.asarray(y, dtype=float).ravel()
    if X.ndim != 2 or X.shape[0] != y.shape[0]:
        raise SelectionError(f"regression needs X (n x p) and y (n); got {X.shape}, {y.shape}")
    if X.shape[0] < 2:
        raise SelectionError(f"regression needs at least 2 samples, got {X.shape[0]}")
    if not (np.all(np.isfinite(X)) and np.all(np.isfinite(y))):
        raise SelectionError("regression inputs must be finite (no NaN or inf)")
    x_mean = X.mean(axis=0)
    y_mean = y.mean()
    coefficients, *_ = np.linalg.lstsq(X - x_mean, y - y_mean, rcond=None)
    intercept = float(y_mean - x_mean @ coefficients)
    r2 = r2_score(y, intercept + X @ coefficients)
    return LinearFit(intercept=intercept, coefficients=coefficients, r2=r2)
