"""Selectors beside the paper's: clustering variants, grey choice, and selection without clusters.

All are scikit-learn ``SelectorMixin`` estimators, fitted on rises (candidates) and the thermal
error, so each composes before any regressor in a ``Pipeline``:

- ``ClusterSelector``: cluster the candidates (``clustering``: the paper's closure, fuzzy
  c-means, k-means, average/complete/Ward linkage; see ``selection.clustering``), then keep
  one per cluster: the largest |psi| (``within="psi"``, the paper's eq. 4) or the largest grey
  relational grade (``within="grey"``, ``selection.grey``).
- ``TopCorrelatedSelector``: the k candidates with the largest |psi|, no clustering.
- ``LassoPathSelector``: the first k candidates to enter the LASSO (``l1_ratio=1``, exact
  path by LARS) or elastic-net path of the standardised candidates.
- ``StabilitySelector``: how often each candidate is among those k over random half-samples
  of the rows (Meinshausen and Buehlmann's stability selection); keep the k most frequent.
- ``GreedyForwardSelector``: greedy forward selection by cross-experiment RMSE
  (``selection.forward.greedy_forward``, the placement study's search): train on the first
  experiment of ``groups``, score on the others; without ``groups`` the rows are cut into
  ``n_blocks`` contiguous time blocks and the first block trains.

Constant candidates are never selected (a ``ClusterSelector`` drops them with a
``SelectionWarning``, as the paper's selector does).

One name for the budget: every selector of the package keeps ``k`` candidates (scikit-learn's
``SelectKBest`` name, so one grid search spans every method and scikit-learn's own). The old
names, ``n_clusters`` (cluster selectors) and ``n_features_to_select`` (the others), are
deprecated aliases for one release: given, they win with a ``FutureWarning``. ``random_state``
is None, an int or a NumPy ``Generator`` (``selection.randomness``); the commands pass ints so
that results are reproducible and recorded.
"""

from __future__ import annotations

import warnings
from numbers import Integral, Real
from typing import ClassVar

import numpy as np
from sklearn.base import BaseEstimator, _fit_context
from sklearn.feature_selection import SelectorMixin
from sklearn.linear_model import enet_path, lars_path
from sklearn.utils._param_validation import Hidden, Interval, StrOptions
from sklearn.utils.validation import check_is_fitted, validate_data

from spindlebench.core.names import DEFAULT_SIMILARITY
from spindlebench.core.names import WITHIN as WITHIN_CHOICES
from spindlebench.selection.closure import CLOSURES
from spindlebench.selection.clustering import CLUSTERINGS, cluster_candidates
from spindlebench.selection.errors import SelectionError, SelectionWarning, column_list
from spindlebench.selection.exhaustive import exhaustive_search, n_subsets
from spindlebench.selection.forward import Block, greedy_forward, usable_candidates
from spindlebench.selection.genetic import GENERATIONS, POPULATION, genetic_choice
from spindlebench.selection.grey import DEFAULT_RHO, NORMALISATIONS, grey_relational_grade
from spindlebench.selection.randomness import RANDOM_STATE_CONSTRAINT, as_generator
from spindlebench.selection.regression import check_groups
from spindlebench.selection.similarity import SIMILARITIES, constant_columns, correlation_with

#: The within-cluster choices (their names and descriptions: ``names.WITHIN``).
WITHIN: tuple[str, ...] = tuple(WITHIN_CHOICES)
#: Points on the LASSO / elastic-net path (log-spaced down to 1e-4 of the largest alpha).
PATH_ALPHAS = 200
PATH_EPS = 1e-4
#: The default of a deprecated alias of ``k`` (not given).
DEPRECATED = "deprecated"
#: The ``_parameter_constraints`` of ``k`` and of a deprecated alias.
K_CONSTRAINT: list = [Interval(Integral, 1, None, closed="left")]
ALIAS_CONSTRAINT: list = [Interval(Integral, 1, None, closed="left"),
                          Hidden(StrOptions({DEPRECATED}))]


def _budget(k: int, n_features: int) -> None:
    if k > n_features:
        raise SelectionError(f"cannot select {k} from {n_features} feature(s): the budget is "
                             "larger than the number of candidates")


