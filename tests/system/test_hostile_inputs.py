"""Issue 11, "done when": a set of hostile inputs, each one line, no traceback, no new file.

Every case builds its bad input in a fresh folder, runs the real command line in-process
(``cli.main``) from that folder, and asserts: exit status != 0, exactly one line on stderr
that starts with ``error:`` and names the file (or flag) and the key, line or column, no
traceback, and not a single new file anywhere in the folder (temporary FMU extractions
included: the temp dir points into it).
"""

from __future__ import annotations

import os
import tempfile
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from conftest import QUICK, REPO
from selection_data import synthetic_experiment
from spindlebench.commands import main as cli
from spindlebench.core.paths import DEFAULT_FMU

TINY = (REPO / "scenarios" / "studies" / "tiny_sweep.toml").read_text(encoding="utf-8")


AIR = "time_s,ambient_C\n0,18\n300,18.5\n600,19\n"

Case = Callable[[Path], tuple[list[str], list[str]]]
CASES: dict[str, Case] = {}


def case(name: str) -> Callable[[Case], Case]:
    def register(build: Case) -> Case:
        assert name not in CASES
        CASES[name] = build
        return build
    return register


def write(folder: Path, name: str, text: str | bytes) -> Path:
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text, encoding="utf-8")
    return path


# --------------------------------------------------------------------------- scenarios

SCENARIO_EDITS = {
    "negative speed": (("rpm = 3000", "rpm = -3000"), "speed.rpm"),
    "speed as text": (("rpm = 3000", 'rpm = "fast"'), "speed.rpm"),
    "kelvin ambient": (("temperature_C = 18.0", "temperature_C = 291.15"),
                       "ambient.temperature_C"),
    "step larger than duration": (("step_s = 10.0", "step_s = 900"), "step_s"),
    "fractional seed": (("seed = 2", "seed = 2.5"), "seed"),
    "negative duration": (("duration_s = 600", "duration_s = -600"), "duration_s"),
    "zero sample interval": (("sample_interval_s = 60", "sample_interval_s = 0"),
                             "sample_interval_s"),
    "unknown speed kind": (('kind = "constant"\nrpm', 'kind = "warp"\nrpm'), "speed.kind"),
    "unknown ambient kind": (('kind = "constant"\ntemperature_C',
                              'kind = "weather"\ntemperature_C'), "ambient.kind"),
    "misspelt key": (("seed = 2", "sed = 2"), "sed"),
    "negative feed": (("x_mm_per_min = 1500", "x_mm_per_min = -1"), "feed.x_mm_per_min"),
    "tiny step": (("step_s = 10.0", "step_s = 1e-9"), "step_s"),
    "NaN ambient": (("temperature_C = 18.0", "temperature_C = nan"), "ambient.temperature_C"),
    "inf duration": (("duration_s = 600", "duration_s = inf"), "duration_s"),
}
for _label, ((_old, _new), _key) in SCENARIO_EDITS.items():
    def _build(tmp: Path, old: str = _old, new: str = _new, key: str = _key):
        scenario = write(tmp, "bad.toml", QUICK.replace(old, new, 1))
        return ["simulate", str(scenario), "-o", "out"], [str(scenario), key]
    case(f"scenario: {_label}")(_build)


# Issue 25: the inputs against the FMU's declared min/max (35 000 rpm ran to the end).
INPUT_EDITS = {
    "speed above the FMU's declared max": (("rpm = 3000", "rpm = 35000"),
                                           ["key 'speed.rpm'", "30000",
                                            "the FMU's declared range"]),
}
for _label, ((_old, _new), _expected) in INPUT_EDITS.items():
    def _build(tmp: Path, old: str = _old, new: str = _new, expected: list = _expected):
        scenario = write(tmp, "bad.toml", QUICK.replace(old, new, 1))
        return ["simulate", str(scenario), "-o", "out"], [str(scenario), *expected]
    case(f"scenario: {_label}")(_build)


@case("scenario: TOML syntax error")
def _(tmp):
    scenario = write(tmp, "bad.toml", QUICK + "\n[speed\n")
    return ["simulate", str(scenario), "-o", "out"], [str(scenario), "line"]


@case("scenario: not UTF-8")
def _(tmp):
    scenario = write(tmp, "bad.toml", QUICK.encode() + b"# \xff\xfe\n")
    return ["simulate", str(scenario), "-o", "out"], [str(scenario), "UTF-8"]


@case("scenario: missing file")
def _(tmp):
    return ["simulate", str(tmp / "none.toml"), "-o", "out"], ["none.toml"]


@case("scenario: unknown parameter")
def _(tmp):
    scenario = write(tmp, "bad.toml", QUICK + "\n[parameters]\nno_such_thing = 1\n")
    return ["simulate", str(scenario), "-o", "out"], [str(scenario), "parameters.no_such_thing"]


@case("scenario: cooling set as a parameter")
def _(tmp):
    scenario = write(tmp, "bad.toml", QUICK + "\n[parameters]\ncooling_enabled = 1\n")
    return ["simulate", str(scenario), "-o", "out"], [str(scenario), "parameters.cooling_enabled"]


@case("scenario: parameter below the FMU's declared min")
def _(tmp):
    scenario = write(tmp, "bad.toml", QUICK + "\n[parameters]\nh_nat = -100\n")
    return (["simulate", str(scenario), "-o", "out"],
            [str(scenario), "parameters.h_nat", "must be ≥", "got -100"])


@case("scenario: parameter above the FMU's declared max")
def _(tmp):
    scenario = write(tmp, "bad.toml", QUICK + "\n[parameters]\nh_nat = 1e6\n")
    return (["simulate", str(scenario), "-o", "out"],
            [str(scenario), "parameters.h_nat", "must be ≤"])


@case("scenario: zero heat capacity")
def _(tmp):
    scenario = write(tmp, "bad.toml", QUICK + "\n[parameters]\nfront_bearing_C = 0\n")
    return (["simulate", str(scenario), "-o", "out"],
            [str(scenario), "parameters.front_bearing_C", "must be ≥"])


@case("scenario: continue from a missing sidecar")
def _(tmp):
    scenario = write(tmp, "bad.toml", QUICK + '\n[initial]\nkind = "continue"\nfrom = "x.json"\n')
    return ["simulate", str(scenario), "-o", "out"], [str(scenario), "initial.from"]


@case("scenario: continue from a non-UTF-8 sidecar")
def _(tmp):
    write(tmp, "x.json", b"\xff\xfe{}")
    scenario = write(tmp, "bad.toml", QUICK + '\n[initial]\nkind = "continue"\nfrom = "x.json"\n')
    return ["simulate", str(scenario), "-o", "out"], [str(scenario), "initial.from", "x.json"]


