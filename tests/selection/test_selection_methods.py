"""The methods practitioners compare: clustering variants, grey grade, selection without
clusters, ridge/PLS; hand-computed small cases, scikit-learn estimator checks (their
doctests run in test_doctests.py)."""

import warnings

import numpy as np
import pytest
from selection_data import experiment_files, synthetic_experiment
from sklearn.pipeline import Pipeline
from sklearn.utils.estimator_checks import parametrize_with_checks
from spindlebench.selection import (
    SelectionError,
    SelectionWarning,
    clustering,
    rises,
)
from spindlebench.selection.clustering import (
    CLUSTERINGS,
    cluster_candidates,
    clusters_from_labels,
    hierarchical_labels,
)
from spindlebench.selection.estimators import RiseRegressor
from spindlebench.selection.grey import grey_relational_grade
from spindlebench.selection.registry import fit_regressor
from spindlebench.selection.regressors import (
    PLSRiseRegressor,
    RidgeRiseRegressor,
)
from spindlebench.selection.selectors import (
    ClusterSelector,
    GreedyForwardSelector,
    LassoPathSelector,
    StabilitySelector,
    TopCorrelatedSelector,
)

SIX = ["T1", "T6", "T8", "T10", "T13", "T16"]


@parametrize_with_checks(
    [ClusterSelector(), ClusterSelector(2, "fcm", "grey"), ClusterSelector(2, "kmeans"),
     ClusterSelector(2, "average"), ClusterSelector(2, "complete"), ClusterSelector(2, "ward"),
     ClusterSelector(2, "kmeans", "grey"), TopCorrelatedSelector(), LassoPathSelector(),
     LassoPathSelector(l1_ratio=0.5), StabilitySelector(n_subsamples=5),
     GreedyForwardSelector(), RidgeRiseRegressor(), PLSRiseRegressor()]
)
def test_sklearn_estimator_checks(estimator, check):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SelectionWarning)
        check(estimator)


def test_grey_grade_by_hand_interval():
    # y -> [0, .5, 1]; x1 == y; x2 = [0, 2, 2] -> [0, 1, 1]; x3 = [4, 2, 0] -> [1, .5, 0]
    y = np.array([0.0, 1.0, 2.0])
    X = np.column_stack([y, [0.0, 2.0, 2.0], [4.0, 2.0, 0.0]])
    # deltas: x1 [0, 0, 0], x2 [0, .5, 0], x3 [1, 0, 1]; min 0, max 1, rho 0.5
    # xi = 0.5 / (delta + 0.5): x2 [1, 1/2, 1] -> 5/6; x3 [1/3, 1, 1/3] -> 5/9
    np.testing.assert_allclose(grey_relational_grade(X, y), [1.0, 5 / 6, 5 / 9])
    # rho = 1: xi = 1 / (delta + 1): x2 [1, 2/3, 1] -> 8/9; x3 [1/2, 1, 1/2] -> 2/3
    np.testing.assert_allclose(grey_relational_grade(X, y, rho=1.0), [1.0, 8 / 9, 2 / 3])


def test_grey_grade_by_hand_mean():
    # y = [1, 2, 3] -> /2 -> [.5, 1, 1.5]; x = [2, 2, 2]+[0, 1, 2]... x2 = [1, 1, 4] -> /2 ->
    # [.5, .5, 2]; deltas x1 (== 2y -> same normalised) [0, 0, 0], x2 [0, .5, .5]
    y = np.array([1.0, 2.0, 3.0])
    X = np.column_stack([2 * y, [1.0, 1.0, 4.0]])
    # min 0, max .5; xi = .25 / (delta + .25): x2 [1, 1/3, 1/3] -> 5/9
    np.testing.assert_allclose(grey_relational_grade(X, y, "mean"), [1.0, 5 / 9])
    with pytest.raises(SelectionError, match="mean 0 in column 1"):
        grey_relational_grade(np.column_stack([y, [-1.0, 0.0, 1.0]]), y, "mean")
    with pytest.raises(SelectionError, match="rho must be"):
        grey_relational_grade(X, y, rho=0.0)
    with pytest.raises(SelectionError, match="unknown grey normalisation"):
        grey_relational_grade(X, y, "initial")


