"""Issue 11: explicit column roles for a user's recording (another logger's naming, dialect).

Runs ``spindlebench evaluate`` on ``docs/examples/other-logger`` (two synthetic runs written
with semicolons, decimal commas, ``Time [s]``, ``... [degC]`` and two displacement channels)
and on variants of it.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from spindlebench.commands import main as cli
from spindlebench.core.errors import SpindlebenchError
from spindlebench.formats.roles import ColumnRoles, choose, detect_dialect

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "other-logger"
TARGET = "dz [um]"


def evaluate(capsys, *args: str, train: Path = EXAMPLE / "run1.csv",
             test: Path = EXAMPLE / "run2.csv"):
    status = cli.main(["evaluate", "--train", str(train), "--test", str(test), "--target",
                       TARGET, "--clusters", "2", *args])
    out, err = capsys.readouterr()
    return status, out, err


def test_the_documented_example_takes_the_temperatures_and_says_what_it_skipped(capsys):
    status, out, err = evaluate(capsys, "--time-column", "Time [s]")
    assert status == 0, err
    first = out.splitlines()[0]
    assert first.startswith("sensors (temperature-looking columns): took Spindle front [degC]")
    assert "skipped: Time [s] (time column); Spindle speed [rpm] (driver/command input); " \
           "dz [um] (target); dx [um] (displacement/thermal error)" in first
    assert "training R2" in out
    page = (EXAMPLE.parents[1] / "recordings.md").read_text(encoding="utf-8")
    assert first in page  # the recordings page shows what the command prints


def test_a_time_column_of_another_name_is_never_a_sensor(capsys):
    status, out, _ = evaluate(capsys, "--differences")
    assert status == 0
    assert "Time [s] (looks like time" in out.splitlines()[0]
    assert "Time [s]-" not in out and "-Time [s]" not in out


def test_a_copy_of_the_target_is_refused_unless_allowed(capsys):
    status, out, err = evaluate(capsys, "--sensors", "*[degC]", "dx [um]")
    assert status == 2 and out == ""
    assert err.count("\n") == 1
    assert "sensor 'dx [um]' follows the target 'dz [um]' with |r| = 1.0000 > 0.999" in err
    status, out, err = evaluate(capsys, "--sensors", "*[degC]", "dx [um]",
                                "--allow-target-copy")
    assert status == 0, err


def test_patterns_and_exclude(capsys):
    status, out, err = evaluate(capsys, "--sensors", "Spindle*", "*air*", "--exclude",
                                "Spindle speed*")
    assert status == 0, err
    assert out.splitlines()[0].startswith(
        "sensors (--sensors): took Spindle front [degC], Spindle motor [degC], "
        "Workshop air [degC]; skipped: Spindle speed [rpm] (--exclude)")
    status, _, err = evaluate(capsys, "--sensors", "Nozzle*")
    assert status == 2 and "sensor pattern matches no column: Nozzle*" in err


def test_the_dialect_is_detected_and_a_wrong_delimiter_says_which_it_looks_like(capsys):
    assert detect_dialect(EXAMPLE / "run1.csv") == (";", ",")
    status, out, err = evaluate(capsys, "--delimiter", ",")
    assert status == 2 and out == ""
    assert err.count("\n") == 1
    assert "line 1: read as one column" in err and "(pass --delimiter ';')" in err
    status, _, err = evaluate(capsys, "--delimiter", ";", "--decimal", ",")
    assert status == 0, err


def test_a_logger_sentinel_in_one_cell_is_named_by_file_line_and_column(tmp_path, capsys):
    frame = pd.read_csv(EXAMPLE / "run1.csv", sep=";", decimal=",")
    frame.loc[57, "Headstock side [degC]"] = 9.9e37
    train = tmp_path / "sentinel.csv"
    frame.to_csv(train, sep=";", decimal=",", index=False)
    status, out, err = evaluate(capsys, train=train)
    assert status == 2 and out == ""
    assert err == (f"error: recording {train}, line 59, column 'Headstock side [degC]': 9.9e+37 "
                   "is not a plausible temperature (-273.15..10000 °C; a logger's error "
                   "value?); 1 such cell(s); remove those samples or --exclude the column\n")


def test_a_canonical_recording_keeps_its_sensors():
    header = ["time_s", *[f"T{i}" for i in range(1, 21)], "drift_um", "spindle_speed_rpm",
              "feed_x_mm_per_min", "feed_y_mm_per_min", "ambient_C", "true_T1_C",
              "true_drift_um", "true_Q_front_bearing_W"]
    choice = choose(header, "drift_um", ColumnRoles(), "r.csv")
    assert choice.sensors == [f"T{i}" for i in range(1, 21)]
    assert choice.time_column == "time_s"
    caiviac = ["time_s", "spindle_rpm", *[f"ch{i}_um" for i in range(1, 6)],
               *[f"t{i}_C" for i in range(1, 17)]]
    assert choose(caiviac, "ch3_um", ColumnRoles(), "c.csv").sensors == \
        [f"t{i}_C" for i in range(1, 17)]


def test_a_given_time_column_must_exist_and_increase(tmp_path, capsys):
    status, _, err = evaluate(capsys, "--time-column", "Zeit")
    assert status == 2 and "--time-column 'Zeit' not found" in err
    frame = pd.read_csv(EXAMPLE / "run1.csv", sep=";", decimal=",")
    frame.loc[10, "Time [s]"] = 0.0
    train = tmp_path / "back.csv"
    frame.to_csv(train, sep=";", decimal=",", index=False)
    status, _, err = evaluate(capsys, "--time-column", "Time [s]", train=train)
    assert status == 2 and f"{train}, line 12: the time column does not increase" in err


def test_no_temperature_looking_column_asks_for_sensors(tmp_path):
    path = tmp_path / "x.csv"
    pd.DataFrame({"a": np.arange(5.0), "b": np.arange(5.0) ** 2, "y": np.arange(5.0)}).to_csv(
        path, index=False)
    with pytest.raises(SpindlebenchError, match=r"no sensor columns .*pass --sensors"):
        choose(["a", "b", "y"], "y", ColumnRoles(), str(path))


def test_the_example_can_be_regenerated(tmp_path):
    """make_example.py writes what is committed (same scenarios, seeds, rounding)."""
    copy = tmp_path / "other-logger"
    shutil.copytree(EXAMPLE, copy)
    import runpy

    assert runpy.run_path(str(copy / "make_example.py"), run_name="example")["main"]() == 0
    for name in ("run1.csv", "run2.csv"):
        assert (copy / name).read_bytes() == (EXAMPLE / name).read_bytes(), (
            f"{name} is stale (the FMU or runner changed): run "
            ".venv/bin/python docs/examples/other-logger/make_example.py and commit it")


SENSORS = ["Spindle front [degC]", "Seat flange [degC]", "Headstock side [degC]",
           "Spindle motor [degC]", "Workshop air [degC]", "X motor [degC]", "Y motor [degC]"]


def paper_folder(tmp_path: Path, extra: str = "") -> Path:
    folder = tmp_path / "recs"
    folder.mkdir()
    for name in ("run1.csv", "run2.csv"):
        shutil.copy(EXAMPLE / name, folder / name)
    names = ", ".join(f'"{s}"' for s in SENSORS)
    (folder / "paper_study.toml").write_text(
        f'target = "{TARGET}"\ntrain = "run1"\ntests = ["run2"]\nsensors_all = [{names}]\n'
        f'six = "auto"\nclusters = [2]\n{extra}', encoding="utf-8")
    return folder


def test_paper_takes_the_roles_from_its_study_file(tmp_path, capsys):
    folder = paper_folder(tmp_path, 'time_column = "Time [s]"\n'
                                    'exclude = ["Workshop*"]\n')
    assert cli.main(["paper", "--recordings", str(folder)]) == 0
    out = capsys.readouterr().out
    assert "target dz [um]" in out and "Workshop air" not in out.split("six = ")[1]
    assert (folder / "paper_study" / "README.md").is_file()


def test_paper_without_its_time_column_says_so(tmp_path, capsys):
    folder = paper_folder(tmp_path)
    assert cli.main(["paper", "--recordings", str(folder)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[-1] == (f"error: recording {folder / 'run1.csv'}: no time column 'time_s'; the "
                       "paper's figures plot against time and needs one: name it with "
                       "--time-column (or time_column)")
    assert not (folder / "paper_study").exists()
    assert cli.main(["paper", "--recordings", str(folder), "--time-column", "Time [s]"]) == 0


# --------------------------------------------------------------------------- other commands


def test_plot_takes_the_roles_and_needs_the_time_column(tmp_path, capsys):
    out = tmp_path / "runs.png"
    args = ["plot", str(EXAMPLE / "run1.csv"), str(EXAMPLE / "run2.csv"), "--target", TARGET,
            "-o", str(out)]
    assert cli.main(args) == 2
    _, err = capsys.readouterr()
    assert err == (f"error: recording {EXAMPLE / 'run1.csv'}: no time column 'time_s'; a plot "
                   "over time needs one: name it with --time-column (or time_column)\n")
    assert not out.exists()
    assert cli.main([*args, "--time-column", "Time [s]", "--exclude", "X motor*"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith(f"sensors (temperature-looking columns) in {EXAMPLE / 'run1.csv'}"
                               ": took Spindle front [degC], ")
    assert "X motor [degC] (--exclude)" in lines[0] and "dx [um] (displacement" in lines[0]
    assert lines[2] == str(out) and out.read_bytes()[:4] == b"\x89PNG"


def test_plot_draws_only_the_named_sensors(tmp_path, capsys):
    from spindlebench.formats.roles import read_with_roles
    from spindlebench.testbench.overview import recordings_figure

    roles = ColumnRoles(time_column="Time [s]", sensors=("Spindle*",), exclude=("*[rpm]",))
    frame, choice = read_with_roles(EXAMPLE / "run1.csv", TARGET, roles, extra=("dx [um]",))
    assert list(frame.columns) == ["time_s", "Spindle front [degC]", "Spindle motor [degC]",
                                   "dz [um]", "dx [um]"]  # the time axis renamed, dx kept
    figure = recordings_figure([frame], ["run1"], target=TARGET, sensors=[choice.sensors])
    try:
        drawn = {line.get_label() for line in figure.axes[0].get_lines()}
        assert drawn == {"Spindle front [degC]", "Spindle motor [degC]"}
    finally:
        import matplotlib.pyplot as plt

        plt.close(figure)


def test_fingerprint_takes_the_roles_and_refuses_a_copy_of_the_target(tmp_path, capsys):
    out = tmp_path / "fp.json"
    base = ["fingerprint", str(EXAMPLE / "run1.csv"), "--target", TARGET, "--json", str(out)]
    assert cli.main(base) == 2
    assert "no time column 'time_s'; the fingerprint (t63 is a time)" in capsys.readouterr().err
    assert cli.main([*base, "--time-column", "Time [s]", "--sensors", "*[degC]",
                     "dx [um]"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "sensor 'dx [um]' follows the target 'dz [um]'" in err
    assert not out.exists()
    assert cli.main([*base, "--time-column", "Time [s]"]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[0].startswith("sensors (temperature-looking columns) in ")
    import json

    row = json.loads(out.read_text(encoding="utf-8"))["recordings"][0]
    assert row["sensors"] == SENSORS and row["time_column"] == "Time [s]"
    assert row["samples"] == len(pd.read_csv(EXAMPLE / "run1.csv", sep=";"))


CALIBRATION_MAP = """
[inputs]
spindle_speed_rpm = "Spindle speed [rpm]"
feed_x_mm_per_min = 0.0
feed_y_mm_per_min = 0.0
ambient_C = "Workshop air [degC]"
[error]
column = "dz [um]"
[temperatures]
"Spindle front [degC]" = "T1"
"Spindle motor [degC]" = "T8"
"""


def test_calibrate_reads_another_loggers_recording_with_its_roles(tmp_path):
    from spindlebench.calibration.mapping import read_map
    from spindlebench.calibration.series import load_series

    outputs = [f"T{i}_C" for i in range(1, 21)] + ["drift_um"]
    path = tmp_path / "map.toml"
    path.write_text(CALIBRATION_MAP, encoding="utf-8")
    run1 = EXAMPLE / "run1.csv"
    with pytest.raises(SpindlebenchError, match=r"run1.csv: no time column 'time_s'; the "
                       r"calibration integrates the model over time"):
        load_series(run1, read_map(path, outputs), None)
    roles = ColumnRoles(time_column="Time [s]")
    series = load_series(run1, read_map(path, outputs), None, roles)
    frame = pd.read_csv(run1, sep=";", decimal=",")
    assert np.array_equal(series.time_s, frame["Time [s]"].to_numpy())
    assert [c.column for c in series.channels] == ["Spindle front [degC]",
                                                   "Spindle motor [degC]", "dz [um]"]
    assert "Time [s]" not in series.ignored and "dx [um]" in series.ignored
    path.write_text(CALIBRATION_MAP + '"dx [um]" = "T2"\n', encoding="utf-8")
    with pytest.raises(SpindlebenchError, match=r"sensor 'dx \[um\]' follows the target "
                       r"'dz \[um\]' with \|r\| = 1.0000"):
        load_series(run1, read_map(path, outputs), None, roles)
    load_series(run1, read_map(path, outputs), None,
                ColumnRoles(time_column="Time [s]", allow_target_copy=True))


def test_every_command_that_reads_recordings_has_the_role_flags():
    """compensate simulates its days and adapt converts a data set whose columns it names
    itself: neither reads a user's recording, so neither has the flags."""
    parser = cli.build_parser()
    flags = {name: {a for action in sub._actions for a in action.option_strings}
             for name, sub in parser.commands.items()}
    common = {"--time-column", "--delimiter", "--decimal"}
    for name in ("evaluate", "fingerprint", "plot", "paper", "calibrate"):
        assert common <= flags[name], name
    for name in ("evaluate", "fingerprint", "plot"):
        assert {"--sensors", "--exclude"} <= flags[name], name
    for name in ("evaluate", "fingerprint", "paper", "calibrate"):
        assert "--allow-target-copy" in flags[name], name
    assert "--allow-target-copy" not in flags["plot"]  # nothing is fitted; a copy is drawn
    for name in ("compensate", "adapt", "simulate", "sweep", "place", "methods", "build"):
        assert not common & flags[name], name


