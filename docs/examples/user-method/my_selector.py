"""A user's own selection method, scored by spindlebench exactly like a built-in.

    PYTHONPATH=docs/examples/user-method spindlebench benchmark \
        --method my_selector:DecorrelatedSelector -o results/benchmark/mine

Any scikit-learn selector works (SelectorMixin, or get_support() after fit); the budget
reaches it as ``k`` and the command's seed as ``random_state`` if it has one.
"""
import numpy as np
from sklearn.base import BaseEstimator
from sklearn.feature_selection import SelectorMixin
from sklearn.utils.validation import check_is_fitted, validate_data


class DecorrelatedSelector(SelectorMixin, BaseEstimator):
    """The candidate most correlated with the error, then each time the most correlated one
    whose |r| with every chosen candidate stays below ``max_overlap`` (a near copy of a
    chosen sensor adds nothing)."""

    def __init__(self, k=3, max_overlap=0.95):
        self.k = k
        self.max_overlap = max_overlap

    def fit(self, X, y):
        X, y = validate_data(self, X, y)
        r_y = np.abs([np.corrcoef(column, y)[0, 1] for column in X.T])
        r_xx = np.abs(np.corrcoef(X, rowvar=False))
        chosen = [int(np.argmax(r_y))]
        while len(chosen) < self.k:
            free = r_xx[:, chosen].max(axis=1) < self.max_overlap
            score = r_y - 2.0 * ~free  # none free: the most correlated of the rest
            score[chosen] = -np.inf
            chosen.append(int(np.argmax(score)))
        self.support_ = np.isin(np.arange(X.shape[1]), chosen)
        return self

    def _get_support_mask(self):
        check_is_fitted(self)
        return self.support_
