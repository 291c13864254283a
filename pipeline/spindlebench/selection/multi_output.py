"""Selectors that choose one candidate set for several thermal errors at once (issue 21).

A five-probe machine has five error components (X, Y, Z drift, tilts A and B); a compensation
of all of them wants one set of sensors, not one per component. Both selectors here take a
target matrix ``Y`` (samples x components; a 1-D ``y`` is one component) and keep ``k``
candidates for all components together:

- ``MultiTaskLassoSelector``: the first ``k`` candidates to enter the multi-task LASSO path
  (scikit-learn's ``lasso_path`` on a 2-D response: the group penalty on each candidate's row
  of coefficients, so a candidate enters for every component at once). Candidates and
  components are standardised first, so a µrad tilt and a µm drift weigh alike.
- ``PLSVIPSelector``: partial least squares with every component as a response
  (``PLSRegression``, ``min(k, rank)`` latent components), keeping the ``k`` candidates of
  largest VIP (variable importance in projection, Wold's measure summed over the latent
  components weighted by the response variance each explains).

With one component they are the LASSO path (same as ``lasso`` up to the solver: coordinate
descent on a grid, not LARS) and PLS1's VIP. Their registry names are in
``method_registry`` (``multi_output=True``), the one place that lists them.
"""

from __future__ import annotations

import warnings
from typing import ClassVar

import numpy as np
from sklearn.base import _fit_context
from sklearn.utils.validation import validate_data

from spindlebench.selection.errors import SelectionError
from spindlebench.selection.selectors import K_CONSTRAINT, SupportFromSelected, _budget
from spindlebench.selection.similarity import constant_columns

#: Points on the multi-task LASSO path (log-spaced down to ``PATH_EPS`` of the largest alpha).
PATH_ALPHAS = 100
PATH_EPS = 1e-4


def _standardised(X: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centred, unit-variance ``X`` and ``Y`` (constant columns of ``X`` left at 0), and the
    mask of the columns of ``X`` that vary."""
    scale = X.std(axis=0)
    varying = scale > 0
    Z = np.zeros_like(X)
    Z[:, varying] = (X[:, varying] - X[:, varying].mean(axis=0)) / scale[varying]
    W = (Y - Y.mean(axis=0)) / Y.std(axis=0)
    return Z, W, varying


class _MultiOutputSelector(SupportFromSelected):
    """Checked ``X`` and a 2-D ``Y`` whose components each vary."""

    def _data(self, X, y):
        X, Y = validate_data(self, X, y, dtype=np.float64, y_numeric=True, multi_output=True,
                             ensure_min_samples=2)
        Y = Y.reshape(len(Y), -1)
        flat = constant_columns(Y)
        if flat.any():
            raise SelectionError(f"target component(s) {np.flatnonzero(flat).tolist()} are "
                                 "constant; nothing to select for them")
        _budget(self.k, X.shape[1])
        return X, Y

    def _standardised_data(self, X, y):
        """``_data``, standardised (``_standardised``), refused if fewer than ``k`` candidates
        vary: ``X``, ``Z``, ``W`` and the mask of the varying columns."""
        X, Y = self._data(X, y)
        Z, W, varying = _standardised(X, Y)
        if varying.sum() < self.k:
            raise SelectionError(f"only {int(varying.sum())} candidate(s) vary; cannot select "
                                 f"{self.k}")
        return X, Z, W, varying

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.multi_output = True
        tags.target_tags.single_output = True
        return tags


class MultiTaskLassoSelector(_MultiOutputSelector):
    """The first k candidates to enter the multi-task LASSO path of all components.

    Walking down the path from the largest penalty, the first point with at least ``k``
    candidates active (a non-zero coefficient row) decides: those candidates ranked by when
    they entered, then by the norm of their coefficient row there. If the path never has
    ``k`` active ones, the rest are filled by their row norm at the smallest penalty.

    Attributes
    ----------
    selected_ : ndarray
        Input columns in order of entry.
    coef_norm_ : ndarray
        Each candidate's coefficient-row norm at the deciding point of the path.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.normal(size=(120, 6))
    >>> Y = np.c_[2 * X[:, 1] + X[:, 4], X[:, 4] - X[:, 1]] + 0.05 * rng.normal(size=(120, 2))
    >>> sorted(MultiTaskLassoSelector(2).fit(X, Y).selected_.tolist())
    [1, 4]
    """

    _parameter_constraints: ClassVar[dict] = {"k": K_CONSTRAINT}

    def __init__(self, k: int = 2):
        self.k = k

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y):
        """Compute the multi-task path on standardised data and keep its first k entries."""
        from sklearn.linear_model import lasso_path

        X, Z, W, varying = self._standardised_data(X, y)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # convergence warnings at tiny penalties
            _, coefs, _ = lasso_path(Z[:, varying], W, eps=PATH_EPS, alphas=PATH_ALPHAS)
        coefs = coefs.reshape(W.shape[1], int(varying.sum()), -1)
        norms = np.sqrt((coefs ** 2).sum(axis=0))  # candidates x penalties, decreasing
        active = norms > 0
        entry = np.where(active.any(axis=1), np.argmax(active, axis=1), active.shape[1])
        reached = np.flatnonzero(active.sum(axis=0) >= self.k)
        step = int(reached[0]) if reached.size else active.shape[1] - 1
        order = np.lexsort((-norms[:, step], entry))
        columns = np.flatnonzero(varying)
        self.coef_norm_ = np.zeros(X.shape[1])
        self.coef_norm_[columns] = norms[:, step]
        self.selected_ = columns[order[:self.k]].astype(np.intp)
        return self


class PLSVIPSelector(_MultiOutputSelector):
    """The k candidates of largest VIP in a PLS regression of all components.

    Attributes
    ----------
    selected_ : ndarray
        Input columns by decreasing VIP.
    vip_ : ndarray
        Every candidate's VIP (0 for a constant one).

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.normal(size=(120, 6))
    >>> Y = np.c_[2 * X[:, 1] + X[:, 4], X[:, 4] - X[:, 1]] + 0.05 * rng.normal(size=(120, 2))
    >>> sorted(PLSVIPSelector(2).fit(X, Y).selected_.tolist())
    [1, 4]
    """

    _parameter_constraints: ClassVar[dict] = {"k": K_CONSTRAINT}

    def __init__(self, k: int = 2):
        self.k = k

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y):
        """Fit PLS on standardised data, rank the candidates by VIP, keep the first k."""
        from sklearn.cross_decomposition import PLSRegression

        X, Z, W, varying = self._standardised_data(X, y)
        p = int(varying.sum())
        components = max(1, min(self.k, p, len(Z) - 1))
        pls = PLSRegression(n_components=components, scale=False).fit(Z[:, varying], W)
        t, w, q = pls.x_scores_, pls.x_weights_, pls.y_loadings_
        explained = (t ** 2).sum(axis=0) * (q ** 2).sum(axis=0)  # per latent component
        weights = (w / np.linalg.norm(w, axis=0)) ** 2
        vip = np.sqrt(p * (weights @ explained) / explained.sum())
        self.vip_ = np.zeros(X.shape[1])
        self.vip_[varying] = vip
        order = np.argsort(-vip, kind="stable")
        self.selected_ = np.flatnonzero(varying)[order[:self.k]].astype(np.intp)
        return self
