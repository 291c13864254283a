"""Max-min transitive closure (eq. 2): hand example, properties, and exact agreement of the
spanning-tree implementation with the paper's repeated squaring on random and real data."""

import numpy as np
import pytest
from selection_data import HAND_R, HAND_T, random_similarity, real_temperatures
from spindlebench.selection import (
    SelectionError,
    closure_by_squaring,
    closure_minimax,
    similarity_matrix,
    transitive_closure,
    with_differences,
)
from spindlebench.selection.closure import maxmin_product


@pytest.mark.parametrize("closure", [closure_by_squaring, closure_minimax])
def test_hand_example(closure):
    np.testing.assert_array_equal(closure(HAND_R), HAND_T)


def test_maxmin_product_by_definition():
    rng = np.random.default_rng(3)
    A, B = rng.random((5, 7)), rng.random((7, 4))
    expected = np.array([[max(min(A[i, k], B[k, j]) for k in range(7)) for j in range(4)]
                         for i in range(5)])
    np.testing.assert_array_equal(maxmin_product(A, B, chunk_bytes=1), expected)


@pytest.mark.parametrize(("n", "seed", "levels"), [(2, 0, None), (17, 1, None), (60, 2, None),
                                                   (45, 3, 4), (30, 4, 1)])
def test_fast_equals_squaring_exactly_on_random(n, seed, levels):
    R = random_similarity(n, seed, levels)
    np.testing.assert_array_equal(closure_minimax(R), closure_by_squaring(R))


@pytest.mark.parametrize("method", ["abs-pearson", "literal"])
def test_fast_equals_squaring_exactly_on_real_data(method):
    frame = real_temperatures()
    sensors = [f"t{i}_C" for i in range(1, 17)]
    candidates = with_differences(frame, sensors).to_numpy()  # 16 + 120 candidates
    R = similarity_matrix(candidates, method)
    T = closure_minimax(R)
    np.testing.assert_array_equal(T, closure_by_squaring(R))
    assert np.unique(T).size > 50  # a real hierarchy, not a trivial matrix


def test_closure_properties():
    R = random_similarity(40, 11)
    T = transitive_closure(R)
    assert np.all(T >= R)                                 # contains R
    np.testing.assert_array_equal(maxmin_product(T, T), T)  # max-min transitive, idempotent
    np.testing.assert_array_equal(transitive_closure(T), T)
    assert np.array_equal(T, T.T) and np.all(np.diagonal(T) == 1.0)
    assert not np.array_equal(T, R)  # random R is not transitive


def test_closure_inputs_checked():
    with pytest.raises(SelectionError, match="symmetric"):
        closure_minimax(np.array([[1.0, 0.2], [0.3, 1.0]]))
    with pytest.raises(SelectionError, match="diagonal"):
        closure_by_squaring(np.array([[0.9, 0.2], [0.2, 1.0]]))
    with pytest.raises(SelectionError, match=r"\[0, 1\]"):
        closure_minimax(np.array([[1.0, np.nan], [np.nan, 1.0]]))
    with pytest.raises(SelectionError, match="unknown closure"):
        transitive_closure(HAND_R, "warshall")