def test_hierarchical_linkages_by_hand():
    # Points on a line at 0, 1, 2.1, 3.3, 4.6 (gaps 1, 1.1, 1.2, 1.3). By hand:
    # single: merges 0-1 (1), +2 (1.1), +3 (1.2), +4 (1.3): a chain.
    # complete: 0-1 (1); then {01}-2 = 2.1, 2-3 = 1.2, 3-4 = 1.3 -> 2-3 (1.2); then
    #   {01}-{23} = 3.3, {23}-4 = 2.5, {01}-4 = 4.6 -> {23}+4 (2.5); last {01}+{234}.
    # average: 0-1 (1); {01}-2 = 1.6 -> 2-3 (1.2); {01}-{23} = 2.2, {23}-4 = 1.9 -> {234}.
    positions = np.array([0.0, 1.0, 2.1, 3.3, 4.6])
    D = np.abs(positions[:, None] - positions[None, :])

    def cut(method, k):
        return [c.tolist() for c in clusters_from_labels(hierarchical_labels(D, k, method))]

    assert cut("single", 2) == [[0, 1, 2, 3], [4]]
    assert cut("single", 3) == [[0, 1, 2], [3], [4]]
    for method in ("complete", "average"):
        assert cut(method, 2) == [[0, 1], [2, 3, 4]]
        assert cut(method, 3) == [[0, 1], [2, 3], [4]]


#: Five points on a line at 0, 1, 2.1, 3.3, 4.6 (the linkage case above), laid on an arc of
#: the unit circle (0.05 rad per unit) spanned by two centred orthonormal series: these are
#: the standardised candidates themselves, and their chords are the line's distances to 0.1 %.
LINE = np.array([0.0, 1.0, 2.1, 3.3, 4.6])


