"""Missing values (sensor dropout) in the selection pipeline: strict by default, opt-in
``drop-rows`` that drops (never fills) incomplete samples, on recordings really produced by the
testbench's sensor-fault example with the committed FMU."""

import json
import warnings

import numpy as np
import pandas as pd
import pytest
from conftest import REPO
from spindlebench.commands import main as cli
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.formats.recording import MissingValueError, read_recording
from spindlebench.selection import SelectionError, SelectionWarning, evaluate
from spindlebench.studies.paper import config as study_config
from spindlebench.studies.paper.analysis import run_study

FAULT_EXAMPLE = REPO / "scenarios" / "examples" / "sensor_faults.toml"
SENSORS = [f"T{i}" for i in range(1, 21)]
TARGET = "drift_um"
N = 121  # samples of the 2-h recordings


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """The sensor-fault example cut to 2 h (its T7 dropout, 5400-6600 s, stays inside; the
    stuck T13 starts at 6600 s instead of 4 h) and the same day without faults and with another
    noise seed, simulated with the committed FMU."""
    text = FAULT_EXAMPLE.read_text(encoding="utf-8")
    assert "duration_s = 21600" in text and 'kind = "dropout"' in text
    assert text.count("start_s = 14400") == 1
    short = text.replace("duration_s = 21600", "duration_s = 7200").replace(
        "start_s = 14400", "start_s = 6600")
    clean = short[: short.index("[[sensors.faults]]")].replace("seed = 15", "seed = 16")
    scenarios = tmp_path_factory.mktemp("scenarios")
    (scenarios / "faults.toml").write_text(short, encoding="utf-8")
    (scenarios / "clean.toml").write_text(clean, encoding="utf-8")
    out = tmp_path_factory.mktemp("recordings")
    assert cli.main(["simulate", str(scenarios), "-o", str(out), "--fmu", str(DEFAULT_FMU),
                     "--quiet"]) == 0
    return out / "faults.csv", out / "clean.csv"


def dropout_lines(path, column="T7"):
    """File line numbers (header = 1) whose ``column`` field is empty, read as plain text."""
    lines = path.read_text(encoding="utf-8").splitlines()
    index = lines[0].split(",").index(column)
    return [n for n, line in enumerate(lines[1:], start=2) if line.split(",")[index] == ""]


def test_the_testbench_writes_the_dropout_as_empty_fields(simulated):
    faults, clean = simulated
    lines = dropout_lines(faults)
    assert len(lines) == 20 and lines == list(range(lines[0], lines[0] + 20))  # 1200 s / 60 s
    assert len(read_recording(clean)) == N == 121  # 0 ... 7200 s, once a minute
    assert dropout_lines(clean) == []
    frame = read_recording(faults, allow_missing=True)
    assert frame["T7"].isna().sum() == 20
    assert frame.drop(columns="T7").notna().all().all()  # nothing else became NaN
    assert frame["time_s"].iloc[lines[0] - 2] == 5400.0


def test_dropout_is_a_one_line_error_by_default(simulated, capsys):
    faults, clean = simulated
    first = dropout_lines(faults)[0]
    with pytest.raises(MissingValueError, match=rf"line {first}, column 'T7': missing value"):
        read_recording(faults)
    with pytest.raises(SelectionError) as info:
        evaluate(faults, [clean], TARGET, k=2)
    message = str(info.value)
    assert "\n" not in message
    assert str(faults) in message and f"line {first}, column 'T7'" in message
    assert "drop-rows" in message
    status = cli.main(["evaluate", "--train", str(clean), "--test", str(faults), "--target",
                       TARGET, "--clusters", "2"])
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1
    assert err.startswith(f"error: recording {faults}, line {first}, column 'T7'")


def test_drop_rows_warns_and_equals_the_manually_filtered_frame(simulated):
    faults, clean = simulated
    with pytest.warns(SelectionWarning, match=r"recording .*faults\.csv: dropped 20 of 121 "
                      r"samples with missing values \(T7: 20\)") as caught:
        result = evaluate(faults, [clean], TARGET, k=3, differences=True, missing="drop-rows")
    assert len(caught) == 1  # the clean test recording loses nothing
    complete = pd.read_csv(faults).dropna(subset=[*SENSORS, TARGET]).reset_index(drop=True)
    assert len(complete) == N - 20
    manual = evaluate(complete, [clean], TARGET, k=3, differences=True)
    assert result.selected == manual.selected
    assert result.coefficients == pytest.approx(manual.coefficients, rel=1e-12)
    assert result.rmse_um == pytest.approx(manual.rmse_um, rel=1e-12)
    assert result.to_dict()["r2"] == pytest.approx(manual.to_dict()["r2"], rel=1e-12)
    np.testing.assert_array_equal(
        result.train_rows, np.flatnonzero(pd.read_csv(faults)["T7"].notna())
    )


