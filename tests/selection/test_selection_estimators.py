"""scikit-learn API: estimator checks, feature names through a Pipeline, equivalence with the
functional core, and the train-on-one-experiment splitter."""

import numpy as np
import pandas as pd
import pytest
from selection_data import synthetic_experiment
from sklearn.base import clone
from sklearn.model_selection import cross_val_score
from sklearn.pipeline import Pipeline
from sklearn.utils.estimator_checks import parametrize_with_checks
from spindlebench.selection import (
    FuzzyClusterSelector,
    PairwiseDifferences,
    RiseRegressor,
    RiseTransformer,
    SelectionError,
    TrainOnOneExperiment,
    evaluate,
    make_selection_pipeline,
    rises,
)

SENSORS = ["T1", "T6", "T8", "T10", "T13", "T16"]


@parametrize_with_checks(
    [PairwiseDifferences(), PairwiseDifferences(include_raw=False), RiseTransformer(),
     FuzzyClusterSelector(), FuzzyClusterSelector(2, "literal", "squaring"), RiseRegressor()]
)
def test_sklearn_estimator_checks(estimator, check):
    check(estimator)


def experiments(n_experiments: int = 3) -> tuple[pd.DataFrame, np.ndarray, np.ndarray]:
    frames = [synthetic_experiment(seed, speed=0.5 + 0.4 * seed) for seed in range(n_experiments)]
    data = pd.concat(frames, ignore_index=True)
    groups = np.repeat([f"exp{i + 1}" for i in range(n_experiments)], [len(f) for f in frames])
    return data, groups, frames


def test_pipeline_feature_names_and_selection():
    data, groups, _ = experiments()
    X = data[SENSORS]
    model = make_selection_pipeline(k=2, differences=True)
    model.fit(X[groups == "exp1"], data["drift_um"][groups == "exp1"])
    names = model[:-1].get_feature_names_out()
    all_names = model["differences"].get_feature_names_out()
    assert len(all_names) == 21 and all_names[6] == "T1-T6" and all_names[-1] == "T13-T16"
    assert len(names) == 2 and set(names) <= set(all_names)
    selector = model["select"]
    assert len(selector.clusters_) == 2 and 0 < selector.eta_ <= 1
    assert selector.closure_.shape == (21, 21)
    assert names[0] == "T1-T10"  # the drift's main driver (see synthetic_experiment)
    for members, chosen in zip(selector.clusters_, selector.selected_, strict=True):
        assert abs(selector.psi_[chosen]) == np.abs(selector.psi_[members]).max()


def test_pipeline_equals_evaluate():
    """The sklearn route (rises per experiment, Pipeline, splitter) and ``evaluate`` agree."""
    data, groups, frames = experiments()
    Xr = rises(data[SENSORS].to_numpy(), groups)
    y = data["drift_um"].to_numpy()
    model = make_selection_pipeline(k=3, differences=True)
    train, test = next(TrainOnOneExperiment(["exp1"]).split(Xr, y, groups))
    model.fit(Xr[train], y[train])
    result = evaluate(frames[0], {"exp2": frames[1], "exp3": frames[2]}, "drift_um",
                      sensors=SENSORS, k=3, differences=True)
    names = list(model[:-1].get_feature_names_out(SENSORS))
    assert names == result.selected
    np.testing.assert_allclose(model["regress"].coef_, list(result.coefficients.values())[1:])
    assert model["regress"].r2_ == pytest.approx(result.to_dict()["r2"])
    predicted = model.predict(Xr[test])
    np.testing.assert_allclose(predicted[: len(frames[1])], result.predictions["exp2"])


def test_selector_on_dataframe_keeps_names():
    data, _, _ = experiments(1)
    selector = FuzzyClusterSelector(2).fit(data[SENSORS], data["drift_um"])
    assert list(selector.get_feature_names_out()) == [SENSORS[i] for i in selector.selected_]
    assert isinstance(clone(selector).k, int)


def test_rise_transformer_reference():
    X = np.array([[20.0, 21.0], [22.0, 25.0], [23.0, 26.0]])
    np.testing.assert_array_equal(RiseTransformer().fit(X).transform(X), X - X[0])
    fixed = RiseTransformer(reference=[19.0, 20.0]).fit(X)
    np.testing.assert_array_equal(fixed.transform(X[1:]), X[1:] - [19.0, 20.0])
    with pytest.raises(SelectionError, match="reference has 3 values"):
        RiseTransformer(reference=[1.0, 2.0, 3.0]).fit(X)


def test_splitter_trains_on_one_tests_on_others():
    groups = np.array(["a", "a", "b", "c", "c", "b"])
    splitter = TrainOnOneExperiment()
    splits = list(splitter.split(np.zeros((6, 1)), groups=groups))
    assert splitter.get_n_splits(groups=groups) == 3
    assert [(tr.tolist(), te.tolist()) for tr, te in splits] == [
        ([0, 1], [2, 3, 4, 5]), ([2, 5], [0, 1, 3, 4]), ([3, 4], [0, 1, 2, 5]),
    ]
    only_b = list(TrainOnOneExperiment(["b"]).split(groups=groups))
    assert len(only_b) == 1 and only_b[0][0].tolist() == [2, 5]
    with pytest.raises(SelectionError, match="needs 'groups'"):
        list(splitter.split(np.zeros((6, 1))))
    with pytest.raises(SelectionError, match="not among the groups"):
        TrainOnOneExperiment(["z"]).get_n_splits(groups=groups)


def test_splitter_in_cross_val_score():
    data, groups, _ = experiments()
    Xr = rises(data[SENSORS].to_numpy(), groups)
    pipe = Pipeline([("select", FuzzyClusterSelector(2)), ("regress", RiseRegressor())])
    scores = cross_val_score(pipe, Xr, data["drift_um"], groups=groups,
                             cv=TrainOnOneExperiment(), scoring="neg_root_mean_squared_error")
    assert scores.shape == (3,) and np.all(np.isfinite(scores))