def _arc_candidates(n: int = 8) -> np.ndarray:
    e1 = np.tile([1.0, -1.0], n // 2)
    e2 = np.repeat([1.0, -1.0], n // 2)
    angle = 0.05 * LINE
    return np.outer(e1 / np.linalg.norm(e1), np.cos(angle)) + \
        np.outer(e2 / np.linalg.norm(e2), np.sin(angle))


def test_ward_and_kmeans_by_hand():
    # Ward (SciPy's distance sqrt(2 |A||B| / (|A| + |B|)) |cA - cB|) on 0, 1, 2.1, 3.3, 4.6:
    # 0-1 (1); {01}-2 = sqrt(4/3) 1.6 = 1.85, 2-3 = 1.2, 3-4 = 1.3 -> 2-3; then
    # {01}-{23} = sqrt(2) 2.2 = 3.11, {23}-4 = sqrt(4/3) 1.9 = 2.19 -> {234}: k = 2 is
    # {01}{234}, k = 3 {01}{23}{4}. k-means minimises the within sum of squares over the four
    # splits of a line: {0}{1234} 7.21, {01}{234} 3.63, {012}{34} 3.05, {0123}{4} 6.06 ->
    # {012}{34}, not Ward's merge. The closure (single linkage) chains: {0123}{4}.
    X = _arc_candidates()
    assert [c.tolist() for c in cluster_candidates(X, 2, "ward")] == [[0, 1], [2, 3, 4]]
    assert [c.tolist() for c in cluster_candidates(X, 3, "ward")] == [[0, 1], [2, 3], [4]]
    assert [c.tolist() for c in cluster_candidates(X, 2, "kmeans")] == [[0, 1, 2], [3, 4]]
    assert [c.tolist() for c in cluster_candidates(X, 2, "closure")] == [[0, 1, 2, 3], [4]]


def test_fcm_memberships_are_the_fixed_point_by_hand():
    # Fuzzy c-means with m = 2 on the arc: centres v_j = sum u_ij^2 x_i / sum u_ij^2 and
    # memberships u_ij = 1 / sum_l (d_ij / d_il)^2, iterated here from a split start until
    # they stop changing; scikit-fuzzy's cmeans must reach the same fixed point.
    X = _arc_candidates()
    points = X.T
    u = np.array([[1.0, 1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 1.0, 1.0]])
    for _ in range(500):
        v = (u**2 @ points) / (u**2).sum(axis=1, keepdims=True)
        d = np.linalg.norm(points[None, :, :] - v[:, None, :], axis=2)
        u = 1.0 / ((d[:, None, :] / d[None, :, :]) ** 2).sum(axis=1)
    found = clustering.fcm_memberships(points, 2, random_state=0)
    order = np.argsort(found[:, 0])[::-1]  # cluster of point 0 first, as u above
    np.testing.assert_allclose(found[order], u, atol=1e-4)
    # the point at 2.1 leans left (membership 0.64), as in k-means' split
    assert u[0].round(2).tolist() == [0.96, 1.0, 0.64, 0.04, 0.04]
    assert [c.tolist() for c in cluster_candidates(X, 2, "fcm")] == [[0, 1, 2], [3, 4]]


def _two_families(n: int = 60) -> np.ndarray:
    t = np.linspace(0.0, 1.0, n)
    return np.column_stack([t, t + 0.02 * t**2, np.sin(9 * t), np.sin(9 * t) + 0.05 * t,
                            t + 0.01 * np.cos(3 * t)])


@pytest.mark.parametrize("method", CLUSTERINGS)
def test_every_clustering_finds_two_obvious_families(method):
    clusters = cluster_candidates(_two_families(), 2, method)
    assert [c.tolist() for c in clusters] == [[0, 1, 4], [2, 3]]


def test_kmeans_and_ward_keep_the_sign_closure_does_not():
    # a series and its mirror image: |r| = 1 (same cluster for the closure and the linkages
    # on 1 - R), but opposite points for k-means, fcm and Ward
    t = np.linspace(0.0, 1.0, 40)
    X = np.column_stack([t, -t + 1e-3 * t**2, np.sin(7 * t)])
    assert [c.tolist() for c in cluster_candidates(X, 2, "closure")] == [[0, 1], [2]]
    assert [c.tolist() for c in cluster_candidates(X, 2, "average")] == [[0, 1], [2]]
    for method in ("kmeans", "ward", "fcm"):
        clusters = cluster_candidates(X, 2, method)
        assert not any({0, 1} <= set(c.tolist()) for c in clusters), method


def test_fcm_and_kmeans_are_seeded():
    X = np.random.default_rng(3).normal(size=(30, 12)).cumsum(axis=0)
    for method in ("fcm", "kmeans"):
        first = cluster_candidates(X, 3, method, random_state=7)
        again = cluster_candidates(X, 3, method, random_state=7)
        assert [c.tolist() for c in first] == [c.tolist() for c in again]


def test_cluster_selector_grey_and_psi_choices():
    data = synthetic_experiment(0)
    X = rises(data[SIX].to_numpy())
    y = data["drift_um"].to_numpy()
    psi = ClusterSelector(3).fit(X, y)
    grey_choice = ClusterSelector(3, within="grey").fit(X, y)
    assert [c.tolist() for c in psi.clusters_] == [c.tolist() for c in grey_choice.clusters_]
    for members, chosen in zip(grey_choice.clusters_, grey_choice.selected_, strict=True):
        grades = grey_relational_grade(X[:, members], y)
        assert chosen == members[int(np.argmax(grades))]
    np.testing.assert_allclose(psi.scores_, np.abs(psi.psi_))


def test_cluster_selector_drops_constant_columns_with_a_warning():
    X = _two_families()
    X = np.column_stack([X, np.full(X.shape[0], 3.0)])
    with pytest.warns(SelectionWarning, match="constant candidate"):
        selector = ClusterSelector(2, "kmeans").fit(X, X[:, 0] + X[:, 2])
    assert 5 not in selector.selected_ and np.isnan(selector.psi_[5])


def test_lasso_and_greedy_find_the_drivers():
    rng = np.random.default_rng(1)
    X = rng.normal(size=(120, 8))  # independent inputs: the path's first two are the drivers
    y = 2.0 * X[:, 3] - 1.0 * X[:, 6] + 0.05 * rng.normal(size=120)
    assert sorted(LassoPathSelector(2).fit(X, y).selected_.tolist()) == [3, 6]
    assert sorted(LassoPathSelector(2, l1_ratio=0.5).fit(X, y).selected_.tolist()) == [3, 6]
    assert sorted(StabilitySelector(2, n_subsamples=20).fit(X, y).selected_.tolist()) == [3, 6]
    greedy = GreedyForwardSelector(2).fit(X, y)
    assert sorted(greedy.selected_.tolist()) == [3, 6]
    assert greedy.scores_[1] < greedy.scores_[0]


def test_greedy_with_groups_scores_on_the_other_experiments():
    rng = np.random.default_rng(2)
    X = rng.normal(size=(90, 5)).cumsum(axis=0)
    y = X[:, 1] + 0.01 * rng.normal(size=90)
    groups = np.repeat(["a", "b", "c"], 30)
    chosen = GreedyForwardSelector(1).fit(X, y, groups=groups).selected_.tolist()
    assert chosen == [1]
    with pytest.raises(SelectionError, match="at least 2 experiments"):
        GreedyForwardSelector(1).fit(X, y, groups=np.repeat("a", 90))


def test_stability_frequencies_are_fractions():
    rng = np.random.default_rng(4)
    X = rng.normal(size=(60, 6))
    y = X[:, 0] + 0.5 * rng.normal(size=60)
    model = StabilitySelector(1, n_subsamples=10, random_state=3).fit(X, y)
    assert model.frequency_.sum() == pytest.approx(1.0)
    assert model.frequency_[0] == model.frequency_.max()


def test_budget_larger_than_candidates_is_one_line():
    X = _two_families()
    for selector in (ClusterSelector(9), LassoPathSelector(9), GreedyForwardSelector(9)):
        with pytest.raises(SelectionError, match="from 5 feature"):
            selector.fit(X, X[:, 0])


def test_regressors_report_coefficients_in_input_units():
    data = synthetic_experiment(1)
    X = rises(data[SIX].to_numpy())
    y = data["drift_um"].to_numpy()
    for model in (RidgeRiseRegressor(), PLSRiseRegressor(3), RiseRegressor()):
        model.fit(X, y)
        np.testing.assert_allclose(model.predict(X), model.intercept_ + X @ model.coef_,
                                   atol=1e-9)
        assert model.r2_ > 0.95
    assert PLSRiseRegressor(9).fit(X[:, :2], y).n_components_ == 2


@pytest.mark.parametrize("selector", [ClusterSelector(2, "ward", "grey"),
                                      LassoPathSelector(2), GreedyForwardSelector(2)])
@pytest.mark.parametrize("regressor", [RiseRegressor(), RidgeRiseRegressor(),
                                       PLSRiseRegressor()])
def test_every_selector_composes_with_every_regressor(selector, regressor):
    data = synthetic_experiment(2)
    X = rises(data[SIX].to_numpy())
    y = data["drift_um"].to_numpy()
    model = Pipeline([("select", selector), ("regress", regressor)]).fit(X, y)
    assert model.predict(X).shape == y.shape
    assert model[:-1].get_feature_names_out(SIX).size == 2


# --- the registry, evaluate --method and spindlebench methods --------------------------------

def test_method_labels_round_trip_and_refuse_nonsense():
    from spindlebench.core.names import REGRESSORS
    from spindlebench.selection.method_registry import METHOD_REGISTRY as METHODS
    from spindlebench.selection.registry import MethodChoice, parse_method

    for method in METHODS:
        for regressor in REGRESSORS:
            choice = MethodChoice(method, "psi", regressor)
            assert parse_method(choice.label) == choice
    assert parse_method("closure").is_paper and parse_method("closure").label == "closure"
    assert parse_method("ward+grey+pls") == MethodChoice("ward", "grey", "pls")
    for bad, message in (("lasso+grey", "has no clusters"), ("kmeans+pls+grey", "out of order"),
                         ("knn", "unknown method"), ("closure+ols+ols", "twice")):
        with pytest.raises(SelectionError, match=message):
            parse_method(bad)


def test_evaluate_every_method_against_a_pipeline(tmp_path):
    """``evaluate`` with any method gives what the registry's Pipeline gives on rises."""
    from spindlebench.selection import evaluate
    from spindlebench.selection.registry import MethodChoice, make_pipeline

    train, *tests = (synthetic_experiment(s, speed=0.5 + 0.4 * s) for s in range(3))
    for choice in (MethodChoice("kmeans", "grey", "ridge"), MethodChoice("lasso", "psi", "pls"),
                   MethodChoice("ward"), MethodChoice("greedy")):
        result = evaluate(train, {"b": tests[0], "c": tests[1]}, "drift_um", sensors=SIX, k=2,
                          differences=True, method=choice)
        model = make_pipeline(choice, 2, differences=True)
        model.fit(rises(train[SIX].to_numpy()), train["drift_um"].to_numpy())
        assert sorted(model[:-1].get_feature_names_out(SIX)) == sorted(result.selected)
        predicted = model.predict(rises(tests[0][SIX].to_numpy()))
        np.testing.assert_allclose(predicted, result.predictions["b"], rtol=1e-9, atol=1e-9)
        assert result.to_dict()["method"]["label"] == choice.label


def test_cli_evaluate_method_within_regressor(tmp_path, capsys):
    import json

    from spindlebench.commands import main as cli

    train, *tests = experiment_files(tmp_path)
    out = tmp_path / "r.json"
    status = cli.main(["evaluate", "--train", str(train), "--test", *map(str, tests),
                       "--target", "drift_um", "--clusters", "2", "--differences",
                       "--method", "fcm", "--within", "grey", "--regressor", "pls",
                       "--seed", "5", "--json", str(out)])
    printed, err = capsys.readouterr()
    assert status == 0, err
    assert "method: fcm+grey+pls (seed 5)" in printed
    record = json.loads(out.read_text())
    assert record["method"] == {"method": "fcm", "within": "grey", "regressor": "pls",
                                "label": "fcm+grey+pls", "seed": 5}
    assert record["provenance"]["method"]["method"] == "fcm" and record["eta"] is None
    status = cli.main(["evaluate", "--train", str(train), "--test", str(tests[0]),
                       "--target", "drift_um", "--clusters", "2", "--method", "lasso",
                       "--within", "grey"])
    assert status == 2
    assert "has no clusters" in capsys.readouterr().err


def test_cli_methods_lists_every_name(capsys):
    from spindlebench.commands import main as cli
    from spindlebench.core.names import REGRESSORS, WITHIN
    from spindlebench.selection.method_registry import METHOD_REGISTRY as METHODS

    assert cli.main(["methods"]) == 0
    printed = capsys.readouterr().out
    for name in (*METHODS, *WITHIN, *REGRESSORS):
        assert f"  {name} " in printed


ALL_SELECTORS = [ClusterSelector, TopCorrelatedSelector, LassoPathSelector, StabilitySelector,
                 GreedyForwardSelector]


@pytest.mark.parametrize("cls", ALL_SELECTORS)
def test_every_selector_takes_k_and_its_old_name_warns(cls):
    """One budget name, ``k``, spans every selector; the old name still works (warned)."""
    from spindlebench.selection.estimators import FuzzyClusterSelector

    X, y = _two_drivers()
    new = cls(k=2).fit(X, y)
    old_name = "n_clusters" if cls in (ClusterSelector, FuzzyClusterSelector) else \
        "n_features_to_select"
    with pytest.warns(FutureWarning, match=f"'{old_name}' is deprecated"):
        old = cls(**{old_name: 2}).fit(X, y)
    assert new.selected_.tolist() == old.selected_.tolist() and len(new.selected_) == 2
    assert "k" in cls().get_params()


def test_fuzzy_cluster_selector_alias_and_one_grid_over_methods():
    from sklearn.model_selection import GridSearchCV
    from spindlebench.selection.estimators import FuzzyClusterSelector

    X, y = _two_drivers()
    with pytest.warns(FutureWarning, match="'n_clusters' is deprecated"):
        old = FuzzyClusterSelector(n_clusters=2).fit(X, y)
    assert old.selected_.tolist() == FuzzyClusterSelector(k=2).fit(X, y).selected_.tolist()
    pipe = Pipeline([("select", TopCorrelatedSelector()), ("regress", RiseRegressor())])
    grid = GridSearchCV(pipe, [{"select": [cls() for cls in ALL_SELECTORS[:3]],
                                "select__k": [1, 2]}], cv=2).fit(X, y)
    assert grid.best_params_["select__k"] in (1, 2)


def _two_drivers():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(80, 5)).cumsum(axis=0)
    return X, 3 * X[:, 2] - 2 * X[:, 4] + 0.1 * rng.normal(size=80)


@pytest.mark.parametrize("make", [lambda rs: ClusterSelector(2, "fcm", random_state=rs),
                                  lambda rs: ClusterSelector(2, "kmeans", random_state=rs),
                                  lambda rs: StabilitySelector(2, n_subsamples=5,
                                                               random_state=rs)])
def test_random_state_none_int_generator_and_global_rng_untouched(make):
    X, y = _two_drivers()
    np.random.seed(123)
    before = np.random.get_state()
    by_int = make(5).fit(X, y).selected_.tolist()
    assert make(5).fit(X, y).selected_.tolist() == by_int
    make(None).fit(X, y)
    gen_a = make(np.random.default_rng(9)).fit(X, y).selected_.tolist()
    gen_b = make(np.random.default_rng(9)).fit(X, y).selected_.tolist()
    assert gen_a == gen_b
    after = np.random.get_state()
    # never reseeded, never drawn from
    assert after[1].tolist() == before[1].tolist() and after[2] == before[2]
    with pytest.raises(ValueError):
        make("seven").fit(X, y)


def test_fcm_start_is_what_cmeans_seed_draws():
    """``fcm_init`` reproduces cmeans(seed=s)'s start, so int seeds keep their results."""
    from skfuzzy.cluster import cmeans
    from spindlebench.selection.randomness import fcm_init

    data = np.random.default_rng(0).normal(size=(4, 30))
    state = np.random.get_state()
    by_seed = cmeans(data, 3, 2.0, error=1e-6, maxiter=50, seed=11)[1]
    np.random.set_state(state)
    by_init = cmeans(data, 3, 2.0, error=1e-6, maxiter=50, init=fcm_init(3, 30, 11))[1]
    np.testing.assert_array_equal(by_seed, by_init)


# --- issue 23: GA over clusters, mutual information, mRMR, gradient boosting, MLP ----------
from spindlebench.selection import genetic  # noqa: E402
from spindlebench.selection.information import MRMRSelector, MutualInfoSelector  # noqa: E402
from spindlebench.selection.nonlinear import (  # noqa: E402
    BoostedRiseRegressor,
    MLPRiseRegressor,
)
from spindlebench.selection.selectors import AllCandidates  # noqa: E402


@parametrize_with_checks(
    [ClusterSelector(2, "kmeans", "ga", population=6, generations=3), MutualInfoSelector(),
     MRMRSelector(), AllCandidates(), BoostedRiseRegressor(n_estimators=10),
     MLPRiseRegressor(max_iter=200)]
)
def test_sklearn_estimator_checks_of_the_new_methods(estimator, check):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SelectionWarning)
        check(estimator)