def test_a_test_recording_drops_only_samples_its_model_reads(simulated):
    faults, clean = simulated
    frame = read_recording(faults, allow_missing=True)
    gap = np.flatnonzero(frame["T7"].isna())
    # both sensors are selected at k = 2, so the model reads T7
    with pytest.warns(SelectionWarning, match=r"dropped 20 of 121 samples .*\(T7: 20\)"):
        result = evaluate(clean, [faults], TARGET, sensors=["T1", "T7"], k=2,
                          missing="drop-rows")
    assert sorted(result.selected) == ["T1", "T7"]
    rows = result.test_rows[str(faults)]
    np.testing.assert_array_equal(rows, np.setdiff1d(np.arange(len(frame)), gap))
    kept = frame.iloc[rows]
    rises = kept[result.selected].to_numpy() - kept[result.selected].to_numpy()[0]
    expected = result.fit.intercept + rises @ result.fit.coefficients
    np.testing.assert_allclose(result.predictions[str(faults)], expected, rtol=1e-12)
    np.testing.assert_array_equal(result.measured[str(faults)], kept[TARGET].to_numpy())
    # a model that does not read T7 keeps every test sample, gap or not
    result = evaluate(clean, [faults], TARGET, sensors=["T1", "T10"], k=2, missing="drop-rows")
    assert len(result.predictions[str(faults)]) == len(frame) == N


def test_rise_reference_is_the_first_complete_sample(simulated):
    _faults, clean = simulated
    frame = read_recording(clean)
    gappy = frame.copy()
    gappy.loc[:2, "T1"] = np.nan  # the first three samples lack T1
    # a frame read from a file names file lines (header = line 1): the 4th sample is line 5
    with pytest.warns(SelectionWarning, match=r"dropped 3 of 121 .*\(T1: 3\).*first complete "
                      r"sample \(line 5\)"):
        result = evaluate(frame, {"gappy": gappy}, TARGET, sensors=["T1", "T10"], k=2,
                          missing="drop-rows")
    prediction = result.predictions["gappy"]
    assert len(prediction) == N - 3
    # rises are zero at the first complete sample: the model predicts its intercept there
    assert prediction[0] == pytest.approx(result.fit.intercept, abs=1e-12)
    rises = frame.loc[3:, ["T1", "T10"]].to_numpy() - frame.loc[3, ["T1", "T10"]].to_numpy()
    order = [["T1", "T10"].index(name) for name in result.selected]
    np.testing.assert_allclose(
        prediction, result.fit.intercept + rises[:, order] @ result.fit.coefficients, rtol=1e-12
    )


def test_sparse_sensor_is_left_out_as_a_candidate(simulated):
    _faults, clean = simulated
    frame = read_recording(clean)
    frame.loc[: int(0.7 * len(frame)), "T7"] = np.nan  # 85 of 121 samples
    with pytest.warns(SelectionWarning, match=r"left out sensor\(s\) missing in more than half "
                      r"of the samples: T7 \(70%\)") as caught:
        result = evaluate(frame, [clean], TARGET, k=2, missing="drop-rows")
    assert "T7" not in result.sensors and len(result.sensors) == 19
    assert not any("dropped" in str(w.message) for w in caught)  # no sample lost for T7
    assert len(result.train_rows) == len(frame)


def test_too_few_complete_samples_is_an_error(simulated):
    _faults, clean = simulated
    frame = read_recording(clean)
    target_gone = frame.assign(**{TARGET: np.nan})
    target_gone.loc[5, TARGET] = 0.0
    with pytest.raises(SelectionError, match=rf"1 complete sample\(s\) .*{TARGET}: 120\)"):
        evaluate(target_gone, [clean], TARGET, k=2, missing="drop-rows")
    all_sensors_gone = frame.assign(T1=np.nan, T10=np.nan)
    with pytest.raises(SelectionError, match="every sensor is missing in more than half"):
        evaluate(all_sensors_gone, [clean], TARGET, sensors=["T1", "T10"], k=2,
                 missing="drop-rows")
    with pytest.raises(SelectionError, match=r"0 complete sample\(s\)"):
        evaluate(clean, {"dead": all_sensors_gone}, TARGET, sensors=["T1", "T10"], k=2,
                 missing="drop-rows")


