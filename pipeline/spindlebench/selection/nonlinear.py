"""Nonlinear regressors after a selector: gradient boosting and a small neural network.

scikit-learn's own estimators, wrapped so that they compose like the linear rise regressors
(seeded by ``random_state``, training R^2 in ``r2_``) and their defaults are the project's:

- ``BoostedRiseRegressor``: ``GradientBoostingRegressor`` (100 trees of depth 3, learning
  rate 0.1). Trees cannot extrapolate: beyond the rises seen in training the prediction is
  flat, which a benchmark across speeds shows.
- ``MLPRiseRegressor``: ``MLPRegressor`` with one hidden layer of 16 tanh units, L-BFGS,
  on standardised rises and a standardised error (a network fitted on raw um and K trains
  badly), weight penalty ``alpha`` 1e-3.

Neither is ``intercept + rises @ coef``: ``evaluate`` reports them without coefficients.
"""

from __future__ import annotations

import warnings
from numbers import Integral, Real
from typing import ClassVar

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin, _fit_context
from sklearn.ensemble import GradientBoostingRegressor
from sklearn.exceptions import ConvergenceWarning
from sklearn.neural_network import MLPRegressor
from sklearn.utils._param_validation import Interval, StrOptions
from sklearn.utils.validation import check_is_fitted, validate_data

from spindlebench.selection.randomness import RANDOM_STATE_CONSTRAINT, int_seed
from spindlebench.selection.regression import r2_score


class BoostedRiseRegressor(RegressorMixin, BaseEstimator):
    """Gradient boosting of the error on rises.

    Parameters
    ----------
    n_estimators : int, default=100
    max_depth : int, default=3
    learning_rate : float, default=0.1
    random_state : None, int or numpy.random.Generator, default=0

    Attributes
    ----------
    model_ : GradientBoostingRegressor
    r2_ : float
        Training R^2.

    Examples
    --------
    One stump with learning rate 1 is the best single split:

    >>> import numpy as np
    >>> X = np.array([[0.0], [1.0], [2.0], [3.0]])
    >>> model = BoostedRiseRegressor(1, max_depth=1, learning_rate=1.0).fit(X, [0, 0, 4, 4])
    >>> model.predict([[0.5], [2.5]]).tolist()
    [0.0, 4.0]
    """

    _parameter_constraints: ClassVar[dict] = {
        "n_estimators": [Interval(Integral, 1, None, closed="left")],
        "max_depth": [Interval(Integral, 1, None, closed="left")],
        "learning_rate": [Interval(Real, 0, None, closed="neither")],
        "random_state": RANDOM_STATE_CONSTRAINT,
    }

    def __init__(self, n_estimators: int = 100, max_depth: int = 3, learning_rate: float = 0.1,
                 random_state=0):
        self.n_estimators = n_estimators
        self.max_depth = max_depth
        self.learning_rate = learning_rate
        self.random_state = random_state

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y):
        """Fit the trees on rises ``X`` and error ``y``."""
        X, y = validate_data(self, X, y, dtype=np.float64, y_numeric=True, ensure_min_samples=2)
        self.model_ = GradientBoostingRegressor(
            n_estimators=self.n_estimators, max_depth=self.max_depth,
            learning_rate=self.learning_rate, random_state=int_seed(self.random_state),
        ).fit(X, y)
        self.r2_ = r2_score(y, self.model_.predict(X))
        return self

    def predict(self, X):
        """Predicted error for rises ``X``."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        return self.model_.predict(X)


class MLPRiseRegressor(RegressorMixin, BaseEstimator):
    """A small neural network (one hidden layer) on standardised rises.

    Parameters
    ----------
    hidden : int, default=16
        Units of the hidden layer.
    activation : {"tanh", "relu", "logistic", "identity"}, default="tanh"
    alpha : float, default=1e-3
        L2 penalty of the weights.
    max_iter : int, default=500
        L-BFGS iterations (a ``ConvergenceWarning`` at the limit is silenced: the network
        after ``max_iter`` steps is the model, as documented).
    random_state : None, int or numpy.random.Generator, default=0

    Attributes
    ----------
    model_ : MLPRegressor
    n_iter_ : int
        L-BFGS iterations run.
    r2_ : float
        Training R^2.

    Examples
    --------
    With the identity activation the network is a linear model, so on an exactly linear
    error it is the least-squares line:

    >>> import numpy as np
    >>> X = np.linspace(0, 10, 30)[:, None]
    >>> model = MLPRiseRegressor(activation="identity", alpha=0.0).fit(X, 3 * X[:, 0] + 1)
    >>> bool(np.allclose(model.predict([[20.0]]), 61.0, atol=1e-3))
    True
    """

    _parameter_constraints: ClassVar[dict] = {
        "hidden": [Interval(Integral, 1, None, closed="left")],
        "activation": [StrOptions({"tanh", "relu", "logistic", "identity"})],
        "alpha": [Interval(Real, 0, None, closed="left")],
        "max_iter": [Interval(Integral, 1, None, closed="left")],
        "random_state": RANDOM_STATE_CONSTRAINT,
    }

    def __init__(self, hidden: int = 16, activation: str = "tanh", alpha: float = 1e-3,
                 max_iter: int = 500, random_state=0):
        self.hidden = hidden
        self.activation = activation
        self.alpha = alpha
        self.max_iter = max_iter
        self.random_state = random_state

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y):
        """Standardise, fit the network, keep the scalings."""
        X, y = validate_data(self, X, y, dtype=np.float64, y_numeric=True, ensure_min_samples=2)
        self.x_mean_, self.x_scale_ = X.mean(axis=0), X.std(axis=0)
        self.x_scale_[self.x_scale_ == 0] = 1.0
        self.y_mean_, self.y_scale_ = float(y.mean()), float(y.std()) or 1.0
        self.model_ = MLPRegressor(hidden_layer_sizes=(self.hidden,),
                                   activation=self.activation, solver="lbfgs",
                                   alpha=self.alpha, max_iter=self.max_iter,
                                   random_state=int_seed(self.random_state))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            self.model_.fit((X - self.x_mean_) / self.x_scale_, (y - self.y_mean_) / self.y_scale_)
        self.n_iter_ = int(self.model_.n_iter_)
        self.r2_ = r2_score(y, self._predict(X))
        return self

    def _predict(self, X: np.ndarray) -> np.ndarray:
        scaled = self.model_.predict((X - self.x_mean_) / self.x_scale_)
        return self.y_mean_ + self.y_scale_ * np.asarray(scaled, dtype=float).ravel()

    def predict(self, X):
        """Predicted error for rises ``X``."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        return self._predict(X)