AMBIENT_FILES = {
    "extra field": ("time_s,ambient_C\n0,18\n300,18.5,7\n600,19\n", "line 3"),
    "time goes back": ("time_s,ambient_C\n0,18\n300,18.5\n200,19\n600,19\n", "line 4"),
    "kelvin": ("time_s,ambient_C\n0,291\n600,292\n", "line 2"),
    "text cell": ("time_s,ambient_C\n0,18\n300,warm\n600,19\n", "line 3"),
    "missing column": ("time_s,air_C\n0,18\n600,19\n", "ambient.value_column"),
    "too short": ("time_s,ambient_C\n0,18\n300,19\n", "ambient.file"),
    "repeated column": ("time_s,ambient_C,ambient_C\n0,18,18\n600,19,19\n", "line 1"),
}
for _label, (_text, _where) in AMBIENT_FILES.items():
    def _build(tmp: Path, text: str = _text, where: str = _where):
        write(tmp, "air.csv", text)
        scenario = write(tmp, "s.toml", QUICK.replace(
            'kind = "constant"\ntemperature_C = 18.0', 'kind = "csv"\nfile = "air.csv"'))
        return ["simulate", str(scenario), "-o", "out"], [where, "air.csv"]
    case(f"ambient CSV: {_label}")(_build)


# --------------------------------------------------------------------------- simulate flags


@case("simulate: negative seed")
def _(tmp):
    scenario = write(tmp, "s.toml", QUICK)
    return ["simulate", str(scenario), "-o", "out", "--seed", "-1"], ["--seed"]


@case("simulate: -o names a text file")
def _(tmp):
    one = write(tmp, "a/one.toml", QUICK)
    write(tmp, "a/two.toml", QUICK)
    return ["simulate", str(one.parent), "-o", "x.txt"], ["x.txt"]


@case("simulate: directory without scenarios")
def _(tmp):
    (tmp / "empty").mkdir()
    return ["simulate", str(tmp / "empty"), "-o", "out"], ["empty", ".toml"]


# --------------------------------------------------------------------------- FMUs


def fmu_variant(tmp: Path, name: str, edit: Callable[[str, bytes], bytes]) -> Path:
    target = tmp / name
    with zipfile.ZipFile(DEFAULT_FMU) as source, zipfile.ZipFile(target, "w") as out:
        for info in source.infolist():
            out.writestr(info, edit(info.filename, source.read(info)))
    return target


@case("FMU: bad CRC inside the zip")
def _(tmp):
    fmu = fmu_variant(tmp, "crc.fmu", lambda name, data: data)
    raw = bytearray(fmu.read_bytes())
    with zipfile.ZipFile(fmu) as archive:
        info = next(i for i in archive.infolist() if i.filename.startswith("binaries/"))
    start = info.header_offset + 30 + len(info.filename) + len(info.extra) + 1000
    raw[start:start + 16] = bytes(16)
    fmu.write_bytes(bytes(raw))
    scenario = write(tmp, "s.toml", QUICK)
    return ["simulate", str(scenario), "-o", "out", "--fmu", str(fmu)], [str(fmu), "binaries/"]


@case("FMU: empty shared library")
def _(tmp):
    fmu = fmu_variant(tmp, "empty.fmu",
                      lambda name, data: b"" if name.startswith("binaries/") else data)
    scenario = write(tmp, "s.toml", QUICK)
    return ["simulate", str(scenario), "-o", "out", "--fmu", str(fmu)], [str(fmu), "binaries/"]


@case("FMU: not a zip")
def _(tmp):
    fmu = write(tmp, "junk.fmu", b"not a zip at all")
    scenario = write(tmp, "s.toml", QUICK)
    return ["simulate", str(scenario), "-o", "out", "--fmu", str(fmu)], [str(fmu)]


@case("FMU: missing")
def _(tmp):
    scenario = write(tmp, "s.toml", QUICK)
    return ["simulate", str(scenario), "-o", "out", "--fmu", "none.fmu"], ["none.fmu"]


@case("FMU: modelDescription.xml is not XML")
def _(tmp):
    fmu = fmu_variant(tmp, "xml.fmu", lambda name, data: b"<fmi" if name ==
                      "modelDescription.xml" else data)
    scenario = write(tmp, "s.toml", QUICK)
    return ["simulate", str(scenario), "-o", "out", "--fmu", str(fmu)], [str(fmu)]


# --------------------------------------------------------------------------- recordings


def recording_text(seed: int = 0) -> str:
    return synthetic_experiment(seed).to_csv(index=False)


def evaluate_case(tmp: Path, train_text: str | bytes, *extra: str) -> list[str]:
    train = write(tmp, "train.csv", train_text)
    test = write(tmp, "test.csv", recording_text(1))
    return ["evaluate", "--train", str(train), "--test", str(test), "--target", "drift_um",
            "--clusters", "2", *extra]


def edited(edit: Callable[[list[str]], list[str]]) -> str:
    return "\n".join(edit(recording_text().splitlines())) + "\n"


def set_cell(lines: list[str], line: int, column: int, value: str) -> list[str]:
    cells = lines[line - 1].split(",")
    cells[column] = value
    lines[line - 1] = ",".join(cells)
    return lines


RECORDINGS = {
    "empty file": ("", ["train.csv", "empty"]),
    "header only": (recording_text().splitlines()[0] + "\n", ["train.csv", "row"]),
    "one row": ("\n".join(recording_text().splitlines()[:2]) + "\n", ["train.csv", "row"]),
    "two rows": ("\n".join(recording_text().splitlines()[:3]) + "\n",
                 ["train.csv", "2 clusters"]),
    "text cell": (edited(lambda ls: set_cell(ls, 5, 1, "hot")), ["train.csv", "line 5"]),
    "inf cell": (edited(lambda ls: set_cell(ls, 7, 1, "inf")), ["train.csv", "line 7"]),
    "empty cell": (edited(lambda ls: set_cell(ls, 9, 1, "")), ["train.csv", "line 9"]),
    "NaN cell": (edited(lambda ls: set_cell(ls, 9, 1, "NaN")), ["train.csv", "line 9"]),
    "short row": (edited(lambda ls: [*ls[:10], ",".join(ls[10].split(",")[:3]), *ls[11:]]),
                  ["train.csv", "line 11"]),
    "long row": (edited(lambda ls: [*ls[:10], ls[10] + ",1", *ls[11:]]),
                 ["train.csv", "line 11", "field(s)"]),
    "repeated column": (edited(lambda ls: [ls[0].replace("T6", "T1"), *ls[1:]]),
                        ["train.csv", "line 1"]),
    "time goes back": (edited(lambda ls: set_cell(ls, 6, 0, "0")), ["train.csv", "line 6"]),
    "sentinel 9.9e37": (edited(lambda ls: set_cell(ls, 58, 2, "9.9e37")),
                        ["train.csv", "line 58", "column"]),
    "below absolute zero": (edited(lambda ls: set_cell(ls, 12, 2, "-9999")),
                            ["train.csv", "line 12", "column"]),
    "not UTF-8": (recording_text().encode() + b"\xff\xfe\n", ["train.csv", "line", "UTF-8"]),
    "semicolons read with comma": (recording_text().replace(",", ";"),
                                   ["train.csv", "line 1", "';'"]),
    "empty column name": (edited(lambda ls: [ls[0].replace("T6", ""), *ls[1:]]),
                          ["train.csv", "line 1", "no name"]),
}
#: Flags a recording case needs besides the defaults.
RECORDING_FLAGS = {"semicolons read with comma": ["--delimiter", ","]}
for _label, (_text, _expect) in RECORDINGS.items():
    def _build(tmp: Path, text: str | bytes = _text, expect: list[str] = _expect,
               label: str = _label):
        return evaluate_case(tmp, text, *RECORDING_FLAGS.get(label, [])), expect
    case(f"recording: {_label}")(_build)


