"""Searching sensor sets by validation RMSE: greedy forward selection and exhaustive search.

The objective of a candidate set S is the one the placement study reports. Both searches
live in the selection package, because both are selection methods too (``evaluate --method
greedy`` / ``exhaustive``): ``spindlebench.selection.forward`` (the objective, greedy forward
selection) and ``spindlebench.selection.exhaustive`` (every m-subset from Gram matrices).
This module is the placement study's view of them.

Both searches only rank sets: the study re-scores the winners with :func:`validation_score`,
so every reported number comes from one plain least-squares fit.
"""

from __future__ import annotations

from spindlebench.selection.exhaustive import (
    EXHAUSTIVE_CHUNK,
    ExhaustiveResult,
    exhaustive_search,
    n_subsets,
    subset_batches,
)
from spindlebench.selection.forward import (
    Block,
    GreedyPath,
    greedy_forward,
    mean_run_rmse,
    usable_candidates,
    validation_score,
)

__all__ = [
    "EXHAUSTIVE_CHUNK",
    "Block",
    "ExhaustiveResult",
    "GreedyPath",
    "exhaustive_search",
    "greedy_forward",
    "mean_run_rmse",
    "n_subsets",
    "subset_batches",
    "usable_candidates",
    "validation_score",
]
