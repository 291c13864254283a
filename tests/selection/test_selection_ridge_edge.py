"""Ridge's penalty at its grid's edge: widened once, then warned (issue 23, item 5)."""

import json
import warnings

import numpy as np
import pytest
from spindlebench.selection import SelectionWarning
from spindlebench.selection.regressors import (
    RidgeRiseRegressor,
    blocked_cv_alpha,
    widened_cv_alpha,
)


def _noise_target():
    """Slow rises and a fast oscillating error they cannot explain: the constant predictor is
    best, so CV wants the largest penalty there is."""
    rng = np.random.default_rng(3)
    t = np.linspace(0, 1, 200)
    X = np.column_stack([t, t**2, np.sqrt(t)])
    return X, np.sin(40 * t) + 0.1 * rng.normal(size=t.size)


def test_largest_penalty_is_widened_then_warned():
    X, y = _noise_target()
    assert blocked_cv_alpha(X, y) == 1e4  # the plain grid's top: the silent case of the issue
    with pytest.warns(SelectionWarning, match="upper edge of its grid even after widening"):
        model = RidgeRiseRegressor().fit(X, y)
    assert model.alpha_at_edge_ == "upper"
    assert model.alphas_.max() == pytest.approx(1e12) and model.alpha_ == model.alphas_.max()
    assert model.alphas_.size == 33  # 17 + 16 new points, same spacing


def test_widening_finds_an_interior_penalty_without_warning():
    """A grid too low for the data: its top is chosen, the widened grid holds the optimum."""
    rng = np.random.default_rng(0)
    t = np.linspace(0, 1, 300)
    X = np.column_stack([t, t + 0.01 * rng.normal(size=t.size)])
    y = 2 * t + 0.3 * rng.normal(size=t.size)
    full = np.logspace(-6, 6, 49)
    best = blocked_cv_alpha(X, y, full)
    at = int(np.flatnonzero(full == best)[0])
    low = full[at - 6: at - 1]  # five penalties, the largest two grid steps below the best
    alpha, grid, edge = widened_cv_alpha(X, y, low)
    assert blocked_cv_alpha(X, y, low) == low[-1]
    assert grid.size == 9 and grid[-1] == pytest.approx(low[-1] * low[-1] / low[0])
    # the widened grid (up to 10 x its old top) holds the optimum: no edge, no warning
    assert edge is None and alpha == pytest.approx(best)
    with warnings.catch_warnings():
        warnings.simplefilter("error", SelectionWarning)
        RidgeRiseRegressor(alphas=np.logspace(-6, 6, 49)).fit(X, y)


def test_edge_warning_is_in_the_evaluate_json(tmp_path):
    from selection_data import experiment_files
    from spindlebench.commands.main import main

    files = experiment_files(tmp_path)
    out = tmp_path / "r.json"
    # the error replaced by a fast oscillation: ridge on any sensors is best as a constant
    import pandas as pd

    for path in files:
        frame = pd.read_csv(path)
        frame["drift_um"] = np.sin(40 * frame["time_s"] / frame["time_s"].max())
        frame.to_csv(path, index=False)
    status = main(["evaluate", "--train", str(files[0]), "--test", *map(str, files[1:]),
                   "--target", "drift_um", "--clusters", "2", "--method", "lasso",
                   "--regressor", "ridge", "--json", str(out)])
    assert status == 0
    record = json.loads(out.read_text())
    assert any("edge of its grid" in w for w in record["provenance"]["warnings"])