EVALUATE_FLAGS = {
    "target not found": (["--target", "dz_um"], ["train.csv", "dz_um"]),
    "sensor not found": (["--sensors", "T1,T99"], ["train.csv", "T99"]),
    "sensor pattern matches nothing": (["--sensors", "Q*"], ["train.csv", "Q*"]),
    "target is a sensor": (["--sensors", "T1,drift_um"], ["train.csv", "drift_um"]),
    "time column not found": (["--time-column", "Zeit"], ["train.csv", "--time-column"]),
    "exclude matches nothing": (["--exclude", "nothing"], ["train.csv", "--exclude"]),
    "bad delimiter": (["--delimiter", "x"], ["--delimiter"]),
    "bad decimal": (["--decimal", ";"], ["--decimal"]),
    "zero clusters": (["--clusters", "0"], ["--clusters"]),
    "too many clusters": (["--clusters", "99"], ["--clusters", "train.csv"]),
    "copy of the target": (["--sensors", "T1,T6,drift_copy"], ["train.csv", "drift_copy"]),
    "json into a folder": (["--json", "."], ["--json .", "is a directory"]),
    "unknown time unit": (["--time-unit", "fortnight"], ["--time-unit"]),
    "unknown encoding": (["--encoding", "klingon"], ["--encoding klingon"]),
    "speed column not found": (["--speed-column", "Drehzahl"], ["train.csv", "Drehzahl"]),
    "target as the time column": (["--time-column", "drift_um"], ["train.csv", "time column"]),
    "time column named as a sensor": (["--sensors", "T1,time_s"], ["train.csv", "'time_s'"]),
}
for _label, (_flags, _expect) in EVALUATE_FLAGS.items():
    def _build(tmp: Path, flags: list[str] = _flags, expect: list[str] = _expect):
        frame = synthetic_experiment(0)
        frame["drift_copy"] = 0.5 * frame["drift_um"] + 1e-6 * np.arange(len(frame))
        argv = evaluate_case(tmp, frame.to_csv(index=False))
        test = synthetic_experiment(1)
        test["drift_copy"] = test["drift_um"]
        write(tmp, "test.csv", test.to_csv(index=False))
        for flag in flags[::2]:  # a flag given here replaces the default one
            if flag in argv:
                at = argv.index(flag)
                del argv[at:at + 2]
        return argv + flags, expect
    case(f"evaluate: {_label}")(_build)


@case("evaluate: train recording missing")
def _(tmp):
    argv = evaluate_case(tmp, recording_text())
    argv[argv.index("--train") + 1] = str(tmp / "none.csv")
    return argv, ["none.csv", "not found"]


@case("evaluate: train recording is a folder")
def _(tmp):
    argv = evaluate_case(tmp, recording_text())
    (tmp / "dir.csv").mkdir()
    argv[argv.index("--train") + 1] = str(tmp / "dir.csv")
    return argv, ["dir.csv", "not a file"]


@case("evaluate: test recording lacks a sensor")
def _(tmp):
    argv = evaluate_case(tmp, recording_text())
    write(tmp, "test.csv", synthetic_experiment(1).drop(columns="T6").to_csv(index=False))
    return argv, ["test.csv", "T6"]


# --------------------------------------------------------------------------- paper


@case("paper: recordings folder missing")
def _(tmp):
    return ["paper", "--recordings", str(tmp / "nothing")], ["nothing"]


@case("paper: an experiment CSV is a folder")
def _(tmp):
    for i in range(1, 5):
        write(tmp, f"recs/exp{i}.csv", recording_text(i))
    (tmp / "recs" / "exp5.csv").mkdir()
    sensors = "T1,T6,T8,T10,T13,T16"
    return (["paper", "--recordings", str(tmp / "recs"), "--sensors-all", sensors, "--six",
             sensors], ["exp5.csv", "folder"])


@case("paper: config not UTF-8")
def _(tmp):
    for i in range(1, 6):
        write(tmp, f"recs/exp{i}.csv", recording_text(i))
    config = write(tmp, "p.toml", b"\xff\xfe")
    return ["paper", "--recordings", str(tmp / "recs"), "--config", str(config)], ["p.toml"]


# ------------------------------------------------- column roles on the other commands


def role_frame(time_column: str = "time_s"):
    """A synthetic recording with a copy of the target; ``time_column=None`` drops time_s."""
    frame = synthetic_experiment(0)
    frame["drift_copy"] = 0.5 * frame["drift_um"] + 1e-6 * np.arange(len(frame))
    return frame.drop(columns="time_s") if time_column is None else frame


def role_recording(tmp: Path, frame=None, **csv) -> Path:
    frame = role_frame() if frame is None else frame
    return write(tmp, "rec.csv", frame.to_csv(index=False, **csv))


def going_back(tmp: Path) -> Path:
    frame = role_frame()
    clock = frame["time_s"].to_numpy().copy()
    clock[20] = clock[10]
    return role_recording(tmp, frame.assign(clock_s=clock))


def sentinel(tmp: Path) -> Path:
    frame = role_frame()
    frame.loc[56, "T6"] = 9.9e37
    return role_recording(tmp, frame)


def with_column(name: str, values) -> Callable[[Path], Path]:
    """The role recording with one more column (a time axis another logger wrote)."""
    def make(tmp: Path) -> Path:
        frame = role_frame()
        return role_recording(tmp, frame.assign(**{name: values(frame)}))
    return make


def latin1(tmp: Path) -> Path:
    frame = role_frame().rename(columns={"T1": "T1 [°C]"})
    return write(tmp, "rec.csv", frame.to_csv(index=False).encode("latin-1"))


def constant_target(tmp: Path) -> Path:
    return role_recording(tmp, role_frame().assign(drift_um=3.0))


