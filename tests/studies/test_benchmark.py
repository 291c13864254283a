"""spindlebench benchmark (issue 23): suite identity, baselines, leaderboard numbers equal to
evaluate's, and a user's method by import path."""

from __future__ import annotations

import hashlib
import json
import sys

import numpy as np
import pandas as pd
import pytest
from conftest import REPO
from selection_data import experiment_files
from spindlebench.commands.main import main
from spindlebench.core.errors import SpindlebenchError
from spindlebench.selection import evaluate
from spindlebench.studies.benchmark import benchmark_report as leaderboard
from spindlebench.studies.benchmark import scoring
from spindlebench.studies.benchmark.benchmark_file import load_suite
from spindlebench.studies.benchmark.tasks import build_tasks

USER_METHOD_DIR = REPO / "docs" / "examples" / "user-method"
TINY_STUDY = """\
[study]
name = "tiny-benchmark"
seed = 5
replicas = 2
climate = "chongqing"

[experiment]
duration_min = 40
step_s = 120.0
sample_interval_s = 120.0

[axes]
months = ["Jan", "Jul"]
speeds_rpm = [2000, 4000]
noise = ["lab"]
faults = ["none"]

[noise.lab]
noise_C = 0.05

[training]
month = "Jan"
speed_rpm = 4000
"""
SUITE = """\
[suite]
name = "tiny"
version = "0.1"
k = 2
seed = 0
methods = ["closure", "kmeans+grey", "lasso+ridge", "mrmr+gbr"]

[[task]]
name = "synthetic"
kind = "synthetic"
study = "tiny-study.toml"
"""


@pytest.fixture(scope="module")
def tiny_suite(tmp_path_factory):
    folder = tmp_path_factory.mktemp("suite")
    (folder / "tiny-study.toml").write_text(TINY_STUDY)
    (folder / "tiny.toml").write_text(SUITE)
    return folder / "tiny.toml"


@pytest.fixture(scope="module")
def board(tiny_suite, tmp_path_factory):
    """The tiny suite plus the user's recordings and the example user method, run once."""
    out = tmp_path_factory.mktemp("board")
    files = experiment_files(tmp_path_factory.mktemp("own"))
    sys.path.insert(0, str(USER_METHOD_DIR))
    try:
        status = main(["benchmark", str(tiny_suite), "--method", "my_selector:DecorrelatedSelector",
                       "--recordings", *map(str, files), "--sensors", "T1", "T6", "T8", "T10",
                       "T13", "T16", "-o", str(out)])
    finally:
        sys.path.remove(str(USER_METHOD_DIR))
    assert status == 0
    return out, files


def test_leaderboard_files_and_suite_identity(board, tiny_suite):
    out, _ = board
    for name in ("leaderboard.md", "leaderboard.csv", "folds.csv", "leaderboard.json",
                 "leaderboard.png"):
        assert (out / name).stat().st_size > 0
    record = json.loads((out / "leaderboard.json").read_text())
    suite = load_suite(tiny_suite)
    assert record["suite"]["version"] == "0.1"
    assert record["suite"]["tasks_sha256"] == suite.tasks_sha256
    assert suite.tasks_sha256 in (out / "leaderboard.md").read_text()
    frame = pd.read_csv(out / "leaderboard.csv")
    tasks = set(frame["task"])
    assert tasks == {"synthetic/default/lab+none", "own"}
    for task in tasks:  # the three baselines are always in, every entrant ranked
        methods = set(frame.loc[frame["task"] == task, "method"])
        assert set(scoring.BASELINES) <= methods
        assert "my_selector:DecorrelatedSelector" in methods
    assert frame["error"].isna().all()


