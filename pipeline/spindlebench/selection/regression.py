"""Step 6: multiple linear regression of the thermal error on temperature rises.

Rises are relative to the first sample of each experiment (the paper's Delta T). The fit is
ordinary least squares with an intercept, solved on centred data with ``numpy.linalg.lstsq``
(the intercept then follows from the means), which is better conditioned than appending a
column of ones to temperatures that sit far from zero.

Bad input is refused in one line rather than answered with NaN or a numpy broadcast error:
fewer samples than features + 1, a reference (first) row with NaN under a column that has
values later, NaN experiment labels, mismatched or empty inputs of ``rmse``/``r2_score``, and
values so large that the sums of squares overflow. Collinear features (a duplicate column, or
``A``, ``B`` and ``A-B`` together) get a ``SelectionWarning`` naming them: the fit is then the
minimum-norm one and their coefficients are not unique.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from spindlebench.selection.errors import (
    SelectionError,
    SelectionOverflowError,
    SelectionWarning,
    check_names,
)


def check_groups(groups: object, n_rows: int | None = None) -> np.ndarray:
    """Experiment labels as a 1-D array (one per row if ``n_rows``), without NaN labels:
    NaN never equals itself, so every NaN row would become an experiment of its own."""
    groups = np.asarray(groups)
    if groups.ndim != 1:
        raise SelectionError(f"groups must be 1-D, got shape {groups.shape}")
    if n_rows is not None and groups.shape != (n_rows,):
        raise SelectionError(f"groups must label each of the {n_rows} rows, got {groups.size}")
    missing = np.flatnonzero(_is_nan_label(groups))
    if missing.size:
        raise SelectionError(
            f"groups: {missing.size} NaN/None label(s), first in row {int(missing[0])}; "
            f"every row needs the experiment it belongs to"
        )
    return groups


def _is_nan_label(groups: np.ndarray) -> np.ndarray:
    if groups.dtype.kind in "fc":
        return np.isnan(groups)
    if groups.dtype.kind == "O":
        return np.array([g is None or (isinstance(g, float) and g != g) for g in groups],
                        dtype=bool)
    return np.zeros(groups.shape, dtype=bool)


def rises(X: np.ndarray, groups: np.ndarray | None = None) -> np.ndarray:
    """``X`` minus the first row of its experiment (``groups`` labels rows; None = one).

    A column whose reference (first) value is NaN or inf while later rows of the experiment
    have values is an error: every rise of it would be NaN. A column with no value at all
    stays NaN (a sensor that dropped out for the whole run loses nothing).
    """
    X = np.asarray(X, dtype=float)
    if X.ndim != 2 or X.shape[0] == 0:
        raise SelectionError(f"rises need a non-empty 2-D array, got shape {X.shape}")
    if groups is None:
        _check_reference(X, None)
        return X - X[0]
    groups = check_groups(groups, X.shape[0])
    out = np.empty_like(X)
    for label in _unique_in_order(groups):
        rows = np.flatnonzero(groups == label)
        _check_reference(X[rows], label)
        out[rows] = X[rows] - X[rows[0]]
    return out


def _check_reference(X: np.ndarray, label: object) -> None:
    bad = np.flatnonzero(~np.isfinite(X[0]) & np.isfinite(X).any(axis=0))
    if bad.size:
        where = "the first row" if label is None else f"the first row of experiment {label!r}"
        raise SelectionError(
            f"rises: {where} (the reference) has NaN/inf in column(s) "
            f"{', '.join(map(str, bad[:10].tolist()))} that have values later; drop the "
            f"incomplete rows first"
        )


def _unique_in_order(values: np.ndarray) -> list:
    seen: dict = {}
    for value in values.tolist():
        seen.setdefault(value, None)
    return list(seen)


def _paired(y: np.ndarray, predicted: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Measured and predicted as equally long 1-D arrays ((n, 1) counts as n samples); a
    length mismatch would otherwise broadcast into an n x n matrix or a numpy error."""
    if type(y) is np.ndarray and type(predicted) is np.ndarray and y.ndim == 1 \
            and y.dtype == np.float64 and predicted.dtype == np.float64 \
            and y.shape == predicted.shape and y.size:  # already so: a study's many scores
        return y, predicted
    y_in, p_in = np.asarray(y, dtype=float), np.asarray(predicted, dtype=float)
    y_flat, p_flat = _samples(y_in), _samples(p_in)
    if y_flat is None or p_flat is None or y_flat.shape != p_flat.shape:
        raise SelectionError(
            f"{what}: measured and predicted must be equally long 1-D arrays, got shapes "
            f"{y_in.shape} and {p_in.shape}"
        )
    if y_flat.size == 0:
        raise SelectionError(f"{what}: needs at least 1 sample, got none")
    return y_flat, p_flat


