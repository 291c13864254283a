"""The CAIVIAC adapter on the real 46 h recording in ../shared/recordings (never copied here)."""

import json

import numpy as np
import pandas as pd
import pytest
from spindlebench.adapters import caiviac
from spindlebench.commands import main as cli
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.provenance import sha256_file
from spindlebench.formats.recording import read_recording

# The schedule as SOURCE.md documents it (0-based rows): the adapter derives it from spindle_rpm.
DOCUMENTED = [  # (first row, first idle row, next run's first row, speeds)
    (31, 991, 1951, (1250.0,)),
    (1951, 2911, 3871, (2500.0,)),
    (3871, 4831, 5791, (3750.0,)),
    (5791, 6751, 7711, (5000.0,)),
    (7711, 8671, 9631, (3500.0,)),
    (9631, 11071, 11115, (500.0, 1500.0, 2500.0, 4500.0)),
]


@pytest.fixture(scope="module")
def source():
    path = caiviac.default_source()
    assert path.is_file(), f"the real recording is expected at {path}"
    return caiviac.read_source(path)


@pytest.fixture(scope="module")
def written(tmp_path_factory, source):
    out = {}
    for phase in caiviac.PHASES:
        folder = tmp_path_factory.mktemp(phase)
        out[phase] = (folder, caiviac.write_runs(folder, phase=phase))
    return out


def test_schedule_is_found_from_spindle_speed(source):
    schedule = caiviac.find_schedule(source["spindle_rpm"].to_numpy())
    assert schedule.n_rows == len(source) == 11115
    assert schedule.baseline == range(0, 31)
    found = [(r.start, r.heating_stop, r.stop, r.speeds_rpm) for r in schedule.runs]
    assert found == DOCUMENTED
    assert [r.name for r in schedule.runs] == [
        "run1_1250rpm", "run2_2500rpm", "run3_3750rpm", "run4_5000rpm", "run5_3500rpm",
        "run6_stepped",
    ]
    assert [r.kind for r in schedule.runs] == ["constant"] * 5 + ["stepped"]


def test_baseline_and_cycles_partition_every_row_once(source):
    schedule = caiviac.find_schedule(source["spindle_rpm"].to_numpy())
    rows = list(schedule.baseline)
    for run in schedule.runs:
        rows.extend(run.rows("cycle"))
    assert rows == list(range(len(source)))
    heating = [i for run in schedule.runs for i in run.rows("heating")]
    assert len(heating) == len(set(heating)) == int((source["spindle_rpm"] > 0).sum())


@pytest.mark.parametrize("phase", caiviac.PHASES)
def test_written_runs_are_canonical_and_lossless(written, source, phase):
    _folder, paths = written[phase]
    assert [p.stem for p in paths] == [f"run{i}_{s}" for i, s in enumerate(
        ["1250rpm", "2500rpm", "3750rpm", "5000rpm", "3500rpm", "stepped"], start=1)]
    covered = []
    for path in paths:
        frame = read_recording(path)
        sidecar = json.loads(path.with_suffix(".json").read_text())
        first, last = sidecar["source_rows"]["first"], sidecar["source_rows"]["last"]
        rows = source.iloc[first : last + 1]
        covered.extend(range(first, last + 1))
        assert len(frame) == len(rows) == sidecar["source_rows"]["count"]
        # time restarts at 0 with the source's 15 s step
        assert frame["time_s"].iloc[0] == 0.0
        assert np.allclose(np.diff(frame["time_s"]), caiviac.SAMPLE_STEP_S)
        # temperatures as measured; displacements re-zeroed, offsets recorded
        for column in caiviac.TEMPERATURES:
            np.testing.assert_allclose(frame[column], rows[column], atol=5e-7)
        for column in caiviac.DISPLACEMENTS:
            assert frame[column].iloc[0] == 0.0
            offset = sidecar["displacement_zero_offsets_um"][column]
            np.testing.assert_allclose(frame[column] + offset, rows[column], atol=2e-6)
        np.testing.assert_array_equal(frame["spindle_speed_rpm"], rows["spindle_rpm"])
        assert sidecar["speeds_rpm"] == sorted(
            set(rows["spindle_rpm"][rows["spindle_rpm"] > 0]), key=list(rows["spindle_rpm"]).index
        )
        assert sidecar["phase"] == phase
        assert sidecar["source"]["sha256"] == sha256_file(caiviac.default_source())
        assert sidecar["recording_sha256"] == sha256_file(path)
        spindle_on = frame["spindle_speed_rpm"] > 0
        if phase == "heating":
            assert spindle_on.all()
        else:  # heating, then the cool-down up to the next switch-on
            assert spindle_on.iloc[0] and not spindle_on.iloc[-1]
            assert (np.diff(spindle_on.astype(int)) <= 0).all()
    assert len(covered) == len(set(covered)), "a source row appears in two runs"
    expected = [i for r in DOCUMENTED for i in range(r[0], r[1] if phase == "heating" else r[2])]
    assert covered == expected


def test_command_line_writes_runs(tmp_path, capsys):
    status = cli.main(["adapt", "caiviac", "--out", str(tmp_path), "--phase", "cycle"])
    assert status == 0
    assert len(capsys.readouterr().out.splitlines()) == 6
    frame = read_recording(tmp_path / "run4_5000rpm.csv")
    assert len(frame) == 1920
    assert frame["ch3_um"].min() < -50  # the largest heating response of the schedule


def _small_source(tmp_path, rpm, **changes):
    n = len(rpm)
    data = {"time_s": np.arange(n) * 15.0, "spindle_rpm": rpm}
    for column in caiviac.DISPLACEMENTS + caiviac.TEMPERATURES:
        data[column] = np.linspace(20.0, 21.0, n)
    data.update(changes)
    path = tmp_path / "data.csv"
    pd.DataFrame(data).to_csv(path, index=False)
    return path