def _ga_case():
    """Two clusters of near copies; the error is exactly 2*a2 - 3*b1 on the second half, so
    OLS on (a2, b1) trained on the first half predicts the second half exactly (RMSE 0) while
    every other pair of members leaves an error: the one best combination, by hand."""
    t = np.linspace(0, 1, 80)
    a = [t, t + 0.05 * np.sin(7 * t), t + 0.05 * np.cos(5 * t)]
    b = [np.sin(3 * t) + 0.05 * t**2, np.sin(3 * t), np.sin(3 * t) + 0.05 * np.sqrt(t)]
    X = np.column_stack(a + b)
    return X, 2 * X[:, 1] - 3 * X[:, 4]


def test_genetic_choice_finds_the_exact_combination_and_is_seeded():
    X, y = _ga_case()
    clusters = [np.array([0, 1, 2]), np.array([3, 4, 5])]
    columns, score = genetic.genetic_choice(X, y, clusters, [0, 3], random_state=1,
                                            population=4, generations=15)
    assert columns.tolist() == [1, 4] and score == pytest.approx(0.0, abs=1e-9)
    # the hand value of one other combination: OLS of y on (a1, b1) on the first half
    train, valid = genetic.blocks(X, y)
    from spindlebench.selection.forward import validation_score

    assert validation_score(train, valid, [0, 3]) > 1e-3
    again = genetic.genetic_choice(X, y, clusters, [0, 3], random_state=1, population=4,
                                   generations=15)
    assert again[0].tolist() == columns.tolist()
    # the selector: same clusters as kmeans finds, the GA's members
    selector = ClusterSelector(2, "kmeans", "ga", population=4, generations=15).fit(X, y)
    assert sorted(selector.selected_.tolist()) == [1, 4]


