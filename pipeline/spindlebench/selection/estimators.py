"""scikit-learn pieces of the method, composable in a ``sklearn.pipeline.Pipeline``.

- ``PairwiseDifferences``: appends every pair's difference ``A-B`` (step 1).
- ``FuzzyClusterSelector``: similarity, closure, cut and |psi| selection (steps 2-5).
- ``RiseRegressor``: OLS with intercept on temperature rises, training R^2 in ``r2_`` (step 6).
- ``RiseTransformer``: subtracts a fixed reference row (explicit, or the first row of fit).

Where the rise reference comes from: the paper's Delta T is relative to the first sample of
*each* experiment, but scikit-learn's ``transform``/``predict`` see neither experiment labels
nor (under its estimator checks) whole experiments: they must give the same answer on any
subset of rows. A "first row of each call" transformer would break that contract, so the
per-experiment rise is data preparation, done once before the pipeline with
``rises(X, groups)`` (``spindlebench.selection.regression``). Every step before the regression
is invariant to per-experiment offsets (correlations centre the data), so only the regression
sees a difference. ``RiseTransformer`` covers the single-experiment case with a fixed,
learned-at-fit reference and passes the estimator checks.

Example::

    Xr = rises(X, groups)
    model = make_selection_pipeline(k=2, differences=True)
    for train, test in TrainOnOneExperiment().split(Xr, y, groups):
        model.fit(Xr[train], y[train]).predict(Xr[test])
"""

from __future__ import annotations

import warnings
from typing import ClassVar

import numpy as np
from sklearn.base import (
    BaseEstimator,
    OneToOneFeatureMixin,
    TransformerMixin,
    _fit_context,
)
from sklearn.pipeline import Pipeline
from sklearn.utils.validation import (
    FLOAT_DTYPES,
    _check_feature_names_in,
    check_is_fitted,
    validate_data,
)

from spindlebench.core.names import DEFAULT_SIMILARITY
from spindlebench.selection.differences import difference_names, pairwise_differences
from spindlebench.selection.errors import SelectionError
from spindlebench.selection.regression import fit_ols
from spindlebench.selection.regressors import LinearRiseModel
from spindlebench.selection.select import select_sensitive_points
from spindlebench.selection.selectors import DEPRECATED, SupportFromSelected


class PairwiseDifferences(TransformerMixin, BaseEstimator):
    """Append the difference ``A-B`` of every pair of input columns, A before B.

    Parameters
    ----------
    include_raw : bool, default=True
        Keep the raw columns in front of the differences (the paper's candidate set).
    """

    # scikit-learn checks it at fit: "no" would otherwise be truthy and keep the raw columns
    _parameter_constraints: ClassVar[dict] = {"include_raw": ["boolean"]}

    def __init__(self, include_raw: bool = True):
        self.include_raw = include_raw

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y=None):
        """Remember the number (and names) of the input columns."""
        validate_data(self, X, dtype=FLOAT_DTYPES)
        return self

    def transform(self, X):
        """Raw columns (if ``include_raw``) followed by all pairwise differences."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=FLOAT_DTYPES, reset=False)
        differences = pairwise_differences(X).astype(X.dtype, copy=False)
        return np.hstack([X, differences]) if self.include_raw else differences

    def get_feature_names_out(self, input_features=None):
        """Input names (if ``include_raw``) followed by ``A-B`` names."""
        check_is_fitted(self)
        names = list(_check_feature_names_in(self, input_features))
        out = (names if self.include_raw else []) + difference_names(names)
        return np.asarray(out, dtype=object)


class RiseTransformer(OneToOneFeatureMixin, TransformerMixin, BaseEstimator):
    """Subtract a reference row: temperature rises Delta T = T - T_ref.

    Parameters
    ----------
    reference : array-like of shape (n_features,) or None, default=None
        The reference temperatures; None takes the first row seen by ``fit``. For rises
        relative to each experiment's own first sample use ``rises(X, groups)`` instead (see
        the module docstring for why).
    """

    def __init__(self, reference=None):
        self.reference = reference

    def fit(self, X, y=None):
        """Store ``reference_`` (the given reference, or the first row of ``X``)."""
        X = validate_data(self, X, dtype=FLOAT_DTYPES)
        if self.reference is None:
            self.reference_ = X[0].copy()
        else:
            reference = np.asarray(self.reference, dtype=float).ravel()
            if reference.shape != (X.shape[1],):
                raise SelectionError(
                    f"reference has {reference.size} values but X has {X.shape[1]} feature(s)"
                )
            bad = np.flatnonzero(~np.isfinite(reference))
            if bad.size:  # every rise of that feature would be NaN
                raise SelectionError(
                    f"reference must be finite; NaN or inf at position(s) "
                    f"{', '.join(map(str, bad[:10].tolist()))}"
                )
            self.reference_ = reference
        return self

    def transform(self, X):
        """``X - reference_``."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=FLOAT_DTYPES, reset=False)
        return X - self.reference_.astype(X.dtype, copy=False)