def test_the_copy_screen_refuses_the_same_first_sensor_as_one_by_one():
    """refuse_target_copies clears most sensors from |r| of all at once: the sensor it
    refuses (and its |r|) is the one the one-by-one np.corrcoef check refuses."""
    from spindlebench.formats.roles import COPY_R, refuse_target_copies

    def one_by_one(frame, names):
        y = frame["y"].to_numpy()
        for name in names:
            x = frame[name].to_numpy()
            keep = np.isfinite(x) & np.isfinite(y)
            if keep.sum() < 3 or np.ptp(x[keep]) == 0 or np.ptp(y[keep]) == 0:
                continue
            r = float(np.corrcoef(x[keep], y[keep])[0, 1])
            if abs(r) > COPY_R:
                return f"sensor {name!r} follows the target 'y' with |r| = {abs(r):.4f}"
        return None

    rng = np.random.default_rng(0)
    refused = 0
    for trial in range(120):
        n, k = int(rng.integers(3, 40)), int(rng.integers(1, 6))
        X, y = rng.normal(size=(n, k)), rng.normal(size=n)
        X[:, rng.integers(k)] = y * rng.choice([-2, 3]) + rng.normal(
            0, 10.0 ** rng.integers(-5, 1), n)  # a copy (|r| above or below COPY_R)
        if trial % 5 == 0:
            X[:, 0] = 1.0  # constant
        if trial % 7 == 0:
            X[rng.integers(n), rng.integers(k)] = np.nan
        frame = pd.DataFrame(X, columns=[f"T{i}" for i in range(k)]).assign(y=y)
        names = list(frame.columns[:-1])
        expected = one_by_one(frame, names)
        if expected is None:
            refuse_target_copies(frame, "y", names, "r.csv", False)
        else:
            refused += 1
            with pytest.raises(SpindlebenchError, match=re.escape(expected)):
                refuse_target_copies(frame, "y", names, "r.csv", False)
    assert 10 < refused < 120  # both outcomes occur