def test_mutual_information_sees_a_nonlinear_driver_correlation_misses():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(400, 3))
    y = X[:, 0] ** 2  # Pearson r with X0 is ~0: top-k-correlated cannot see it
    assert MutualInfoSelector(1).fit(X, y).selected_.tolist() == [0]
    scores = MutualInfoSelector(3).fit(X, y).scores_
    assert scores[0] > 0.5 and max(scores[1:]) < 0.1  # nats: independent columns near 0


def test_mrmr_by_hand_redundancy():
    """Relevance minus mean redundancy, computed here from mutual_info_regression itself."""
    from sklearn.feature_selection import mutual_info_regression

    rng = np.random.default_rng(1)
    a, b = rng.normal(size=(2, 300))
    X = np.column_stack([a, a + 0.01 * rng.normal(size=300), b])
    y = a + 0.7 * b
    selector = MRMRSelector(2).fit(X, y)
    relevance = mutual_info_regression(X, y, n_neighbors=3, random_state=0)
    np.testing.assert_allclose(selector.relevance_, relevance)
    first = int(np.argmax(relevance))
    assert first in (0, 1) and selector.selected_.tolist() == [first, 2]
    rest = [i for i in range(3) if i != first]
    redundancy = mutual_info_regression(X[:, rest], X[:, first], n_neighbors=3, random_state=0)
    assert selector.scores_[1] == pytest.approx(max(relevance[rest] - redundancy))
    assert (relevance[rest] - redundancy)[rest.index(2)] > (relevance[rest] - redundancy)[0]


