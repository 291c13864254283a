"""``evaluate`` and ``spindlebench evaluate``: the JSON contract, numbers recomputed
independently, the real recording, and one-line errors for bad input."""

import json

import numpy as np
import pandas as pd
import pytest
from selection_data import REAL_RECORDING, experiment_files
from spindlebench.commands import main as cli
from spindlebench.selection import SelectionWarning, evaluate

KEYS = ["selected", "psi", "eta", "clusters", "coefficients", "r2", "rmse_um", "mean_rmse_um",
        "method", "provenance"]


@pytest.fixture
def recordings(tmp_path):
    return experiment_files(tmp_path)


def run_cli(capsys, *args):
    status = cli.main(["evaluate", *map(str, args)])
    out, err = capsys.readouterr()
    return status, out, err


def test_cli_json_contract_and_numbers(recordings, tmp_path, capsys):
    out_json = tmp_path / "out" / "result.json"
    train, *tests = recordings
    status, out, err = run_cli(capsys, "--train", train, "--test", *tests, "--target", "drift_um",
                               "--clusters", "2", "--differences", "--json", out_json)
    assert status == 0, err
    assert "training R2" in out and "mean" in out
    record = json.loads(out_json.read_text())
    assert list(record) == KEYS
    assert list(record["rmse_um"]) == [str(path) for path in tests]
    assert len(record["selected"]) == len(record["psi"]) == len(record["clusters"]) == 2
    assert all(s in c for s, c in zip(record["selected"], record["clusters"], strict=True))
    assert sum(len(c) for c in record["clusters"]) == 21  # 6 sensors + 15 differences
    assert list(record["coefficients"]) == ["intercept", *record["selected"]]
    assert record["provenance"]["train"]["sha256"] and len(record["provenance"]["tests"]) == 2
    assert record["provenance"]["sensors"] == ["T1", "T6", "T8", "T10", "T13", "T16"]
    assert sorted(p.name for p in out_json.parent.iterdir()) == ["result.json"]

    # recompute everything from the CSVs with plain numpy
    def candidates(frame):
        values = {}
        for name in record["selected"]:
            a, _, b = name.partition("-")
            column = frame[a] - frame[b] if b else frame[a]
            values[name] = (column - column.iloc[0]).to_numpy()
        return np.column_stack(list(values.values()))

    train_frame = pd.read_csv(train)
    X, y = candidates(train_frame), train_frame["drift_um"].to_numpy()
    design = np.column_stack([np.ones(len(y)), X])
    beta, *_ = np.linalg.lstsq(design, y, rcond=None)
    np.testing.assert_allclose(list(record["coefficients"].values()), beta, rtol=1e-8)
    assert record["r2"] == pytest.approx(1 - np.var(y - design @ beta) / np.var(y), rel=1e-9)
    for path in tests:
        frame = pd.read_csv(path)
        predicted = beta[0] + candidates(frame) @ beta[1:]
        expected = np.sqrt(np.mean((frame["drift_um"].to_numpy() - predicted) ** 2))
        assert record["rmse_um"][str(path)] == pytest.approx(expected, rel=1e-9)
    assert record["mean_rmse_um"] == pytest.approx(np.mean(list(record["rmse_um"].values())))
    for name, psi in zip(record["selected"], record["psi"], strict=True):
        column = candidates(train_frame)[:, record["selected"].index(name)]
        assert psi == pytest.approx(np.corrcoef(column, y)[0, 1], abs=1e-12)
    # the synthetic drift is 4 (T1 - T10) - 2 (T13 - T16): differences explain it
    assert record["selected"][0] == "T1-T10" and record["r2"] > 0.99
    assert record["mean_rmse_um"] < 1.0


def test_differences_beat_raw_on_synthetic(recordings):
    train, *tests = recordings
    raw = evaluate(train, tests, "drift_um", k=2)
    diff = evaluate(train, tests, "drift_um", k=2, differences=True)
    assert diff.mean_rmse_um < raw.mean_rmse_um
    assert [s for s in raw.selected if "-" in s] == []