def test_leaderboard_md_tables_are_those_the_docs_make_from_leaderboard_json(board):
    """docs/benchmark.md's tables are rendered from leaderboard.json (docs/hooks/tables.py)
    by the same functions that write leaderboard.md: the two agree table for table."""
    out, _ = board
    record = json.loads((out / "leaderboard.json").read_text())
    text = (out / "leaderboard.md").read_text()
    assert leaderboard.overall_table(record["overall"]) in text
    tasks = leaderboard.tasks_of(record["rows"])
    assert tasks == list(dict.fromkeys(pd.read_csv(out / "leaderboard.csv")["task"]))
    for task in tasks:
        assert f"## {task}\n\n" + leaderboard.task_table(record["rows"], task,
                                                     record["suite"]["band_um"]) in text
    assert record["provenance"]["command"].startswith("spindlebench benchmark")


def test_leaderboard_numbers_equal_evaluate(board, tiny_suite):
    """The test the issue asks for: a built-in method's leaderboard RMSE is the mean over
    folds of what evaluate gives on the same recordings."""
    out, files = board
    frame = pd.read_csv(out / "leaderboard.csv").set_index(["task", "method"])
    suite = load_suite(tiny_suite)
    (task,) = build_tasks(suite.tasks[0])
    for label in suite.methods:
        by_evaluate = np.mean([evaluate(fold.train, fold.tests, task.target, list(task.sensors),
                                        k=suite.k, method=_choice(label),
                                        seed=suite.seed).mean_rmse_um for fold in task.folds])
        assert frame.loc[(task.name, label), "rmse_um"] == by_evaluate, label
    six = ["T1", "T6", "T8", "T10", "T13", "T16"]
    for label in suite.methods:  # the user's recordings, evaluate reading the files itself
        folds = [evaluate(train, [f for f in files if f != train], "drift_um", six, k=suite.k,
                          method=_choice(label)).mean_rmse_um for train in files]
        assert frame.loc[("own", label), "rmse_um"] == pytest.approx(np.mean(folds),
                                                                     rel=1e-12), label


def test_baselines_by_hand(board):
    out, files = board
    frame = pd.read_csv(out / "leaderboard.csv").set_index(["task", "method"])
    runs = [pd.read_csv(f) for f in files]
    constant, replay = [], []
    for i, train in enumerate(runs):
        tests = [r for j, r in enumerate(runs) if j != i]
        y0 = train["drift_um"].to_numpy()
        constant.append(np.mean([np.sqrt(np.mean((t["drift_um"] - y0.mean()) ** 2))
                                 for t in tests]))
        replay.append(np.mean([np.sqrt(np.mean((t["drift_um"] - np.interp(
            t["time_s"], train["time_s"], y0)) ** 2)) for t in tests]))
    assert frame.loc[("own", "baseline:constant"), "rmse_um"] == pytest.approx(np.mean(constant))
    assert frame.loc[("own", "baseline:replay"), "rmse_um"] == pytest.approx(np.mean(replay))
    # OLS on all sensors reads all six; a baseline reads no sensor and is never marked
    assert frame.loc[("own", "baseline:ols-all"), "n_sensors"] == 6
    assert frame.loc[("own", "baseline:constant"), "n_sensors"] == 0


def test_worse_than_a_baseline_is_marked(board):
    out, _ = board
    frame = pd.read_csv(out / "leaderboard.csv", keep_default_na=False)
    for _, part in frame.groupby("task"):
        base = part.set_index("method").loc[list(scoring.BASELINES), "rmse_um"].astype(float)
        for row in part.itertuples():
            if row.method in scoring.BASELINES:
                assert row.worse_than == ""
                continue
            expected = [b for b in scoring.BASELINES if float(row.rmse_um) > base[b]]
            assert (row.worse_than.split(";") if row.worse_than else []) == expected


def test_user_method_provenance(board):
    out, _ = board
    record = json.loads((out / "leaderboard.json").read_text())
    code = record["provenance"]["entrants"]["my_selector:DecorrelatedSelector"]["code"][0]
    source = USER_METHOD_DIR / "my_selector.py"
    assert code["source_sha256"] == hashlib.sha256(source.read_bytes()).hexdigest()
    assert code["module"] == "my_selector" and code["path"] == "my_selector:DecorrelatedSelector"