def test_boosting_stump_and_mlp_identity_by_hand():
    X = np.array([[0.0], [1.0], [2.0], [3.0], [4.0]])
    y = np.array([1.0, 1.0, 1.0, 6.0, 6.0])
    stump = BoostedRiseRegressor(1, max_depth=1, learning_rate=1.0).fit(X, y)
    # by hand: the best split is between 2 and 3; the leaves are the two means
    np.testing.assert_allclose(stump.predict([[-5.0], [2.4], [2.6], [99.0]]), [1, 1, 6, 6])
    assert stump.r2_ == pytest.approx(1.0)
    lin = np.linspace(0, 5, 40)[:, None] * [1.0, 0.3] + [[0.0, 0.0]]
    lin[:, 1] += np.sin(lin[:, 0])
    target = 2.0 * lin[:, 0] - 1.5 * lin[:, 1] + 4.0
    net = MLPRiseRegressor(activation="identity", alpha=0.0, max_iter=2000).fit(lin, target)
    np.testing.assert_allclose(net.predict(lin), target, atol=1e-3)


def test_new_labels_run_through_evaluate(tmp_path):
    from spindlebench.selection import evaluate

    files = experiment_files(tmp_path)
    for label in ("kmeans+ga", "mi", "mrmr+gbr", "all-candidates+mlp", "all-candidates"):
        result = evaluate(files[0], files[1:], "drift_um", SIX, k=2, method=parse_label(label))
        assert np.isfinite(result.mean_rmse_um)
        expected = 2 if not label.startswith("all-candidates") else len(SIX)
        assert len(result.selected) == expected
        record = result.to_dict()
        assert (record["coefficients"] is None) == (label in ("mrmr+gbr", "all-candidates+mlp"))