ROLE_CASES = {
    # issue 25: time units, sample indices, dates, encodings, roles
    "sample index as time": (with_column("sample", lambda f: range(len(f))),
                             ["--time-column", "sample"], ["rec.csv", "'sample'",
                                                           "sample index", "--time-unit"]),
    "time unit contradicts the name": (with_column("Zeit [min]", lambda f: f["time_s"] / 60),
                                       ["--time-column", "Zeit [min]", "--time-unit", "h"],
                                       ["rec.csv", "--time-unit h", "'Zeit [min]'"]),
    "bad time unit": (lambda t: role_recording(t), ["--time-unit", "fortnight"],
                      ["--time-unit"]),
    "time unit without a time column": (lambda t: role_recording(t, role_frame(None)),
                                        ["--time-unit", "min"], ["rec.csv", "--time-unit"]),
    "date column with a bad cell": (with_column("stamp", lambda f: [
        "2024-03-01 08:00:00" if i != 7 else "yesterday" for i in range(len(f))]),
        ["--time-column", "stamp"], ["rec.csv", "line 9", "'stamp'", "date/time"]),
    "Latin-1 without --encoding": (latin1, [], ["rec.csv", "not UTF-8", "--encoding"]),
    "unknown encoding": (lambda t: role_recording(t), ["--encoding", "klingon"],
                         ["--encoding klingon"]),
    "speed column not found": (lambda t: role_recording(t), ["--speed-column", "Drehzahl"],
                               ["rec.csv", "--speed-column 'Drehzahl'"]),
    "speed column is a sensor": (lambda t: role_recording(t),
                                 ["--sensors", "T1,T6", "--speed-column", "T6"],
                                 ["rec.csv", "--speed-column 'T6'"]),
    "target as the time column": (lambda t: role_recording(t), ["--time-column", "drift_um"],
                                  ["rec.csv", "'drift_um'", "time column"]),
    "time column named as a sensor": (lambda t: role_recording(t),
                                      ["--sensors", "T1,time_s"],
                                      ["rec.csv", "--sensors", "'time_s'"]),
    "copy of the target": (lambda t: role_recording(t), ["--sensors", "T1,T6,drift_copy"],
                           ["rec.csv", "drift_copy", "|r|"]),
    "no time column": (lambda t: role_recording(t, role_frame(None)), [],
                       ["rec.csv", "no time column 'time_s'"]),
    "time column not found": (lambda t: role_recording(t), ["--time-column", "Zeit"],
                              ["rec.csv", "--time-column 'Zeit'"]),
    "time column goes back": (going_back, ["--time-column", "clock_s"],
                              ["rec.csv", "line 22", "does not increase"]),
    "exclude matches nothing": (lambda t: role_recording(t), ["--exclude", "nothing"],
                                ["rec.csv", "--exclude 'nothing'"]),
    "sensor pattern matches nothing": (lambda t: role_recording(t), ["--sensors", "Q*"],
                                       ["rec.csv", "Q*"]),
    "decimal comma read as point": (lambda t: role_recording(t, sep=";", decimal=","),
                                    ["--decimal", "."], ["rec.csv", "line 2", "column"]),
    "semicolons read with comma": (lambda t: role_recording(t, sep=";"),
                                   ["--delimiter", ","], ["rec.csv", "line 1", "';'"]),
    "sentinel in a sensor": (sentinel, [], ["rec.csv", "line 58", "column 'T6'"]),
    "bad decimal flag": (lambda t: role_recording(t), ["--decimal", ";"], ["--decimal"]),
}
#: What each command reading recordings is given besides the recording and the role flags.
ROLE_COMMANDS = {
    "fingerprint": lambda rec: ["fingerprint", str(rec), "--target", "drift_um"],
    "plot": lambda rec: ["plot", str(rec), "--target", "drift_um", "-o", "fig.png"],
}
for _command, _argv in ROLE_COMMANDS.items():
    for _label, (_make, _flags, _expect) in ROLE_CASES.items():
        if _command == "plot" and _label == "copy of the target":
            continue  # plot draws a copy of the target (it fits nothing)
        def _build(tmp: Path, make=_make, flags=_flags, expect=_expect, argv=_argv):
            return argv(make(tmp)) + flags, expect
        case(f"{_command}: {_label}")(_build)


@case("fingerprint: constant target")
def _(tmp):
    return ["fingerprint", str(constant_target(tmp)), "--target", "drift_um"], [
        "rec.csv", "'drift_um' is constant"]


CALIBRATION_MAP = """[inputs]
spindle_speed_rpm = "spindle_speed_rpm"
feed_x_mm_per_min = 0.0
feed_y_mm_per_min = 0.0
ambient_C = "unknown"
[error]
column = "drift_um"
[temperatures]
T1 = "T1"
T6 = "T6"
"""


@case("calibrate: no time column")
def _(tmp):
    rec = role_recording(tmp, role_frame(None))
    mapping = write(tmp, "map.toml", CALIBRATION_MAP)
    return (["calibrate", str(rec), "--map", str(mapping), "-o", "m.toml"],
            ["rec.csv", "no time column 'time_s'"])


@case("calibrate: semicolons read with comma")
def _(tmp):
    rec = role_recording(tmp, sep=";")
    mapping = write(tmp, "map.toml", CALIBRATION_MAP)
    return (["calibrate", str(rec), "--map", str(mapping), "-o", "m.toml", "--delimiter", ","],
            ["rec.csv", "line 1", "';'"])


@case("paper: no time column")
def _(tmp):
    for i in range(1, 6):
        write(tmp, f"recs/exp{i}.csv", synthetic_experiment(i).drop(columns="time_s")
              .to_csv(index=False))
    sensors = "T1,T6,T8,T10,T13,T16"
    return (["paper", "--recordings", str(tmp / "recs"), "--sensors-all", sensors, "--six",
             sensors], ["exp1.csv", "no time column 'time_s'"])


@case("evaluate: decimal comma read as point")
def _(tmp):
    argv = evaluate_case(tmp, synthetic_experiment(0).to_csv(index=False, sep=";",
                                                               decimal=","))
    return [*argv, "--decimal", "."], ["train.csv", "line 2", "column"]


# --------------------------------------------------------------------------- studies


STUDY_EDITS = {
    "zero replicas": (("replicas = 2", "replicas = 0"), "study.replicas"),
    "unknown month": (('months = ["Jan", "Jul"]', 'months = ["Jan", "Juli"]'), "axes.months"),
    "unknown climate": (('climate = "chongqing"', 'climate = "atlantis"'), "study.climate"),
    "name escapes results/": (('name = "tiny-sweep"', 'name = "../../escape"'), "study.name"),
    "negative speed": (("speeds_rpm = [2000, 4000]", "speeds_rpm = [-2000, 4000]"),
                       "axes.speeds_rpm"),
    "speed above the FMU's declared max": (("speeds_rpm = [2000, 4000]",
                                            "speeds_rpm = [2000, 35000]"), "axes.speeds_rpm"),
    "unknown parameter": (("[training]", "[parameters]\nno_such = 1.0\n\n[training]"),
                          "parameters.no_such"),
}
for _label, ((_old, _new), _key) in STUDY_EDITS.items():
    def _build(tmp: Path, old: str = _old, new: str = _new, key: str = _key):
        study = write(tmp, "study.toml", TINY.replace(old, new, 1))
        return ["sweep", str(study), "--workers", "0", "--no-progress"], [str(study), key]
    case(f"study: {_label}")(_build)


