"""Temperature-sensitive point selection of Xu et al. (2023), with constructed differences.

Steps: candidates (sensors + pairwise differences) -> fuzzy similarity R (eq. 1) -> max-min
closure t(R) (eq. 2) -> cut into k clusters (eq. 3) -> per cluster the candidate most
correlated with the error (eq. 4) -> OLS on rises -> train on one experiment, test on others.

Beside it, the methods practitioners compare (``selectors``, ``regressors``): other
clusterings (fuzzy c-means, k-means, average/complete/Ward linkage), the grey relational grade
inside a cluster, LASSO / elastic-net paths, stability selection, greedy forward selection,
and ridge / PLS after any selector.
"""

from spindlebench.selection.closure import (
    closure_by_squaring,
    closure_minimax,
    maximum_spanning_tree,
    transitive_closure,
)
from spindlebench.selection.clustering import CLUSTERINGS, cluster_candidates
from spindlebench.selection.cut import Cut, cut_at, cut_for_clusters
from spindlebench.selection.differences import (
    difference_names,
    pairwise_differences,
    with_differences,
)
from spindlebench.selection.errors import SelectionError, SelectionWarning
from spindlebench.selection.estimators import (
    FuzzyClusterSelector,
    PairwiseDifferences,
    RiseRegressor,
    RiseTransformer,
    make_selection_pipeline,
)
from spindlebench.selection.evaluate import CandidateSet, Evaluation, evaluate
from spindlebench.selection.grey import grey_relational_grade
from spindlebench.selection.hierarchy import linkage_from_similarity
from spindlebench.selection.regression import LinearFit, fit_ols, r2_score, rises, rmse
from spindlebench.selection.regressors import PLSRiseRegressor, RidgeRiseRegressor
from spindlebench.selection.select import Selection, select_sensitive_points
from spindlebench.selection.selectors import (
    ClusterSelector,
    GreedyForwardSelector,
    LassoPathSelector,
    StabilitySelector,
    TopCorrelatedSelector,
)
from spindlebench.selection.similarity import (
    SIMILARITIES,
    constant_columns,
    correlation_with,
    similarity_matrix,
)
from spindlebench.selection.splitter import TrainOnOneExperiment

__all__ = [
    "CLUSTERINGS",
    "SIMILARITIES",
    "CandidateSet",
    "ClusterSelector",
    "Cut",
    "Evaluation",
    "FuzzyClusterSelector",
    "GreedyForwardSelector",
    "LassoPathSelector",
    "LinearFit",
    "PLSRiseRegressor",
    "PairwiseDifferences",
    "RidgeRiseRegressor",
    "RiseRegressor",
    "RiseTransformer",
    "Selection",
    "SelectionError",
    "SelectionWarning",
    "StabilitySelector",
    "TopCorrelatedSelector",
    "TrainOnOneExperiment",
    "closure_by_squaring",
    "closure_minimax",
    "cluster_candidates",
    "constant_columns",
    "correlation_with",
    "cut_at",
    "cut_for_clusters",
    "difference_names",
    "evaluate",
    "fit_ols",
    "grey_relational_grade",
    "linkage_from_similarity",
    "make_selection_pipeline",
    "maximum_spanning_tree",
    "pairwise_differences",
    "r2_score",
    "rises",
    "rmse",
    "select_sensitive_points",
    "similarity_matrix",
    "transitive_closure",
    "with_differences",
]