def test_real_recording_cycles(tmp_path):
    data = pd.read_csv(REAL_RECORDING)
    cycles = {"c1250": slice(31, 1951), "c2500": slice(1951, 3871), "c3750": slice(3871, 5791)}
    paths = {}
    for name, rows in cycles.items():
        frame = data.iloc[rows].copy()
        frame["time_s"] -= frame["time_s"].iloc[0]
        frame["ch3_um"] -= frame["ch3_um"].iloc[0]
        paths[name] = tmp_path / f"{name}.csv"
        frame.to_csv(paths[name], index=False)
    result = evaluate(paths["c1250"], [paths["c1250"], paths["c2500"], paths["c3750"]],
                      "ch3_um", k=3, differences=True, similarity="literal")
    assert result.sensors == [f"t{i}_C" for i in range(1, 17)]  # ch*_um, spindle_rpm excluded
    assert len(result.candidates) == 136 and len(result.selected) == 3
    assert result.fit.r2 > 0.9
    psi = result.selection.psi
    for members, chosen in zip(result.selection.clusters, result.selection.selected, strict=True):
        assert abs(psi[chosen]) == np.abs(psi[members]).max()
    # predicting the training run itself: RMSE^2 = (1 - R^2) var(y)
    y = result.measured[str(paths["c1250"])]
    assert result.rmse_um[str(paths["c1250"])] == pytest.approx(
        np.sqrt((1 - result.fit.r2) * np.var(y)), rel=1e-9
    )
    assert all(np.isfinite(v) for v in result.rmse_um.values())


def write_variant(tmp_path, source, name, change):
    frame = pd.read_csv(source)
    frame = change(frame)
    path = tmp_path / name
    frame.to_csv(path, index=False)
    return path


def test_constant_sensor_warned_and_dropped(recordings, tmp_path, capsys):
    def flat(frame):
        frame["T6"] = 21.0
        return frame

    train = write_variant(tmp_path, recordings[0], "flat.csv", flat)
    status, out, err = run_cli(capsys, "--train", train, "--test", recordings[1], "--target",
                               "drift_um", "--clusters", "3", "--differences")
    assert status == 0
    assert "warning: dropping 1 constant candidate(s) (zero variance): T6" in err
    assert "(1 constant dropped)" in out
    with pytest.warns(SelectionWarning):
        result = evaluate(train, [recordings[1]], "drift_um", k=3)
    assert all("T6" not in cluster for cluster in result.clusters)


@pytest.mark.parametrize(("change", "extra", "message"), [
    (None, ["--target", "nope_um"], "target column 'nope_um' not found"),
    (None, ["--sensors", "T1,T99"], "sensor column(s) not found: T99"),
    (None, ["--sensors", "T1,,T6"], "--sensors: empty name"),
    (None, ["--sensors", "T1,drift_um"], "also listed as a sensor"),
    (None, ["--clusters", "0"], "at least 1"),
    (None, ["--clusters", "7"], "larger than the number of candidates"),
    (lambda f: f.drop(columns="T16"), [], "sensor columns differ from the training file"),
    (lambda f: f.assign(T99=f["T1"]), [], "extra: ['T99']"),
    (lambda f: f.assign(T8=f["T8"].where(f.index != 9)), [], "line 11, column 'T8': missing"),
    (lambda f: f.iloc[:1], [], "has 1 data row(s)"),
])
def test_bad_input_is_one_line_error(recordings, tmp_path, capsys, change, extra, message):
    test = recordings[1]
    if change is not None:
        test = write_variant(tmp_path, test, "bad.csv", change)
    args = ["--train", recordings[0], "--test", test, "--target", "drift_um", "--clusters", "2",
            *extra]  # a repeated --clusters overrides the first
    status, _, err = run_cli(capsys, *args)
    assert status == 2
    assert err.startswith("error: ") and err.count("\n") == 1
    assert message in err


def test_missing_file(recordings, tmp_path, capsys):
    status, _, err = run_cli(capsys, "--train", tmp_path / "none.csv", "--test", recordings[1],
                             "--target", "drift_um", "--clusters", "2")
    assert status == 2 and "none.csv: file not found" in err


def test_constant_target_in_training_file_is_named(recordings, tmp_path, capsys):
    train = write_variant(tmp_path, recordings[0], "flat_error.csv",
                          lambda f: f.assign(drift_um=0.0))
    status, _, err = run_cli(capsys, "--train", train, "--test", recordings[1], "--target",
                             "drift_um", "--clusters", "2")
    assert status == 2 and err.count("\n") == 1
    assert err.startswith(f"error: recording {train}: target column 'drift_um' is constant")


@pytest.mark.parametrize("sensors", [["T1", "T6", "T8"], ["T1,T6,T8"], ["T1,", "T6,", "T8"],
                                     ["T1,T6", "T8"]])