def test_drop_rows_still_rejects_what_is_not_missing(simulated):
    _faults, clean = simulated
    frame = read_recording(clean)
    with pytest.raises(SelectionError, match=r"line 6, column 'T3': infinite value 'inf'"):
        evaluate(frame.assign(T3=frame["T3"].where(frame.index != 4, np.inf)), [clean], TARGET,
                 k=2, missing="drop-rows")
    text = frame.astype(object)
    text.loc[7, "T3"] = "broken"
    with pytest.raises(SelectionError, match=r"line 9, column 'T3': non-numeric value 'broken'"):
        evaluate(text, [clean], TARGET, sensors=SENSORS, k=2, missing="drop-rows")
    with pytest.raises(SelectionError, match=r"missing: 'fill' is not one of error, drop-rows"):
        evaluate(frame, [clean], TARGET, k=2, missing="fill")


@pytest.mark.parametrize(("text", "message"), [
    ("time_s,T1\n0,20\n15,NA\n30,21\n", "line 3, column 'T1': NaN value 'NA'"),
    ("time_s,T1\n0,20\n15,inf\n30,21\n", "line 3, column 'T1': infinite value"),
    ("time_s,T1\n0,20\n15,True\n30,21\n", "line 3, column 'T1': non-numeric value 'True'"),
    ("time_s,T1,T2\n0,20,1\n15,21\n30,21,1\n", "line 3: 2 field"),
    ("time_s,T1\n0,20\n\n30,21\n", "line 3: 0 field"),
    ("time_s,T1\n0,20\n,21\n30,21\n", "line 3, column 'time_s': missing value"),
])
def test_allow_missing_reads_only_empty_and_nan_cells(tmp_path, text, message):
    good = tmp_path / "good.csv"
    good.write_text("time_s,T1,T2\n0,20, \n15,NaN,1\n30,nan,2\n45,21,3\n\n")
    frame = read_recording(good, allow_missing=True)
    assert frame["T1"].isna().tolist() == [False, True, True, False]
    assert frame["T2"].isna().tolist() == [True, False, False, False]
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(SpindlebenchError, match=message) as info:
        read_recording(path, allow_missing=True)
    assert not isinstance(info.value, MissingValueError) and "\n" not in str(info.value)


def test_cli_drop_rows_reports_the_warning_and_provenance(simulated, tmp_path, capsys):
    faults, clean = simulated
    out = tmp_path / "result.json"
    status = cli.main(["evaluate", "--train", str(faults), "--test", str(clean), "--target",
                       TARGET, "--clusters", "2", "--missing", "drop-rows", "--json", str(out)])
    _, err = capsys.readouterr()
    assert status == 0, err
    assert f"warning: recording {faults}: dropped 20 of 121 samples" in err
    record = json.loads(out.read_text())
    assert record["provenance"]["missing"] == "drop-rows"
    assert any("T7: 20" in warning for warning in record["provenance"]["warnings"])


def test_paper_study_option_and_config_key(simulated, tmp_path, capsys):
    faults, _clean = simulated
    folder = faults.parent
    args = ["paper", "--recordings", str(folder), "--train", "clean", "--tests", "faults",
            "--clusters", "2", "--out", str(tmp_path / "study")]
    assert cli.main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "column 'T7': missing value" in err and "drop-rows" in err
    assert cli.main([*args, "--missing", "drop-rows"]) == 0
    readme = (tmp_path / "study" / "README.md").read_text()
    assert "Missing values: `drop-rows`" in readme
    provenance = json.loads((tmp_path / "study" / "provenance.json").read_text())
    assert provenance["study"]["missing"] == "drop-rows"

    toml = tmp_path / "study.toml"
    toml.write_text('train = "clean"\ntests = ["faults"]\nsensors_all = ["T1", "T7"]\n'
                    'six = ["T1", "T7"]\nclusters = [2]\nmissing = "drop-rows"\n')
    config = study_config.load(toml)
    assert config.missing == "drop-rows"
    with pytest.warns(SelectionWarning, match="dropped 20 of 121"):
        result = run_study(folder, config)
    gap = read_recording(faults, allow_missing=True)["T7"].isna().to_numpy()
    for cell in result.cells:  # both sensors selected: no prediction inside the gap
        assert len(cell.predictions_um["faults"]) == N
        np.testing.assert_array_equal(np.isnan(cell.predictions_um["faults"]), gap)
    toml.write_text('missing = "fill"\n')
    with pytest.raises(SpindlebenchError, match="key 'missing': 'fill' is not one of"):
        study_config.load(toml)