@case("study: parameter outside the FMU's declared bounds")
def _(tmp):
    study = write(tmp, "study.toml", TINY + "\n[parameters]\nh_nat = -100.0\n")
    return (["sweep", str(study), "--workers", "0", "--no-progress"],
            [str(study), "parameters.h_nat", "must be ≥ 0"])


@case("study: results folder holds other files")
def _(tmp):
    study = write(tmp, "study.toml", TINY)
    write(tmp, "taken/notes.txt", "mine")
    return (["sweep", str(study), "-o", str(tmp / "taken"), "--workers", "0", "--no-progress"],
            ["taken", "not a study results folder"])


@case("study: both --workers and --dask-address")
def _(tmp):
    study = write(tmp, "study.toml", TINY)
    return (["sweep", str(study), "--workers", "1", "--dask-address", "tcp://h:1"],
            ["--dask-address"])


# --------------------------------------------------------------------------- build


@case("build: segments out of range")
def _(tmp):
    return ["build", "--segments", "100000", "--out", str(tmp / "o.fmu")], ["--segments"]


@case("build: no model source")
def _(tmp):
    (tmp / "models").mkdir()
    return ["build", "--models", str(tmp / "models"), "--out", str(tmp / "o.fmu")], ["models"]


@case("build: model source not UTF-8")
def _(tmp):
    write(tmp, "models/SpindleBench.mo", b"package SpindleBench\n\xff\nend SpindleBench;\n")
    return (["build", "--models", str(tmp / "models"), "--out", str(tmp / "o.fmu")],
            ["SpindleBench.mo:2"])


# --------------------------------------------------------------------------- issue 25

# Special files as inputs: a FIFO blocked forever (no writer), /dev/zero never ended (it
# filled the memory). Each input kind of each command, as a FIFO and as /dev/zero.
def fifo(tmp: Path, name: str) -> Path:
    import os

    path = tmp / name
    os.mkfifo(path)
    return path


SPECIAL_INPUTS: dict[str, Callable[[Path, Path], list[str]]] = {
    "simulate scenario": lambda tmp, p: ["simulate", str(p), "-o", "out.csv"],
    "sweep study": lambda tmp, p: ["sweep", str(p), "-o", "out", "--workers", "0", "-q"],
    "place study": lambda tmp, p: ["place", str(p), "-o", "out", "--workers", "0", "-q"],
    "compensate study": lambda tmp, p: ["compensate", str(p), "-o", "out"],
    "plot recording": lambda tmp, p: ["plot", str(p), "-o", "fig.png"],
    "fingerprint recording": lambda tmp, p: ["fingerprint", str(p), "--target", "drift_um"],
    "evaluate train": lambda tmp, p: ["evaluate", "--train", str(p), "--test",
                                      str(write(tmp, "test.csv", recording_text(1))),
                                      "--target", "drift_um", "--clusters", "2"],
    "evaluate test": lambda tmp, p: ["evaluate", "--train",
                                     str(write(tmp, "train.csv", recording_text(0))),
                                     "--test", str(p), "--target", "drift_um",
                                     "--clusters", "2"],
    "calibrate recording": lambda tmp, p: ["calibrate", str(p), "--map",
                                           str(write(tmp, "map.toml", CALIBRATION_MAP)),
                                           "-o", "m.toml"],
    "calibrate map": lambda tmp, p: ["calibrate", str(role_recording(tmp)), "--map", str(p),
                                     "-o", "m.toml"],
    "simulate machine": lambda tmp, p: ["simulate", str(write(tmp, "q.toml", QUICK)),
                                        "-o", "out.csv", "--machine", str(p)],
    "simulate FMU": lambda tmp, p: ["simulate", str(write(tmp, "q.toml", QUICK)),
                                    "-o", "out.csv", "--fmu", str(p)],
    "paper config": lambda tmp, p: ["paper", "--recordings", str(tmp), "--config", str(p),
                                    "--out", str(tmp / "o")],
    "measured ambient": lambda tmp, p: ["simulate", str(write(tmp, "q.toml", QUICK.replace(
        'kind = "constant"\ntemperature_C = 18.0',
        f'kind = "csv"\nfile = "{p}"\ntime_column = "time_s"\nvalue_column = "ambient_C"'))),
        "-o", "out.csv"],
}
for _label, _argv in SPECIAL_INPUTS.items():
    def _fifo(tmp: Path, argv=_argv, label=_label):
        path = fifo(tmp, "in.toml" if "toml" in label or "study" in label or "scenario" in label
                    or "map" in label or "machine" in label else "in.csv")
        return argv(tmp, path), [str(path), "FIFO", "not a regular file"]

    def _zero(tmp: Path, argv=_argv):
        return argv(tmp, Path("/dev/zero")), ["/dev/zero", "character device"]
    case(f"special file: FIFO as {_label}")(_fifo)
    if _label != "simulate machine":  # a name or a .toml path: /dev/zero is neither
        case(f"special file: /dev/zero as {_label}")(_zero)


# An output over an input, a device, a FIFO or the root folder: the input was replaced.
@case("output: evaluate --json naming the training CSV")
def _(tmp):
    argv = evaluate_case(tmp, recording_text())
    return [*argv, "--json", argv[2]], ["--json", "train.csv", "inputs"]


@case("output: evaluate --json naming a test CSV")
def _(tmp):
    argv = evaluate_case(tmp, recording_text())
    return [*argv, "--json", argv[4]], ["--json", "test.csv", "inputs"]


@case("output: evaluate --json onto a character device")
def _(tmp):
    return [*evaluate_case(tmp, recording_text()), "--json", "/dev/null"], [
        "--json /dev/null", "character device"]


@case("output: evaluate --json onto a FIFO")
def _(tmp):
    out = fifo(tmp, "out.json")
    return [*evaluate_case(tmp, recording_text()), "--json", str(out)], [
        "--json", "out.json", "FIFO"]


@case("output: fingerprint --json onto a FIFO")
def _(tmp):
    out = fifo(tmp, "out.json")
    return ["fingerprint", str(role_recording(tmp)), "--target", "drift_um", "--json",
            str(out)], ["--json", "out.json", "FIFO"]


@case("output: plot -o onto a FIFO")
def _(tmp):
    out = fifo(tmp, "fig.png")
    return ["plot", str(role_recording(tmp)), "-o", str(out)], ["-o", "fig.png", "FIFO"]


@case("output: simulate -o naming its measured-ambient CSV")
def _(tmp):
    air = write(tmp, "air.csv", AIR)
    scenario = write(tmp, "q.toml", QUICK.replace(
        'kind = "constant"\ntemperature_C = 18.0',
        'kind = "csv"\nfile = "air.csv"\ntime_column = "time_s"\nvalue_column = "ambient_C"'))
    return ["simulate", str(scenario), "-o", str(air)], ["-o", "air.csv", "inputs"]