def _samples(values: np.ndarray) -> np.ndarray | None:
    if values.ndim == 1:
        return values
    if values.ndim == 2 and values.shape[1] == 1:
        return values[:, 0]
    return None


def r2_score(y: np.ndarray, predicted: np.ndarray) -> float:
    """Coefficient of determination 1 - SS_res / SS_tot (NaN for a constant target, and
    where the inputs hold NaN)."""
    y, predicted = _paired(y, predicted, "r2_score")
    with np.errstate(over="ignore", invalid="ignore"):
        return _r2(y, predicted, y.mean(), bool(np.isfinite(y).all()
                                                and np.isfinite(predicted).all()))


def _r2(y: np.ndarray, predicted: np.ndarray, y_mean: float, finite_input: bool) -> float:
    """``r2_score`` of equally long 1-D float64 arrays, ``y_mean`` being ``y.mean()`` and
    ``finite_input`` whether both are finite (a fit knows both already), under the
    caller's ``errstate``."""
    residual = y - predicted
    total = y - y_mean
    ss_res, ss_tot = residual @ residual, total @ total
    if finite_input and not (np.isfinite(ss_res) and np.isfinite(ss_tot)):
        raise SelectionOverflowError("values too large for R2 (overflow in the sums of squares)")
    if ss_tot == 0:
        return float("nan")  # undefined for a constant target
    return float(1.0 - ss_res / ss_tot)


def rmse(y: np.ndarray, predicted: np.ndarray) -> float:
    """Root-mean-square error, in the unit of ``y`` (NaN where the inputs hold NaN)."""
    y, predicted = _paired(y, predicted, "rmse")
    with np.errstate(over="ignore", invalid="ignore"):
        residual = y - predicted
        # np.mean(residual ** 2) is this sum divided by the count; without np.mean's
        # Python-level wrapper (half of an RMSE's time, and a sweep takes ~400 per training run)
        value = float(np.sqrt(np.add.reduce(residual * residual) / residual.size))
    if not math.isfinite(value) and np.isfinite(y).all() and np.isfinite(predicted).all():
        raise SelectionOverflowError("values too large for the RMSE (overflow)")
    return value


def rmse_each(ys: Sequence[np.ndarray], predictions: Sequence[np.ndarray]) -> list[float]:
    """``[rmse(y, p) for y, p in zip(ys, predictions)]``, to the last bit, in one reduction.

    Why: a sweep scores every method on 23 held-out runs, and 23 calls of ``rmse`` cost
    several times one reduction over the runs stacked. Equally long float64 runs are stacked
    as rows: numpy's pairwise sum then runs along each (contiguous) row exactly as on the
    run alone (tests compare the two). Anything else, or a result that is not finite (NaN
    input, or an overflow ``rmse`` raises on), takes ``rmse`` pair by pair, so the values and
    errors are its own, in its order."""
    if len(ys) != len(predictions):
        raise SelectionError(f"rmse_each: {len(ys)} measured but {len(predictions)} predicted")
    stacked = stacked_rows(ys), stacked_rows(predictions)
    if stacked[0] is not None and stacked[1] is not None:
        values = rmse_rows(stacked[0], stacked[1])
        if values is not None:
            return values
    return [rmse(y, p) for y, p in zip(ys, predictions, strict=True)]