def test_checked_recordings_reused_give_what_evaluate_gives_each_time(simulated):
    """One load, many evaluations (a study's one pass): every k, group and method gives the
    same predictions, rows, warnings and errors as ``evaluate`` reading the files afresh."""
    import warnings

    from spindlebench.selection.evaluate import evaluate_checked, load_recordings
    from spindlebench.selection.registry import MethodChoice

    faults, clean = simulated
    train, tests = load_recordings(clean, [faults], "drop-rows")
    cases = [dict(sensors=sensors, k=k, differences=differences, method=method)
             for sensors in (None, ["T1", "T6", "T7", "T13"], ["T7"])
             for k in (1, 2, 3) for differences in (False, True)
             for method in ("closure", "kmeans")]
    outcomes = {"ok": 0, "error": 0}
    for case in cases:
        kwargs = dict(case, method=MethodChoice(case["method"]))
        with warnings.catch_warnings(record=True) as fresh_warnings:
            warnings.simplefilter("always")
            try:
                fresh = evaluate(clean, [faults], TARGET, missing="drop-rows", **kwargs)
            except SelectionError as exc:
                fresh = exc
        with warnings.catch_warnings(record=True) as reused_warnings:
            warnings.simplefilter("always")
            try:
                reused = evaluate_checked(train, tests, TARGET, missing="drop-rows", **kwargs)
            except SelectionError as exc:
                reused = exc
        assert [str(w.message) for w in reused_warnings] == \
            [str(w.message) for w in fresh_warnings]
        if isinstance(fresh, SelectionError):
            assert str(reused) == str(fresh)
            outcomes["error"] += 1
            continue
        outcomes["ok"] += 1
        assert reused.selected == fresh.selected and reused.rmse_um == fresh.rmse_um
        for name in fresh.predictions:
            assert np.array_equal(reused.predictions[name], fresh.predictions[name])
            assert np.array_equal(reused.test_rows[name], fresh.test_rows[name])
    assert outcomes["ok"] and outcomes["error"]  # k > candidates fails for the one-sensor set


def test_column_rises_are_the_columns_of_rises_and_raise_as_it_does():
    """Per-column rises (made once per column) are the columns of the block's rises to the
    bit; a column whose reference is missing while later values are not raises rises' own
    error; one missing everywhere stays NaN."""
    from spindlebench.selection.evaluate import CheckedRecording

    rng = np.random.default_rng(6)
    frame = pd.DataFrame(rng.normal(size=(50, 3)) * 30 + 20, columns=["A", "B", "C"])
    frame["D"] = np.nan
    frame["E"] = frame["A"]
    frame.loc[0, "E"] = np.nan
    recording = CheckedRecording("run", frame)
    for columns in (["A"], ["C", "A"], ["A", "B", "C", "D"]):
        block = CheckedRecording("run", frame).rises(columns)
        for i, rise in enumerate(recording.column_rises(columns)):
            assert np.array_equal(rise, block[:, i], equal_nan=True)
    with pytest.raises(SelectionError) as per_column:
        recording.column_rises(["A", "E"])
    with pytest.raises(SelectionError) as block:
        CheckedRecording("run", frame).rises(["A", "E"])
    assert str(per_column.value) == str(block.value)


@pytest.mark.parametrize(("order", "first"), [("abc", "b"), ("acb", "c")])
def test_the_first_failing_test_recording_in_order_is_named(order, first):
    """The held-out runs are prepared, predicted and scored in passes, but the error is the
    first run's that fails, as run by run: b's prediction overflows, c has too few samples."""
    rng = np.random.default_rng(0)
    t = np.linspace(0, 1, 60)[:, None]

    def run() -> pd.DataFrame:
        X = 20 + 5 * t * rng.uniform(0.5, 2, size=(1, 4)) + rng.normal(size=(60, 4)) * 0.1
        frame = pd.DataFrame(X, columns=["S1", "S2", "S3", "S4"])
        frame["drift_um"] = 3 * (X[:, 0] - X[0, 0]) + rng.normal(size=60) * 0.05
        return frame

    train, runs = run(), {name: run() for name in "abc"}
    runs["b"][["S1", "S2", "S3", "S4"]] = np.repeat(t, 4, axis=1) * 1e308
    runs["c"].loc[1:, ["S1", "S2", "S3", "S4"]] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(SelectionError, match=f"^recording {first}: "):
            evaluate(train, {name: runs[name] for name in order}, "drift_um", k=2,
                     missing="drop-rows")


