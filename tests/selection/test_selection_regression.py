"""OLS on rises: against numpy lstsq, R^2 and RMSE by definition, rises per experiment."""

import numpy as np
import pytest
from spindlebench.selection import SelectionError, fit_ols, r2_score, rises, rmse


def test_ols_matches_lstsq_with_intercept_column():
    rng = np.random.default_rng(2)
    X = 25 + rng.normal(size=(100, 3)).cumsum(axis=0)  # far from zero, like temperatures
    y = 2.0 - 3.0 * X[:, 0] + 0.7 * X[:, 2] + rng.normal(0, 0.5, 100)
    fit = fit_ols(X, y)
    design = np.column_stack([np.ones(100), X])
    expected, *_ = np.linalg.lstsq(design, y, rcond=None)
    np.testing.assert_allclose([fit.intercept, *fit.coefficients], expected, rtol=1e-9)
    fitted = design @ expected
    assert fit.r2 == pytest.approx(1 - np.sum((y - fitted) ** 2) / np.sum((y - y.mean()) ** 2))
    np.testing.assert_allclose(fit.predict(X), fitted, rtol=1e-10)
    assert 0.9 < fit.r2 < 1.0


def test_exact_recovery_and_metrics():
    X = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 2.0], [3.0, 1.0]])
    y = 1.5 + 2.0 * X[:, 0] - 0.5 * X[:, 1]
    fit = fit_ols(X, y)
    assert fit.intercept == pytest.approx(1.5)
    np.testing.assert_allclose(fit.coefficients, [2.0, -0.5])
    assert fit.r2 == pytest.approx(1.0)
    assert rmse([1.0, 2.0, 3.0], [1.0, 2.0, 7.0]) == pytest.approx(np.sqrt(16 / 3))
    assert r2_score([1.0, 2.0, 3.0], [2.0, 2.0, 2.0]) == pytest.approx(0.0)
    assert np.isnan(r2_score([1.0, 1.0], [1.0, 1.0]))


def test_rises_relative_to_first_sample_of_each_experiment():
    X = np.array([[10.0, 1.0], [12.0, 4.0], [20.0, 5.0], [23.0, 5.0], [11.0, 2.0]])
    np.testing.assert_array_equal(rises(X), X - X[0])
    groups = np.array(["a", "a", "b", "b", "a"])
    np.testing.assert_array_equal(
        rises(X, groups), [[0, 0], [2, 3], [0, 0], [3, 0], [1, 1]]
    )
    with pytest.raises(SelectionError, match="label each"):
        rises(X, groups[:3])


def test_bad_regression_input():
    with pytest.raises(SelectionError, match="at least 2 samples"):
        fit_ols(np.ones((1, 2)), np.ones(1))
    with pytest.raises(SelectionError, match="finite"):
        fit_ols(np.array([[1.0], [np.inf]]), np.array([1.0, 2.0]))


def _low_rank_candidates(seed: int, n_sensors: int = 6, n: int = 120):
    from spindlebench.selection.differences import pairwise_differences

    rng = np.random.default_rng(seed)
    t = np.linspace(0, 1, n)[:, None]
    rises = (1 - np.exp(-t * rng.uniform(1, 6, n_sensors))) * rng.uniform(1, 5, n_sensors) \
        + rng.normal(0, 0.02, (n, n_sensors))
    rises = rises - rises[0]
    y = rises @ rng.normal(0, 2, n_sensors) + rng.normal(0, 0.1, n)
    return rises, np.hstack([rises, pairwise_differences(rises)]), y


def test_factored_cv_gives_the_full_svds_penalty(monkeypatch):
    """blocked_cv_alpha with factors (the candidates as rises @ matrix) picks the penalty the
    full SVDs pick; a race closer than FACTORED_MARGIN is decided by the full SVDs."""
    from spindlebench.selection import regressors
    from spindlebench.selection.differences import with_differences_matrix

    for seed in range(8):
        rises, X, y = _low_rank_candidates(seed)
        assert np.array_equal(rises @ with_differences_matrix(6), X)
        factors = (rises, with_differences_matrix(6))
        full = regressors._fold_errors(X, y, regressors.RIDGE_ALPHAS, 5)
        factored = regressors._fold_errors(X, y, regressors.RIDGE_ALPHAS, 5, factors)
        assert np.allclose(full, factored, rtol=1e-9, atol=0)
        assert regressors.blocked_cv_alpha(X, y, factors=factors) == \
            regressors.blocked_cv_alpha(X, y)
    calls = []
    original = regressors._fold_errors
    monkeypatch.setattr(regressors, "_fold_errors",
                        lambda *args: calls.append(len(args)) or original(*args))
    rises, X, y = _low_rank_candidates(0)
    clear = np.array([1e-3, 1e2])
    assert regressors.blocked_cv_alpha(X, y, clear, factors=(rises, with_differences_matrix(6)))
    assert calls == [5]  # the factored errors only
    calls.clear()
    tie = np.array([1e-3, 1e-3, 1e2])  # no margin at all: the full SVDs decide
    regressors.blocked_cv_alpha(X, y, tie, factors=(rises, with_differences_matrix(6)))
    assert calls == [5, 4]



