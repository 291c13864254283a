"""Bad input to the selection API is one clear error (or a warning naming what it changes),
never a silent NaN, a broadcast error or a per-character iteration."""

import numpy as np
import pytest
from selection_data import synthetic_experiment
from spindlebench.selection import (
    PairwiseDifferences,
    RiseRegressor,
    RiseTransformer,
    SelectionError,
    SelectionWarning,
    TrainOnOneExperiment,
    cut_at,
    evaluate,
    fit_ols,
    r2_score,
    rises,
    rmse,
    select_sensitive_points,
    similarity_matrix,
    transitive_closure,
)
from spindlebench.selection.errors import SelectionOverflowError

rng = np.random.default_rng(0)
X = rng.normal(size=(50, 6)).cumsum(axis=0)
y = X @ np.arange(1.0, 7.0) + rng.normal(size=50)


@pytest.mark.parametrize("score", [rmse, r2_score])
def test_scores_need_equal_lengths_and_samples(score):
    with pytest.raises(SelectionError, match=r"shapes \(50,\) and \(49,\)"):
        score(y, y[:-1])
    with pytest.raises(SelectionError, match=r"shapes \(50,\) and \(50, 2\)"):
        score(y, np.column_stack([y, y]))
    with pytest.raises(SelectionError, match="at least 1 sample"):
        score([], [])
    assert score(y, y[:, None]) == score(y, y)  # (n, 1) is n samples, not an n x n broadcast


def test_scores_refuse_overflow_but_pass_nan_through():
    with pytest.raises(SelectionOverflowError, match="overflow"):
        rmse([1e200, -1e200], [0.0, 0.0])
    with pytest.raises(SelectionOverflowError, match="overflow"):
        r2_score([1e200, -1e200], [0.0, 0.0])
    assert np.isnan(rmse([1.0, np.nan], [1.0, 2.0]))  # a dropped-out sensor's score is NaN


def test_splitter_refuses_nan_groups_and_takes_a_string_as_one_label():
    with pytest.raises(SelectionError, match="50 NaN/None label"):
        list(TrainOnOneExperiment().split(X, y, np.full(50, np.nan)))
    mixed = np.array(["a"] * 20 + ["b"] * 20 + [None] * 10, dtype=object)
    with pytest.raises(SelectionError, match="first in row 40"):
        list(TrainOnOneExperiment().split(X, y, mixed))
    groups = np.array(["ab"] * 25 + ["cd"] * 25)
    splits = list(TrainOnOneExperiment(train_groups="ab").split(X, y, groups))
    assert len(splits) == 1 and splits[0][0].tolist() == list(range(25))
    with pytest.raises(SelectionError, match="empty"):
        TrainOnOneExperiment(train_groups=[]).get_n_splits(groups=groups)


def test_rises_refuse_nan_labels_and_a_nan_reference():
    with pytest.raises(SelectionError, match="NaN/None label"):
        rises(X, np.r_[np.zeros(49), np.nan])
    bad = X.copy()
    bad[0, 2] = np.nan
    with pytest.raises(SelectionError, match=r"first row \(the reference\).*column\(s\) 2"):
        rises(bad)
    with pytest.raises(SelectionError, match="experiment 1"):
        rises(np.vstack([X, bad]), np.r_[np.zeros(50), np.ones(50)])
    dropped = X.copy()
    dropped[:, 2] = np.nan  # a whole-run dropout loses nothing: it stays NaN
    assert np.isnan(rises(dropped)[:, 2]).all()


def test_nan_and_bad_thresholds_and_names_are_refused():
    bad = X.copy()
    bad[3, 1] = np.nan
    with pytest.raises(SelectionError, match="NaN or inf in column 1"):
        similarity_matrix(bad)
    T = transitive_closure(similarity_matrix(X))
    for eta in (np.nan, 2.0, -0.1, "0.5", True):
        with pytest.raises(SelectionError, match="eta must be a number in"):
            cut_at(T, eta)
    assert len(cut_at(T, 0.0).clusters) == 1
    with pytest.raises(SelectionError, match="1 name"):
        select_sensitive_points(X, y, 2, names=["a"])
    with pytest.raises(ValueError, match="NaN"):
        RiseTransformer(reference=[np.nan] * 6).fit(X)


def test_overflow_in_correlations_names_the_columns():
    big = X * 1e200  # correlations were silently 0 (norms inf), so every psi was 0
    with pytest.raises(SelectionOverflowError, match=r"too large to correlate.*in a, b, c"):
        select_sensitive_points(big, y, 2, names=list("abcdef"))


def test_underdetermined_and_collinear_regressions():
    with pytest.raises(SelectionError, match="features \\+ 1 = 7 samples, got 3"):
        fit_ols(X[:3], y[:3])
    with pytest.raises(ValueError, match="features \\+ 1"):
        RiseRegressor().fit(X[:3], y[:3])
    twice = np.column_stack([X, X[:, 1]])
    with pytest.warns(SelectionWarning, match=r"feature\(s\) g are linear combinations.*rank 6"):
        fit = fit_ols(twice, y, names=list("abcdefg"))
    assert np.isfinite(fit.coefficients).all()
    with pytest.warns(SelectionWarning, match=r"column 6 are linear"):
        RiseRegressor().fit(twice, y)


def test_include_raw_must_be_a_bool():
    with pytest.raises(ValueError, match="include_raw"):
        PairwiseDifferences(include_raw="no").fit(X)
    assert PairwiseDifferences(include_raw=False).fit_transform(X).shape == (50, 15)


def test_evaluate_takes_one_test_path_as_a_string(tmp_path):
    paths = []
    for seed in range(2):
        paths.append(tmp_path / f"exp{seed}.csv")
        synthetic_experiment(seed).to_csv(paths[-1], index=False)
    result = evaluate(str(paths[0]), str(paths[1]), "drift_um", k=2)
    assert list(result.rmse_um) == [str(paths[1])]
    assert list(evaluate(paths[0], paths[1], "drift_um", k=2).rmse_um) == [str(paths[1])]