def parse_label(label):
    from spindlebench.selection.registry import parse_method

    return parse_method(label)


def test_a_ridge_fit_reports_its_penalty_and_ols_none():
    """Issue 25: the penalty (and whether it sits at its grid's edge) goes into the JSON."""
    rng = np.random.default_rng(3)
    X = rng.normal(size=(60, 3))
    y = X @ [2.0, -1.0, 0.5] + 0.5 * rng.normal(size=60)
    fit = fit_regressor("ridge", X, y)
    assert fit.penalty["alpha"] > 0 and set(fit.penalty) == {"alpha", "grid", "at_edge"}
    assert fit_regressor("ols", X, y).penalty is None


# --- issue 23: exhaustive search outside place -------------------------------------------
from spindlebench.selection.selectors import ExhaustiveSelector  # noqa: E402


@parametrize_with_checks([ExhaustiveSelector()])
def test_sklearn_estimator_checks_of_exhaustive(estimator, check):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SelectionWarning)
        check(estimator)


def _pair_case():
    """y = a + b exactly; c = a + b + a wiggle is the best single predictor, so greedy takes
    c first and no pair containing c is exact; (a, b) fits every half exactly."""
    t = np.linspace(0, 1, 80)
    a, b, d = t, np.sin(4 * t), np.cos(2 * t) * t
    c = a + b + 0.2 * np.cos(9 * t)
    return np.column_stack([a, d, b, c]), a + b