def rmse_rows(ys: np.ndarray, predictions: np.ndarray) -> list[float] | None:
    """``rmse_each(list(ys), list(predictions))`` of two runs-by-samples arrays stacked
    already (C-contiguous float64 of one shape), to the last bit: the same reduction on
    the same layout. Why: a study scores each of its many models on the same held-out
    runs, whose measured and true values are stacked once for all of them instead of once
    per score. None for other arrays, or a result that is not finite (``rmse_each`` then
    scores pair by pair, with ``rmse``'s errors)."""
    if ys.ndim != 2 or ys.shape != predictions.shape or not ys.shape[1] \
            or ys.dtype != np.float64 or predictions.dtype != np.float64 \
            or not (ys.flags.c_contiguous and predictions.flags.c_contiguous):
        return None
    with np.errstate(over="ignore", invalid="ignore"):
        residuals = ys - predictions
        values = np.sqrt(np.add.reduce(residuals * residuals, axis=1) / residuals.shape[1])
    return values.tolist() if np.isfinite(values).all() else None


def stacked_rows(arrays: Sequence[np.ndarray]) -> np.ndarray | None:
    """Equally long 1-D float64 arrays as the rows of one array; None for anything else
    (no arrays, other shapes or types: ``rmse`` converts those its own way)."""
    if not arrays or not all(type(a) is np.ndarray for a in arrays):
        return None
    try:  # np.array: np.stack's array of equal shapes (and its error for unequal ones),
        stacked = np.array(arrays)  # without its Python wrapper (a third of the time)
    except ValueError:  # not equally long
        return None
    return stacked if stacked.ndim == 2 and stacked.dtype == np.float64 else None


@dataclass(frozen=True)
class LinearFit:
    """y ~ intercept + X @ coefficients, with its training R^2."""

    intercept: float
    coefficients: np.ndarray
    r2: float
    #: A penalised fit's penalty (ridge: ``alpha``, the grid ``grid`` and ``at_edge``,
    #: "lower"/"upper" when the cross-validation chose an end of the grid); None for OLS.
    penalty: dict | None = None

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Predicted error for candidate values (rises) ``X`` (inf where they overflow)."""
        return self.predict_each([X])[0]

    def predict_each(self, Xs: Sequence[np.ndarray]) -> list[np.ndarray]:
        """``[self.predict(X) for X in Xs]``, the same product on each ``X`` (its own shape
        and layout, so its own bits) under one ``errstate`` instead of one per ``X``: a
        study predicts each model's 23 held-out runs, where entering it was most of a
        prediction's time."""
        with np.errstate(over="ignore", invalid="ignore"):
            return [self.intercept + np.asarray(X, dtype=float) @ self.coefficients
                    for X in Xs]

    def predict_stacked(self, Xs: np.ndarray) -> np.ndarray:
        """``predict_each(list(Xs))`` of float64 runs stacked (runs, samples, candidates) as
        one (runs, samples) array, in one product: numpy's matmul makes the same call on
        each run's block as on the block alone, so each run's row has its own bits (tests
        compare the two), without a product per run (a study predicts each of its many
        models on 23 held-out runs)."""
        with np.errstate(over="ignore", invalid="ignore"):
            return self.intercept + Xs @ self.coefficients


