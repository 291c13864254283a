"""Cross-experiment validation: train on one experiment, test on the others.

The inverse of scikit-learn's ``LeaveOneGroupOut``: each split trains on a single group
(experiment) and tests on all remaining groups, which is the paper's protocol (fit on
experiment 1, predict experiments 2-5).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import numpy as np
from sklearn.model_selection import BaseCrossValidator

from spindlebench.selection.errors import SelectionError
from spindlebench.selection.regression import check_groups


class TrainOnOneExperiment(BaseCrossValidator):
    """Splits with one experiment as the training set and all others as the test set.

    Parameters
    ----------
    train_groups : sequence, single label or None
        Group labels to use as training experiments, in this order (e.g. ``["exp1"]``, or just
        ``"exp1"``, for the paper's single fold). None means every group, in order of first
        appearance. NaN group labels are an error (each would be an experiment of its own).
    """

    def __init__(self, train_groups: Sequence | None = None):
        self.train_groups = train_groups

    def _groups(self, groups) -> tuple[np.ndarray, list]:
        if groups is None:
            raise SelectionError("TrainOnOneExperiment needs 'groups' (the experiment of each row)")
        groups = check_groups(groups)
        present = list(dict.fromkeys(groups.tolist()))
        if len(present) < 2:
            raise SelectionError(
                f"train-on-one-experiment needs at least 2 experiments, got {len(present)}"
            )
        if self.train_groups is None:
            return groups, present
        if isinstance(self.train_groups, (str, bytes)) or np.ndim(self.train_groups) == 0:
            chosen = [self.train_groups]  # one label: "exp1" is not 'e', 'x', 'p', '1'
        else:
            chosen = list(self.train_groups)
        if not chosen:
            raise SelectionError("train_groups is empty; give at least one experiment or None")
        missing = [label for label in chosen if label not in present]
        if missing:
            raise SelectionError(f"training experiment(s) not among the groups: {missing}")
        return groups, chosen

    def get_n_splits(self, X=None, y=None, groups=None) -> int:
        """Number of splits: the number of training experiments."""
        return len(self._groups(groups)[1])

    def split(self, X=None, y=None, groups=None) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """Yield (train rows, test rows) per training experiment."""
        groups, chosen = self._groups(groups)
        if X is not None and len(X) != len(groups):
            raise SelectionError(f"X has {len(X)} rows but groups has {len(groups)}")
        for label in chosen:
            in_train = groups == label
            yield np.flatnonzero(in_train), np.flatnonzero(~in_train)

    def _iter_test_masks(self, X=None, y=None, groups=None):  # pragma: no cover - unused
        for _, test in self.split(X, y, groups):
            mask = np.zeros(len(groups), dtype=bool)
            mask[test] = True
            yield mask