for _where, _make in (("/", lambda tmp: "/"), ("a character device", lambda tmp: "/dev/null"),
                      ("a FIFO", lambda tmp: str(fifo(tmp, "out")))):
    for _command in ("simulate", "sweep", "place"):
        def _build(tmp: Path, make=_make, command=_command):
            target = make(tmp)
            source = write(tmp, "study.toml", TINY if command == "sweep" else
                           QUICK if command == "simulate" else
                           (REPO / "scenarios" / "studies" / "tiny_placement.toml")
                           .read_text(encoding="utf-8"))
            extra = [] if command == "simulate" else ["--workers", "0", "-q"]
            return [command, str(source), "-o", target, *extra], ["-o", Path(target).name
                                                                   or "/"]
        if not (_where == "/" and _command in ("simulate", "sweep")):  # those two are below
            case(f"output: {_command} -o {_where}")(_build)


@case("output: fingerprint --figure onto a FIFO")
def _(tmp):
    out = fifo(tmp, "fig.png")
    return (["fingerprint", str(role_recording(tmp)), "--target", "drift_um", "--figure",
             str(out)], ["--figure", "fig.png", "FIFO"])


@case("output: calibrate -o onto a FIFO")
def _(tmp):
    mapping = write(tmp, "map.toml", CALIBRATION_MAP)
    out = fifo(tmp, "m.toml")
    return (["calibrate", str(role_recording(tmp)), "--map", str(mapping), "-o", str(out)],
            ["-o", "m.toml", "FIFO"])


@case("output: simulate -o the root folder")
def _(tmp):
    return ["simulate", str(write(tmp, "q.toml", QUICK)), "-o", "/"], ["-o /", "root folder"]


@case("output: sweep -o the root folder")
def _(tmp):
    study = write(tmp, "study.toml", TINY)
    return ["sweep", str(study), "-o", "/", "--workers", "0", "-q"], ["-o /", "root folder"]


@case("output: compensate -o a character device")
def _(tmp):
    study = write(tmp, "study.toml", TINY)
    return ["compensate", str(study), "-o", "/dev/null"], ["-o /dev/null", "character device"]


@case("output: calibrate -o naming its map")
def _(tmp):
    mapping = write(tmp, "map.toml", CALIBRATION_MAP)
    return (["calibrate", str(role_recording(tmp)), "--map", str(mapping), "-o",
             str(mapping)], ["-o", "map.toml", "inputs"])


# Numbers: seeds out of the generators' range, nested TOML, Unicode digits, huge scenarios.
for _seed in ("18446744073709551616", "-1", "4294967296"):
    def _build(tmp: Path, seed: str = _seed):
        return [*evaluate_case(tmp, recording_text()), "--method", "kmeans", "--seed",
                seed], ["--seed", seed, "2**32 - 1"]
    case(f"evaluate: seed {_seed}")(_build)


@case("paper: seed 2**64 in its config")
def _(tmp):
    for i in range(1, 3):
        write(tmp, f"runs/exp{i}.csv", recording_text(i))
    config = write(tmp, "config.toml", 'train = "exp1"\ntests = ["exp2"]\n'
                   'seed = 18446744073709551616\n')
    return ["paper", "--recordings", str(tmp / "runs"), "--config", str(config), "--out",
            str(tmp / "o")], ["config.toml", "seed", "2**32 - 1"]


@case("study: methods seed 2**64")
def _(tmp):
    study = write(tmp, "study.toml", TINY.replace("[methods]", "[methods]\nseed = "
                                                  "18446744073709551616"))
    return ["sweep", str(study), "--workers", "0", "-q"], [str(study), "methods.seed"]


DEEP = {"arrays": "x = " + "[" * 3000 + "]" * 3000 + "\n",
        "inline tables": "x = " + "{a = " * 1000 + "1" + "}" * 1000 + "\n"}
for _what, _text in DEEP.items():
    def _scenario(tmp: Path, text: str = _text):
        scenario = write(tmp, "deep.toml", QUICK + text)
        return ["simulate", str(scenario), "-o", "out.csv"], [str(scenario), "nested too deeply"]

    def _study(tmp: Path, text: str = _text):
        study = write(tmp, "deep.toml", text + TINY)
        return ["sweep", str(study), "--workers", "0", "-q"], [str(study), "nested too deeply"]

    def _map(tmp: Path, text: str = _text):
        mapping = write(tmp, "deep.toml", text + CALIBRATION_MAP)
        return (["calibrate", str(role_recording(tmp)), "--map", str(mapping), "-o", "m.toml"],
                [str(mapping), "nested too deeply"])
    case(f"scenario: deeply nested {_what}")(_scenario)
    case(f"study: deeply nested {_what}")(_study)
    case(f"calibrate: map with deeply nested {_what}")(_map)


for _label, _cell in (("full-width digits", "１８"), ("Arabic-Indic digits", "١٨"),
                      ("superscript digits", "¹⁸")):
    def _build(tmp: Path, cell: str = _cell):
        write(tmp, "air.csv", f"time_s,ambient_C\n0,18\n300,{cell}\n600,19\n")
        scenario = write(tmp, "q.toml", QUICK.replace(
            'kind = "constant"\ntemperature_C = 18.0',
            'kind = "csv"\nfile = "air.csv"\ntime_column = "time_s"\n'
            'value_column = "ambient_C"'))
        return ["simulate", str(scenario), "-o", "out.csv"], ["air.csv", "line 3", "ASCII"]
    case(f"ambient CSV: {_label}")(_build)


@case("recording: a 3 GB sparse file")
def _(tmp):
    big = tmp / "big.csv"
    with open(big, "wb") as handle:  # sparse: no disk space used
        handle.truncate(3 * 1024**3)
    return ["plot", str(big), "-o", "fig.png"], ["big.csv", "too large"]


@case("recording: a 200 000-character header field")
def _(tmp):
    rec = write(tmp, "rec.csv", "time_s," + "T" * 200_000 + ",drift_um\n0,1,0\n60,2,1\n")
    return ["plot", str(rec), "-o", "fig.png"], ["rec.csv", "line 1", "field limit"]


@case("scenario: 7.8 M samples (90 days at 1 s)")
def _(tmp):
    scenario = write(tmp, "big.toml", QUICK.replace("duration_s = 600", "duration_s = 7776000")
                     .replace("step_s = 10.0", "step_s = 1.0")
                     .replace("sample_interval_s = 60", "sample_interval_s = 1"))
    return ["simulate", str(scenario), "-o", "out.csv"], [str(scenario), "sample_interval_s",
                                                           "at most 1,000,000"]


for _command in ("sweep", "place", "compensate"):
    def _build(tmp: Path, command: str = _command):
        """A study without -o wrote into results/<name> of the current folder."""
        text = {"sweep": TINY, "place": (REPO / "scenarios" / "studies" / "tiny_placement.toml")
                .read_text(encoding="utf-8"),
                "compensate": (REPO / "scenarios" / "studies" / "compensate_month.toml")
                .read_text(encoding="utf-8")}[command]
        study = write(tmp, "study.toml", text)
        return [command, str(study)], [str(study), "-o/--out", "results/"]
    case(f"study: {_command} without -o")(_build)


