"""The sweep's methods: study-file labels, group:label specs, the six_diff group's
differences, and the per-slice ranking of every method (no simulation needed)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from conftest import REPO
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import SENSORS
from spindlebench.studies.family.family_file import load_study
from spindlebench.studies.family.methods import MethodSpec, method_specs, run_method
from spindlebench.studies.sweep.summary import Scored, rank_by_slice

TINY = REPO / "scenarios" / "studies" / "tiny_sweep.toml"


def _study(tmp_path, methods_lines: str):
    text = TINY.read_text(encoding="utf-8").replace("clusters = [2, 3]",
                                                    "clusters = [2, 3]\n" + methods_lines)
    path = tmp_path / "study.toml"
    path.write_text(text, encoding="utf-8")
    return load_study(path)


def test_methods_key_gives_group_label_specs(tmp_path):
    study = _study(tmp_path, 'methods = ["closure", "kmeans+grey", "lasso+ridge"]\nseed = 4')
    assert study.methods.methods == ("closure", "kmeans+grey", "lasso+ridge")
    names = [spec.name for spec in method_specs(study.methods)]
    assert names[:6] == ["all_raw", "all_raw", "all_raw:kmeans+grey", "all_raw:kmeans+grey",
                         "all_raw:lasso+ridge", "all_raw:lasso+ridge"]
    spec = next(s for s in method_specs(study.methods) if s.name == "six_diff:kmeans+grey")
    assert spec.group == "six_diff" and spec.choice.within == "grey" and spec.seed == 4
    assert MethodSpec("ridge", None).group is None
    everything = _study(tmp_path, 'methods = ["all"]').methods.methods
    assert everything[0] == "closure" and "exhaustive" in everything and len(everything) == 14
    assert "all-candidates" not in everything  # k does not apply to it


@pytest.mark.parametrize("line, message", [
    ('methods = ["knn"]', "key 'methods.methods': unknown method 'knn'"),
    ('methods = ["lasso+grey"]', "has no clusters"),
    ('methods = ["ward", "ward+psi+ols"]', "listed twice"),
    ("seed = -2", "seed"),
])
def test_bad_methods_are_one_line(tmp_path, line, message):
    with pytest.raises(SpindlebenchError, match=message):
        _study(tmp_path, line)


def _frame(seed: int, speed: float) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    t = np.arange(120) * 120.0
    ambient = 10 + 3 * t / t[-1]
    columns = {"time_s": t}
    for i, name in enumerate(SENSORS):
        columns[name] = ambient + speed * (0.2 + 0.1 * i) * (1 - np.exp(-t / (800 + 300 * i))) \
            + rng.normal(0, 0.02, t.size)
    columns["T10"] = ambient + rng.normal(0, 0.02, t.size)
    drift = 6 * (columns["T1"] - columns["T10"]) - 1.5 * (columns["T13"] - columns["T16"])
    columns["drift_um"] = drift - drift[0]
    columns["true_drift_rise_um"] = columns["drift_um"]
    return pd.DataFrame(columns)


def test_six_diff_selects_from_differences_and_methods_run():
    train = _frame(1, 1.0)
    tests = {"b": _frame(2, 0.6), "c": _frame(3, 1.3)}
    diff = run_method(MethodSpec("six_diff", 2), train, tests, "abs-pearson")
    assert any("-" in name for name in diff["b"].selected.split(";"))
    raw = run_method(MethodSpec("six_raw", 2), train, tests, "abs-pearson")
    assert not any("-" in name for name in raw["b"].selected.split(";"))
    for name in ("six_diff:ward+grey+pls", "all_raw:greedy", "six_diff:stability+ridge"):
        scores = run_method(MethodSpec(name, 2), train, tests, "abs-pearson")
        assert set(scores) == {"b", "c"}
        assert all(np.isfinite(s.rmse_um) and len(s.selected.split(";")) == 2
                   for s in scores.values())


def test_rank_by_slice_orders_every_method_by_median():
    rows = []
    for fault in ("none", "T1-stuck"):
        for method, k, values in (("six_diff", 2, [3.0, 5.0]), ("six_raw", 2, [1.0, 2.0]),
                                  ("ridge", None, [2.0, 2.0]), ("oracle", None, [0.1, 0.1])):
            worse = 4.0 if (fault == "T1-stuck" and method == "six_raw") else 0.0
            for i, value in enumerate(values):
                rows.append({"data": "measured", "method": method, "k": k,
                             "rmse_um": value + worse, "fault": fault, "noise": "lab",
                             "test_experiment": f"e{i}"})
    results = pd.DataFrame(rows)
    for axis in ("test_season", "test_month", "test_speed_rpm", "test_programme",
                 "test_cooling", "train_experiment"):
        results[axis] = "x"
    ranks = rank_by_slice(results)
    whole = ranks[ranks["axis"] == "all"].sort_values("rank")
    assert list(whole["method"]) == ["ridge", "six_raw", "six_diff"]  # medians 2, 3.5, 4
    stuck = ranks[(ranks["axis"] == "fault") & (ranks["value"] == "T1-stuck")]
    assert list(stuck.sort_values("rank")["method"]) == ["ridge", "six_diff", "six_raw"]
    none = ranks[(ranks["axis"] == "fault") & (ranks["value"] == "none")]
    assert list(none.sort_values("rank")["method"]) == ["six_raw", "ridge", "six_diff"]
    assert "oracle" not in set(ranks["method"]) and set(ranks["of"]) == {3}


def _old_scores(train, tests, spec, similarity="abs-pearson"):
    """What each method scored before the one pass: every method on its own copies of the
    frames, through the public ``evaluate`` or the baselines' frame-based formulas."""
    from sklearn.linear_model import Ridge
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from spindlebench.selection import PairwiseDifferences, correlation_with, evaluate, fit_ols
    from spindlebench.selection.regression import rises, rmse
    from spindlebench.selection.regressors import blocked_cv_alpha
    from spindlebench.studies.family.methods import GROUP_SENSORS, SIX_DIFF

    train = train.copy()
    tests = {name: frame.copy() for name, frame in tests.items()}

    def raw(frame):
        return rises(np.asfortranarray(frame.loc[:, list(SENSORS)].to_numpy(dtype=float)))

    def scored(frames, predictions):
        return {name: (rmse(frame["drift_um"].to_numpy(float), predictions[name]),
                       rmse(frame["true_drift_rise_um"].to_numpy(float), predictions[name]))
                for name, frame in frames.items()}

    y = train["drift_um"].to_numpy(float)
    if spec.group is not None:
        import warnings
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = evaluate(train, tests, "drift_um", sensors=list(GROUP_SENSORS[spec.group]),
                              k=spec.k, differences=spec.group == SIX_DIFF,
                              similarity=similarity, missing="drop-rows", method=spec.choice,
                              seed=spec.seed)
        kept = {name: frame.iloc[result.test_rows[name]] for name, frame in tests.items()}
        return scored(kept, result.predictions)
    if spec.name == "top-k-correlated":
        psi = np.nan_to_num(np.abs(correlation_with(raw(train), y)), nan=-1.0)
        chosen = np.argsort(-psi, kind="stable")[: spec.k]
        fit = fit_ols(raw(train)[:, chosen], y)
        return scored(tests, {n: fit.predict(raw(f)[:, chosen]) for n, f in tests.items()})
    if spec.name == "ridge":
        alpha = blocked_cv_alpha(PairwiseDifferences().fit(raw(train)).transform(raw(train)), y)
        model = make_pipeline(PairwiseDifferences(), StandardScaler(),
                              Ridge(alpha=alpha)).fit(raw(train), y)
        return scored(tests, {n: model.predict(raw(f)) for n, f in tests.items()})
    return scored(tests, {n: fit_ols(raw(f), f["drift_um"].to_numpy(float)).predict(raw(f))
                          for n, f in tests.items()})


