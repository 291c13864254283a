"""Regressors after a selector: ridge and PLS on rises, beside OLS (``RiseRegressor``).

Thermal-error papers use these besides multiple linear regression. All three are linear in
the rises, so each exposes ``intercept_`` and ``coef_`` in the units of its input (um and
um/K), which is what ``evaluate`` reports and what a controller would run.

- ``RidgeRiseRegressor``: ridge on standardised rises, the penalty chosen by K-fold
  cross-validation over *contiguous time blocks* of the training run (``blocked_cv_alpha``):
  neighbouring samples of a heating curve are nearly equal, so a shuffled split would reward
  fitting noise.
  A penalty at the edge of its grid is widened once (``widened_cv_alpha``) and, still at
  the edge, warned (one line, a ``SelectionWarning``, hence in ``evaluate --json``'s
  ``provenance.warnings``): at the upper edge the fit is the constant training mean in
  effect, at the lower edge it is OLS.
- ``PLSRiseRegressor``: scikit-learn's ``PLSRegression`` with at most ``n_components``
  components (never more than the features it is given, so it composes after a selector of
  any budget).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from numbers import Integral
from typing import ClassVar

import numpy as np
import scipy.linalg
from sklearn.base import BaseEstimator, RegressorMixin, _fit_context
from sklearn.cross_decomposition import PLSRegression
from sklearn.model_selection import KFold
from sklearn.utils._param_validation import Interval
from sklearn.utils.validation import check_is_fitted, validate_data

from spindlebench.selection.errors import SelectionWarning
from spindlebench.selection.regression import r2_score

RIDGE_ALPHAS = np.logspace(-4, 4, 17)


#: ``blocked_cv_alpha`` with ``factors`` trusts the errors of the factored SVDs only when the
#: best penalty beats the runner-up by more than this fraction of its error; a closer race is
#: decided by the full SVDs. Measured on 336 training runs of the season sweep (every run of
#: 2 replicas x 7 conditions): the two ways' errors differ by at most 4.4e-11 of the error
#: (median 2e-14), the closest race was 3.1e-8 (1 % of the races are closer than 1e-7).
#: The folds stacked (``_factored_fold_errors``), on the 280 training runs of a 10-replica
#: sweep's jobs: at most 6.6e-11, no race within the margin, the full SVDs' penalty on all.
FACTORED_MARGIN = 1e-8
#: The factored cross-validation takes a candidate's deviation from the data, not from the
#: factors, below this fraction of its fold's largest deviation (``_factored_fold_errors``).
CONSTANT_FRACTION = 1e-10


def blocked_cv_alpha(X: np.ndarray, y: np.ndarray, alphas: np.ndarray = RIDGE_ALPHAS,
                     n_folds: int = 5,
                     factors: tuple[np.ndarray, np.ndarray] | None = None) -> float:
    """The ridge penalty with the lowest K-fold error over contiguous time blocks.

    Blocks, not shuffled rows (see the module docstring). One SVD per fold serves every
    alpha, which makes this some fifty times faster than a grid search refitting per alpha.
    Columns are standardised per fold (a constant column stays 0).

    ``factors`` ``(A, B)`` with ``X = A @ B`` (``A`` n × r with r much smaller than X's
    columns: 20 raw rises and their 190 differences are ``A @ [I | D]``) give the same
    penalty in a fraction of the time: each fold's standardised ``X`` is then
    ``(A - mean) @ B / scale``, whose SVD follows from a QR of the n × r ``A`` and an SVD of
    an r × columns matrix instead of the n × columns one. That rounds differently, so the
    factored errors decide only a clear race (``FACTORED_MARGIN``); a close one is decided
    by the full SVDs, so the penalty is the one the full SVDs give. (So the factored way
    also scores every alpha in one product rather than one by one: another rounding, some
    1e-15 of the error, far inside that margin.)
    """
    X = np.asarray(X, dtype=float)
    y = np.asarray(y, dtype=float)
    if factors is not None:
        errors = _fold_errors(X, y, alphas, n_folds, factors)
        best, runner_up = np.partition(errors, 1)[:2] if len(errors) > 1 else (errors[0], np.inf)
        if np.isfinite(errors).all() and runner_up - best > FACTORED_MARGIN * best:
            return float(alphas[int(np.argmin(errors))])
    return float(alphas[int(np.argmin(_fold_errors(X, y, alphas, n_folds)))])


def _fold_errors(X: np.ndarray, y: np.ndarray, alphas: np.ndarray, n_folds: int,
                 factors: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Summed squared validation error per alpha (full SVDs, or factored ones)."""
    if factors is not None:
        return _factored_fold_errors(X, y, alphas, n_folds, *factors)
    errors = np.zeros(len(alphas))
    for train, valid in KFold(min(n_folds, X.shape[0])).split(X):
        X_train = X[train]
        mean = X_train.mean(axis=0)
        scale = X_train.std(axis=0)
        scale[scale == 0] = 1.0
        Xv = (X[valid] - mean) / scale
        y_mean = y[train].mean()
        U, s, Vt = np.linalg.svd((X_train - mean) / scale, full_matrices=False)
        Uty = U.T @ (y[train] - y_mean)
        for i, alpha in enumerate(alphas):  # the errors that decide a close race
            coef = Vt.T @ (s / (s**2 + alpha) * Uty)
            errors[i] += np.sum((Xv @ coef + y_mean - y[valid]) ** 2)
    return errors