@case("study: inproc Dask address")
def _(tmp):
    study = write(tmp, "study.toml", TINY)
    return (["sweep", str(study), "-o", "out", "--dask-address", "inproc://x"],
            ["--dask-address", "inproc://x", "tcp://HOST:PORT"])


# ------------------------------------------------- issue 28: more faults, same promise

TINY_COMPENSATE = (REPO / "scenarios" / "studies" / "tiny_compensate.toml").read_text(
    encoding="utf-8")
SHIPPED_MACHINE = REPO / "scenarios" / "machines" / "default.toml"


@case("study: more simulations than a study may run")
def _(tmp):
    study = write(tmp, "study.toml", TINY.replace("replicas = 2", "replicas = 10000", 1)
                  .replace("speeds_rpm = [2000, 4000]", "speeds_rpm = [" + ", ".join(
                      str(1000 + 10 * i) for i in range(10)) + "]", 1))
    return (["sweep", str(study), "--workers", "0", "--no-progress"],
            [str(study), "axes.speeds_rpm", "200,000 simulations"])


@case("study: the .lock is a symbolic link")
def _(tmp):
    study = write(tmp, "study.toml", TINY)
    victim = write(tmp, "victim.txt", "keep\n")
    (tmp / "res").mkdir()
    (tmp / "res" / ".lock").symlink_to(victim)
    return (["sweep", str(study), "-o", str(tmp / "res"), "--workers", "0", "--no-progress"],
            [".lock", "symbolic link"])


@case("study: -o names a FIFO")
def _(tmp):
    study = write(tmp, "study.toml", TINY)
    os.mkfifo(tmp / "pipe")
    return (["sweep", str(study), "-o", str(tmp / "pipe"), "--workers", "0", "--no-progress"],
            ["pipe", "a FIFO"])


@case("compensate: fault_from_day after the last day")
def _(tmp):
    study = write(tmp, "comp.toml", TINY_COMPENSATE.replace("fault_from_day = 3",
                                                            "fault_from_day = 40", 1))
    return ["compensate", str(study), "-o", "out"], [str(study), "fault_from_day", "last day"]


@case("compensate: -o is a sweep's folder")
def _(tmp):
    study = write(tmp, "comp.toml", TINY_COMPENSATE)
    write(tmp, "sweep/state.json", "{}\n")
    write(tmp, "sweep/README.md", "a sweep's README\n")
    return ["compensate", str(study), "-o", str(tmp / "sweep")], ["sweep", "state.json"]


@case("calibrate: -o is the shipped default machine")
def _(tmp):
    # a recording calibrate refuses anyway: code that lost the check fails here, not by
    # replacing the shipped file (so are the other shipped-file cases)
    rec = role_recording(tmp, role_frame(None))
    mapping = write(tmp, "map.toml", CALIBRATION_MAP)
    return (["calibrate", str(rec), "--map", str(mapping), "-o", str(SHIPPED_MACHINE)],
            ["default.toml", "--overwrite-shipped"])


@case("build: other segments into the committed FMU")
def _(tmp):
    (tmp / "models").mkdir()  # no source: a build that lost the check fails, writes nothing
    return (["build", "--segments", "3", "--models", str(tmp / "models"), "--out",
             str(DEFAULT_FMU)], ["SpindleBench.fmu", "--overwrite-shipped"])


@case("simulate: -o inside the package source")
def _(tmp):
    scenario = write(tmp, "s.toml", QUICK.replace("seed = 2", "sed = 2"))  # refused anyway
    return (["simulate", str(scenario), "-o", str(REPO / "pipeline" / "spindlebench" / "x.csv")],
            ["x.csv", "--overwrite-shipped"])


@case("build: brackets nested thousands deep")
def _(tmp):
    deep = "(" * 5000 + "1" + ")" * 5000
    write(tmp, "models/SpindleBench.mo", f"package SpindleBench\n  constant Real c = {deep};\n"
          "end SpindleBench;\n")
    return (["build", "--models", str(tmp / "models"), "--out", str(tmp / "o.fmu")],
            ["SpindleBench.mo:2", "nested"])


@case("build: classes nested hundreds deep")
def _(tmp):
    names = [f"P{i}" for i in range(300)]
    text = "package SpindleBench\n" + "".join(f"package {n}\n" for n in names) + "".join(
        f"end {n};\n" for n in reversed(names)) + "end SpindleBench;\n"
    write(tmp, "models/SpindleBench.mo", text)
    return (["build", "--models", str(tmp / "models"), "--out", str(tmp / "o.fmu")],
            ["SpindleBench.mo:21", "nested"])


@case("plot: a 100 000-character title")
def _(tmp):
    rec = role_recording(tmp)
    return (["plot", str(rec), "--target", "drift_um", "-o", "fig.png", "--title", "x" * 100_000],
            ["--title", "100,000"])


@case("evaluate: --target is the time column")
def _(tmp):
    return [*evaluate_case(tmp, recording_text())[:-4], "--target", "time_s", "--clusters",
            "2"], ["train.csv", "'time_s'", "time column"]


@case("evaluate: --differences on 5 000 sensors")
def _(tmp):
    header = ",".join(["time_s", "drift_um", *(f"T{i}" for i in range(5000))])
    rows = [",".join([str(60 * r), str(0.1 * r), *(str(20 + 0.01 * r + 1e-4 * i)
                                                    for i in range(5000))]) for r in range(6)]
    argv = evaluate_case(tmp, header + "\n" + "\n".join(rows) + "\n", "--differences")
    return argv, ["train.csv", "5000 sensors", "--differences"]


def fmu_with(tmp: Path, name: str, extra: dict[str, bytes] | None = None,
             tweak: Callable[[zipfile.ZipInfo, bytes], tuple[zipfile.ZipInfo, bytes]]
             | None = None) -> Path:
    """The shipped FMU with members added (``extra``) or each (info, data) changed."""
    target = tmp / name
    with zipfile.ZipFile(DEFAULT_FMU) as source, zipfile.ZipFile(target, "w") as out:
        for info in source.infolist():
            data = source.read(info)
            if tweak is not None:
                info, data = tweak(info, data)
            out.writestr(info, data)
        for member, data in (extra or {}).items():
            out.writestr(member, data)
    return target


def _so(info: zipfile.ZipInfo) -> bool:
    return info.filename.startswith("binaries/") and info.filename.endswith(".so")


def _declared_huge(tmp: Path) -> Path:
    """A member whose central directory says it unpacks to 4 GB (a zip bomb's claim)."""
    fmu = fmu_with(tmp, "bomb.fmu")
    raw = bytearray(fmu.read_bytes())
    at = raw.find(b"PK\x01\x02")
    raw[at + 24:at + 28] = (0xF0000000).to_bytes(4, "little")
    fmu.write_bytes(bytes(raw))
    return fmu