def test_stacked_candidates_are_each_recordings_matrix_to_the_bit_and_layout():
    """A model's candidates of every held-out run made at once are each run's own
    ``CandidateSet.matrix`` (values and row-major layout); runs of other lengths, or too
    many candidates, are made run by run (None)."""
    from spindlebench.selection.evaluate import (
        CandidateSet,
        CheckedRecording,
        _stacked_candidates,
    )

    rng = np.random.default_rng(9)
    sensors = ("A", "B", "C", "D")

    def recording(name: str, n: int) -> CheckedRecording:
        frame = pd.DataFrame(rng.normal(size=(n, 4)).cumsum(axis=0), columns=list(sensors))
        return CheckedRecording(name, frame)

    train = recording("train", 40)
    tests = {name: recording(name, 40) for name in "xyz"}
    candidates = CandidateSet(sensors, True)
    for columns in ((0,), (1, 5), (9, 2, 7), (4, 5, 6, 7)):
        stacked = _stacked_candidates(train, tests, candidates, columns)
        for block, test in zip(stacked, tests.values(), strict=True):
            alone = candidates.matrix(test, columns)
            assert np.array_equal(block, alone)
            assert block.flags.c_contiguous and alone.flags.c_contiguous
    assert _stacked_candidates(train, {**tests, "short": recording("short", 30)}, candidates,
                               (0, 1)) is None
    assert _stacked_candidates(train, tests, candidates, tuple(range(9))) is None


def test_checked_recording_values_and_problems_whatever_the_column_dtypes():
    """A frame whose columns pandas gives as one float64 block (float64 beside ints and
    float32) is read from that block: the values of ``frame[column].to_numpy(float)`` and
    the problems found column by column; text and booleans keep their own messages."""
    from spindlebench.selection.evaluate import CheckedRecording, _column_problem

    rng = np.random.default_rng(8)
    frame = pd.DataFrame({"A": rng.normal(size=6), "B": np.arange(6),
                          "C": rng.normal(size=6).astype(np.float32)})
    frame.loc[2, "A"], frame.loc[4, "C"] = np.inf, np.nan
    mixed = frame.assign(D=["x"] * 6, E=[True] * 6)
    for table in (frame, mixed):
        recording = CheckedRecording("run", table)
        for column in table.columns:
            for missing in ("error", "drop-rows"):
                assert recording.problem(column, missing) == \
                    _column_problem(table, column, missing)
            if column in "ABC":
                assert recording.values(column).dtype == np.float64
                assert np.array_equal(recording.values(column),
                                      table[column].to_numpy(dtype=float), equal_nan=True)
    assert CheckedRecording("run", frame)._float_block() is not None
    assert CheckedRecording("run", mixed)._float_block() is None


def test_checks_kept_per_recording_raise_again_in_order():
    """evaluate_checked keeps that its recordings passed their checks (and that the target
    varies): a recording that fails a check, or a constant target, raises the same error at
    every call, and the recordings' order decides which one is named."""
    from spindlebench.selection.evaluate import evaluate_checked, load_recordings

    rng = np.random.default_rng(11)

    def run() -> pd.DataFrame:
        frame = pd.DataFrame(rng.normal(size=(30, 3)).cumsum(axis=0), columns=["A", "B", "C"])
        frame["drift_um"] = frame["A"] * 2 + rng.normal(size=30) * 0.1
        return frame

    train, good, bad, worse = run(), run(), run(), run()
    bad.loc[5, "B"], worse.loc[3, "A"] = np.inf, np.inf
    recordings = load_recordings(train, {"good": good, "bad": bad, "worse": worse})
    for _ in range(2):
        with pytest.raises(SelectionError, match=r"^recording bad, row 5, column 'B'"):
            evaluate_checked(*recordings, "drift_um", k=2)
    assert evaluate_checked(recordings[0], {"good": recordings[1]["good"]}, "drift_um",
                            k=2).rmse_um.keys() == {"good"}
    flat = load_recordings(train.assign(drift_um=1.5), {"good": good})
    for _ in range(2):
        with pytest.raises(SelectionError, match="target column 'drift_um' is constant"):
            evaluate_checked(*flat, "drift_um", k=2)