def test_exhaustive_by_hand_beats_greedy_and_equals_brute_force():
    import itertools

    from spindlebench.selection.forward import validation_score
    from spindlebench.selection.selectors import _validation_blocks

    X, y = _pair_case()
    chosen = ExhaustiveSelector(2).fit(X, y)
    assert chosen.selected_.tolist() == [0, 2]
    assert chosen.score_ == pytest.approx(0.0, abs=1e-9) and chosen.n_combinations_ == 6
    # by hand: every pair refitted with one plain OLS on the first half, scored on the second
    train, valid = _validation_blocks(X, y, None, 2, 2, "test")
    scores = {pair: validation_score(train, valid, pair)
              for pair in itertools.combinations(range(4), 2)}
    assert min(scores, key=scores.get) == (0, 2)
    assert sorted(scores.values())[1] > 1e-3  # the runner-up leaves an error
    greedy = GreedyForwardSelector(2).fit(X, y).selected_.tolist()
    assert greedy[0] == 3 and scores[tuple(sorted(greedy))] > 1e-3


def test_exhaustive_refuses_above_its_combination_budget_in_one_line():
    X, y = _pair_case()
    with pytest.raises(SelectionError, match=r"C\(4, 2\) = 6 subsets, more than "
                                             r"max_combinations = 5"):
        ExhaustiveSelector(2, max_combinations=5).fit(X, y)
    assert ExhaustiveSelector(2, max_combinations=6).fit(X, y).selected_.tolist() == [0, 2]


def test_exhaustive_is_registered_once_and_runs_through_evaluate(tmp_path):
    from spindlebench.selection import evaluate
    from spindlebench.selection.method_registry import METHOD_REGISTRY

    entry = METHOD_REGISTRY["exhaustive"]
    assert entry.budget and not entry.seeded and not entry.clustered
    files = experiment_files(tmp_path)
    result = evaluate(files[0], files[1:], "drift_um", SIX, k=2, method=parse_label("exhaustive"))
    import pandas as pd

    train = pd.read_csv(files[0])
    rises = train[SIX].to_numpy(float) - train[SIX].to_numpy(float)[0]
    by_hand = ExhaustiveSelector(2).fit(rises, train["drift_um"].to_numpy(float))
    assert result.selected == [SIX[i] for i in by_hand.selected_]