def _encrypted(tmp: Path) -> Path:
    """A member flagged as encrypted in the central directory (general purpose bit 0)."""
    fmu = fmu_with(tmp, "enc.fmu")
    raw = bytearray(fmu.read_bytes())
    at = raw.find(b"PK\x01\x02")
    raw[at + 8] |= 0x01
    fmu.write_bytes(bytes(raw))
    return fmu


def _lzma(info: zipfile.ZipInfo, data: bytes) -> tuple[zipfile.ZipInfo, bytes]:
    if info.filename == "sources/SpindleBench.h":
        info.compress_type = zipfile.ZIP_LZMA
    return info, data


def _not_elf(info: zipfile.ZipInfo, data: bytes) -> tuple[zipfile.ZipInfo, bytes]:
    return info, (b"#!/bin/sh\necho hello\n" if _so(info) else data)


def _executable(info: zipfile.ZipInfo, data: bytes) -> tuple[zipfile.ZipInfo, bytes]:
    return info, (data[:16] + (2).to_bytes(2, "little") + data[18:] if _so(info) else data)


def _other_token(info: zipfile.ZipInfo, data: bytes) -> tuple[zipfile.ZipInfo, bytes]:
    if info.filename == "modelDescription.xml":
        import re

        data = re.sub(rb'instantiationToken="[^"]*"', b'instantiationToken="{0000}"', data)
    return info, data


FMU_ARCHIVES = {
    "member climbs out with ..": (lambda t: fmu_with(t, "a.fmu", {"../evil.txt": b"x"}),
                                  ["'..'"]),
    "absolute member name": (lambda t: fmu_with(t, "a.fmu", {"/tmp/evil.txt": b"x"}),
                             ["absolute"]),
    "backslash in a member name": (lambda t: fmu_with(t, "a.fmu", {"..\\evil.txt": b"x"}),
                                   ["backslash"]),
    "drive colon in a member name": (lambda t: fmu_with(t, "a.fmu", {"C:evil.txt": b"x"}),
                                     ["colon"]),
    "encrypted member": (_encrypted, ["encrypted"]),
    "LZMA member": (lambda t: fmu_with(t, "a.fmu", tweak=_lzma), ["compression method 14"]),
    "declared 4 GB": (_declared_huge, ["zip bomb"]),
    "binary not ELF": (lambda t: fmu_with(t, "a.fmu", tweak=_not_elf), ["not an ELF"]),
    "binary an executable, not a library": (lambda t: fmu_with(t, "a.fmu", tweak=_executable),
                                            ["not a shared object"]),
    "token of another build": (lambda t: fmu_with(t, "a.fmu", tweak=_other_token),
                               ["instantiationToken"]),
}
for _label, (_make, _expect) in FMU_ARCHIVES.items():
    def _build(tmp: Path, make=_make, expect=_expect):
        fmu = make(tmp)
        scenario = write(tmp, "s.toml", QUICK)
        return (["simulate", str(scenario), "-o", "out", "--fmu", str(fmu)],
                [fmu.name, *expect])
    case(f"FMU: {_label}")(_build)


@case("evaluate: train recording is a FIFO")
def _(tmp):
    argv = evaluate_case(tmp, recording_text())
    os.mkfifo(tmp / "pipe.csv")
    argv[argv.index("--train") + 1] = str(tmp / "pipe.csv")
    return argv, ["pipe.csv", "is a FIFO"]


@case("scenario: a FIFO")
def _(tmp):
    os.mkfifo(tmp / "pipe.toml")
    return ["simulate", str(tmp / "pipe.toml"), "-o", "out"], ["pipe.toml", "a FIFO"]


@case("ambient CSV: a FIFO")
def _(tmp):
    os.mkfifo(tmp / "air.csv")
    scenario = write(tmp, "s.toml", QUICK.replace(
        'kind = "constant"\ntemperature_C = 18.0', 'kind = "csv"\nfile = "air.csv"'))
    return ["simulate", str(scenario), "-o", "out"], ["air.csv", "a FIFO"]


@case("paper: recordings folder is a FIFO")
def _(tmp):
    os.mkfifo(tmp / "recs")
    return ["paper", "--recordings", str(tmp / "recs")], ["recs", "a FIFO"]


@case("fingerprint: a password file named as a recording")
def _(tmp):
    write(tmp, "rec.csv", "root:x:0:0:root:/root:/bin/bash\nbin:x:2:2:bin:/bin:/sbin/nologin\n")
    return ["fingerprint", str(tmp / "rec.csv"), "--target", "drift_um"], ["rec.csv", "1 column"]


@case("ambient CSV: header without the value column names none of the others")
def _(tmp):
    write(tmp, "air.csv", "time_s,secret_token_abc\n0,18\n600,19\n")
    scenario = write(tmp, "s.toml", QUICK.replace(
        'kind = "constant"\ntemperature_C = 18.0', 'kind = "csv"\nfile = "air.csv"'))
    return ["simulate", str(scenario), "-o", "out"], ["air.csv", "2 column(s)"]


AMBIENT_FILES_28 = {
    "underscore in a number": ("time_s,ambient_C\n0,18\n300,1_8\n600,19\n", "line 3"),
}
for _label, (_text, _where) in AMBIENT_FILES_28.items():
    def _build(tmp: Path, text: str = _text, where: str = _where):
        write(tmp, "air.csv", text)
        scenario = write(tmp, "s.toml", QUICK.replace(
            'kind = "constant"\ntemperature_C = 18.0', 'kind = "csv"\nfile = "air.csv"'))
        return ["simulate", str(scenario), "-o", "out"], [where, "air.csv"]
    case(f"ambient CSV: {_label}")(_build)


# --------------------------------------------------------------------------- the test


def snapshot(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


def test_there_are_at_least_200_hostile_inputs():
    assert len(CASES) >= 200, len(CASES)
    commands = {name.split(":")[0] for name in CASES}
    assert {"fingerprint", "plot", "calibrate", "paper", "evaluate", "recording"} <= commands


@pytest.mark.parametrize("name", sorted(CASES))
def test_a_hostile_input_is_one_line_naming_where_and_writes_nothing(
        name, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    scratch = tmp_path / "systmp"  # FMPy's extraction folder lands here
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    argv, expected = CASES[name](tmp_path)
    before = snapshot(tmp_path)
    try:
        status = cli.main(argv)
    except SystemExit as exc:  # argparse: a usage mistake
        status = exc.code
    out, err = capsys.readouterr()
    assert status != 0, (name, out)
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("error: "), err
    assert "Traceback" not in err
    for text in expected:
        assert text in lines[0], (text, lines[0])
    # it names where: one of the files or flags it was given, or a file they name (air.csv)
    named = [Path(a).name for a in argv if Path(a).suffix or "/" in a] + \
        [a for a in argv if a.startswith("--")] + [Path(p).name for p in before]
    assert any(name in lines[0] for name in named), (named, lines[0])
    assert snapshot(tmp_path) == before
