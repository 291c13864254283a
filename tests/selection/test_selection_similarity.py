"""Fuzzy similarity (eq. 1): both readings, range, diagonal, symmetry, constant columns."""

import numpy as np
import pytest
from spindlebench.selection import (
    SelectionError,
    constant_columns,
    correlation_with,
    similarity_matrix,
)


@pytest.fixture
def sample():
    rng = np.random.default_rng(7)
    base = rng.normal(size=(80, 3)).cumsum(axis=0)
    return np.column_stack([base, base[:, 0] * -2 + 30, base[:, 1] + rng.normal(size=80)])


def test_abs_pearson_equals_numpy_corrcoef(sample):
    R = similarity_matrix(sample)
    np.testing.assert_allclose(R, np.abs(np.corrcoef(sample, rowvar=False)), atol=1e-12)
    assert R[0, 3] == pytest.approx(1.0)  # perfectly anti-correlated -> similar


def test_literal_formula_by_hand(sample):
    a, b = sample[:, 1], sample[:, 4]
    da, db = a - a.mean(), b - b.mean()
    expected = np.sum(np.abs(da) * np.abs(db)) / (np.sqrt(np.sum(da**2)) * np.sqrt(np.sum(db**2)))
    literal = similarity_matrix(sample, "literal")
    assert literal[1, 4] == pytest.approx(expected, rel=1e-12)
    assert np.all(literal >= similarity_matrix(sample) - 1e-12)  # |sum| <= sum of |.|


@pytest.mark.parametrize("method", ["abs-pearson", "literal"])
def test_unit_diagonal_symmetric_in_unit_interval(sample, method):
    R = similarity_matrix(sample + 1000.0, method)  # a large offset must not matter
    assert np.array_equal(R, R.T)
    assert np.all(np.diagonal(R) == 1.0)
    assert R.min() >= 0.0 and R.max() <= 1.0
    np.testing.assert_allclose(R, similarity_matrix(sample, method), atol=1e-9)


def test_unknown_method_and_constant_column_rejected(sample):
    with pytest.raises(SelectionError, match="unknown similarity"):
        similarity_matrix(sample, "spearman")
    with pytest.raises(SelectionError, match="constant"):
        similarity_matrix(np.column_stack([sample, np.full(80, 25.0)]))


def test_constant_columns_tolerate_rounding_of_offset_differences():
    rng = np.random.default_rng(0)
    a = 25 + rng.normal(size=100)
    offset = (a + 0.1) - a  # 0.1 up to rounding: constant
    mask = constant_columns(np.column_stack([a, offset, np.zeros(100), a * 1e-9]))
    assert mask.tolist() == [False, True, True, False]


def test_correlation_keeps_sign():
    t = np.linspace(0, 1, 50)
    psi = correlation_with(np.column_stack([t, -t**2, np.sin(7 * t)]), 3 * t + 1)
    assert psi[0] == pytest.approx(1.0)
    assert psi[1] < -0.9
    with pytest.raises(SelectionError, match=r"target .* is constant"):
        correlation_with(t[:, None], np.ones(50))


def test_the_median_of_constant_columns_is_numpys_to_the_bit():
    """similarity._median replaces np.median (which imports numpy.ma) in constant_columns."""
    from spindlebench.selection.similarity import _median

    rng = np.random.default_rng(3)
    for n in [*range(1, 12), 100, 101]:
        for trial in range(20):
            values = rng.normal(size=n) * 10.0 ** rng.integers(-8, 8)
            if trial % 3 == 0:
                values = np.round(values, 1)  # ties and -0.0
            if trial % 5 == 0 and n > 2:
                values[rng.integers(n)] = np.nan
            expected = np.median(values)
            got = _median(values)
            assert np.float64(got).tobytes() == np.float64(expected).tobytes() or \
                (np.isnan(got) and np.isnan(expected)), (values, got, expected)


def test_similarity_shares_its_standardised_columns_with_the_correlation():
    """similarity_and_standardized gives similarity_matrix's R and standardized's columns,
    and the correlation from those columns is correlation_with's, to the bit (both
    readings of eq. 1)."""
    from spindlebench.selection.similarity import (
        correlation_with,
        similarity_and_standardized,
        similarity_matrix,
        standardized,
    )

    rng = np.random.default_rng(12)
    X = rng.normal(size=(181, 21)).cumsum(axis=0) * 0.3 + 25.0
    y = X[:, 2] * 1.5 - X[:, 7] + rng.normal(size=181)
    for method in ("abs-pearson", "literal"):
        R, Z = similarity_and_standardized(X, method)
        assert np.array_equal(R, similarity_matrix(X, method))
        assert np.array_equal(Z, standardized(X))
        assert np.array_equal(correlation_with(X, y, standardized_X=Z), correlation_with(X, y))