def test_one_pass_scores_equal_each_method_on_its_own_frames(tmp_path):
    """score_all converts and checks the recordings once for every method and k: its scores
    are those of each method run alone on fresh frames, to the last bit; also with a test
    run that lost a sensor for good (NaN column) and one with a gap (NaN rows)."""
    from spindlebench.studies.family.methods import score_all

    study = _study(tmp_path, 'methods = ["closure", "kmeans+grey"]\n'
                             'baselines = ["top-k-correlated", "ridge"]\n'
                             'ground_truth = true\ngroups = ["all_raw", "six_raw", "six_diff"]')
    specs = method_specs(study.methods)
    assert {s.name for s in specs} >= {"six_diff", "ridge", "oracle", "top-k-correlated"}
    train = _frame(1, 1.0)
    gap, lost = _frame(4, 0.9), _frame(5, 1.1)
    gap.loc[30:33, "T6"] = np.nan
    lost["T13"] = np.nan
    tests = {"b": _frame(2, 0.6), "c": _frame(3, 1.3), "gap": gap, "lost": lost}
    rows = pd.DataFrame(score_all(specs, train, tests, "abs-pearson"))
    assert (rows["error"] != "").any() and (rows["error"] == "").any()  # both paths taken
    _assert_scores_as_before(rows, specs, train, tests)
    # complete runs only: ridge standardises them stacked (with "lost" it goes run by run)
    complete = {name: tests[name] for name in ("b", "c", "gap")}
    complete["gap"] = complete["gap"].ffill()
    rows = pd.DataFrame(score_all(specs, train, complete, "abs-pearson"))
    assert (rows["error"] == "").all()
    _assert_scores_as_before(rows, specs, train, complete)


def _assert_scores_as_before(rows, specs, train, tests):
    from spindlebench.core.console import one_line_error

    for spec in specs:
        mine = rows[(rows["method"] == spec.name)
                    & (rows["k"].fillna(-1) == (-1 if spec.k is None else spec.k))]
        try:
            old = _old_scores(train, tests, spec)
        except Exception as exc:  # the old path failed: the one pass records the same error
            assert set(mine["error"]) == {one_line_error(exc)}
            continue
        assert (mine["error"] == "").all(), spec
        for _, row in mine.iterrows():
            assert (row["rmse_um"], row["rmse_true_um"]) == old[row["test_experiment"]], spec


