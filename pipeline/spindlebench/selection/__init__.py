"""Temperature-sensitive point selection of Xu et al. (2023), with constructed differences.

Steps: candidates (sensors + pairwise differences) -> fuzzy similarity R (eq. 1) -> max-min
closure t(R) (eq. 2) -> cut into k clusters (eq. 3) -> per cluster the candidate most
correlated with the error (eq. 4) -> OLS on rises -> train on one experiment, test on others.

Beside it, the methods practitioners compare (``selectors``, ``regressors``): other
clusterings (fuzzy c-means, k-means, average/complete/Ward linkage), the grey relational grade
inside a cluster, LASSO / elastic-net paths, stability selection, greedy forward selection,
and ridge / PLS after any selector.

Importing this package is cheap: each name is imported from its module on first use (PEP 562
``__getattr__``), so ``from spindlebench.selection import evaluate`` does not pull in
scikit-learn, SciPy's cluster module or Numba; only the methods that need them import them
(together about 3 s of CPU on this busy machine, most of a command's start-up).
"""

from __future__ import annotations

import importlib
from typing import Any

# ``evaluate`` is also a submodule's name: importing the submodule (any ``from
# spindlebench.selection.evaluate import ...``) sets the package attribute ``evaluate`` to the
# module, which ``__getattr__`` cannot undo, so the function is bound here, after it.
from spindlebench.selection.evaluate import evaluate as evaluate

#: Each public name and the module of this package that defines it.
_HOMES: dict[str, str] = {
    "closure_by_squaring": "closure",
    "closure_minimax": "closure",
    "maximum_spanning_tree": "closure",
    "transitive_closure": "closure",
    "CLUSTERINGS": "clustering",
    "cluster_candidates": "clustering",
    "Cut": "cut",
    "cut_at": "cut",
    "cut_for_clusters": "cut",
    "difference_names": "differences",
    "pairwise_differences": "differences",
    "with_differences": "differences",
    "SelectionError": "errors",
    "SelectionWarning": "errors",
    "FuzzyClusterSelector": "estimators",
    "PairwiseDifferences": "estimators",
    "RiseRegressor": "estimators",
    "RiseTransformer": "estimators",
    "make_selection_pipeline": "estimators",
    "CandidateSet": "evaluate",
    "Evaluation": "evaluate",
    "grey_relational_grade": "grey",
    "linkage_from_similarity": "hierarchy",
    "MRMRSelector": "information",
    "MutualInfoSelector": "information",
    "BoostedRiseRegressor": "nonlinear",
    "MLPRiseRegressor": "nonlinear",
    "EstimatorFit": "regression",
    "LinearFit": "regression",
    "fit_ols": "regression",
    "r2_score": "regression",
    "rises": "regression",
    "rmse": "regression",
    "PLSRiseRegressor": "regressors",
    "RidgeRiseRegressor": "regressors",
    "Selection": "select",
    "select_sensitive_points": "select",
    "AllCandidates": "selectors",
    "ClusterSelector": "selectors",
    "GreedyForwardSelector": "selectors",
    "LassoPathSelector": "selectors",
    "StabilitySelector": "selectors",
    "TopCorrelatedSelector": "selectors",
    "SIMILARITIES": "similarity",
    "constant_columns": "similarity",
    "correlation_with": "similarity",
    "similarity_matrix": "similarity",
    "TrainOnOneExperiment": "splitter",
}

__all__ = sorted([*_HOMES, "evaluate"])


def __getattr__(name: str) -> Any:
    """The public ``name``, imported from its module on first use and then kept."""
    try:
        module = _HOMES[name]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_HOMES))

