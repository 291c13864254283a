"""Steps 2-5 together: one candidate per cluster, the one with the largest |psi|, sign kept;
constant candidates dropped with a warning."""

import numpy as np
import pytest
from spindlebench.selection import (
    PairwiseDifferences,
    SelectionError,
    SelectionWarning,
    constant_columns,
    rises,
    select_sensitive_points,
)


@pytest.fixture
def data():
    """Two families of candidates: family A follows a, family B follows b; the error is
    -3a + 0.5b, so within A the cleanest copy of a wins, with a negative psi."""
    rng = np.random.default_rng(4)
    t = np.linspace(0, 1, 200)
    a = 1 - np.exp(-5 * t)
    b = np.sin(9 * t)
    X = np.column_stack([
        a + rng.normal(0, 0.05, 200),   # 0: A, noisy
        a + rng.normal(0, 0.001, 200),  # 1: A, clean -> kept
        b + rng.normal(0, 0.01, 200),   # 2: B, clean -> kept
        b + rng.normal(0, 0.2, 200),    # 3: B, noisy
    ])
    y = -3 * a + 0.5 * b
    return X, y


def test_keeps_strongest_per_cluster_with_sign(data):
    X, y = data
    result = select_sensitive_points(X, y, 2)
    assert [m.tolist() for m in result.clusters] == [[0, 1], [2, 3]]
    assert result.selected.tolist() == [1, 2]
    assert result.selected_psi[0] < -0.9  # negative correlation, reported with its sign
    np.testing.assert_allclose(result.psi, [np.corrcoef(x, y)[0, 1] for x in X.T], atol=1e-12)
    assert np.all(np.abs(result.psi[result.selected]) >= np.abs(result.psi[[0, 3]]))


def test_squaring_and_literal_options_run(data):
    X, y = data
    fast = select_sensitive_points(X, y, 2)
    slow = select_sensitive_points(X, y, 2, closure="squaring")
    np.testing.assert_array_equal(fast.closure, slow.closure)
    assert fast.selected.tolist() == slow.selected.tolist()
    literal = select_sensitive_points(X, y, 2, similarity="literal")
    assert np.all(literal.similarity >= fast.similarity - 1e-12)


def test_constant_candidate_dropped_with_warning_never_nan(data):
    X, y = data
    X = np.column_stack([X[:, :2], np.full(200, 21.5), X[:, 2:]])
    with pytest.warns(SelectionWarning, match=r"dropping 1 constant candidate.*: T_const"):
        result = select_sensitive_points(X, y, 2, names=["A0", "A1", "T_const", "B0", "B1"])
    assert result.dropped.tolist() == [2] and 2 not in result.selected
    assert np.isnan(result.psi[2])
    assert np.all(np.isfinite(result.similarity)) and np.all(np.isfinite(result.closure))
    assert result.similarity.shape == (4, 4)


@pytest.mark.parametrize(("k", "message"), [
    (0, "at least 1"), (5, "larger than the number of candidates"), (True, "integer"),
])
def test_bad_cluster_counts(data, k, message):
    X, y = data
    with pytest.raises(SelectionError, match=message):
        select_sensitive_points(X, y, k)


def test_k_larger_than_varying_candidates(data):
    X, y = data
    X = np.column_stack([X[:, 0], np.zeros(200), np.ones(200)])
    with pytest.warns(SelectionWarning), pytest.raises(SelectionError, match="only 1 candidate"):
        select_sensitive_points(X, y, 2)


def test_bad_samples(data):
    X, y = data
    with pytest.raises(SelectionError, match="at least 2 samples"):
        select_sensitive_points(X[:1], y[:1], 1)
    X = X.copy()
    X[5, 1] = np.nan
    with pytest.raises(SelectionError, match="NaN"):
        select_sensitive_points(X, y, 2)


def test_offset_pair_difference_is_constant_also_as_rises():
    """B = A + 0.1: the rise of A-B is rounding noise (~1e-15), which must count as constant
    rather than be correlated with anything."""
    a = np.linspace(28, 36, 300) + 0.01 * np.sin(np.arange(300))  # crosses 32: rounding
    c = 22 + np.cos(np.arange(300) / 30)                           # of a + 0.1 varies
    raw = np.column_stack([a, a + 0.1, c])
    assert np.ptp(rises(raw)[:, 0] - rises(raw)[:, 1]) > 0  # the noise this test is about
    for candidates in (PairwiseDifferences().fit_transform(raw),
                       PairwiseDifferences().fit_transform(rises(raw))):
        assert constant_columns(candidates).tolist() == [False] * 3 + [True, False, False]
    with pytest.warns(SelectionWarning, match=r"constant candidate\(s\) \(zero variance\): A-B$"):
        result = select_sensitive_points(PairwiseDifferences().fit_transform(rises(raw)), a - c,
                                         2, names=["A", "B", "C", "A-B", "A-C", "B-C"])
    assert result.dropped.tolist() == [3]


def test_sensitive_points_select_every_k_as_select_sensitive_points_does():
    """One SensitivePoints for k = 1..5 (its R, t(R), psi and tree made once) gives what a
    fresh select_sensitive_points gives per k, and warns and raises the same, per k."""
    import warnings

    from spindlebench.selection.errors import SelectionError, SelectionWarning
    from spindlebench.selection.select import SensitivePoints

    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 1.0, 60)[:, None]
    X = np.hstack([t ** p + 0.05 * rng.standard_normal((60, 1)) for p in (1, 1, 2, 3, 5, 8)])
    X = np.hstack([X, np.ones((60, 1))])  # a constant candidate: dropped with a warning
    y = 3.0 * t[:, 0] ** 2 + 0.01 * rng.standard_normal(60)
    names = [f"c{i}" for i in range(X.shape[1])]
    points = SensitivePoints(X, y, names=names)
    for k in (1, 2, 3, 4, 5):
        with warnings.catch_warnings(record=True) as shared_warned:
            warnings.simplefilter("always")
            shared = points.select(k)
        with warnings.catch_warnings(record=True) as fresh_warned:
            warnings.simplefilter("always")
            fresh = select_sensitive_points(X, y, k, names=names)
        assert [str(w.message) for w in shared_warned] == [str(w.message) for w in fresh_warned]
        assert any(issubclass(w.category, SelectionWarning) for w in shared_warned)
        assert shared.eta == fresh.eta
        assert [c.tolist() for c in shared.clusters] == [c.tolist() for c in fresh.clusters]
        np.testing.assert_array_equal(shared.selected, fresh.selected)
        np.testing.assert_array_equal(shared.psi, fresh.psi)
        np.testing.assert_array_equal(shared.closure, fresh.closure)
    for k in (0, 7):  # too few or too many clusters: the same one-line error each time
        with pytest.raises(SelectionError) as shared_error, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            points.select(k)
        with pytest.raises(SelectionError) as fresh_error, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            select_sensitive_points(X, y, k, names=names)
        assert str(shared_error.value) == str(fresh_error.value)