def test_ridge_candidates_are_the_transformers_to_the_bit_and_layout():
    """The ridge baseline's per-run candidates skip scikit-learn's validation: the same
    values and the same memory layout as ``PairwiseDifferences().fit(X).transform(X)`` (its
    products round by layout), for the column-major rises the sweep makes and others."""
    from spindlebench.selection import PairwiseDifferences
    from spindlebench.selection.differences import pairwise_differences
    from spindlebench.studies.family.methods import ridge_candidates

    rng = np.random.default_rng(7)
    raw = rng.normal(size=(181, 20)) * 5
    infinite = np.asfortranarray(raw[:, :5])
    infinite[3, 1], infinite[4, 2] = np.inf, -np.inf
    for X in (np.asfortranarray(raw - raw[0]), raw - raw[0], raw[:, :6],
              np.asfortranarray(raw[:, :2]), np.asfortranarray(raw[:, :1]), infinite):
        made = ridge_candidates(X)
        transformed = np.hstack([X, pairwise_differences(X)]) if X is infinite else \
            PairwiseDifferences().fit(X).transform(X)
        assert np.array_equal(made, transformed, equal_nan=True)
        assert made.tobytes("A") == transformed.tobytes("A")
        assert made.flags.c_contiguous == transformed.flags.c_contiguous
        assert made.flags.f_contiguous == transformed.flags.f_contiguous


def test_top_k_choice_of_each_k_is_the_first_k_of_the_ranking():
    """The top-k baseline selects all 20 once and takes the first k: the choice selecting
    k on its own makes, ties (equal |psi|) included; a constant sensor falls back to k."""
    import warnings

    from spindlebench.selection.registry import select_with
    from spindlebench.studies.family.methods import TOP_K, _top_k_ranking

    rng = np.random.default_rng(8)
    X = rng.normal(size=(60, 20)).cumsum(axis=0)
    X[:, 5], X[:, 11] = X[:, 2], -X[:, 2]  # ties in |psi|
    y = X[:, 2] + X[:, 7] + rng.normal(size=60)
    ranking = _top_k_ranking(X, y)
    for k in range(1, 21):
        assert select_with(TOP_K, X, y, k, names=SENSORS).selected.tolist() == \
            ranking[:k].tolist()
    X[:, 3] = 1.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert _top_k_ranking(X, y) is None


def test_scored_codes_and_labels_are_pandas_factorize_of_each_column():
    """Text columns are coded through their object array: the codes, labels (and their
    dtype), lookups and missing values (-1) of ``pd.factorize(column, sort=True)``, text that
    reads as "NA" or "None" and empty text included; other columns as they were."""
    results = pd.DataFrame({
        "method": pd.array(["ridge", "NA", None, "all_raw", "ridge", "", "None"], dtype="str"),
        "replica": [3, 1, 2, 1, 3, 2, 1],
        "test_speed_rpm": [2000.0, np.nan, 4000.0, 2000.0, np.nan, 4000.0, 2000.0],
        "rmse_um": [1.0, 2.0, np.nan, 3.0, 4.0, 5.0, 6.0]})
    scored = Scored(results)
    for column in ("method", "replica", "test_speed_rpm"):
        codes, labels = pd.factorize(results[column], sort=True)
        np.testing.assert_array_equal(scored.all_codes(column), codes)
        pd.testing.assert_index_equal(scored._labels[column], labels, exact=True)
        np.testing.assert_array_equal(scored.codes(column), codes[scored.ok])
        assert [scored.code(column, value) for value in labels] == list(range(len(labels)))
    assert scored.code("method", "absent") == -1 and scored.all_codes("method")[2] == -1
    assert [scored.label("method", code) for code in range(4)] == ["", "NA", "None", "all_raw"]



@pytest.mark.parametrize("run", [1, 3, 50])
def test_scored_codes_a_text_column_of_long_runs_as_pandas_factorize(run):
    """Runs of one value (coded once per run) or short runs (every cell coded), missing
    cells and text pandas would read as missing among them: ``pd.factorize``'s codes and
    labels on every row."""
    rng = np.random.default_rng(run)
    pool = np.array(["b", "NA", "a", "", "None", "é,\"q\"", "nan", None], dtype=object)
    cells = np.repeat(pool[rng.integers(0, len(pool), 400)], rng.integers(1, 2 * run, 400))
    results = pd.DataFrame({"method": pd.array(cells, dtype="str"),
                            "rmse_um": rng.normal(size=len(cells))})
    codes, labels = pd.factorize(results["method"], sort=True)
    scored = Scored(results)
    np.testing.assert_array_equal(scored.all_codes("method"), codes)
    pd.testing.assert_index_equal(scored._labels["method"], labels, exact=True)
    assert (codes == -1).any() and len(labels) == len(pool) - 1