@dataclass
class EstimatorFit:
    """A fitted model that is not ``intercept + X @ coefficients`` (gradient boosting, a
    network, a user's regressor or pipeline): the estimator, its training R^2; ``intercept``
    is NaN and ``coefficients`` None, so reports say there are none."""

    estimator: object
    r2: float
    intercept: float = math.nan
    coefficients: None = None

    def predict(self, X: np.ndarray) -> np.ndarray:
        """The estimator's prediction for candidate values (rises) ``X``, one value a row."""
        with np.errstate(over="ignore", invalid="ignore"):
            values = np.asarray(self.estimator.predict(np.asarray(X, dtype=float)), dtype=float)
        if values.shape not in ((X.shape[0],), (X.shape[0], 1)):
            raise SelectionError(f"{type(self.estimator).__name__}.predict gave shape "
                                 f"{values.shape} for {X.shape[0]} sample(s); one value each "
                                 "is needed")
        return values.reshape(-1)


def fit_ols(X: np.ndarray, y: np.ndarray, names: Sequence[str] | None = None) -> LinearFit:
    """Ordinary least squares with intercept.

    Needs at least features + 1 samples (fewer fit any data exactly and mean nothing).
    Collinear features give a ``SelectionWarning`` naming them (``names`` or "column i") and
    the minimum-norm fit. Values whose squares overflow raise ``SelectionOverflowError``.
    """
    X = np.asarray(X, dtype=float)
    y = np.asarray(y, dtype=float).ravel()
    if X.ndim != 2 or X.shape[0] != y.shape[0]:
        raise SelectionError(f"regression needs X (n x p) and y (n); got {X.shape}, {y.shape}")
    if X.shape[0] < 2:
        raise SelectionError(f"regression needs at least 2 samples, got {X.shape[0]}")
    if X.shape[0] < X.shape[1] + 1:
        raise SelectionError(
            f"regression needs at least features + 1 = {X.shape[1] + 1} samples, got "
            f"{X.shape[0]} (with fewer, any data fit exactly)"
        )
    check_names(names, X.shape[1])
    if not (np.isfinite(X).all() and np.isfinite(y).all()):
        raise SelectionError("regression inputs must be finite (no NaN or inf)")
    with np.errstate(over="ignore", invalid="ignore"):
        # X.mean(axis=0) and y.mean(): the same sums and divisions (as ``rmse``), without
        # np.mean's Python wrapper (a sweep fits 18 models per training run)
        x_mean = np.add.reduce(X, axis=0) / X.shape[0]
        y_mean = np.add.reduce(y) / y.shape[0]
        centred = X - x_mean
        try:
            coefficients, _, rank, _ = np.linalg.lstsq(centred, y - y_mean, rcond=None)
        except np.linalg.LinAlgError as exc:
            raise SelectionOverflowError(
                f"values too large to fit (overflow; the solver failed: {exc})"
            ) from exc
        intercept = float(y_mean - x_mean @ coefficients)
        fitted = intercept + X @ coefficients
    if not (np.isfinite(intercept) and np.isfinite(coefficients).all()
            and np.isfinite(fitted).all()):
        raise SelectionOverflowError("values too large to fit (overflow)")
    if rank < X.shape[1]:
        _warn_collinear(centred, int(rank), names)
    with np.errstate(over="ignore", invalid="ignore"):  # r2_score(y, fitted): both finite
        r2 = _r2(y, fitted, y_mean, True)
    return LinearFit(intercept=intercept, coefficients=coefficients, r2=r2)


def _warn_collinear(centred: np.ndarray, rank: int, names: Sequence[str] | None) -> None:
    """Name the features that add nothing to the ones before them (a constant column, a
    duplicate, or a sum or difference of others)."""
    dependent: list[str] = []
    independent: list[int] = []
    for j in range(centred.shape[1]):
        trial = [*independent, j]
        if np.linalg.matrix_rank(centred[:, trial]) == len(trial):
            independent = trial
        else:
            dependent.append(str(names[j]) if names is not None else f"column {j}")
    which = f"feature(s) {', '.join(dependent)} are" if dependent else "features are"
    warnings.warn(
        f"regression: {which} linear combinations of the "
        f"others or constant (rank {rank} of {centred.shape[1]}); the fit is the "
        f"minimum-norm one and their coefficients are not unique",
        SelectionWarning,
        stacklevel=3,
    )