def test_user_method_in_evaluate_with_params(tmp_path, monkeypatch, capsys):
    monkeypatch.syspath_prepend(str(USER_METHOD_DIR))
    files = experiment_files(tmp_path)
    out = tmp_path / "r.json"
    status = main(["evaluate", "--train", str(files[0]), "--test", *map(str, files[1:]),
                   "--target", "drift_um", "--clusters", "2",
                   "--method", "my_selector:DecorrelatedSelector+ridge",
                   "--method-param", "max_overlap=0.9", "--json", str(out)])
    assert status == 0
    record = json.loads(out.read_text())
    assert record["method"]["method"] == "my_selector:DecorrelatedSelector[max_overlap=0.9]"
    assert record["method"]["code"][0]["params"] == {"max_overlap": 0.9}
    assert len(record["selected"]) == 2
    # a regressor in the method's place is one line, not a traceback
    assert main(["evaluate", "--train", str(files[0]), "--test", str(files[1]),
                 "--target", "drift_um", "--clusters", "2",
                 "--method", "sklearn.linear_model:Ridge"]) == 2
    assert "must be a selector" in capsys.readouterr().err


def test_scikit_learn_classes_by_path_match_their_direct_use(tmp_path):
    """SelectKBest (its k is the package's budget name) and a plain regressor by path give
    what the same scikit-learn code gives by hand on the rises."""
    from sklearn.feature_selection import SelectKBest, f_regression
    from sklearn.linear_model import Ridge
    from spindlebench.selection import rises

    files = experiment_files(tmp_path)
    six = ["T1", "T6", "T8", "T10", "T13", "T16"]
    label = ('sklearn.feature_selection:SelectKBest[score_func="@sklearn.feature_selection:'
             'f_regression"]+sklearn.linear_model:Ridge[alpha=2.0]')
    result = evaluate(files[0], files[1:], "drift_um", six, k=2, method=_choice(label))
    train = pd.read_csv(files[0])
    X, y = rises(train[six].to_numpy()), train["drift_um"].to_numpy()
    support = SelectKBest(f_regression, k=2).fit(X, y).get_support()
    assert result.selected == [s for s, keep in zip(six, support, strict=True) if keep]
    model = Ridge(alpha=2.0).fit(X[:, support], y)
    test = pd.read_csv(files[1])
    predicted = model.predict(rises(test[six].to_numpy())[:, support])
    np.testing.assert_allclose(result.predictions[str(files[1])], predicted)
    assert result.to_dict()["coefficients"] is None


def test_suite_hash_covers_tasks_not_methods(tiny_suite, tmp_path):
    base = load_suite(tiny_suite).tasks_sha256
    (tmp_path / "tiny-study.toml").write_text(TINY_STUDY)
    (tmp_path / "a.toml").write_text(SUITE.replace('"mrmr+gbr"', '"lasso"'))
    assert load_suite(tmp_path / "a.toml").tasks_sha256 == base
    (tmp_path / "b.toml").write_text(SUITE.replace("k = 2", "k = 3"))
    assert load_suite(tmp_path / "b.toml").tasks_sha256 != base
    (tmp_path / "tiny-study.toml").write_text(TINY_STUDY.replace("seed = 5", "seed = 6"))
    assert load_suite(tmp_path / "a.toml").tasks_sha256 != base
    (tmp_path / "c.toml").write_text(SUITE.replace('kind = "synthetic"', 'kind = "synth"'))
    with pytest.raises(SpindlebenchError, match=r"c.toml: key 'task\[0\].kind': must be one of"):
        load_suite(tmp_path / "c.toml")
    (tmp_path / "d.toml").write_text(SUITE.replace('"closure"', '"closur"'))
    with pytest.raises(SpindlebenchError, match=r"suite\.methods"):
        load_suite(tmp_path / "d.toml")