def _abs_psi(X: np.ndarray, y: np.ndarray) -> np.ndarray:
    """|psi| of every column, -1 for constant ones (ranked last)."""
    out = np.full(X.shape[1], -1.0)
    varying = ~constant_columns(X)
    if varying.any():
        out[varying] = np.abs(correlation_with(X[:, varying], y))
    return out


class SupportFromSelected(SelectorMixin, BaseEstimator):
    """``selected_`` (input columns, in the order the method chose them) -> support mask;
    the target is required. Every selector of the package derives from it."""

    def _get_support_mask(self):
        check_is_fitted(self)
        mask = np.zeros(self.n_features_in_, dtype=bool)
        mask[self.selected_] = True
        return mask

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.required = True
        return tags


    def _k(self) -> int:
        """The budget: ``k``, or a deprecated alias given instead (warned)."""
        for alias in ("n_clusters", "n_features_to_select"):
            value = getattr(self, alias, DEPRECATED)
            if not (isinstance(value, str) and value == DEPRECATED):
                warnings.warn(f"{type(self).__name__}: '{alias}' is deprecated and will be "
                              f"removed in the next release; use 'k' (it overrides k={self.k})",
                              FutureWarning, stacklevel=3)
                return value
        return self.k


class _Selector(SupportFromSelected):
    """A selector of this module: checked data, a target that is not constant."""

    def _data(self, X, y):
        X, y = validate_data(self, X, y, dtype=np.float64, y_numeric=True, ensure_min_samples=2)
        if constant_columns(y[:, None])[0]:
            raise SelectionError("the target (thermal error) is constant; nothing to select")
        return X, y