class FuzzyClusterSelector(SupportFromSelected):
    """Keep one candidate per fuzzy cluster: the one most correlated with the error.

    Parameters
    ----------
    k : int, default=2
        Requested number of clusters (the paper uses 2, 3, 4), hence of selected candidates.
    similarity : {"abs-pearson", "literal"}, default="abs-pearson"
        Reading of eq. 1 (see ``spindlebench.selection.similarity``).
    closure : {"fast", "squaring"}, default="fast"
        Implementation of t(R); both give identical results.
    n_clusters : int, deprecated
        Old name of ``k`` (one release; given, it wins with a ``FutureWarning``).

    Attributes
    ----------
    eta_ : float
        Threshold of the cut.
    clusters_ : list of ndarray
        Input column indices of each cluster, ordered by first member.
    selected_ : ndarray
        Input column index kept from each cluster (same order as ``clusters_``).
    psi_ : ndarray of shape (n_features_in_,)
        Pearson correlation of every input column with the error; NaN for constant columns,
        which are dropped with a ``SelectionWarning``.
    similarity_, closure_ : ndarray
        R and t(R) over the non-constant columns ``kept_``, formed when first read. Inputs of
        raw sensors and all their differences (``PairwiseDifferences``) above 2 000 columns
        are selected without them (``select_sensitive_points``); there they are formed up to
        6 000 columns, beyond that reading them is a ``SelectionError``.
    """

    def __init__(self, k: int = 2, similarity: str = DEFAULT_SIMILARITY,
                 closure: str = "fast", n_clusters=DEPRECATED):
        self.k = k
        self.similarity = similarity
        self.closure = closure
        self.n_clusters = n_clusters

    def fit(self, X, y):
        """Run steps 2-5 on candidates ``X`` and thermal error ``y``."""
        X, y = validate_data(self, X, y, dtype=np.float64, y_numeric=True, ensure_min_samples=2)
        names = getattr(self, "feature_names_in_", None)
        selection = select_sensitive_points(
            X, y, self._k(), self.similarity, self.closure, names=names
        )
        self.selection_ = selection
        self.eta_ = selection.eta
        self.clusters_ = selection.clusters
        self.selected_ = selection.selected
        self.psi_ = selection.psi
        self.kept_ = selection.kept
        return self

    @property
    def similarity_(self) -> np.ndarray:
        check_is_fitted(self, "selection_")
        return self.selection_.similarity

    @property
    def closure_(self) -> np.ndarray:
        check_is_fitted(self, "selection_")
        return self.selection_.closure


class RiseRegressor(LinearRiseModel):
    """Ordinary least squares with intercept of the thermal error on temperature rises.

    Attributes
    ----------
    intercept_ : float
    coef_ : ndarray of shape (n_features_in_,)
    r2_ : float
        Training R^2 (the paper's Table 5).
    """

    def fit(self, X, y):
        """Fit on rises ``X`` and error ``y``."""
        X, y = validate_data(self, X, y, dtype=np.float64, y_numeric=True, ensure_min_samples=2)
        names = getattr(self, "feature_names_in_", None)
        fit = fit_ols(X, y, names=None if names is None else list(names))
        self.intercept_ = fit.intercept
        self.coef_ = fit.coefficients
        self.r2_ = fit.r2
        return self


def make_selection_pipeline(
    k: int = 2,
    differences: bool = False,
    similarity: str = DEFAULT_SIMILARITY,
    closure: str = "fast",
    n_clusters: int | None = None,
) -> Pipeline:
    """The paper's model as a Pipeline; feed it rises (``rises(X, groups)``).
    ``n_clusters`` is the deprecated old name of ``k`` (one release)."""
    if n_clusters is not None:
        warnings.warn("make_selection_pipeline: 'n_clusters' is deprecated and will be removed "
                      "in the next release; use 'k'", FutureWarning, stacklevel=2)
        k = n_clusters
    steps = [("differences", PairwiseDifferences())] if differences else []
    steps += [
        ("select", FuzzyClusterSelector(k, similarity, closure)),
        ("regress", RiseRegressor()),
    ]
    return Pipeline(steps)
