"""``regressors.standardised_ridge``: scikit-learn's StandardScaler then Ridge, to the bit."""

import numpy as np
import pytest
from sklearn.linear_model import Ridge
from sklearn.preprocessing import StandardScaler
from spindlebench.selection.regressors import standardised_ridge


def _cases():
    """Column-major candidates as the sweep's ridge makes them (more columns than samples:
    the kernel form), row-major ones, more samples than columns, a constant column."""
    rng = np.random.default_rng(11)
    raw = rng.normal(size=(181, 20)).cumsum(axis=0)
    wide = np.hstack([np.asfortranarray(raw), rng.normal(size=(181, 190))])
    tall = rng.normal(size=(120, 9)) * 10 ** rng.uniform(-3, 3, 9)
    tall[:, 4] = 2.5
    y_wide, y_tall = raw[:, 3] + rng.normal(size=181), rng.normal(size=120)
    return [(wide, y_wide), (np.ascontiguousarray(wide), y_wide), (tall, y_tall),
            (np.asfortranarray(tall), y_tall)]


@pytest.mark.parametrize("case", range(4))
@pytest.mark.parametrize("alpha", [1e-4, 31.622776601683793, 1e4])
def test_the_fit_is_scikit_learns_to_the_bit(case, alpha):
    X, y = _cases()[case]
    scaler = StandardScaler().fit(X)
    ridge = Ridge(alpha=alpha).fit(scaler.transform(X), y)
    fitted = standardised_ridge(X, y, alpha)
    assert fitted is not None
    for mine, theirs in [(fitted.mean, scaler.mean_), (fitted.scale, scaler.scale_),
                         (fitted.coef, ridge.coef_), (fitted.intercept, ridge.intercept_)]:
        assert np.shape(mine) == np.shape(theirs)
        assert np.array_equal(mine, theirs)


def test_values_scikit_learn_refuses_are_left_to_it():
    X, y = _cases()[2]
    X = X.copy()
    X[5, 1] = np.nan
    assert standardised_ridge(X, y, 1.0) is None
    assert standardised_ridge(X[:, 2:], np.where(np.arange(120) == 3, np.inf, y), 1.0) is None