def test_sensors_space_or_comma_separated(recordings, tmp_path, capsys, sensors):
    out_json = tmp_path / "result.json"
    status, _, err = run_cli(capsys, "--train", recordings[0], "--test", recordings[1],
                             "--target", "drift_um", "--clusters", "2", "--sensors", *sensors,
                             "--json", out_json)
    assert status == 0, err
    assert json.loads(out_json.read_text())["provenance"]["sensors"] == ["T1", "T6", "T8"]


def test_with_sensors_a_gap_in_an_unused_column_is_ignored(recordings, tmp_path, capsys):
    """--sensors T1,T6: a blank T13 cell and a text column do not matter; a blank in T6 does,
    and without --sensors (every column a sensor) the T13 gap is still an error."""
    gaps = write_variant(tmp_path, recordings[1], "gaps.csv", lambda f: f.assign(
        T13=f["T13"].where(f.index != 15), note="text"))
    args = ["--train", recordings[0], "--test", gaps, "--target", "drift_um", "--clusters", "2"]
    status, out, err = run_cli(capsys, *args, "--sensors", "T1", "T6")
    assert status == 0, err
    assert "gaps.csv" in out
    status, _, err = run_cli(capsys, *args)
    assert status == 2 and "line 17, column 'T13': missing value" in err
    gap6 = write_variant(tmp_path, recordings[1], "gap6.csv",
                         lambda f: f.assign(T6=f["T6"].where(f.index != 15)))
    status, _, err = run_cli(capsys, "--train", recordings[0], "--test", gap6, "--target",
                             "drift_um", "--clusters", "2", "--sensors", "T1,T6")
    assert status == 2 and err.count("\n") == 1
    assert "gap6.csv, line 17, column 'T6': missing value" in err
    assert "--missing drop-rows" in err


@pytest.mark.parametrize("with_bom", [(True, True), (True, False), (False, True)])
def test_utf8_byte_order_mark_is_ignored(recordings, tmp_path, capsys, with_bom):
    """An Excel export with a BOM evaluates like the plain file, whether both files or only one
    has it (time_s became a sensor '\\ufefftime_s', or the files' sensors 'differed')."""
    paths = []
    for path, bom in zip(recordings[:2], with_bom, strict=True):
        copy = tmp_path / f"bom_{path.name}"
        copy.write_bytes((b"\xef\xbb\xbf" if bom else b"") + path.read_bytes())
        paths.append(copy)
    status, _, err = run_cli(capsys, "--train", paths[0], "--test", paths[1], "--target",
                             "drift_um", "--clusters", "2", "--json", tmp_path / "bom.json")
    assert status == 0, err
    plain = tmp_path / "plain.json"
    assert run_cli(capsys, "--train", recordings[0], "--test", recordings[1], "--target",
                   "drift_um", "--clusters", "2", "--json", plain)[0] == 0
    got, want = (json.loads((tmp_path / name).read_text()) for name in ("bom.json", "plain.json"))
    assert got["provenance"]["sensors"] == want["provenance"]["sensors"]
    assert "time_s" not in got["provenance"]["sensors"]
    assert list(got["rmse_um"].values()) == list(want["rmse_um"].values())


@pytest.mark.parametrize("big_file", ["train", "test"])
def test_values_too_large_are_one_line_and_no_json(recordings, tmp_path, capsys, big_file):
    """Every cell x 1e200: the sums of squares overflow. It printed overflow warnings, then a
    JSON traceback (inf), or without --json 'training R2: nan' and RMSE inf with exit 0."""
    big = write_variant(tmp_path, recordings[0 if big_file == "train" else 1], "big.csv",
                        lambda f: f * 1e200)
    train, test = (big, recordings[1]) if big_file == "train" else (recordings[0], big)
    out_json = tmp_path / "o.json"
    for extra in ([], ["--json", out_json]):
        status, out, err = run_cli(capsys, "--train", train, "--test", test, "--target",
                                   "drift_um", "--clusters", "2", *extra)
        assert status == 2 and out == ""
        # issue 11: a temperature column at 1e200 °C is refused as implausible on reading
        # (the overflow itself is refused in the API, test_selection_bad_input)
        assert err.count("\n") == 1 and "not a plausible temperature" in err
        assert err.startswith(f"error: recording {big}, line 2, column 'T1'")
    assert not out_json.exists()
