"""MAP.toml: how a recording's columns relate to the model (``spindlebench calibrate --map``).

A recording of a real machine has its own column names, no feed or ambient column perhaps, an
error probe with its own sign, and sensors somewhere on the machine. The map says, once:

```toml
[inputs]                            # each FMU input: a column name or a constant
spindle_speed_rpm = "spindle_rpm"
feed_x_mm_per_min = 0.0
feed_y_mm_per_min = 0.0
ambient_C = "unknown"               # or a column, or a number; "unknown": estimated

[ambient]                           # only with ambient_C = "unknown"
knot_h = 4.0                        # piecewise-linear ambient, a knot every 4 h (> 0; a
                                    # knot_h longer than the recording: one constant)

[error]                             # optional: the measured thermal error
column = "ch3_um"
sign = -1                           # +1: positive when the tool moves toward the table
                                    # (as the model's drift_um), -1: the opposite

[temperatures]                      # column = model output
t1_C = "T1"                         # a sensor of the model, T1 … T20
t5_C = "node_spindle_motor"         # or a node of the temperature field (node_<part>[_<i>])

[noise]                             # optional: 1-sigma noise of a column (K or µm); default:
t1_C = 0.05                         # estimated from the column's sample-to-sample scatter

[units]                             # optional: what the time and temperature columns hold
time_unit = "s"                     # "s", "min", "h", or "sample" (then sample_s = 15.0)
temperatures = "absolute"           # or "rise" (above base_C, e.g. base_C = 21.5)
```

A time column that looks like a sample index (whole numbers from 0 or 1 in steps of 1) or
temperature columns that all start within ±2 K of 0 (rises, not °C) are refused with one line
unless ``[units]`` says what they are: a sample index read as seconds "fitted" a 72 s run
at 0 °C to a real machine.

Every key is checked; a bad one is one line naming the map file and the dotted key. Columns of
the recording the map does not name are ignored (``unmapped_columns`` lists them).
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.limits import MAX_FEED_MM_PER_MIN, MAX_RPM
from spindlebench.formats.recording import (
    AMBIENT_COLUMN,
    DRIFT_COLUMN,
    DRIVER_COLUMNS,
    FEED_X_COLUMN,
    FEED_Y_COLUMN,
    NODE_PREFIX,
    SPEED_COLUMN,
    TEMPERATURE_SUFFIX,
    TIME_COLUMN,
    node_of_output,
    node_output,
)
from spindlebench.formats.toml import Table, load_toml

INPUTS = DRIVER_COLUMNS
UNKNOWN = "unknown"
DRIFT_OUTPUT = DRIFT_COLUMN
_SENSOR = re.compile(r"^T([1-9]|1[0-9]|20)$")


def recording_map_text(sensors: Iterable[str]) -> str:
    """The MAP.toml of a spindlebench recording: every input and ``drift_um`` under their own
    names, and each of ``sensors`` (``T1`` ...) as itself. What a twin calibration (the model
    against a recording it simulated, e.g. ``bench/bench_calibration.py``) maps with.

    >>> print(recording_map_text(["T1"]).splitlines()[-1])
    T1 = "T1"
    """
    lines = ["[inputs]", *(f'{name} = "{name}"' for name in INPUTS),
             "[error]", f'column = "{DRIFT_COLUMN}"', "[temperatures]",
             *(f'{name} = "{name}"' for name in sensors)]
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class RecordingMap:
    """The map of one MAP.toml file (see the module docstring)."""

    path: Path
    inputs: dict[str, str | float]  # FMU input -> column name, constant, or UNKNOWN (ambient)
    ambient_knot_h: float
    error_column: str | None
    error_sign: float
    temperatures: dict[str, str]  # column -> model output name (T1_C, node_x_C)
    noise: dict[str, float] = field(default_factory=dict)
    time_unit: str | None = None  # None: not said (a sample-index-looking axis is refused)
    sample_s: float | None = None  # seconds per sample with time_unit = "sample"
    temperatures_kind: str | None = None  # "absolute", "rise", or None (not said)
    base_C: float | None = None  # noqa: N815  (added to rises)

    @property
    def ambient_unknown(self) -> bool:
        return self.inputs[AMBIENT_COLUMN] == UNKNOWN

    def columns(self) -> list[str]:
        """Every recording column the map uses."""
        used = [v for v in self.inputs.values() if isinstance(v, str) and v != UNKNOWN]
        used += list(self.temperatures)
        if self.error_column:
            used.append(self.error_column)
        return list(dict.fromkeys(used))

    def check_columns(self, header: Iterable[str], recording: Path,
                      time_column: str = TIME_COLUMN) -> list[str]:
        """Raise naming the key whose column ``recording`` lacks; return the unmapped columns
        (other than the time axis ``time_column``)."""
        header = list(header)
        present = set(header)
        for key, value in self.inputs.items():
            if isinstance(value, str) and value != UNKNOWN and value not in present:
                raise SpindlebenchError(f"{self.path}: key 'inputs.{key}': column {value!r} is "
                                        f"not in {recording}")
        if self.error_column and self.error_column not in present:
            raise SpindlebenchError(f"{self.path}: key 'error.column': column "
                                    f"{self.error_column!r} is not in {recording}")
        for column in self.temperatures:
            if column not in present:
                raise SpindlebenchError(f"{self.path}: key 'temperatures.{column}': column is "
                                        f"not in {recording}")
        used = set(self.columns()) | {time_column}
        return [c for c in header if c not in used]


def _output_name(table: Table, column: str, value: Any, outputs: set[str]) -> str:
    if not isinstance(value, str):
        raise table.error(column, f"must be a model output name (T1 … T20 or node_…), "
                                  f"got {value!r}")
    if _SENSOR.match(value):
        return f"{value}{TEMPERATURE_SUFFIX}"
    node = value.removeprefix(NODE_PREFIX).removesuffix(TEMPERATURE_SUFFIX)
    if value.startswith(NODE_PREFIX) and node_output(node) in outputs:
        return node_output(node)
    nodes = sorted(NODE_PREFIX + n for n in map(node_of_output, outputs) if n)
    near = difflib.get_close_matches(value, nodes, n=3)
    hint = f"did you mean {', '.join(near)}?" if near else f"nodes: {nodes[0]} … {nodes[-1]}"
    raise table.error(column, f"{value!r} is not a model sensor (T1 … T20) or node ({hint})")


#: The range of each operating input the model declares (its Modelica ``min``/``max``, the
#: limits a scenario is checked against); the ambient has its own check (kelvin, far too cold).
INPUT_RANGES = {SPEED_COLUMN: (0.0, MAX_RPM, "rev/min"),
                FEED_X_COLUMN: (0.0, MAX_FEED_MM_PER_MIN, "mm/min"),
                FEED_Y_COLUMN: (0.0, MAX_FEED_MM_PER_MIN, "mm/min")}


def _column_or_constant(table: Table, key: str, allow_unknown: bool) -> str | float:
    value = table.raw(key)
    if isinstance(value, bool) or not isinstance(value, str | int | float):
        raise table.error(key, f"must be a column name or a number, got {value!r}")
    if isinstance(value, str):
        if value == UNKNOWN and not allow_unknown:
            raise table.error(key, "only ambient_C may be \"unknown\"")
        if not value:
            raise table.error(key, "empty column name")
        return value
    low, high, unit = INPUT_RANGES.get(key, (None, None, ""))
    return table.number(key, minimum=low, maximum=high, unit=unit)


def read_map(path: str | Path, outputs: Iterable[str]) -> RecordingMap:
    """Read and check a MAP.toml file against the model's ``outputs``."""
    path = Path(path)
    outputs = set(outputs)
    top = Table(load_toml(path, "map"), path)
    inputs_table = top.table("inputs")
    inputs = {key: _column_or_constant(inputs_table, key, key == AMBIENT_COLUMN) for key in INPUTS}
    inputs_table.finish()
    ambient = top.table("ambient", required=False)
    if ambient.data and inputs[AMBIENT_COLUMN] != UNKNOWN:
        raise ambient.error(next(ambient.names()), "only with inputs.ambient_C = \"unknown\"")
    knot_h = ambient.number("knot_h", 4.0, minimum=0.0, unit="h")
    if knot_h == 0.0:  # knots 0 h apart: no ambient at all, not "constant" (say so)
        raise ambient.error("knot_h", "must be > 0 h (hours between the estimated ambient's "
                            "knots); for a constant ambient give a knot_h longer than the "
                            "recording")
    ambient.finish()
    error = top.table("error", required=False)
    error_column = error.string("column", None)
    sign = error.number("sign", 1.0)
    if sign not in (1.0, -1.0):
        raise error.error("sign", f"must be +1 or -1, got {sign:g}")
    error.finish()
    temperatures_table = top.table("temperatures", required=False)
    if "temperatures" in top.data and not temperatures_table.data:
        raise top.error("temperatures", "the table is empty: map at least one column to a "
                        "model sensor (t1_C = \"T1\"), or leave the table out to calibrate "
                        "on the error column alone")
    temperatures = {
        str(column): _output_name(temperatures_table, str(column),
                                  temperatures_table.raw(column), outputs)
        for column in list(temperatures_table.names())
    }
    if not temperatures and not error_column:
        raise top.error("temperatures", "the map names no temperature column and no error "
                        "column: nothing to calibrate on")
    noise_table = top.table("noise", required=False)
    known = set(temperatures) | ({error_column} if error_column else set())
    noise: dict[str, float] = {}
    for column in list(noise_table.names()):
        if column not in known:
            raise noise_table.error(column, "is not a temperature or error column of the map")
        noise[column] = noise_table.number(column, positive=True)
    units = top.table("units", required=False)
    time_unit = units.string("time_unit", None, choices=TIME_UNITS)
    sample_s = units.number("sample_s", None, positive=True) if time_unit == "sample" else None
    if time_unit == "sample" and sample_s is None:
        raise units.error("sample_s", "time_unit = \"sample\" needs sample_s (seconds)")
    kind = units.string("temperatures", None, choices=("absolute", "rise"))
    base = units.number("base_C", None) if kind == "rise" else None
    if kind == "rise" and base is None:
        raise units.error("base_C", "temperatures = \"rise\" needs base_C (°C the rises are "
                          "above)")
    units.finish()
    top.finish()
    return RecordingMap(
        path=path, inputs=inputs, ambient_knot_h=knot_h, error_column=error_column,
        error_sign=sign, temperatures=temperatures, noise=noise, time_unit=time_unit,
        sample_s=sample_s, temperatures_kind=kind, base_C=base,
    )


