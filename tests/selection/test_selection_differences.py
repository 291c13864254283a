"""Constructed temperature differences: names, order, values and counts."""

import numpy as np
import pandas as pd
import pytest
from spindlebench.selection import (
    SelectionError,
    difference_names,
    pairwise_differences,
    with_differences,
)


def test_names_follow_given_order_a_before_b():
    assert difference_names(["T1", "T2", "T3", "T4"]) == [
        "T1-T2", "T1-T3", "T1-T4", "T2-T3", "T2-T4", "T3-T4",
    ]
    assert difference_names(["b", "a"]) == ["b-a"]


@pytest.mark.parametrize(("n", "expected"), [(1, 0), (2, 1), (6, 15), (16, 120), (20, 190)])
def test_counts(n, expected):
    assert len(difference_names([f"T{i}" for i in range(n)])) == expected
    assert pairwise_differences(np.zeros((3, n))).shape == (3, expected)


def test_values_match_names():
    rng = np.random.default_rng(1)
    frame = pd.DataFrame(rng.normal(size=(5, 4)), columns=["T1", "T6", "T8", "T10"])
    out = with_differences(frame, ["T8", "T1", "T10"])
    assert list(out.columns) == ["T8", "T1", "T10", "T8-T1", "T8-T10", "T1-T10"]
    np.testing.assert_array_equal(out["T8-T10"], frame["T8"] - frame["T10"])
    np.testing.assert_array_equal(out["T1-T10"], frame["T1"] - frame["T10"])


def test_repeated_names_rejected():
    with pytest.raises(SelectionError, match="repeated: T1"):
        difference_names(["T1", "T2", "T1"])


def test_few_candidates_column_by_column_equal_the_block_path(monkeypatch):
    """CandidateSet.matrix builds a model's few candidates column by column: the values (to
    the bit, NaN where a sensor has none) and layout of the all-sensors block path."""
    import importlib

    from spindlebench.selection.evaluate import CandidateSet, CheckedRecording

    evaluate = importlib.import_module("spindlebench.selection.evaluate")  # not the function

    rng = np.random.default_rng(5)
    sensors = [f"T{i}" for i in range(1, 9)]
    frame = pd.DataFrame(rng.normal(size=(50, 8)).cumsum(axis=0), columns=sensors)
    frame["T8"] = np.nan  # a sensor lost for the whole run
    recording = CheckedRecording("r", frame)
    candidates = CandidateSet(tuple(sensors), True)
    for k in (1, 2, 4, evaluate.FEW_CANDIDATES):
        for _ in range(20):
            columns = sorted(rng.choice(len(candidates.names), k, replace=False).tolist())
            few = candidates.matrix(recording, columns)
            monkeypatch.setattr(evaluate, "FEW_CANDIDATES", 0)
            block = candidates.matrix(recording, columns)
            monkeypatch.undo()
            assert few.tobytes() == block.tobytes() and few.strides == block.strides
