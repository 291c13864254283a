"""Selection by mutual information: the k most informative candidates, and mRMR.

Mutual information catches dependence a correlation misses (a rise that drives the error
nonlinearly). ``MutualInfoSelector`` ranks the candidates by their estimated mutual
information with the error (scikit-learn's ``mutual_info_regression``, the Kraskov k-nearest-
neighbour estimator with ``n_neighbors`` 3; it adds a tiny seeded jitter, so the ranking is
seeded). ``MRMRSelector`` (Peng et al. 2005, "MID" form) adds candidates greedily by
relevance minus redundancy: the first is the most informative; each next one maximises its
mutual information with the error minus its mean mutual information with those already
chosen, so a near copy of a chosen sensor is passed over.
"""

from __future__ import annotations

from numbers import Integral
from typing import ClassVar

import numpy as np
from sklearn.base import _fit_context
from sklearn.feature_selection import mutual_info_regression
from sklearn.utils._param_validation import Interval

from spindlebench.selection.errors import SelectionError
from spindlebench.selection.randomness import RANDOM_STATE_CONSTRAINT, int_seed
from spindlebench.selection.selectors import K_CONSTRAINT, _budget, _Selector
from spindlebench.selection.similarity import constant_columns


def mutual_information(X: np.ndarray, y: np.ndarray, n_neighbors: int, seed: int) -> np.ndarray:
    """Estimated mutual information (nats) of each column of ``X`` with ``y``; -1 for
    constant columns (ranked last)."""
    out = np.full(X.shape[1], -1.0)
    varying = ~constant_columns(X)
    if varying.any():
        out[varying] = mutual_info_regression(X[:, varying], y, n_neighbors=n_neighbors,
                                              random_state=seed)
    return out


class MutualInfoSelector(_Selector):
    """The ``k`` candidates with the largest mutual information with the error.

    Parameters
    ----------
    k : int, default=2
    n_neighbors : int, default=3
        Neighbours of the Kraskov estimator.
    random_state : None, int or numpy.random.Generator, default=0

    Attributes
    ----------
    scores_ : ndarray of shape (n_features_in_,)
        Mutual information with the error (nats; -1 for constant columns).
    selected_ : ndarray
        Input columns, most informative first.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.normal(size=(200, 3))
    >>> MutualInfoSelector(1).fit(X, X[:, 1] ** 2).selected_.tolist()
    [1]
    """

    _parameter_constraints: ClassVar[dict] = {
        "k": K_CONSTRAINT,
        "n_neighbors": [Interval(Integral, 1, None, closed="left")],
        "random_state": RANDOM_STATE_CONSTRAINT,
    }

    def __init__(self, k: int = 2, n_neighbors: int = 3, random_state=0):
        self.k = k
        self.n_neighbors = n_neighbors
        self.random_state = random_state

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y):
        """Estimate each column's mutual information with ``y`` and keep the top ``k``."""
        X, y = self._data(X, y)
        _budget(self.k, X.shape[1])
        self.scores_ = mutual_information(X, y, self.n_neighbors, int_seed(self.random_state))
        order = [i for i in np.argsort(-self.scores_, kind="stable") if self.scores_[i] >= 0]
        if len(order) < self.k:
            raise SelectionError(f"only {len(order)} candidate(s) vary; cannot select {self.k}")
        self.selected_ = np.asarray(order[: self.k], dtype=np.intp)
        return self


class MRMRSelector(_Selector):
    """Minimum redundancy, maximum relevance (mutual information; greedy).

    Parameters
    ----------
    k : int, default=2
    n_neighbors : int, default=3
    random_state : None, int or numpy.random.Generator, default=0

    Attributes
    ----------
    relevance_ : ndarray of shape (n_features_in_,)
        Mutual information with the error (-1 for constant columns).
    selected_ : ndarray
        Input columns in the order they were added.
    scores_ : ndarray
        Relevance minus mean redundancy of each added column when it was added.

    Examples
    --------
    Of a column and its near copy (0 and 1) only one is taken; the second pick is the
    independent column 2:

    >>> import numpy as np
    >>> rng = np.random.default_rng(1)
    >>> a, b = rng.normal(size=(2, 300))
    >>> X = np.column_stack([a, a + 0.01 * rng.normal(size=300), b])
    >>> MRMRSelector(2).fit(X, a + 0.7 * b).selected_.tolist()
    [1, 2]
    """

    _parameter_constraints: ClassVar[dict] = MutualInfoSelector._parameter_constraints

    def __init__(self, k: int = 2, n_neighbors: int = 3, random_state=0):
        self.k = k
        self.n_neighbors = n_neighbors
        self.random_state = random_state

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y):
        """Add, ``k`` times, the column with the largest relevance minus redundancy."""
        X, y = self._data(X, y)
        _budget(self.k, X.shape[1])
        seed = int_seed(self.random_state)
        self.relevance_ = mutual_information(X, y, self.n_neighbors, seed)
        varying = np.flatnonzero(self.relevance_ >= 0)
        if varying.size < self.k:
            raise SelectionError(f"only {varying.size} candidate(s) vary; cannot select {self.k}")
        chosen = [int(varying[np.argmax(self.relevance_[varying])])]
        scores = [float(self.relevance_[chosen[0]])]
        redundancy = np.zeros(X.shape[1])
        while len(chosen) < self.k:
            rest = np.array([i for i in varying if i not in chosen])
            redundancy[rest] += mutual_info_regression(X[:, rest], X[:, chosen[-1]],
                                                       n_neighbors=self.n_neighbors,
                                                       random_state=seed)
            merit = self.relevance_[rest] - redundancy[rest] / len(chosen)
            best = int(np.argmax(merit))
            chosen.append(int(rest[best]))
            scores.append(float(merit[best]))
        self.selected_ = np.asarray(chosen, dtype=np.intp)
        self.scores_ = np.asarray(scores)
        return self
