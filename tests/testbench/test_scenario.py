"""Scenario files: the shipped ones load, the paper's match Table 2, bad input gets one line."""

from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from spindlebench.core.errors import SpindlebenchError
from spindlebench.testbench import drivers
from spindlebench.testbench.scenario import (
    ConstantFeed,
    ConstantSpeed,
    MeasuredAmbient,
    SeasonAmbient,
    load_scenario,
    resolve_initial,
)

ROOT = REPO
SCENARIOS = ROOT / "scenarios"

BASE = """\
duration_s = 3600
step_s = 1.0
sample_interval_s = 60
seed = 3

[speed]
kind = "constant"
rpm = 4000

[feed]
kind = "constant"
x_mm_per_min = 1500
y_mm_per_min = 1500

[ambient]
kind = "season"
low_C = 5.3
high_C = 10.4
"""


def write(tmp_path: Path, text: str, name: str = "s.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_every_shipped_scenario_loads():
    files = sorted([*SCENARIOS.glob("paper/*.toml"), *SCENARIOS.glob("examples/*.toml")])
    assert len(files) >= 10
    for path in files:
        scenario = load_scenario(path)
        assert scenario.n_steps * scenario.step_s == pytest.approx(scenario.duration_s)


PAPER_TABLE_2 = {  # experiment: (rpm, ambient low, ambient high), Xu et al. 2023
    1: (4000, 5.3, 10.4),
    2: (2000, 7.3, 11.1),
    3: (4000, 9.6, 12.6),
    4: (4000, 20.5, 23.7),
    5: (2000, 23.6, 27.5),
}


@pytest.mark.parametrize("number", sorted(PAPER_TABLE_2))
def test_paper_scenarios_follow_table_2(number):
    rpm, low, high = PAPER_TABLE_2[number]
    scenario = load_scenario(SCENARIOS / "paper" / f"exp{number}.toml")
    assert scenario.name == f"exp{number}"
    assert scenario.speed == ConstantSpeed(rpm=rpm)
    assert scenario.feed == ConstantFeed(1500.0, 1500.0)
    assert isinstance(scenario.ambient, SeasonAmbient)
    signals = drivers.drive(scenario)
    # the recorded ambient spans exactly the table's range over the run
    assert signals.ambient_C.min() == pytest.approx(low, abs=1e-9)
    assert signals.ambient_C.max() == pytest.approx(high, abs=1e-9)
    assert scenario.initial.kind == "cold"
    assert scenario.sensors.quantum_C == pytest.approx(0.1)


def test_paper_scenarios_differ_in_seed():
    seeds = {load_scenario(SCENARIOS / "paper" / f"exp{n}.toml").seed for n in PAPER_TABLE_2}
    assert len(seeds) == 5


def test_base_scenario_defaults(tmp_path):
    scenario = load_scenario(write(tmp_path, BASE))
    assert scenario.name == "s"
    assert scenario.n_steps == 3600
    assert scenario.steps_per_sample == 60
    assert scenario.cooling.mode == "off"
    assert scenario.initial.kind == "cold"
    assert scenario.parameters == {}
    assert scenario.to_dict()["speed"] == {"rpm": 4000.0, "kind": "constant"}


def test_scenario_is_frozen(tmp_path):
    scenario = load_scenario(write(tmp_path, BASE))
    with pytest.raises(AttributeError):
        scenario.duration_s = 5  # type: ignore[misc]


BAD_CASES = {
    # name: (edit of BASE, dotted key the message must name, words it must contain)
    "unknown top-level key": ('colour = "red"\n' + BASE, "colour", "unknown key"),
    "unknown nested key": (BASE.replace("rpm = 4000", "rpm = 4000\nrmp = 5"), "speed.rmp",
                           "did you mean 'rpm'"),
    "missing field": (BASE.replace("duration_s = 3600\n", ""), "duration_s", "missing"),
    "missing nested field": (BASE.replace("high_C = 10.4\n", ""), "ambient.high_C", "missing"),
    "missing table": (BASE.replace('[feed]\nkind = "constant"\nx_mm_per_min = 1500\n'
                                   'y_mm_per_min = 1500\n', ""), "feed", "missing"),
    "wrong type": (BASE.replace("rpm = 4000", 'rpm = "fast"'), "speed.rpm", "number"),
    "boolean as number": (BASE.replace("seed = 3", "seed = true"), "seed", "integer"),
    "negative speed": (BASE.replace("rpm = 4000", "rpm = -4000"), "speed.rpm",
                       "in [0, 30000] rev/min (the FMU's declared range), got -4000"),
    "kelvin ambient": (BASE.replace("high_C = 10.4", "high_C = 283.5"), "ambient.high_C",
                       "kelvin"),
    "high below low": (BASE.replace("high_C = 10.4", "high_C = 1.0"), "ambient.high_C",
                       "below"),
    "comm step larger than duration": (BASE.replace("step_s = 1.0", "step_s = 7200"),
                                       "step_s", "larger than the duration"),
    "sample not multiple of step": (BASE.replace("sample_interval_s = 60",
                                                 "sample_interval_s = 2.5"),
                                    "sample_interval_s", "multiple"),
    "speed step after the end": (
        BASE.replace('kind = "constant"\nrpm = 4000',
                     'kind = "steps"\nsteps = [{at_s = 0, rpm = 1000}, {at_s = 7200, rpm = 2000}]'),
        "speed.steps[1].at_s", "duration"),
    "speed steps out of order": (
        BASE.replace('kind = "constant"\nrpm = 4000',
                     'kind = "steps"\nsteps = [{at_s = 600, rpm = 1000}, {at_s = 0, rpm = 2000}]'),
        "speed.steps[1].at_s", "increasing"),
    "cycle longer than duration": (
        BASE.replace('kind = "constant"\nrpm = 4000',
                     'kind = "cycles"\nrpm = 3000\non_s = 3000\noff_s = 1200'),
        "speed.on_s", "longer than the duration"),
    "unknown speed kind": (BASE.replace('kind = "constant"\nrpm', 'kind = "ramp"\nrpm'),
                           "speed.kind", "one of"),
    "unknown fault sensor": (BASE + '[[sensors.faults]]\nsensor = "T21"\nkind = "dropout"\n',
                             "sensors.faults[0].sensor", "one of"),
    "fault ends before it starts": (
        BASE + '[[sensors.faults]]\nsensor = "T3"\nkind = "dropout"\nstart_s = 600\nend_s = 60\n',
        "sensors.faults[0].end_s", "after"),
    "offset fault without offset": (BASE + '[[sensors.faults]]\nsensor = "T3"\nkind = "offset"\n',
                                    "sensors.faults[0].offset_C", "missing"),
    "cooling setpoint in kelvin": (BASE + '[cooling]\nmode = "absolute"\nsetpoint_C = 293.15\n',
                                   "cooling.setpoint_C", "kelvin"),
    "negative noise": (BASE + "[sensors]\nnoise_C = -0.1\n", "sensors.noise_C", "in [0, 5]"),
    "parameter not a number": (BASE + '[parameters]\nk_front = "high"\n', "parameters.k_front",
                               "number"),
    "continue without source": (BASE + '[initial]\nkind = "continue"\n', "initial.from",
                                "missing"),
    "continue from a scenario file": (
        BASE + '[initial]\nkind = "continue"\nfrom = "day1.toml"\n', "initial.from",
        "without .toml ('day1')"),
    "continue from nothing": (BASE + '[initial]\nkind = "continue"\nfrom = " "\n',
                              "initial.from", "empty"),
    "step too small for numpy": (BASE.replace("step_s = 1.0", "step_s = 1e-300"), "step_s",
                                 ">= 0.001"),
    "too many steps": (BASE.replace("duration_s = 3600", "duration_s = 7776000")
                       .replace("step_s = 1.0", "step_s = 0.5"), "step_s", "at most 10,000,000"),
    "speed above the studies' limit": (BASE.replace("rpm = 4000", "rpm = 1e12"), "speed.rpm",
                                       "in [0, 30000]"),
    "stepped speed above the limit": (
        BASE.replace('kind = "constant"\nrpm = 4000',
                     'kind = "steps"\nsteps = [{at_s = 0, rpm = 40001}]'),
        "speed.steps[0].rpm", "in [0, 30000]"),
    "feed above rapid traverse": (BASE.replace("x_mm_per_min = 1500", "x_mm_per_min = 1e15"),
                                  "feed.x_mm_per_min", "in [0, 60000] mm/min"),
    "speed table is a number": (BASE.replace('[speed]\nkind = "constant"\nrpm = 4000\n', "")
                                .replace("seed = 3", "seed = 3\nspeed = 4000"), "speed", "table"),
}


@pytest.mark.parametrize("case", sorted(BAD_CASES))
def test_bad_scenario_gives_one_line_naming_file_and_key(tmp_path, case):
    text, key, words = BAD_CASES[case]
    path = write(tmp_path, text, "bad_scenario.toml")
    with pytest.raises(SpindlebenchError) as info:
        load_scenario(path)
    message = str(info.value)
    assert "\n" not in message
    assert str(path) in message
    assert f"'{key}'" in message
    assert words in message


def test_invalid_toml_names_file_and_line(tmp_path):
    path = write(tmp_path, BASE + "[cooling]\nmode = \n")
    with pytest.raises(SpindlebenchError, match=r"s\.toml: not valid TOML: .*line 20"):
        load_scenario(path)


def test_missing_file(tmp_path):
    with pytest.raises(SpindlebenchError, match=r"nope\.toml: scenario file not found"):
        load_scenario(tmp_path / "nope.toml")


def test_misspelled_required_key_is_pointed_out(tmp_path):
    path = write(tmp_path, BASE.replace("duration_s =", "duraton_s ="))
    with pytest.raises(SpindlebenchError, match="'duraton_s' a misspelling"):
        load_scenario(path)


# --------------------------------------------------------------------------- measured ambient

CSV_SCENARIO = BASE.replace(
    'kind = "season"\nlow_C = 5.3\nhigh_C = 10.4\n', 'kind = "csv"\nfile = "amb.csv"\n'
)


def test_measured_ambient_is_interpolated(tmp_path):
    (tmp_path / "amb.csv").write_text("# comment\ntime_s,ambient_C\n0,10\n1800,12\n3600,11\n")
    scenario = load_scenario(write(tmp_path, CSV_SCENARIO))
    assert isinstance(scenario.ambient, MeasuredAmbient)
    values = drivers.ambient_C(scenario.ambient, np.array([0.0, 900.0, 1800.0, 2700.0, 3600.0]))
    np.testing.assert_allclose(values, [10.0, 11.0, 12.0, 11.5, 11.0])
    assert scenario.to_dict()["ambient"]["n_points"] == 3


@pytest.mark.parametrize(
    ("rows", "expected"),
    [
        ("0,10\n1800,abc\n3600,11\n", r"amb\.csv: line 4: expected numbers"),
        ("0,10\n1800,290\n3600,11\n", r"amb\.csv: line 4: ambient 290 °C is implausible"),
        ("0,10\n1800,11\n1800,11\n3600,11\n", r"amb\.csv: line 5: time 1800 s does not increase"),
        ("0,10\n1800,11\n", r"'ambient.file': .*covers 0–1800 s but the run needs 0–3600 s"),
    ],
)
def test_bad_measured_ambient_names_file_and_line(tmp_path, rows, expected):
    (tmp_path / "amb.csv").write_text("# comment\ntime_s,ambient_C\n" + rows)
    with pytest.raises(SpindlebenchError, match=expected):
        load_scenario(write(tmp_path, CSV_SCENARIO))


def test_measured_ambient_wrong_column(tmp_path):
    (tmp_path / "amb.csv").write_text("t,temp\n0,10\n3600,11\n")
    with pytest.raises(SpindlebenchError, match=r"'ambient.time_column': column 'time_s' not in"):
        load_scenario(write(tmp_path, CSV_SCENARIO))


def test_shipped_ambient_series_covers_its_scenario():
    scenario = load_scenario(SCENARIOS / "examples" / "measured_ambient.toml")
    values = drivers.drive(scenario).ambient_C
    assert 10.0 < values.min() < values.max() < 20.0


def test_non_utf8_scenario_and_ambient_csv_are_one_line(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes(BASE.replace("seed = 3", "# Grüße\nseed = 3").encode("latin-1"))
    with pytest.raises(SpindlebenchError, match=r"latin1\.toml: not valid TOML: not UTF-8"):
        load_scenario(path)
    (tmp_path / "amb.csv").write_bytes("time_s,ambient_C\n0,10\n3600,11 °C\n".encode("latin-1"))
    with pytest.raises(SpindlebenchError, match=r"'ambient.file': .*amb\.csv is not UTF-8"):
        load_scenario(write(tmp_path, CSV_SCENARIO))


@pytest.mark.parametrize(
    ("value", "scenario_name", "file_name"),
    [
        ("day1_warmup", "day1_warmup", None),
        ("run.v2", "run.v2", None),
        ("day1_warmup.json", None, "day1_warmup.json"),
        ("day1_warmup.CSV", None, "day1_warmup.json"),
        ("runs/day1", None, "day1"),
    ],
)
def test_initial_from_is_a_scenario_name_or_a_path(tmp_path, value, scenario_name, file_name):
    """No '/' and no .json/.csv: a sibling scenario, found later in the output folder."""
    path = write(tmp_path, BASE + f'[initial]\nkind = "continue"\nfrom = "{value}"\n')
    initial = load_scenario(path).initial
    assert initial.from_scenario == scenario_name
    if file_name is None:
        assert initial.from_file is None
        resolved = resolve_initial(load_scenario(path), tmp_path / "out").initial
        assert resolved.from_file == tmp_path / "out" / f"{value}.json"
    else:
        assert initial.from_file == (tmp_path / value).with_name(file_name).resolve()


def test_ambient_csv_with_a_duplicated_column_is_one_line(tmp_path):
    """Which of two 'ambient_C' columns was meant is a guess; it used to take the first."""
    (tmp_path / "amb.csv").write_text("time_s,ambient_C,ambient_C\n0,10,30\n3600,11,31\n",
                                      encoding="utf-8")
    text = BASE.replace('kind = "season"\nlow_C = 5.3\nhigh_C = 10.4',
                        'kind = "csv"\nfile = "amb.csv"')
    with pytest.raises(SpindlebenchError) as info:
        load_scenario(write(tmp_path, text))
    message = str(info.value)
    assert "\n" not in message
    assert "amb.csv: line 1: column 'ambient_C' appears more than once" in message