class ClusterSelector(_Selector):
    """Cluster the candidates, keep one per cluster (|psi| or grey relational grade).

    Parameters
    ----------
    k : int, default=2
        Number of clusters, hence of selected candidates.
    clustering : {"closure", "fcm", "kmeans", "average", "complete", "ward"}, default="closure"
        How candidates are clustered (``spindlebench.selection.clustering``).
    within : {"psi", "grey", "ga"}, default="psi"
        Choice inside a cluster: largest |Pearson r| with the error, largest grey
        relational grade, or the combination a genetic algorithm finds best by validation
        RMSE (``selection.genetic``; starts from the |psi| choice).
    similarity : {"abs-pearson", "literal"}, default="abs-pearson"
        Reading of eq. 1 (for ``closure``, ``average`` and ``complete``).
    closure : {"fast", "squaring"}, default="fast"
        Implementation of t(R) (same result).
    normalisation : {"interval", "mean"}, default="interval"
        Normalisation of the grey grade.
    rho : float, default=0.5
        Distinguishing coefficient of the grey grade.
    random_state : None, int or numpy.random.Generator, default=0
        Seed of ``fcm``, ``kmeans`` and the genetic algorithm.
    population, generations : int, default=30, 40
        Of the genetic algorithm (``within="ga"`` only).
    n_clusters : int, deprecated
        Old name of ``k`` (one release).

    Attributes
    ----------
    clusters_ : list of ndarray
        Input column indices of each cluster, ordered by first member.
    selected_ : ndarray
        The input column kept from each cluster (same order).
    psi_ : ndarray of shape (n_features_in_,)
        Correlation with the error (NaN for dropped constant columns).
    scores_ : ndarray of shape (n_features_in_,)
        What ``within`` ranks by: |psi| or the grey grade (NaN for constant columns).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 60)
    >>> X = np.column_stack([t, t + 0.02 * t**2, np.sin(9 * t), np.sin(9 * t) + 0.05 * t])
    >>> y = 2 * t + np.sin(9 * t)
    >>> selector = ClusterSelector(2, clustering="kmeans", within="grey").fit(X, y)
    >>> [members.tolist() for members in selector.clusters_]
    [[0, 1], [2, 3]]
    >>> selector.get_support().tolist()
    [False, True, False, True]
    """

    _parameter_constraints: ClassVar[dict] = {
        "k": K_CONSTRAINT,
        "clustering": [StrOptions(set(CLUSTERINGS))],
        "within": [StrOptions(set(WITHIN))],
        "similarity": [StrOptions(set(SIMILARITIES))],
        "closure": [StrOptions(set(CLOSURES))],
        "normalisation": [StrOptions(set(NORMALISATIONS))],
        "rho": [Interval(Real, 0, 1, closed="right")],
        "random_state": RANDOM_STATE_CONSTRAINT,
        "population": [Interval(Integral, 2, None, closed="left")],
        "generations": [Interval(Integral, 1, None, closed="left")],
        "n_clusters": ALIAS_CONSTRAINT,
    }

    def __init__(self, k: int = 2, clustering: str = "closure", within: str = "psi",
                 similarity: str = DEFAULT_SIMILARITY, closure: str = "fast",
                 normalisation: str = "interval", rho: float = DEFAULT_RHO,
                 random_state=0, population: int = POPULATION, generations: int = GENERATIONS,
                 n_clusters=DEPRECATED):
        self.k = k
        self.clustering = clustering
        self.within = within
        self.similarity = similarity
        self.closure = closure
        self.normalisation = normalisation
        self.rho = rho
        self.random_state = random_state
        self.population = population
        self.generations = generations
        self.n_clusters = n_clusters

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y):
        """Cluster the columns of ``X`` and keep the best of each cluster."""
        X, y = self._data(X, y)
        names = getattr(self, "feature_names_in_", None)
        names = None if names is None else [str(n) for n in names]
        k = self._k()
        _budget(k, X.shape[1])
        constant = constant_columns(X)
        kept = np.flatnonzero(~constant)
        if constant.any():
            warnings.warn(f"dropping {int(constant.sum())} constant candidate(s) (zero "
                          f"variance): {column_list(np.flatnonzero(constant), names)}",
                          SelectionWarning, stacklevel=2)
        if k > kept.size:
            raise SelectionError(f"cannot make {k} clusters: only {kept.size} "
                                 "candidate(s) vary")
        kept_names = None if names is None else [names[i] for i in kept]
        X_kept = _columns(X, kept)  # once, not once per use
        members = cluster_candidates(X_kept, k, self.clustering,
                                     self.similarity, self.closure, self.random_state,
                                     kept_names)
        self.psi_ = np.full(X.shape[1], np.nan)
        self.psi_[kept] = correlation_with(X_kept, y, kept_names)
        self.scores_ = np.full(X.shape[1], np.nan)
        if self.within in ("psi", "ga"):
            self.scores_[kept] = np.abs(self.psi_[kept])
        else:
            self.scores_[kept] = grey_relational_grade(X_kept, y, self.normalisation,
                                                       self.rho, kept_names)
        self.clusters_ = [kept[m] for m in members]
        self.selected_ = np.array([c[int(np.argmax(self.scores_[c]))] for c in self.clusters_],
                                  dtype=np.intp)
        if self.within == "ga":
            self.selected_, self.ga_score_ = genetic_choice(
                X, y, self.clusters_, self.selected_, self.random_state, self.population,
                self.generations)
        return self


def _columns(X: np.ndarray, kept: np.ndarray) -> np.ndarray:
    """``X[:, kept]``, or ``X`` itself where that gather would copy it unchanged (every
    column kept of an F-ordered ``X``, as ``select_with`` passes it: ``X[:, kept]`` is
    F-ordered too, so the same layout and the same bits of every column sum)."""
    if kept.size == X.shape[1] and min(X.shape) > 1 and X.flags.f_contiguous and \
            np.array_equal(kept, np.arange(X.shape[1])):
        return X
    return X[:, kept]


class TopCorrelatedSelector(_Selector):
    """The ``k`` candidates most correlated (|psi|) with the error.

    Parameters
    ----------
    k : int, default=2
    n_features_to_select : int, deprecated
        Old name of ``k`` (one release).

    Attributes
    ----------
    selected_ : ndarray
        Input columns, strongest first.
    scores_ : ndarray of shape (n_features_in_,)
        |psi| (-1 for constant columns).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 30)
    >>> X = np.column_stack([np.sin(5 * t), t, t**3])
    >>> TopCorrelatedSelector(1).fit(X, 2 * t).selected_.tolist()
    [1]
    """

    _parameter_constraints: ClassVar[dict] = {
        "k": K_CONSTRAINT,
        "n_features_to_select": ALIAS_CONSTRAINT,
    }

    def __init__(self, k: int = 2, n_features_to_select=DEPRECATED):
        self.k = k
        self.n_features_to_select = n_features_to_select

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y):
        """Rank the columns of ``X`` by |psi|."""
        X, y = self._data(X, y)
        k = self._k()
        _budget(k, X.shape[1])
        self.scores_, ranking = correlation_ranking(X, y)
        self.selected_ = ranking[:k]
        return self