def test_small_schedule_is_cut_without_hard_coded_rows(tmp_path):
    rpm = [0, 0, 800, 800, 800, 0, 0, 1600, 1600, 0, 400, 900]
    path = _small_source(tmp_path, np.repeat(rpm, 5))  # every spindle-on block >= 10 samples
    paths = caiviac.write_runs(tmp_path / "out", path, phase="cycle")
    assert [p.stem for p in paths] == ["run1_800rpm", "run2_1600rpm", "run3_stepped"]
    assert [len(read_recording(p)) for p in paths] == [25, 15, 10]


def test_bad_sources_give_one_line_errors(tmp_path):
    with pytest.raises(SpindlebenchError, match="not found"):
        caiviac.read_source(tmp_path / "missing.csv")
    path = _small_source(tmp_path, [0, 100, 100])
    frame = pd.read_csv(path).drop(columns=["t7_C"])
    frame.to_csv(path, index=False)
    with pytest.raises(SpindlebenchError, match=r"missing column.*t7_C"):
        caiviac.read_source(path)
    path = _small_source(tmp_path, [0, 100, 100], t3_C=["20.1", "oops", "20.3"])
    with pytest.raises(SpindlebenchError, match=r"line 3, column t3_C"):
        caiviac.read_source(path)
    path = _small_source(tmp_path, [0, 100, 100], time_s=[0.0, 15.0, 15.0])
    with pytest.raises(SpindlebenchError, match="line 4: time_s"):
        caiviac.read_source(path)
    path = _small_source(tmp_path, [0, 0, 0])
    with pytest.raises(SpindlebenchError, match="never turns"):
        caiviac.write_runs(tmp_path / "out", path)
    assert not (tmp_path / "out").exists()


def test_no_constant_speed_run_is_one_line_and_writes_nothing(tmp_path, capsys):
    path = _small_source(tmp_path, [0] * 5 + [1000, 2000] * 5 + [0] * 5)
    out = tmp_path / "out"
    status = cli.main(["adapt", "caiviac", "--source", str(path), "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1
    assert "0 constant-speed run(s)" in err and str(path) in err
    assert not out.exists()


def test_only_one_run_is_an_error_too(tmp_path):
    path = _small_source(tmp_path, [0] * 5 + [1000] * 10 + [0] * 5)
    with pytest.raises(SpindlebenchError, match="another run to predict"):
        caiviac.write_runs(tmp_path / "out", path)
    assert not (tmp_path / "out").exists()


def test_inf_cell_is_one_line_naming_line_and_column(tmp_path):
    temps = np.linspace(20.0, 21.0, 12).astype(object)
    temps[4] = "inf"
    path = _small_source(tmp_path, [0, 0] + [100] * 10, t5_C=temps)
    with pytest.raises(SpindlebenchError, match=r"line 6, column t5_C: non-finite value 'inf'"):
        caiviac.read_source(path)


def test_a_short_spindle_on_block_is_skipped_with_a_warning(tmp_path, capsys):
    rpm = [0] * 3 + [800] * 12 + [0] * 3 + [1600] + [0] * 3 + [400] * 10 + [0] * 2
    path = _small_source(tmp_path, rpm)
    out = tmp_path / "out"
    assert cli.main(["adapt", "caiviac", "--source", str(path), "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1
    assert "warning:" in captured.err and "skipped run2_1600rpm (rows 18-18)" in captured.err
    assert sorted(p.name for p in out.glob("*.csv")) == ["run1_800rpm.csv", "run3_400rpm.csv"]
    assert all(len(read_recording(p)) >= caiviac.MIN_RUN_SAMPLES for p in out.glob("*.csv"))
    assert 'tests = ["run3_400rpm"]' in (out / caiviac.STUDY_FILE).read_text()


def test_iso_map_beside_the_runs_names_all_five_channels(tmp_path):
    from spindlebench.studies.iso230_3.channels import load_map

    mapping_path = tmp_path / caiviac.ISO_MAP_FILE
    mapping_path.write_text(caiviac.ISO_MAP_TEXT)
    mapping = load_map(mapping_path)
    displacement = [c for d in mapping.directions.values() for c in d.columns]
    assert sorted(displacement) == list(caiviac.DISPLACEMENTS)
    assert set(caiviac.DISPLACEMENT_CHANNELS) == set(caiviac.DISPLACEMENTS)
    assert set(mapping.temperatures) <= set(caiviac.TEMPERATURES)


def test_run_summary_matches_the_written_runs(written):
    """The runs table of docs/validation.md (``run_summary``) says what the adapter wrote: each
    run's source rows and its re-zeroed ch3 over heating and at the end of the cycle."""
    summary = {row["run"]: row for row in caiviac.run_summary()}
    for phase in caiviac.PHASES:
        _, paths = written[phase]
        assert sorted(summary) == sorted(p.stem for p in paths)
        for path in paths:
            row = summary[path.stem]
            sidecar = json.loads(path.with_suffix(".json").read_text(encoding="utf-8"))
            rows = row["heating_rows"] if phase == "heating" else row["cycle_rows"]
            assert rows == [sidecar["source_rows"]["first"], sidecar["source_rows"]["last"]]
            error = read_recording(path)[caiviac.AXIAL_TARGET].to_numpy()
            if phase == "heating":
                assert row["heating_min_um"] == pytest.approx(error.min(), abs=1e-6)
                assert row["heating_max_um"] == pytest.approx(error.max(), abs=1e-6)
                assert row["end_of_heating_um"] == pytest.approx(error[-1], abs=1e-6)
            else:
                assert row["end_of_cycle_um"] == pytest.approx(error[-1], abs=1e-6)
