"""Reading canonical recordings: real data, default sensors, and one-line errors naming the
file, line and column for every kind of bad input."""

import numpy as np
import pytest
from selection_data import REAL_RECORDING, synthetic_experiment
from spindlebench.core.errors import SpindlebenchError
from spindlebench.formats.recording import default_sensors, read_recording

GOOD = "time_s,T1,T2,drift_um\n0,20.0,21.0,0.0\n15,20.5,21.1,1.5\n30,21.0,21.3,2.5\n"


def write(tmp_path, text, name="rec.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_reads_real_recording():
    frame = read_recording(REAL_RECORDING)
    assert frame.shape == (11115, 23)
    assert all(dtype == np.float64 for dtype in frame.dtypes)
    assert frame["time_s"].iloc[-1] == 166710
    assert frame.attrs["path"].endswith("data.csv")
    assert default_sensors(frame, "ch3_um") == [f"t{i}_C" for i in range(1, 17)]


def test_reads_good_file_and_trailing_blank_line(tmp_path):
    frame = read_recording(write(tmp_path, GOOD + "\n"))
    assert list(frame.columns) == ["time_s", "T1", "T2", "drift_um"]
    assert frame["drift_um"].tolist() == [0.0, 1.5, 2.5]


def test_default_sensors_exclude_truth_drivers_and_displacements():
    frame = synthetic_experiment(0)
    frame["ambient_C"] = 20.0
    frame["feed_x_mm_per_min"] = 1500.0
    frame["true_T1_C"] = frame["T1"]
    frame["ch2_um"] = 0.0
    assert default_sensors(frame, "drift_um") == ["T1", "T6", "T8", "T10", "T13", "T16"]


@pytest.mark.parametrize(("text", "message"), [
    ("", "empty file"),
    ("time_s,T1\n", "has 0 data row"),
    ("time_s,T1\n0,20\n", "has 1 data row"),
    ("time_s,T1,T1\n0,1,2\n1,1,2\n", "line 1: repeated column"),
    (",T1\n0,1\n1,2\n", "line 1: column 1 has no name"),
    ("time_s,T1\n0,20\n15,abc\n", "line 3, column 'T1': non-numeric value 'abc'"),
    ("time_s,T1\n0,20\n15,\n30,21\n", "line 3, column 'T1': missing value"),
    ("time_s,T1\n0,20\n15,21\n30\n", "line 4, column 'T1': missing value"),
    ("time_s,T1\n0,NaN\n15,21\n", "line 2, column 'T1': NaN value 'NaN'"),
    ("time_s,T1\n0,20\n15,inf\n", "line 3, column 'T1': infinite value"),
    ("time_s,T1\n0,True\n15,False\n", "line 2, column 'T1': non-numeric value 'True'"),
    ("time_s,T1\n0,20\n15,21,99\n", "line 3: 3 field\\(s\\), the header has 2"),
    ("time_s,T1\n0,20\n15,21\n15,22\n", "line 4: 'time_s' does not increase"),
])
def test_bad_input_one_line_errors(tmp_path, text, message):
    path = write(tmp_path, text)
    with pytest.raises(SpindlebenchError, match=message) as info:
        read_recording(path)
    assert str(path) in str(info.value)
    assert "\n" not in str(info.value)


def test_missing_file(tmp_path):
    with pytest.raises(SpindlebenchError, match=r"nope\.csv: file not found"):
        read_recording(tmp_path / "nope.csv")
    with pytest.raises(SpindlebenchError, match="not a file"):
        read_recording(tmp_path)


def test_columns_reads_and_checks_only_the_columns_used(tmp_path):
    """A gap or a note in a column the caller does not use does not reject the file; the used
    columns (and time_s) are checked as ever; every line must still have all its fields."""
    text = "time_s,T1,T2,T3,note\n0,20.0,21.0,,start\n15,20.5,21.1,22,\n30,21.0,21.3,22,x\n"
    path = write(tmp_path, text)
    with pytest.raises(SpindlebenchError, match="line 2, column 'T3': missing value"):
        read_recording(path)
    frame = read_recording(path, columns=["T1", "T2", "T99"])
    assert list(frame.columns) == ["time_s", "T1", "T2"]
    assert frame.attrs["header"] == ["time_s", "T1", "T2", "T3", "note"]
    assert frame["T2"].tolist() == [21.0, 21.1, 21.3]
    with pytest.raises(SpindlebenchError, match="line 2, column 'T3': missing value"):
        read_recording(path, columns=["T1", "T3"])
    short = write(tmp_path, "time_s,T1,T2,T3\n0,20,21,22\n15,20.5,21.1\n30,21,21.3,22\n",
                  "short.csv")
    with pytest.raises(SpindlebenchError, match="line 3: 3 field"):
        read_recording(short, columns=["T1"])
    quoted = write(tmp_path, 'time_s,T1,note\n0,20,"a, b"\n15,21,\n', "quoted.csv")
    assert read_recording(quoted, columns=["T1"])["T1"].tolist() == [20.0, 21.0]
    bad_time = write(tmp_path, "time_s,T1,T2\n0,20,\n0,21,\n", "time.csv")
    with pytest.raises(SpindlebenchError, match="'time_s' does not increase"):
        read_recording(bad_time, columns=["T1"])


@pytest.mark.parametrize("body", [GOOD, GOOD.replace("21.1", ""), GOOD.replace("21.1", "x")])
def test_utf8_byte_order_mark_is_not_part_of_the_first_name(tmp_path, body):
    """Excel's "CSV UTF-8" starts with a BOM: the first column is still 'time_s' (it was
    '\\ufefftime_s' and became a sensor), on the fast path, the allow_missing path and in an
    error message naming a cell."""
    path = tmp_path / "bom.csv"
    path.write_bytes(b"\xef\xbb\xbf" + body.encode())
    if "x" in body:
        with pytest.raises(SpindlebenchError, match=r"line 3, column 'T2': non-numeric") as info:
            read_recording(path)
        assert "\ufeff" not in str(info.value)
        return
    frame = read_recording(path, allow_missing=True)
    assert list(frame.columns) == ["time_s", "T1", "T2", "drift_um"]
    assert frame.attrs["header"][0] == "time_s"
    assert default_sensors(frame, "drift_um") == ["T1", "T2"]
    assert list(read_recording(path, allow_missing=True, columns=["T1"]).columns) == [
        "time_s", "T1"]


def test_recorded_outputs_leave_out_probes_unless_asked_and_mechanisms_that_are_off():
    from spindlebench.formats.recording import recorded_outputs

    names = ("T1_C", "drift_um", "probe_X1_um", "node_column_front_C", "Q_jacket_W",
             "jacket_outlet_C", "Q_rotor_W", "front_preload_thermal_N")
    off = {"jacket_enabled": 0.0, "rotor_loss_fraction": 0.0, "front_preload_N_per_K": 0.0}
    assert recorded_outputs(names, probes=False, switches=off) == ("T1_C", "drift_um")
    assert recorded_outputs(names, probes=True, switches={**off, "jacket_enabled": 1.0}) == (
        "T1_C", "drift_um", "probe_X1_um", "node_column_front_C", "Q_jacket_W",
        "jacket_outlet_C")
    # an FMU without a mechanism's switch parameter: its output, if any, is recorded
    assert recorded_outputs(names, probes=False, switches={}) == (
        "T1_C", "drift_um", "Q_jacket_W", "jacket_outlet_C", "Q_rotor_W",
        "front_preload_thermal_N")