def fold_sizes(n_samples: int, n_folds: int) -> np.ndarray:
    """The lengths of ``KFold(n_folds)``'s contiguous validation blocks, in order (the
    first ``n_samples % n_folds`` one sample longer), as scikit-learn splits them."""
    sizes = np.full(n_folds, n_samples // n_folds)
    sizes[: n_samples % n_folds] += 1
    return sizes


def _factored_fold_errors(X: np.ndarray, y: np.ndarray, alphas: np.ndarray, n_folds: int,
                          A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``_fold_errors`` of ``X = A @ B`` from small factored problems, every fold at once.

    Each fold's centred training ``X`` is ``Ac @ B`` (``Ac``: the fold's ``A`` centred);
    ``Ac = Q R`` with ``Q`` orthonormal, so the columns' standard deviations are those of
    ``R @ B`` (norms over sqrt(samples)), the standardised ``X``'s SVD is ``Q`` times that
    of the r × columns ``R @ B / scale``, and ``Q``'s share of the target,
    ``Q.T @ (y - mean)``, is the last column of the R of ``[Ac | y - mean]``. The
    validation rows are predicted through ``A`` too: ``(A - mean) @ (B / scale) @ V @
    filter``. Why: the folds' QRs, SVDs and products are each one stacked LAPACK or BLAS
    call (training parts zero-padded to one length, which changes no R) instead of one per
    fold and alpha, and no fold's n × columns ``X`` is copied or scanned: a fifth of the
    ridge baseline's time before. The errors round differently from the full SVDs'
    (``FACTORED_MARGIN``). A candidate whose deviation there is below ``CONSTANT_FRACTION``
    of the fold's largest, where R's rounding could leave a column constant in the data
    (an exact zero: scale 1) a tiny scale, takes its deviation from the data as before."""
    n, r = A.shape
    k = min(n_folds, n)
    sizes = fold_sizes(n, k)
    stops = np.cumsum(sizes)
    augmented = np.zeros((k, n - int(sizes.min()), r + 1))
    means = np.empty((k, r))
    y_means = np.empty(k)
    trains = []
    for fold, (start, stop) in enumerate(zip(stops - sizes, stops, strict=True)):
        train = np.r_[0:start, stop:n]
        A_train, y_train = A[train], y[train]
        means[fold], y_means[fold] = A_train.mean(axis=0), y_train.mean()
        augmented[fold, : train.size, :r] = A_train - means[fold]
        augmented[fold, : train.size, r] = y_train - y_means[fold]
        trains.append(train)
    R = np.linalg.qr(augmented, mode="r")
    RB = R[:, :r, :r] @ B
    scale = np.sqrt(np.einsum("fij,fij->fj", RB, RB) / (n - sizes)[:, None])
    for fold, columns in zip(*np.nonzero(
            scale <= CONSTANT_FRACTION * scale.max(axis=1, keepdims=True)), strict=True):
        scale[fold, columns] = X[trains[fold], columns].std()
    scale[scale == 0] = 1.0
    # the SVD of the transposed (tall) matrix: M.T = U' s Vt' gives M's U = Vt'.T, V = U'
    V, s, Ut = np.linalg.svd(np.swapaxes(RB / scale[:, None, :], 1, 2), full_matrices=False)
    Uty = Ut @ R[:, :r, r:]  # (folds, r, 1)
    filters = s[:, :, None] / (s[:, :, None] ** 2 + alphas) * Uty
    per_fold = ((B / scale[:, None, :]) @ V) @ filters  # (folds, r, alphas)
    fold_of = np.repeat(np.arange(k), sizes)
    predicted = np.einsum("ir,ira->ia", A - means[fold_of], per_fold[fold_of])
    return np.sum((predicted + y_means[fold_of, None] - y[:, None]) ** 2, axis=0)


@dataclass(frozen=True)
class StandardisedRidge:
    """``make_pipeline(StandardScaler(), Ridge(alpha))`` fitted: the scaler's ``mean_`` and
    ``scale_``, the ridge's ``coef_`` and ``intercept_``."""

    mean: np.ndarray
    scale: np.ndarray
    coef: np.ndarray
    intercept: np.ndarray


def standardised_ridge(X: np.ndarray, y: np.ndarray, alpha: float) -> StandardisedRidge | None:
    """``StandardScaler().fit(X)`` and ``Ridge(alpha).fit(scaler.transform(X), y)`` of
    finite float64 ``X`` and ``y`` (1-D), as scikit-learn 1.9 computes them
    (``_incremental_mean_and_var``, ``_is_constant_feature``; ``_preprocess_data`` and the
    "auto" solver's Cholesky on X^T X, or on X X^T when there are more columns than
    samples): the same NumPy and SciPy operations on arrays of the same layouts, so the
    same bits (tests compare the two), without scikit-learn checking the arrays (half of
    the two fits' time, the sweep's ridge baseline fits one per training run). None where
    scikit-learn would do otherwise (values it refuses, a Cholesky that fails: it then
    falls back to an SVD): the caller fits scikit-learn's estimators.
    """
    if X.ndim != 2 or y.ndim != 1 or X.shape[0] != y.shape[0] or X.shape[0] < 1 \
            or X.dtype != np.float64 or y.dtype != np.float64 \
            or not (np.isfinite(X).all() and np.isfinite(y).all()):
        return None
    n_samples, n_features = X.shape
    # StandardScaler.partial_fit, first call, no NaN: _incremental_mean_and_var from zeros
    count = n_samples - np.zeros(n_features)
    total = np.sum(X, axis=0)
    mean = (np.zeros(n_features) + total) / count
    deviation = X - total / count
    correction = np.sum(deviation, axis=0)
    deviation **= 2
    unnormalised = np.sum(deviation, axis=0)
    unnormalised -= correction**2 / count
    variance = unnormalised / count
    eps = np.finfo(np.float64).eps
    seen = count[0]
    constant = variance <= seen * eps * variance + (seen * mean * eps) ** 2
    scale = np.sqrt(variance)
    scale[constant] = 1.0
    Z = (X - mean) / scale  # StandardScaler.transform
    if not np.isfinite(Z).all():  # Ridge would refuse
        return None
    # Ridge.fit: _preprocess_data centres a copy, then the Cholesky solver
    offset = np.asarray(np.average(Z, axis=0))
    Z -= offset
    y_offset = np.asarray(np.average(y, axis=0))
    targets = (y - y_offset).reshape(-1, 1)
    try:
        if n_features > n_samples:
            K = Z @ Z.T
            K.flat[:: n_samples + 1] += alpha
            dual = scipy.linalg.solve(K, targets, assume_a="pos", overwrite_a=False)
            coef = (Z.T @ dual).T
        else:
            A = Z.T @ Z
            Xy = Z.T @ targets
            A.flat[:: n_features + 1] += alpha
            coef = scipy.linalg.solve(A, Xy, assume_a="pos", overwrite_a=True).T
    except np.linalg.LinAlgError:  # scikit-learn then solves by SVD
        return None
    coef = np.divide(np.ravel(coef), np.ones(n_features))
    return StandardisedRidge(mean, scale, coef, y_offset - offset @ coef)


def widened_cv_alpha(X: np.ndarray, y: np.ndarray, alphas: np.ndarray = RIDGE_ALPHAS,
                     n_folds: int = 5) -> tuple[float, np.ndarray, str | None]:
    """``blocked_cv_alpha``, widening the grid once when the penalty sits at its edge.

    Why: the largest penalty of the grid makes ridge the constant training mean in effect
    (issue 23: the largest of the grid was chosen in 20 of 66 cells of a real set, silently).
    An edge choice is re-decided on the grid extended beyond that edge by the grid's own span
    in log space (1e-4..1e4 -> up to 1e12, or down to 1e-12), at the same spacing. Returns the
    penalty, the grid it was chosen on, and ``"upper"``/``"lower"`` if it is still at that
    grid's edge (else None); the caller warns.
    """
    alphas = np.sort(np.asarray(alphas, dtype=float))
    alpha = blocked_cv_alpha(X, y, alphas, n_folds)
    if alphas.size < 2:
        return alpha, alphas, None
    edge = "upper" if alpha == alphas[-1] else "lower" if alpha == alphas[0] else None
    if edge is None:
        return alpha, alphas, None
    span = alphas[-1] / alphas[0]
    extension = alphas[1:] * span if edge == "upper" else alphas[:-1] / span
    grid = np.sort(np.concatenate([alphas, extension]))
    alpha = blocked_cv_alpha(X, y, grid, n_folds)
    still = (edge == "upper" and alpha == grid[-1]) or (edge == "lower" and alpha == grid[0])
    return alpha, grid, edge if still else None


def edge_message(alpha: float, edge: str) -> str:
    """The one-line warning of a penalty still at its (widened) grid's edge."""
    effect = ("the fit is the constant training mean in effect" if edge == "upper"
              else "the fit is ordinary least squares in effect")
    return (f"ridge: the cross-validated penalty {alpha:.3g} is the {edge} edge of its grid "
            f"even after widening it once; {effect}")


class LinearRiseModel(RegressorMixin, BaseEstimator):
    """A fitted ``error = intercept_ + rises @ coef_``: the prediction every rise regressor
    shares (OLS, ridge, PLS); subclasses fit ``intercept_`` and ``coef_``."""

    def predict(self, X):
        """Predicted error for rises ``X``."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        return self.intercept_ + X @ self.coef_


class RidgeRiseRegressor(LinearRiseModel):
    """Ridge regression on standardised rises, penalty by blocked cross-validation.

    Parameters
    ----------
    alphas : array-like of float or None, default=None
        Penalties tried (None: 17 values from 1e-4 to 1e4, log-spaced).
    n_folds : int, default=5
        Contiguous time blocks of the cross-validation (fewer if there are fewer samples).

    Attributes
    ----------
    alpha_ : float
        The chosen penalty.
    alphas_ : ndarray
        The grid it was chosen on (``alphas``, widened once if the first choice was an edge).
    alpha_at_edge_ : {"upper", "lower"} or None
        The edge of ``alphas_`` the penalty still sits at (warned), else None.
    intercept_ : float
    coef_ : ndarray of shape (n_features_in_,)
        In the units of the input (um/K for rises), not of the standardised columns.
    r2_ : float
        Training R^2.

    Examples
    --------
    >>> import numpy as np
    >>> X = np.linspace(0, 10, 40)[:, None] * [1.0, 0.5]
    >>> y = 3.0 * X[:, 0] + 1.0
    >>> model = RidgeRiseRegressor().fit(X, y)
    >>> bool(np.allclose(model.predict(X), y, atol=0.1))
    True
    """

    _parameter_constraints: ClassVar[dict] = {
        "alphas": ["array-like", None],
        "n_folds": [Interval(Integral, 2, None, closed="left")],
    }

    def __init__(self, alphas=None, n_folds: int = 5):
        self.alphas = alphas
        self.n_folds = n_folds

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y):
        """Choose the penalty on blocks of ``X``, then fit on all of it."""
        X, y = validate_data(self, X, y, dtype=np.float64, y_numeric=True, ensure_min_samples=2)
        alphas = RIDGE_ALPHAS if self.alphas is None else np.asarray(self.alphas, dtype=float)
        self.alpha_, self.alphas_, self.alpha_at_edge_ = widened_cv_alpha(X, y, alphas,
                                                                           self.n_folds)
        if self.alpha_at_edge_ is not None:
            warnings.warn(edge_message(self.alpha_, self.alpha_at_edge_), SelectionWarning,
                          stacklevel=2)
        mean, scale = X.mean(axis=0), X.std(axis=0)
        scale[scale == 0] = 1.0
        Z = (X - mean) / scale
        y_mean = y.mean()
        U, s, Vt = np.linalg.svd(Z, full_matrices=False)
        coef_z = Vt.T @ (s / (s**2 + self.alpha_) * (U.T @ (y - y_mean)))
        self.coef_ = coef_z / scale
        self.intercept_ = float(y_mean - mean @ self.coef_)
        self.r2_ = r2_score(y, self.intercept_ + X @ self.coef_)
        return self


class PLSRiseRegressor(LinearRiseModel):
    """Partial least squares (scikit-learn ``PLSRegression``) on rises.

    Parameters
    ----------
    n_components : int, default=2
        Largest number of components; capped at the number of features (and samples - 1).

    Attributes
    ----------
    n_components_ : int
        Components used.
    pls_ : PLSRegression
        The fitted scikit-learn model.
    intercept_ : float
    coef_ : ndarray of shape (n_features_in_,)
        In the units of the input.
    r2_ : float
        Training R^2.

    Examples
    --------
    Two rises that are one rise (proportional) leave a single component:

    >>> import numpy as np
    >>> rise = np.linspace(0, 10, 40)
    >>> model = PLSRiseRegressor().fit(np.column_stack([rise, 0.5 * rise]), 2.0 * rise)
    >>> model.n_components_
    1
    """

    _parameter_constraints: ClassVar[dict] = {
        "n_components": [Interval(Integral, 1, None, closed="left")],
    }

    def __init__(self, n_components: int = 2):
        self.n_components = n_components

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y):
        """Fit PLS with min(n_components, rank-limited) components."""
        X, y = validate_data(self, X, y, dtype=np.float64, y_numeric=True, ensure_min_samples=2)
        rank = int(np.linalg.matrix_rank(X - X.mean(axis=0)))
        self.n_components_ = max(1, min(self.n_components, X.shape[1], X.shape[0] - 1, rank))
        self.pls_ = PLSRegression(self.n_components_).fit(X, y)
        self.coef_ = np.asarray(self.pls_.coef_, dtype=float).reshape(-1)
        # PLSRegression predicts (X - mean(X)) @ coef + mean(y); fold the centring in
        self.intercept_ = float(np.ravel(self.pls_.intercept_)[0] - X.mean(axis=0) @ self.coef_)
        self.r2_ = r2_score(y, self.intercept_ + X @ self.coef_)
        return self