def test_default_suite_loads_with_a_version():
    from conftest import SHARED_RECORDINGS

    root = SHARED_RECORDINGS if SHARED_RECORDINGS.is_dir() else \
        REPO.parents[1] / "shared" / "recordings"
    if not (root / "caiviac-fl-thermal" / "data.csv").is_file():
        pytest.skip("the CAIVIAC recording is not beside this checkout")
    suite = load_suite("default", root)
    assert suite.version and len(suite.tasks_sha256) == 64
    assert [t.kind for t in suite.tasks] == ["synthetic", "synthetic", "synthetic", "scenarios",
                                             "scenarios", "caiviac", "caiviac"]
    assert suite.version == "2.0"
    iso = next(t for t in suite.tasks if t.name == "iso230-3-spindle")
    assert [p.name for p in iso.predict] == ["spindle.toml"] and iso.probes and not iso.others


def test_stability_and_ranks():
    assert scoring.stability([("T1", "T2"), ("T1", "T2")]) == 1.0
    assert scoring.stability([("T1", "T2"), ("T1", "T3")]) == pytest.approx(1 / 3)
    assert scoring.stability([("T1",)]) is None
    assert scoring.stability([(), ()]) == 1.0
    entries = [scoring.Entry("t", name) for name in ("a", "b", *scoring.BASELINES)]
    for entry, value in zip(entries, (1.0, 9.0, 5.0, 0.5, 2.0), strict=True):
        entry.folds = [scoring.FoldScore("f", {"x": value}, np.array([value]), ())]
    frame = leaderboard.rows(entries, 5.0).set_index("method")
    assert frame.loc["a", "rank"] == 2 and frame.loc["b", "rank"] == 5
    assert frame.loc["a", "worse_than"] == "baseline:replay"
    assert frame.loc["b", "worse_than"] == "baseline:constant;baseline:replay;baseline:ols-all"


def _choice(label):
    from spindlebench.selection.registry import parse_method

    return parse_method(label)


@pytest.mark.parametrize(("label", "message"), [
    ("nope_module_x.mod:Cls", "cannot import 'nope_module_x.mod'"),
    ("sklearn.linear_model:Nope", "has no 'Nope'"),
    ("sklearn.feature_selection:SelectKBest[kk=3]", "unknown parameter(s) kk"),
    ("sklearn.feature_selection:SelectKBest[k=2,k=3]", "given twice"),
    ("sklearn:", "write an import path"),
    ("lasso+sklearn.feature_selection:SelectKBest", "has no predict()"),
])
def test_bad_user_methods_are_one_line(label, message):
    from spindlebench.selection.registry import parse_method

    with pytest.raises(SpindlebenchError) as caught:
        parse_method(label)
    assert message in str(caught.value) and "\n" not in str(caught.value)


def test_user_method_in_a_sweep_study_file(tmp_path, monkeypatch):
    """Study files take a user's label like a built-in one (sweep, and compensate's
    group:label models)."""
    from spindlebench.studies.compensation.compensation_file import _check_model
    from spindlebench.studies.family.family_file import load_study
    from spindlebench.studies.family.methods import method_specs

    monkeypatch.syspath_prepend(str(USER_METHOD_DIR))
    label = "my_selector:DecorrelatedSelector[max_overlap=0.9]+ridge"
    path = tmp_path / "study.toml"
    path.write_text(TINY_STUDY + f'\n[methods]\nclusters = [2]\nmethods = ["{label}"]\n')
    specs = method_specs(load_study(path).methods)
    mine = [s for s in specs if s.name == f"six_diff:{label}"]
    assert mine and mine[0].choice.user_method.params == (("max_overlap", 0.9),)
    assert _check_model(f"all_raw:{label}") is None


PIPELINE_MODULE = """\
from sklearn.feature_selection import SelectKBest, f_regression
from sklearn.linear_model import Ridge
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler


def ScaledRidge():
    return Pipeline([("scale", StandardScaler()), ("select", SelectKBest(f_regression, k=2)),
                     ("ridge", Ridge(alpha=1.0))])
"""