def correlation_ranking(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``TopCorrelatedSelector``'s ranking of checked data: (|psi| of every column, -1 for
    constant ones; the columns by it, strongest first, the first one on ties). Its own
    home, so a study ranking its training run's candidates once for every k
    (``family.methods``) ranks them as the selector does."""
    scores = _abs_psi(X, y)
    return scores, np.argsort(-scores, kind="stable")


def path_order(X: np.ndarray, y: np.ndarray, k: int, l1_ratio: float) -> np.ndarray:
    """The first ``k`` columns to enter the elastic-net path of standardised ``X``.

    The LASSO's path (``l1_ratio`` 1) is computed exactly by LARS (``lars_path``, its kinks);
    an elastic net's on a grid of ``PATH_ALPHAS`` penalties (``enet_path``).

    Walking down the path from the largest alpha, the first point with at least k active
    candidates decides: its active candidates ranked by when they entered, then by |coef|
    there. If the path never has k active ones (collinear data), the rest are filled by |psi|.
    """
    mean, scale = X.mean(axis=0), X.std(axis=0)
    varying = scale > 0
    Z = np.zeros_like(X)
    Z[:, varying] = (X[:, varying] - mean[varying]) / scale[varying]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # convergence warnings at tiny alphas
        if l1_ratio == 1.0:  # the LASSO: LARS gives the exact path, kink by kink
            coefs = _lars_prefix(Z, y - y.mean(), k)
        else:
            _, coefs, _ = enet_path(Z, y - y.mean(), l1_ratio=l1_ratio, eps=PATH_EPS,
                                    alphas=PATH_ALPHAS)
    active = coefs != 0  # p x n_alphas, alphas decreasing
    entry = np.where(active.any(axis=1), np.argmax(active, axis=1), active.shape[1])
    counts = active.sum(axis=0)
    reached = np.flatnonzero(counts >= k)
    step = int(reached[0]) if reached.size else active.shape[1] - 1
    magnitude = np.abs(coefs[:, step])
    # |psi| only breaks ties of (entry, |coef|); where the path reaches k, the first k are
    # among the candidates that entered by ``step`` (at least k of them), so only theirs
    # is needed (the same order: lexsort is stable and every other key is the same).
    among = np.flatnonzero((entry <= step) & varying) if reached.size else \
        np.arange(X.shape[1])
    psi = _abs_psi(X[:, among], y)
    ranked = among[np.lexsort((-psi, -magnitude[among], entry[among]))]
    ranked = [int(i) for i in ranked if varying[i]]
    return np.asarray(ranked[:k], dtype=np.intp)


#: LARS steps ``lars_path`` takes at most (its default ``max_iter``): the whole LASSO path.
LARS_MAX_ITER = 500


def _lars_prefix(Z: np.ndarray, y: np.ndarray, k: int) -> np.ndarray:
    """The LASSO path's coefficients (p x kinks) up to the first kink with ``k`` active
    candidates, or the whole path (``LARS_MAX_ITER`` steps) if it never has k.

    LARS is sequential: its first s steps do not depend on how many follow, so a path cut
    at ``max_iter`` = s is the whole path's first s + 1 kinks, bit for bit. It starts at k
    steps (k entries if nothing drops out) and doubles until k are active at once or the
    path ends; on 3 321 candidates this is a handful of the whole path's ~360 steps, each
    of which costs a pass over the data (issue 26's placement speed).
    """
    steps = min(k, LARS_MAX_ITER)
    while True:
        _, _, coefs = lars_path(Z, y, method="lasso", max_iter=steps)
        ended = coefs.shape[1] < steps + 1  # stopped before max_iter: the path's end
        if ended or steps >= LARS_MAX_ITER or ((coefs != 0).sum(axis=0) >= k).any():
            return coefs
        steps = min(2 * steps, LARS_MAX_ITER)


class LassoPathSelector(_Selector):
    """The first k candidates to enter the LASSO or elastic-net path.

    Parameters
    ----------
    k : int, default=2
    l1_ratio : float, default=1.0
        1 is the LASSO; below 1 an elastic net (scikit-learn's ``enet_path``).
    n_features_to_select : int, deprecated
        Old name of ``k`` (one release).

    Attributes
    ----------
    selected_ : ndarray
        Input columns in order of entry into the path.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.normal(size=(80, 5))
    >>> y = 3 * X[:, 2] - 2 * X[:, 4] + 0.1 * rng.normal(size=80)
    >>> LassoPathSelector(2).fit(X, y).selected_.tolist()
    [2, 4]
    """

    _parameter_constraints: ClassVar[dict] = {
        "k": K_CONSTRAINT,
        "n_features_to_select": ALIAS_CONSTRAINT,
        "l1_ratio": [Interval(Real, 0, 1, closed="right")],
    }

    def __init__(self, k: int = 2, l1_ratio: float = 1.0, n_features_to_select=DEPRECATED):
        self.k = k
        self.l1_ratio = l1_ratio
        self.n_features_to_select = n_features_to_select

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y):
        """Compute the path on standardised ``X`` and keep its first k entries."""
        X, y = self._data(X, y)
        k = self._k()
        _budget(k, X.shape[1])
        self.selected_ = path_order(X, y, k, self.l1_ratio)
        if self.selected_.size < k:
            raise SelectionError(f"only {self.selected_.size} candidate(s) vary; cannot select "
                                 f"{k}")
        return self


class StabilitySelector(_Selector):
    """Stability selection: the k candidates most often on the LASSO path's first k over
    random half-samples of the rows.

    Parameters
    ----------
    k : int, default=2
    n_subsamples : int, default=50
    sample_fraction : float, default=0.5
        Fraction of the rows drawn (without replacement) per subsample.
    l1_ratio : float, default=1.0
    random_state : None, int or numpy.random.Generator, default=0
    n_features_to_select : int, deprecated
        Old name of ``k`` (one release).

    Attributes
    ----------
    frequency_ : ndarray of shape (n_features_in_,)
        Fraction of subsamples that selected each candidate.
    selected_ : ndarray
        The most frequent ones (ties: order on the full data's path).

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.normal(size=(80, 5))
    >>> y = 3 * X[:, 2] - 2 * X[:, 4] + 0.1 * rng.normal(size=80)
    >>> sorted(StabilitySelector(2, n_subsamples=10).fit(X, y).selected_.tolist())
    [2, 4]
    """

    _parameter_constraints: ClassVar[dict] = {
        "k": K_CONSTRAINT,
        "n_features_to_select": ALIAS_CONSTRAINT,
        "n_subsamples": [Interval(Integral, 1, None, closed="left")],
        "sample_fraction": [Interval(Real, 0, 1, closed="right")],
        "l1_ratio": [Interval(Real, 0, 1, closed="right")],
        "random_state": RANDOM_STATE_CONSTRAINT,
    }

    def __init__(self, k: int = 2, n_subsamples: int = 50, sample_fraction: float = 0.5,
                 l1_ratio: float = 1.0, random_state=0, n_features_to_select=DEPRECATED):
        self.k = k
        self.n_subsamples = n_subsamples
        self.sample_fraction = sample_fraction
        self.l1_ratio = l1_ratio
        self.random_state = random_state
        self.n_features_to_select = n_features_to_select

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y):
        """Count, over subsamples, how often each candidate is among the path's first k."""
        X, y = self._data(X, y)
        k = self._k()
        _budget(k, X.shape[1])
        rng = as_generator(self.random_state)
        size = max(2, round(self.sample_fraction * X.shape[0]))
        counts = np.zeros(X.shape[1])
        for _ in range(self.n_subsamples):
            rows = np.sort(rng.choice(X.shape[0], size=size, replace=False))
            if constant_columns(y[rows, None])[0]:
                continue
            counts[path_order(X[rows], y[rows], k, self.l1_ratio)] += 1
        self.frequency_ = counts / self.n_subsamples
        full = path_order(X, y, X.shape[1], self.l1_ratio)
        tie_rank = np.full(X.shape[1], X.shape[1])
        tie_rank[full] = np.arange(full.size)
        varying = ~constant_columns(X)
        order = [int(i) for i in np.lexsort((tie_rank, -self.frequency_)) if varying[i]]
        if len(order) < k:
            raise SelectionError(f"only {len(order)} candidate(s) vary; cannot select {k}")
        self.selected_ = np.asarray(order[:k], dtype=np.intp)
        return self


def _validation_blocks(X: np.ndarray, y: np.ndarray, groups, n_blocks: int, k: int,
                       what: str) -> tuple[Block, Block]:
    """The training part and the validation runs of a search by validation RMSE (greedy,
    exhaustive): with ``groups`` the first experiment trains and the others validate; without,
    the first of ``n_blocks`` contiguous time blocks trains and the others validate."""
    if groups is not None:
        groups = check_groups(groups, X.shape[0])
        labels = list(dict.fromkeys(groups.tolist()))
        if len(labels) < 2:
            raise SelectionError(f"{what} needs at least 2 experiments in groups (one trains, "
                                 "the others score)")
        is_train = groups == labels[0]
        valid_rows = np.concatenate([np.flatnonzero(groups == g) for g in labels[1:]])
        starts = np.cumsum([0] + [int((groups == g).sum()) for g in labels[1:-1]])
    else:
        if X.shape[0] < 2 * n_blocks:
            raise SelectionError(f"{what} needs at least {2 * n_blocks} samples for "
                                 f"{n_blocks} blocks, got {X.shape[0]}")
        edges = np.linspace(0, X.shape[0], n_blocks + 1).round().astype(int)
        is_train = np.arange(X.shape[0]) < edges[1]
        valid_rows = np.arange(edges[1], X.shape[0])
        starts = edges[1:-1] - edges[1]
    train = Block(X[is_train], y[is_train], np.array([0]))
    valid = Block(X[valid_rows], y[valid_rows], np.asarray(starts, dtype=np.intp))
    if train.X.shape[0] < k + 2:
        raise SelectionError(f"{what}: {train.X.shape[0]} training sample(s) cannot fit {k} "
                             "input(s)")
    return train, valid


class GreedyForwardSelector(_Selector):
    """Greedy forward selection by cross-experiment RMSE of an OLS on the chosen rises.

    Parameters
    ----------
    k : int, default=2
    n_blocks : int, default=2
        Without ``groups`` at fit: the rows are cut into this many contiguous time blocks, the
        first trains and the others are the "other experiments" that score a candidate set.
    n_features_to_select : int, deprecated
        Old name of ``k`` (one release).

    Attributes
    ----------
    selected_ : ndarray
        Input columns in the order greedy search added them.
    scores_ : ndarray
        Mean validation RMSE after each addition.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 60)
    >>> X = np.column_stack([t**2, np.sin(3 * t), t])
    >>> GreedyForwardSelector(1).fit(X, 5 * t).selected_.tolist()
    [2]
    """

    _parameter_constraints: ClassVar[dict] = {
        "k": K_CONSTRAINT,
        "n_features_to_select": ALIAS_CONSTRAINT,
        "n_blocks": [Interval(Integral, 2, None, closed="left")],
    }

    def __init__(self, k: int = 2, n_blocks: int = 2, n_features_to_select=DEPRECATED):
        self.k = k
        self.n_blocks = n_blocks
        self.n_features_to_select = n_features_to_select

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y, groups=None):
        """Greedy search: train on the first experiment (or block), score on the rest."""
        X, y = self._data(X, y)
        k = self._k()
        _budget(k, X.shape[1])
        train, valid = _validation_blocks(X, y, groups, self.n_blocks, k,
                                          "greedy forward selection")
        path = greedy_forward(train, valid, k)
        if len(path.chosen) < k:
            raise SelectionError(f"greedy forward selection found only {len(path.chosen)} "
                                 f"independent candidate(s) on the training part; cannot "
                                 f"select {k}")
        self.selected_ = np.asarray(path.chosen, dtype=np.intp)
        self.scores_ = np.asarray(path.scores)
        return self


#: Subsets ``ExhaustiveSelector`` scores at most by default (C(20, 3) = 1140 raw sensors at
#: k = 3; C(210, 3) = 1 521 520 with every difference is refused): about a second here.
DEFAULT_MAX_COMBINATIONS = 200_000


class ExhaustiveSelector(_Selector):
    """Every k-subset of the candidates, scored by validation RMSE; the best is kept.

    The objective is greedy forward selection's (``forward.validation_score``: OLS on the
    training part's rises, mean RMSE over the validation runs), so the two differ only in
    the search: greedy grows one set, this scores all ``C(n, k)`` of them
    (``exhaustive.exhaustive_search``, from Gram matrices) and finds the best set where greedy
    misses it. No randomness: ties go to the first subset in lexicographic order, so there is
    no seed. Above ``max_combinations`` subsets it refuses in one line rather than run for
    hours.

    Parameters
    ----------
    k : int, default=2
    n_blocks : int, default=2
        Without ``groups`` at fit: the rows are cut into this many contiguous time blocks, the
        first trains and the others validate (as greedy's).
    max_combinations : int, default=200000
        The largest ``C(n, k)`` scored; more is a ``SelectionError``.

    Attributes
    ----------
    selected_ : ndarray
        The best subset's input columns, ascending.
    score_ : float
        Its mean validation RMSE.
    n_combinations_ : int
        How many subsets were scored.

    Examples
    --------
    ``y = a + b`` exactly; ``c`` is each of them plus noise, the best single predictor, so
    greedy starts with it and no pair with ``c`` is exact; every pair is scored here:

    >>> import numpy as np
    >>> t = np.linspace(0, 1, 80)
    >>> a, b = t, np.sin(4 * t)
    >>> c = a + b + 0.2 * np.cos(9 * t)
    >>> X = np.column_stack([a, b, c])
    >>> ExhaustiveSelector(2).fit(X, a + b).selected_.tolist()
    [0, 1]
    >>> GreedyForwardSelector(2).fit(X, a + b).selected_.tolist()[0]
    2
    """

    _parameter_constraints: ClassVar[dict] = {
        "k": K_CONSTRAINT,
        "n_blocks": [Interval(Integral, 2, None, closed="left")],
        "max_combinations": [Interval(Integral, 1, None, closed="left")],
    }

    def __init__(self, k: int = 2, n_blocks: int = 2,
                 max_combinations: int = DEFAULT_MAX_COMBINATIONS):
        self.k = k
        self.n_blocks = n_blocks
        self.max_combinations = max_combinations

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y, groups=None):
        """Score every k-subset: train on the first experiment (or block), score the rest."""
        X, y = self._data(X, y)
        k = self._k()
        _budget(k, X.shape[1])
        count = n_subsets(X.shape[1], k)
        if count > self.max_combinations:
            raise SelectionError(
                f"exhaustive search: C({X.shape[1]}, {k}) = {count:,} subsets, more than "
                f"max_combinations = {self.max_combinations:,}; use fewer candidates (no "
                "differences), a smaller k, or greedy")
        train, valid = _validation_blocks(X, y, groups, self.n_blocks, k, "exhaustive search")
        pool = usable_candidates(train)
        if pool.size < k:
            raise SelectionError(f"exhaustive search: only {pool.size} candidate(s) vary on the "
                                 f"training part; cannot select {k}")
        result = exhaustive_search(train, valid, k, pool)
        if not np.isfinite(result.score):
            raise SelectionError("exhaustive search: no subset gave a finite validation RMSE")
        self.selected_ = np.asarray(sorted(result.chosen), dtype=np.intp)
        self.score_ = result.score
        self.n_combinations_ = result.evaluated
        return self


class AllCandidates(_Selector):
    """No selection: every candidate that varies (``all-candidates``; k does not apply).

    ``all-candidates+ols`` is OLS on all sensors (a benchmark baseline);
    ``all-candidates+REGRESSOR`` hands a
    regressor, or a user's pipeline with its own selection, every candidate.

    Attributes
    ----------
    selected_ : ndarray
        Every non-constant input column, in input order.
    """

    _parameter_constraints: ClassVar[dict] = {}

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y):
        """Keep the columns of ``X`` that vary."""
        X, y = self._data(X, y)
        self.selected_ = np.flatnonzero(~constant_columns(X)).astype(np.intp)
        if self.selected_.size == 0:
            raise SelectionError("every candidate is constant; nothing to keep")
        return self