def test_factored_cv_folds_and_constant_candidates():
    """The factored errors use KFold's blocks, and candidates constant in the data (a dead
    sensor's zero rises, the difference of two identical sensors, one constant in a fold's
    training part only) keep scale 1 as the full SVDs give them: the same errors to
    rounding, the same penalty."""
    from sklearn.model_selection import KFold
    from spindlebench.selection import regressors
    from spindlebench.selection.differences import with_differences_matrix

    for n, k in ((181, 5), (10, 3), (7, 7), (12, 5)):
        blocks = [len(valid) for _, valid in KFold(k).split(np.zeros(n))]
        assert regressors.fold_sizes(n, k).tolist() == blocks
    for seed in range(4):
        rises, _, y = _low_rank_candidates(seed)
        rises[:, 1] = 0.0  # a dead sensor
        rises[:, 3] = rises[:, 2]  # two identical ones
        rises[: len(rises) * 3 // 5, 4] = 0.0  # flat until the fourth fold
        factors = (rises, with_differences_matrix(6))
        X = rises @ factors[1]
        full = regressors._fold_errors(X, y, regressors.RIDGE_ALPHAS, 5)
        factored = regressors._fold_errors(X, y, regressors.RIDGE_ALPHAS, 5, factors)
        assert np.allclose(full, factored, rtol=1e-9, atol=0)
        assert regressors.blocked_cv_alpha(X, y, factors=factors) == \
            regressors.blocked_cv_alpha(X, y)

def test_rmse_is_the_textbook_formula_to_the_bit():
    """rmse sums the squares without np.mean's wrapper: the same bits as np.mean, also
    around the blocks of numpy's pairwise summation (8, 128 elements)."""
    from spindlebench.selection.regression import rmse

    rng = np.random.default_rng(3)
    for n in (1, 2, 7, 8, 9, 127, 128, 129, 181, 1000, 4099):
        for _ in range(20):
            y, p = rng.normal(size=n) * 50, rng.normal(size=n) * 50
            assert rmse(y, p) == float(np.sqrt(np.mean((y - p) ** 2)))
    assert np.isnan(rmse(np.array([1.0, np.nan]), np.array([1.0, 2.0])))


def test_rmse_each_is_rmse_of_each_pair_to_the_bit():
    """One reduction over the stacked runs gives each run's own bits (numpy's pairwise sum
    runs along each row as on the row alone), around the summation's blocks too; unequal
    lengths, NaN and overflow take rmse pair by pair (its values, its error)."""
    from spindlebench.selection.regression import rmse_each

    rng = np.random.default_rng(4)
    for n in (1, 2, 7, 8, 9, 127, 128, 129, 181, 1000, 4099):
        ys = [rng.normal(size=n) * 10.0 ** rng.uniform(-3, 3) for _ in range(23)]
        ps = [rng.normal(size=n) * 50 for _ in range(23)]
        assert rmse_each(ys, ps) == [rmse(y, p) for y, p in zip(ys, ps, strict=True)]
    uneven = [np.arange(3.0), np.arange(5.0)]
    assert rmse_each(uneven, [u + 1 for u in uneven]) == [1.0, 1.0]
    with_nan = rmse_each([np.array([1.0, np.nan]), np.ones(2)], [np.ones(2), np.zeros(2)])
    assert np.isnan(with_nan[0]) and with_nan[1] == 1.0
    assert rmse_each([], []) == []
    with pytest.raises(SelectionError, match="overflow"):
        rmse_each([np.ones(2), np.full(2, 1e300)], [np.zeros(2), np.full(2, -1e300)])
    with pytest.raises(SelectionError, match="2 measured but 1 predicted"):
        rmse_each([np.ones(2), np.ones(2)], [np.ones(2)])



def test_rmse_rows_is_rmse_of_each_row_to_the_bit():
    """Runs stacked once (C-contiguous) score as rmse scores each run; any other stack
    (another layout, dtype or shape) or a score that is not finite gives None, for the
    caller's pair-by-pair way."""
    from spindlebench.selection.regression import rmse_rows

    rng = np.random.default_rng(5)
    for n in (1, 8, 127, 129, 181, 4099):
        ys = rng.normal(size=(23, n)) * 10.0 ** rng.uniform(-3, 3)
        ps = rng.normal(size=(23, n)) * 50
        assert rmse_rows(ys, ps) == [rmse(y, p) for y, p in zip(ys, ps, strict=True)]
    ys, ps = rng.normal(size=(3, 9)), rng.normal(size=(3, 9))
    assert rmse_rows(np.asfortranarray(ys), ps) is None
    assert rmse_rows(ys, ps.astype(np.float32)) is None
    assert rmse_rows(ys, ps[:, :8].copy()) is None
    assert rmse_rows(np.empty((2, 0)), np.empty((2, 0))) is None
    ys[1, 3] = np.nan
    assert rmse_rows(ys, ps) is None

def test_linear_fit_predict_each_is_predict_of_each():
    """The same product per input under one errstate: the same bits as predict."""
    from spindlebench.selection.regression import LinearFit

    rng = np.random.default_rng(5)
    fit = LinearFit(intercept=0.3, coefficients=rng.normal(size=3), r2=1.0)
    Xs = [rng.normal(size=(n, 3)) * 40 for n in (2, 181, 200)] + [
        np.asfortranarray(rng.normal(size=(181, 3)))]
    for each, X in zip(fit.predict_each(Xs), Xs, strict=True):
        assert np.array_equal(each, fit.predict(X))
    assert np.isinf(fit.predict_each([np.full((2, 3), 1e308)])[0]).any()


def test_linear_fit_predict_stacked_is_predict_of_each_run_to_the_bit():
    """One product over the runs stacked gives each run's row the bits of its own product,
    for the few candidates a study's models read (1..8) and runs of several lengths."""
    from spindlebench.selection.regression import LinearFit

    rng = np.random.default_rng(12)
    for k in range(1, 9):
        for samples in (2, 7, 180, 181):
            fit = LinearFit(intercept=float(rng.normal()), coefficients=rng.normal(size=k),
                            r2=0.0)
            runs = rng.normal(size=(23, samples, k)) * 10
            stacked = fit.predict_stacked(runs)
            for row, each in zip(stacked, fit.predict_each(list(runs)), strict=True):
                assert np.array_equal(row, each)


def test_fit_ols_is_the_centred_lstsq_to_the_bit():
    """fit_ols' means without np.mean's wrapper and its R^2 from the fit's own mean: the
    intercept, coefficients and R^2 of the textbook steps (np.mean, lstsq, r2_score)."""
    rng = np.random.default_rng(13)
    for n, p in ((181, 3), (181, 20), (7, 2), (129, 1), (4099, 5)):
        for _ in range(10):
            X = np.asfortranarray(rng.normal(size=(n, p)) * 10 ** rng.uniform(-3, 3))
            y = rng.normal(size=n) * 10 ** rng.uniform(-2, 2)
            fit = fit_ols(X, y)
            x_mean, y_mean = X.mean(axis=0), y.mean()
            coefficients = np.linalg.lstsq(X - x_mean, y - y_mean, rcond=None)[0]
            intercept = float(y_mean - x_mean @ coefficients)
            assert fit.intercept == intercept
            assert np.array_equal(fit.coefficients, coefficients)
            assert fit.r2 == r2_score(y, intercept + X @ coefficients)


def test_stacked_rows_is_np_stack_of_equally_long_runs():
    """Equally long 1-D float64 runs (float32 ones converted as np.stack converts them)
    stack as np.stack stacks them, C-contiguous; anything else is None."""
    from spindlebench.selection.regression import stacked_rows

    rng = np.random.default_rng(14)
    runs = [rng.normal(size=181) for _ in range(23)]
    strided = [np.asfortranarray(rng.normal(size=(181, 3)))[:, 1] for _ in range(3)]
    for arrays in (runs, strided, [runs[0], runs[1].astype(np.float32)]):
        stacked = stacked_rows(arrays)
        assert stacked.flags.c_contiguous and stacked.tobytes() == np.stack(arrays).tobytes()
    assert stacked_rows([]) is None
    assert stacked_rows([runs[0], runs[1][:-1]]) is None
    assert stacked_rows([runs[0][:, None], runs[1][:, None]]) is None
    assert stacked_rows([runs[0], list(runs[1])]) is None
    assert stacked_rows([np.arange(3), np.arange(3)]) is None