def test_user_pipeline_in_the_regressor_place(tmp_path, monkeypatch):
    """A user's pipeline (its own selection inside) after all-candidates sees every
    candidate, its nested parameters set from the label, and predicts as it does by hand."""
    from spindlebench.selection import rises

    (tmp_path / "mypipe_bench.py").write_text(PIPELINE_MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    files = experiment_files(tmp_path)
    six = ["T1", "T6", "T8", "T10", "T13", "T16"]
    label = "all-candidates+mypipe_bench:ScaledRidge[select__k=3]"
    result = evaluate(files[0], files[1:], "drift_um", six, k=1, method=_choice(label))
    assert result.selected == six  # all-candidates: the pipeline selects for itself
    sys.path.insert(0, str(tmp_path))
    try:
        from mypipe_bench import ScaledRidge
    finally:
        sys.path.remove(str(tmp_path))
    train, test = pd.read_csv(files[0]), pd.read_csv(files[2])
    model = ScaledRidge().set_params(select__k=3).fit(rises(train[six].to_numpy()),
                                                      train["drift_um"].to_numpy())
    np.testing.assert_allclose(result.predictions[str(files[2])],
                               model.predict(rises(test[six].to_numpy())))
    assert result.to_dict()["method"]["code"][0]["params"] == {"select__k": 3}


def test_a_missing_real_recording_fails_only_its_task(tiny_suite, tmp_path):
    text = tiny_suite.read_text() + '\n[[task]]\nname = "real"\nkind = "caiviac"\n' \
        'source = "nowhere/data.csv"\n'
    (tmp_path / "tiny-study.toml").write_text(TINY_STUDY)
    (tmp_path / "s.toml").write_text(text)
    suite = load_suite(tmp_path / "s.toml", tmp_path)
    assert suite.tasks[1].content["source_sha256"] == "missing"
    with pytest.raises(SpindlebenchError, match=r"key 'task\[1\]\.source': no such recording"):
        build_tasks(suite.tasks[1])
    assert main(["benchmark", str(tmp_path / "s.toml"), "--recordings-root", str(tmp_path),
                 "--tasks", "synthetic", "--only", "--method", "closure",
                 "-o", str(tmp_path / "out")]) == 0
    record = json.loads((tmp_path / "out" / "leaderboard.json").read_text())
    assert record["provenance"]["partial"] is True


def test_suite_hash_ignores_comments_but_not_parameters(tmp_path):
    machine = (REPO / "scenarios" / "machines" / "ambient-following.toml").read_text()
    (tmp_path / "m.toml").write_text(machine)
    (tmp_path / "tiny-study.toml").write_text(
        TINY_STUDY.replace('climate = "chongqing"', 'climate = "chongqing"\nmachine = "m.toml"'))
    (tmp_path / "s.toml").write_text(SUITE)
    base = load_suite(tmp_path / "s.toml").tasks_sha256
    (tmp_path / "m.toml").write_text("# a new comment\n" + machine)
    assert load_suite(tmp_path / "s.toml").tasks_sha256 == base
    assert "\nA_column = 5.0" in machine
    (tmp_path / "m.toml").write_text(machine.replace("\nA_column = 5.0", "\nA_column = 6.0"))
    assert load_suite(tmp_path / "s.toml").tasks_sha256 != base


# --- issue 23: the rollout metric, scenario and population tasks ---------------------------
SCENARIO = """\
name = "{name}"
duration_s = 7200
step_s = 60.0
sample_interval_s = 120.0
seed = {seed}

[speed]
kind = "steps"
steps = [{{ at_s = 0, rpm = {rpm} }}, {{ at_s = {stop}, rpm = 0 }}]

[feed]
kind = "constant"
x_mm_per_min = 0
y_mm_per_min = 0

[ambient]
kind = "constant"
temperature_C = 20.0

[sensors]
noise_C = 0.05
quantum_C = 0.1

[initial]
kind = "cold"
"""
SCENARIO_SUITE = """\
[suite]
name = "tiny-scenarios"
version = "0.1"
k = 2
methods = ["lasso", "dynamic:tf1", "dynamic:observer"]

[[task]]
name = "iso"
kind = "scenarios"
train = ["a.toml", "b.toml"]
predict = ["iso.toml"]
others = false
targets = ["drift_um", "drift_y_um"]
probes = true
"""


@pytest.fixture(scope="module")
def scenario_suite(tmp_path_factory):
    folder = tmp_path_factory.mktemp("scenario-suite")
    for name, rpm, stop, seed in (("a", 4000, 7140, 1), ("b", 2000, 7140, 2),
                                  ("iso", 4000, 3600, 3)):
        (folder / f"{name}.toml").write_text(SCENARIO.format(name=name, rpm=rpm, stop=stop,
                                                             seed=seed))
    (folder / "s.toml").write_text(SCENARIO_SUITE)
    return folder / "s.toml"


@pytest.fixture(scope="module")
def scenario_board(scenario_suite, tmp_path_factory):
    out = tmp_path_factory.mktemp("scenario-board")
    assert main(["benchmark", str(scenario_suite), "-o", str(out)]) == 0
    return pd.read_csv(out / "leaderboard.csv"), pd.read_csv(out / "folds.csv")


@pytest.fixture(scope="module")
def scenario_tasks(scenario_suite):
    return build_tasks(load_suite(scenario_suite).tasks[0])


def test_scenario_task_folds_targets_and_probes(scenario_suite, scenario_tasks):
    suite = load_suite(scenario_suite)
    tasks = scenario_tasks
    assert [t.name for t in tasks] == ["iso/drift_um", "iso/drift_y_um"]
    for task in tasks:  # each training scenario once; only the ISO run predicted
        assert [(f.train_name, list(f.tests)) for f in task.folds] == [("a", ["iso"]),
                                                                      ("b", ["iso"])]
        assert "probe_X1_um" in task.folds[0].train  # probes = true on every run
    # the hash covers the scenario files' bytes
    before = suite.tasks_sha256
    path = scenario_suite.parent / "iso.toml"
    path.write_text(path.read_text().replace("seed = 3", "seed = 4"))
    try:
        assert load_suite(scenario_suite).tasks_sha256 != before
    finally:
        path.write_text(path.read_text().replace("seed = 4", "seed = 3"))


@pytest.mark.slow
def test_rollout_equals_rmse_for_static_models_not_for_the_observer(scenario_board):
    frame, folds = scenario_board
    assert frame["error"].isna().all(), frame["error"].dropna().tolist()
    static = ~frame["method"].str.startswith("dynamic:observer")
    # a static model (and tf1, which reads no measurement) has no state to reset: its
    # rollout is its ordinary prediction
    assert (frame.loc[static, "rollout_rmse_um"] == frame.loc[static, "rmse_um"]).all()
    observer = frame[~static]
    assert (observer["rollout_rmse_um"] != observer["rmse_um"]).all()
    assert (folds.groupby(["task", "method"])["rollout_rmse_um"].mean().round(12)
            == frame.set_index(["task", "method"])["rollout_rmse_um"].round(12)
            .sort_index()).all()


@pytest.mark.slow
def test_observer_rollout_by_hand(scenario_tasks, scenario_board):
    """The observer's rollout is its network run open loop from the held-out run's start."""
    from spindlebench.identification.estimators import ObserverRegressor
    from spindlebench.identification.model import Inputs
    from spindlebench.selection.regression import rmse

    _, folds = scenario_board
    task = scenario_tasks[0]
    fold = task.folds[0]
    used = folds[(folds.task == task.name) & (folds.method == "dynamic:observer")
                 & (folds.fold == fold.name)]
    sensors = used["sensors"].iloc[0].split(";")
    columns = ["time_s", "spindle_speed_rpm", *sensors]

    def inputs(run):  # time, speed, and the sensors' rises since the run's first row
        X = run[columns].to_numpy(float, copy=True)
        X[:, 2:] -= X[0, 2:]
        return X

    model = ObserverRegressor(n_nodes=1, disturbances=1, random_state=0).fit(
        inputs(fold.train), fold.train["drift_um"].to_numpy(float))
    test = fold.tests["iso"]
    y = test["drift_um"].to_numpy(float)
    open_loop = model.fit_.predict(Inputs(test["time_s"].to_numpy(float),
                                          test["spindle_speed_rpm"].to_numpy(float)))[:, 0]
    filtered = model.predict(inputs(test))
    assert used["rollout_rmse_um"].iloc[0] == pytest.approx(rmse(y, open_loop), rel=1e-9)
    assert used["rmse_um"].iloc[0] == pytest.approx(rmse(y, filtered), rel=1e-9)


class _ZeroRollout:
    """A regressor whose rollout predicts no error at all (the hook's contract)."""

    def fit(self, X, y):
        self.mean_ = float(np.mean(y))
        return self

    def predict(self, X):
        return np.full(len(X), self.mean_)

    def predict_rollout(self, run):
        return np.zeros(len(run))


def test_a_regressor_with_the_hook_is_scored_by_it(scenario_tasks):
    from spindlebench.selection.regression import EstimatorFit
    from spindlebench.studies.benchmark import rollout

    task = scenario_tasks[0]
    test = task.folds[0].tests["iso"]
    y = test["drift_um"].to_numpy(float)
    fit = EstimatorFit(_ZeroRollout().fit(None, y), 0.0)
    assert np.array_equal(rollout.rollout_of(fit.estimator, test, y + 1.0), np.zeros(len(y)))
    assert np.array_equal(rollout.rollout_of(object(), test, y + 1.0), y + 1.0)  # static
    with pytest.raises(SpindlebenchError, match="one each is needed"):
        rollout.rollout_of(type("Bad", (), {"predict_rollout": lambda self, r: [1.0]})(),
                           test, y)


def test_unknown_dynamic_model_is_one_line(tmp_path):
    (tmp_path / "tiny-study.toml").write_text(TINY_STUDY)
    (tmp_path / "d.toml").write_text(SUITE.replace('"closure",', '"dynamic:nope", "closure",'))
    with pytest.raises(SpindlebenchError, match=r"suite\.methods.*unknown dynamic model 'nope'"):
        load_suite(tmp_path / "d.toml")


def test_population_task_draws_the_sweep_machines_in_memory(tmp_path):
    from spindlebench.machines.variants import load_machine
    from spindlebench.studies.benchmark.tasks import family_studies
    from spindlebench.studies.family.family_file import load_study
    from spindlebench.studies.family.population import draw_parameters
    from spindlebench.testbench.runner import inspect_fmu

    study_text = TINY_STUDY.replace(
        'months = ["Jan", "Jul"]',
        'machines = { population = 2, base = "default", spread = 0.2, seed = 4 }\n'
        'months = ["Jan", "Jul"]')
    (tmp_path / "tiny-study.toml").write_text(study_text)
    (tmp_path / "s.toml").write_text(SUITE)
    study = load_study(tmp_path / "tiny-study.toml")
    members = family_studies(study, tmp_path / "tiny-study.toml")
    assert [name for name, _ in members] == ["default-p001", "default-p002"]
    known = inspect_fmu(study.fmu).parameters
    for index, (_, member) in enumerate(members, start=1):
        assert dict(member.machine.parameters) == draw_parameters(
            study.population, load_machine("default"), known, index)
    assert members[0][1].machine.parameters != members[1][1].machine.parameters
    tasks = build_tasks(load_suite(tmp_path / "s.toml").tasks[0])
    assert [t.name for t in tasks] == ["synthetic/default-p001/lab+none",
                                       "synthetic/default-p002/lab+none"]
    # the machines differ, so their held-out runs do
    first, second = (t.folds[0].tests for t in tasks)
    assert list(first) == list(second) and first
    for name in first:
        assert not np.allclose(first[name]["drift_um"], second[name]["drift_um"])
