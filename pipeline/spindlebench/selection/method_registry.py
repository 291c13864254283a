"""The one registry of selection methods: each method's name, line, kind and factory, once.

Everything that knows a method reads this table: ``registry.MethodChoice`` (which names
exist, which are clustered), ``registry.make_selector`` (the estimator), ``spindlebench
methods`` (the listing), ``clustering.CLUSTERINGS`` / ``PAIRWISE_CLUSTERINGS``,
``evaluate``'s seed line, the study readers (``methods = ["all"]``) and the placement study's
n x n refusal. Adding a method is one ``Method`` entry here (and its selector code, usually in
``selectors.py``) plus a test.

The table is cheap to import (no scikit-learn): a factory imports its estimator's module when
it is called.

Examples
--------
>>> METHOD_REGISTRY["kmeans"].clustered, METHOD_REGISTRY["kmeans"].seeded
(True, True)
>>> [m.name for m in METHOD_REGISTRY.values() if m.pairwise]
['closure', 'average', 'complete', 'ward']
>>> type(METHOD_REGISTRY["lasso"].make(3)).__name__
'LassoPathSelector'
>>> with registered(Method("dummy", "a test's method", factory=lambda k, **_: None)):
...     "dummy" in METHOD_REGISTRY
True
>>> "dummy" in METHOD_REGISTRY
False
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

from spindlebench.core.names import (
    ALL_CANDIDATES,
    DEFAULT_METHOD,
    DEFAULT_METHOD_SEED,
    DEFAULT_SIMILARITY,
    DEFAULT_WITHIN,
    JOINT_UNION,
)

#: ``factory(k, *, within, similarity, random_state)`` -> an unfitted selector keeping ``k``
#: candidates (``selected_``, and ``clusters_`` for a clustered method).
Factory = Callable[..., Any]


@dataclass(frozen=True)
class Method:
    """One selection method.

    ``clustered``: it partitions the candidates and keeps one per cluster (so ``within``
    applies); ``seeded``: its result depends on the seed; ``pairwise``: it forms an n x n
    matrix over the n candidates (the placement study refuses it above
    ``pairs.MAX_FORMED_CANDIDATES``); ``budget``: it keeps k candidates (what a study file's
    ``methods = ["all"]`` lists); ``multi_output``: its selector also takes several
    targets (a samples x components ``y``) and keeps one set for all of them, so it is a
    joint selection of ``multi_target.evaluate_targets`` (``--joint``); ``factory``: builds
    its selector.
    """

    name: str
    description: str
    clustered: bool = False
    seeded: bool = False
    pairwise: bool = False
    factory: Factory | None = None
    budget: bool = True
    multi_output: bool = False

    def make(self, k: int, *, within: str = DEFAULT_WITHIN,
             similarity: str = DEFAULT_SIMILARITY,
             random_state: int = DEFAULT_METHOD_SEED) -> Any:
        """The selector of this method keeping ``k`` candidates."""
        if self.factory is None:
            return _cluster_selector(self.name)(k, within=within, similarity=similarity,
                                                random_state=random_state)
        return self.factory(k, within=within, similarity=similarity, random_state=random_state)


def _cluster_selector(clustering: str) -> Factory:
    """The factory of a clustering that ``clustering.cluster_candidates`` implements."""
    def factory(k: int, *, within: str, similarity: str, random_state: int) -> Any:
        from spindlebench.selection.selectors import ClusterSelector

        return ClusterSelector(k, clustering=clustering, within=within, similarity=similarity,
                               random_state=random_state)
    return factory


def _top_correlated(k: int, **_: Any) -> Any:
    from spindlebench.selection.selectors import TopCorrelatedSelector

    return TopCorrelatedSelector(k)


def _lasso(k: int, **_: Any) -> Any:
    from spindlebench.selection.selectors import LassoPathSelector

    return LassoPathSelector(k, l1_ratio=1.0)


def _elastic_net(k: int, **_: Any) -> Any:
    from spindlebench.selection.selectors import LassoPathSelector

    return LassoPathSelector(k, l1_ratio=0.5)


def _stability(k: int, *, random_state: int, **_: Any) -> Any:
    from spindlebench.selection.selectors import StabilitySelector

    return StabilitySelector(k, random_state=random_state)


def _mutual_information(k: int, *, random_state: int, **_: Any) -> Any:
    from spindlebench.selection.information import MutualInfoSelector

    return MutualInfoSelector(k, random_state=random_state)


def _mrmr(k: int, *, random_state: int, **_: Any) -> Any:
    from spindlebench.selection.information import MRMRSelector

    return MRMRSelector(k, random_state=random_state)


def _multi_task_lasso(k: int, **_: Any) -> Any:
    from spindlebench.selection.multi_output import MultiTaskLassoSelector

    return MultiTaskLassoSelector(k)


def _pls_vip(k: int, **_: Any) -> Any:
    from spindlebench.selection.multi_output import PLSVIPSelector

    return PLSVIPSelector(k)


def _all_candidates(k: int, **_: Any) -> Any:
    from spindlebench.selection.selectors import AllCandidates

    return AllCandidates()


def _greedy(k: int, **_: Any) -> Any:
    from spindlebench.selection.selectors import GreedyForwardSelector

    return GreedyForwardSelector(k)


def _exhaustive(k: int, **_: Any) -> Any:
    from spindlebench.selection.selectors import ExhaustiveSelector

    return ExhaustiveSelector(k)


_BUILT_IN: tuple[Method, ...] = (
    # cluster methods first; the first is the paper's (names.DEFAULT_METHOD)
    Method(DEFAULT_METHOD, "the paper's fuzzy equivalence closure t(R) cut into k clusters "
           "(single linkage on 1 - R)", clustered=True, pairwise=True),
    Method("fcm", "fuzzy c-means (scikit-fuzzy cmeans, fuzzifier 2) on the standardised "
           "series; each candidate to its largest membership", clustered=True, seeded=True),
    Method("kmeans", "k-means (scikit-learn, 10 starts) on the standardised series",
           clustered=True, seeded=True),
    Method("average", "hierarchical clustering, average linkage on 1 - R (SciPy)",
           clustered=True, pairwise=True),
    Method("complete", "hierarchical clustering, complete linkage on 1 - R (SciPy)",
           clustered=True, pairwise=True),
    Method("ward", "hierarchical clustering, Ward linkage on the standardised series (SciPy)",
           clustered=True, pairwise=True),
    Method("top-k-correlated", "the k candidates with the largest |psi|, no clustering",
           factory=_top_correlated),
    Method("lasso", "the first k candidates to enter the LASSO path (standardised rises)",
           factory=_lasso),
    Method("elastic-net", "the first k candidates to enter the elastic-net path (l1_ratio 0.5)",
           factory=_elastic_net),
    Method("stability", "stability selection: the k most frequent on the LASSO path's first k "
           "over 50 random half-samples", seeded=True, factory=_stability),
    Method("greedy", "greedy forward selection by cross-experiment RMSE of OLS (train on the "
           "first half of the run, score on the second)", factory=_greedy),
    Method("exhaustive", "every k-subset scored by greedy's objective (OLS on the first half "
           "of the run, RMSE on the second); the best; refused above 200 000 subsets",
           factory=_exhaustive),
    Method("mi", "the k candidates with the largest mutual information with the error "
           "(scikit-learn mutual_info_regression, 3 neighbours, seeded)", seeded=True,
           factory=_mutual_information),
    Method("mrmr", "minimum redundancy maximum relevance: greedily the candidate whose mutual "
           "information with the error minus its mean with those chosen is largest",
           seeded=True, factory=_mrmr),
    Method("mtlasso", "the first k candidates to enter the multi-task LASSO path of every "
           "target at once (standardised; one candidate set for all targets)",
           factory=_multi_task_lasso, multi_output=True),
    Method("pls-vip", "the k candidates of largest VIP in a PLS regression with every target "
           "as a response (standardised; one candidate set for all targets)",
           factory=_pls_vip, multi_output=True),
    Method(ALL_CANDIDATES, "no selection: every candidate (k does not apply); "
           "all-candidates+ols is OLS on all sensors, all-candidates+REGRESSOR gives a "
           "regressor or a pipeline of your own every candidate", factory=_all_candidates,
           budget=False),
)

#: Every selection method by name, in listing order (cluster methods first, the paper's first).
METHOD_REGISTRY: dict[str, Method] = {method.name: method for method in _BUILT_IN}


def method_names(*, clustered: bool | None = None, seeded: bool | None = None,
                 pairwise: bool | None = None, budget: bool | None = None,
                 multi_output: bool | None = None) -> tuple[str, ...]:
    """The registered names, in order, optionally only those with the given kinds."""
    return tuple(m.name for m in METHOD_REGISTRY.values()
                 if (multi_output is None or m.multi_output == multi_output)
                 and (clustered is None or m.clustered == clustered)
                 and (seeded is None or m.seeded == seeded)
                 and (pairwise is None or m.pairwise == pairwise)
                 and (budget is None or m.budget == budget))


def joint_names() -> tuple[str, ...]:
    """The joint selections of several targets (``multi_target.evaluate_targets``): the union
    of the per-target selections, then every multi-output method."""
    return (JOINT_UNION, *method_names(multi_output=True))


def descriptions(*, clustered: bool | None = None) -> dict[str, str]:
    """``{name: line}`` of the registered methods (all, or only (non-)clustered ones)."""
    return {name: METHOD_REGISTRY[name].description
            for name in method_names(clustered=clustered)}


def get_method(name: str) -> Method:
    """The registered method ``name`` (``KeyError`` if none; ``MethodChoice`` checks names)."""
    return METHOD_REGISTRY[name]


@contextmanager
def registered(method: Method) -> Iterator[Method]:
    """``method`` registered for the block only (tests, and a user's experiment)."""
    if method.name in METHOD_REGISTRY:
        raise ValueError(f"method {method.name!r} is already registered")
    METHOD_REGISTRY[method.name] = method
    try:
        yield method
    finally:
        del METHOD_REGISTRY[method.name]
