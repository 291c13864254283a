"""Issue 25: a recording's time unit, dates, encoding and speed column, made explicit.

A column ``Zeit [min]`` was read as seconds (a 6 h run became 0-0.10 h in ``plot`` and
``fingerprint`` without a word), a date/time column was refused as non-numeric, a sample
index was taken for seconds, a Latin-1 file had no ``--encoding``, and a user's speed column
could not be named.
"""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

import numpy as np
import pytest
from spindlebench.calibration.mapping import read_map
from spindlebench.calibration.series import load_series
from spindlebench.commands import main as cli
from spindlebench.core.errors import SpindlebenchError
from spindlebench.formats.roles import ColumnRoles, read_table_with_roles, read_with_roles
from spindlebench.formats.time_axis import looks_like_sample_index, unit_from_name

MINUTES = np.arange(0.0, 361.0, 10.0)  # a 6 h run, one sample per 10 min


def recording(path: Path, time_name: str, times, *, encoding: str = "utf-8",
              speed: str | None = None, start_C: float = 20.0) -> Path:
    t_h = MINUTES / 60.0
    t1 = start_C + 10 * (1 - np.exp(-t_h))
    t2 = start_C + 6 * (1 - np.exp(-t_h / 2))
    drift = 4 * (1 - np.exp(-t_h / 1.5)) + 0.01 * np.sin(7 * t_h)
    lines = [",".join([time_name, "T1 [°C]", "T2 [°C]", "dz_um",
                       *([speed] if speed else [])])]
    for i, when in enumerate(times):
        cells = [str(when), f"{t1[i]:.4f}", f"{t2[i]:.4f}", f"{drift[i]:.4f}"]
        lines.append(",".join(cells + ([str(4000 if t_h[i] < 3 else 2000)] if speed else [])))
    path.write_bytes(("\n".join(lines) + "\n").encode(encoding))
    return path


@pytest.mark.parametrize(("name", "unit"), [
    ("Zeit [min]", "min"), ("time (h)", "h"), ("t_min", "min"), ("elapsed [s]", "s"),
    ("time_s", "s"), ("Time", None), ("timestamp", None), ("t [ms]", "ms"), ("days", None),
    ("Zeit [Minuten]", None)])
def test_the_unit_is_read_from_the_column_name(name, unit):
    assert unit_from_name(name) == unit


def test_minutes_in_the_name_are_read_as_seconds_and_said(tmp_path):
    path = recording(tmp_path / "r.csv", "Zeit [min]", MINUTES)
    table, choice = read_table_with_roles(path, "dz_um", ColumnRoles(time_column="Zeit [min]"))
    assert table["time_s"][-1] == 6 * 3600
    assert "'Zeit [min]' in min (its name), read as seconds" in choice.report()


def test_time_unit_flag_converts_a_unitless_column(tmp_path):
    path = recording(tmp_path / "r.csv", "Zeit", MINUTES / 60.0)
    frame, choice = read_with_roles(path, "dz_um", ColumnRoles(time_column="Zeit",
                                                              time_unit="h"))
    assert frame["time_s"].iloc[-1] == pytest.approx(6 * 3600)
    assert "(--time-unit)" in choice.time_note


def test_a_date_time_column_is_seconds_since_its_first_row(tmp_path):
    start = dt.datetime(2024, 3, 1, 8, 0)
    stamps = [(start + dt.timedelta(minutes=float(m))).isoformat(sep=" ") for m in MINUTES]
    path = recording(tmp_path / "r.csv", "timestamp", stamps)
    table, choice = read_table_with_roles(path, "dz_um", ColumnRoles(time_column="timestamp"))
    assert table.columns[0] == "time_s"
    assert table["time_s"].tolist() == (MINUTES * 60).tolist()
    assert "dates/times" in choice.report()


def test_a_sample_index_is_refused_unless_its_unit_is_given(tmp_path):
    path = recording(tmp_path / "r.csv", "sample", range(len(MINUTES)))
    with pytest.raises(SpindlebenchError, match="'sample' counts 0, 1, 2"):
        read_table_with_roles(path, "dz_um", ColumnRoles(time_column="sample"))
    table, _ = read_table_with_roles(path, "dz_um", ColumnRoles(time_column="sample",
                                                                time_unit="min"))
    assert table["time_s"][1] == 60.0
    assert looks_like_sample_index(np.arange(1, 10)) and not looks_like_sample_index(
        np.arange(0, 30, 10))


def test_plot_and_fingerprint_of_a_latin1_recording_in_minutes_with_a_speed_column(
        tmp_path, capsys):
    path = recording(tmp_path / "r.csv", "Zeit [min]", MINUTES, encoding="latin-1",
                     speed="Drehzahl")
    roles = ["--time-column", "Zeit [min]", "--encoding", "latin-1", "--speed-column",
             "Drehzahl", "--target", "dz_um"]
    assert cli.main(["plot", str(path), "-o", str(tmp_path / "r.png"), *roles]) == 0
    out = capsys.readouterr().out
    assert "Drehzahl (--speed-column)" in out and "read as seconds" in out
    reference = tmp_path / "reference"
    reference.mkdir()
    recording(reference / "a.csv", "time_s", MINUTES * 60)
    text = (reference / "a.csv").read_text(encoding="utf-8").replace("dz_um", "drift_um")
    (reference / "a.csv").write_text(text, encoding="utf-8")
    assert cli.main(["fingerprint", str(path), *roles, "--json", str(tmp_path / "f.json"),
                     "--reference", str(reference)]) == 0
    row = json.loads((tmp_path / "f.json").read_text(encoding="utf-8"))["recordings"][0]
    assert row["programme"] == [{"start_h": 0.0, "rpm": 4000.0},
                                {"start_h": 3.0, "rpm": 2000.0}]
    assert row["t63_ratio"] is not None


OUTPUTS = [f"T{i}_C" for i in range(1, 21)] + ["drift_um"]
MAP = """[inputs]
spindle_speed_rpm = 3000.0
feed_x_mm_per_min = 0.0
feed_y_mm_per_min = 0.0
ambient_C = 20.0
[error]
column = "dz_um"
[temperatures]
"T1 [°C]" = "T1"
"T2 [°C]" = "T2"
"""


def test_calibration_refuses_rises_and_converts_minutes(tmp_path):
    mapping = tmp_path / "map.toml"
    mapping.write_text(MAP, encoding="utf-8")
    recording_map = read_map(mapping, OUTPUTS)
    rises = recording(tmp_path / "rises.csv", "time_s", MINUTES * 60, start_C=0.0)
    with pytest.raises(SpindlebenchError, match=r"starts within ±2 of 0 .*rises, not °C"):
        load_series(rises, recording_map, None)
    minutes = recording(tmp_path / "min.csv", "t_min", MINUTES)
    series = load_series(minutes, recording_map, None, ColumnRoles(time_column="t_min"))
    assert series.time_s[-1] == 6 * 3600