#: Units a map's time column may be in, and seconds per unit (``sample``: ``sample_s``).
TIME_UNITS = ("s", "min", "h", "sample")
_SECONDS = {"s": 1.0, "min": 60.0, "h": 3600.0}


def seconds_per_unit(recording_map: RecordingMap) -> float:
    """Seconds per unit of the recording's time column (1 when the map does not say)."""
    unit = recording_map.time_unit
    if unit == "sample":
        return float(recording_map.sample_s)
    return _SECONDS.get(unit, 1.0) if unit else 1.0


def looks_like_sample_index(time_s: np.ndarray) -> bool:
    """Whole numbers from 0 or 1 in steps of exactly 1: a row counter, not seconds."""
    t = np.asarray(time_s, dtype=float)
    return (len(t) > 2 and t[0] in (0.0, 1.0) and bool(np.all(np.diff(t) == 1.0)))


def apply_units(recording_map: RecordingMap, time_s: np.ndarray,
                temperatures: dict[str, np.ndarray], where: str
                ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The time axis in seconds and the temperatures in °C, as the map's ``[units]`` says;
    without it, a sample-index axis or rise-looking temperatures are one line."""
    unit = recording_map.time_unit
    if unit is None and looks_like_sample_index(time_s):
        raise SpindlebenchError(
            f"recording {where}: the time column counts 0, 1, 2, … like a sample index; if it "
            f"is seconds say so in {recording_map.path.name} ([units] time_unit = \"s\"), "
            "else time_unit = \"sample\" with sample_s")
    if unit == "sample":
        time_s = (time_s - time_s[0]) * recording_map.sample_s
    elif unit is not None:
        time_s = time_s * _SECONDS[unit]
    kind = recording_map.temperatures_kind
    firsts = [v[np.isfinite(v)][0] for v in temperatures.values() if np.isfinite(v).any()]
    if kind is None and firsts and max(abs(f) for f in firsts) < 2.0:
        raise SpindlebenchError(
            f"recording {where}: every temperature column starts within ±2 of 0 "
            f"({', '.join(temperatures)}): rises, not °C? say so in "
            f"{recording_map.path.name} ([units] temperatures = \"rise\", base_C = …) or "
            "temperatures = \"absolute\"")
    if kind == "rise":
        temperatures = {c: v + recording_map.base_C for c, v in temperatures.items()}
    return time_s, temperatures


def constant_inputs(recording_map: RecordingMap) -> Mapping[str, float]:
    """The inputs the map gives as constants."""
    return {k: v for k, v in recording_map.inputs.items() if isinstance(v, float)}
