"""Column roles of a user's recording: which column is time, which are sensors, which not.

A recording from another logger names its columns its own way (``Time``, ``Spindle front
[degC]``, ``dx [um]``), so nothing is guessed silently. The roles are explicit:

- ``time_column`` (``--time-column``): the time axis in seconds (default ``time_s``); a
  command that plots or resamples refuses a recording without it.
- ``sensors`` (``--sensors``): names or patterns (``"T*"``, ``"*[degC]"``: ``*`` and ``?``
  are wildcards, brackets are literal); each must match at least one column. Without it,
  only columns that look like temperatures (``T3``, ``t3_C``, ``... [degC]``, ``... °C``,
  ``Temp...``) are sensors, and
  :meth:`RoleChoice.report` says which were taken and which skipped, and why.
- ``exclude`` (``--exclude``): names or patterns never used as sensors.
- A candidate whose |r| with the target exceeds :data:`COPY_R` is refused as a likely copy
  of the target (a second displacement channel) unless ``allow_target_copy``.
- ``delimiter`` / ``decimal`` (``--delimiter``/``--decimal``): the CSV dialect, detected from
  the header and first data line when not given (``;`` with decimal comma, tab, ``|``);
  ``encoding`` (``--encoding``): the text encoding (default UTF-8; ``latin-1``, ``cp1252``).
- ``time_unit`` (``--time-unit``): the unit of the time column (``s``, ``ms``, ``min``,
  ``h``, ``d``). Without it the unit is read from the column's name (``Zeit [min]``,
  ``time (h)``, ``t_min``), and said in :meth:`RoleChoice.report`; a name without a unit is
  seconds, except that a column counting 0, 1, 2, … (a sample index, not a time) is refused
  until ``--time-unit`` says what it counts. A date/time column (``2024-03-01 08:00:00``) is
  read as seconds elapsed since its first row.
- ``speed_column`` (``--speed-column``): the user's spindle-speed column (rev/min), read as
  ``spindle_speed_rpm`` so ``plot`` draws the inputs and ``fingerprint`` knows the programme.
"""

from __future__ import annotations

import argparse
import csv
import functools
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from spindlebench.core.errors import SpindlebenchError, columns_hint, quoted_name
from spindlebench.core.files import MAX_RECORDING_BYTES, check_input
from spindlebench.core.listflags import split_list_flag
from spindlebench.core.names import KELVIN_OFFSET
from spindlebench.formats.recording import (
    SPEED_COLUMN,
    TIME_COLUMN,
    RecordingTable,
    check_encoding,
    not_sensor_reason,
    read_header,
    read_table,
)
from spindlebench.formats.time_axis import TIME_UNITS, time_axis_seconds, unit_from_name

if TYPE_CHECKING:  # a DataFrame only where a caller asks for one: ``evaluate`` needs none
    import pandas as pd

#: |Pearson r| with the target above which a candidate is taken for a copy of the target.
COPY_R = 0.999
#: Columns skipped for one reason that :meth:`RoleChoice.report` names one by one.
LISTED = 3
#: Delimiters the detection chooses from, and the decimal marks a user may give.
DELIMITERS = (",", ";", "\t", "|")
DECIMALS = (".", ",")

#: Names that look like a temperature: T3 / t3_C / x_C / "... [degC]" / "... (°C)" / Temp...
_TEMPERATURE = re.compile(
    r"^[Tt]\d+$|_C$|deg ?C|°C|\[C\]|\(C\)|^temp|temperature", re.IGNORECASE)
#: Names that look like time.
_TIME = re.compile(r"^(t|time|zeit|timestamp|date|datetime|elapsed)\b|^time_|time$|\[s\]$",
                   re.IGNORECASE)


@dataclass(frozen=True)
class ColumnRoles:
    """What the user said about a recording's columns (None: not said, use the rule)."""

    time_column: str | None = None
    sensors: tuple[str, ...] | None = None
    exclude: tuple[str, ...] = ()
    allow_target_copy: bool = False
    delimiter: str | None = None
    decimal: str | None = None
    encoding: str | None = None
    time_unit: str | None = None
    speed_column: str | None = None

    @classmethod
    def from_args(cls, args: argparse.Namespace) -> ColumnRoles:
        """The roles given on a command line built with :func:`add_role_arguments`."""
        sensors = split_list_flag("--sensors", getattr(args, "sensors", None), what="name")
        exclude = split_list_flag("--exclude", getattr(args, "exclude", None), what="name")
        return cls(time_column=args.time_column,
                   sensors=None if sensors is None else tuple(sensors),
                   exclude=tuple(exclude or ()),
                   allow_target_copy=getattr(args, "allow_target_copy", False),
                   delimiter=_delimiter(args.delimiter, "--delimiter"),
                   decimal=_decimal(args.decimal, "--decimal"),
                   encoding=getattr(args, "encoding", None),
                   time_unit=getattr(args, "time_unit", None),
                   speed_column=getattr(args, "speed_column", None))


@dataclass
class RoleChoice:
    """The roles applied to one recording: the time column, sensors, and what was skipped."""

    time_column: str | None
    sensors: list[str]
    skipped: list[tuple[str, str]] = field(default_factory=list)  # (column, why)
    by_rule: bool = True
    #: How the time column was read, when not plain seconds (``as_time_s`` sets it).
    time_note: str | None = None

    def report(self, where: str | None = None) -> str:
        """One line: the sensors taken (``in <where>`` for a command reading several
        recordings) and the columns skipped with the reason; more than
        :data:`LISTED` columns skipped for one reason (a synthetic recording's ``true_*``
        truth) are named by their first two and counted."""
        how = "temperature-looking columns" if self.by_rule else "--sensors"
        by_reason: dict[str, list[str]] = {}
        for name, why in self.skipped:
            by_reason.setdefault(why, []).append(name)
        parts: list[str] = []
        for name, why in self.skipped:
            group = by_reason[why]
            if len(group) <= LISTED:
                parts.append(f"{name} ({why})")
            elif name == group[0]:
                parts.append(f"{group[0]}, {group[1]}, ... ({len(group)} columns: {why})")
        skipped = "; ".join(parts) or "none"
        place = "" if where is None else f" in {where}"
        time = f"; time: {self.time_note}" if self.time_note else ""
        return (f"sensors ({how}){place}: took {', '.join(self.sensors)}; skipped: {skipped}"
                f"{time}")


def add_role_arguments(parser: argparse.ArgumentParser, *, sensors: bool = True,
                       exclude: bool = True, copies: bool = True, speed: bool = True) -> None:
    """The column-role flags every command that reads user recordings shares.

    ``sensors=False``: the command names its sensors another way (a study's
    ``sensors_all``), so no ``--sensors``; ``exclude=False``: every column it uses is
    named (a calibration map), so no ``--exclude``; ``copies=False``: the command fits
    nothing, so a copy of the target is not refused and ``--allow-target-copy`` is absent;
    ``speed=False``: the command's columns are mapped another way (a calibration map).
    """
    parser.add_argument("--time-column", metavar="NAME", default=None,
                        help=f"the time column (default: {TIME_COLUMN}); numbers in the unit "
                        "of --time-unit or of its name ('Zeit [min]'), or dates/times")
    parser.add_argument("--time-unit", metavar="UNIT", default=None,
                        choices=sorted(TIME_UNITS, key=TIME_UNITS.get),
                        help="unit of the time column: s, ms, min, h or d (default: from the "
                        "column's name, else seconds)")
    if speed:
        parser.add_argument("--speed-column", metavar="NAME", default=None,
                            help="the spindle-speed column in rev/min (read as "
                            "spindle_speed_rpm: plot draws it, fingerprint reports the "
                            "programme)")
    parser.add_argument("--encoding", metavar="NAME", default=None,
                        help="text encoding of the recording (default: UTF-8; e.g. latin-1)")
    if sensors:
        parser.add_argument(
            "--sensors", nargs="+", metavar="NAME",
            help="sensor columns: names or glob patterns ('T*', '*[degC]'), space- or "
            "comma-separated; only these, the target and the time column are read and "
            "checked (default: the columns that look like temperatures, listed on stdout)")
    if exclude:
        parser.add_argument("--exclude", nargs="+", metavar="NAME", default=None,
                            help="columns (names or glob patterns) never used as sensors")
    if copies:
        parser.add_argument("--allow-target-copy", action="store_true",
                            help=f"keep a sensor whose |r| with the target exceeds {COPY_R} "
                            "(refused by default as a likely copy of the target)")
    parser.add_argument("--delimiter", default=None, metavar="CHAR",
                        help="CSV field delimiter: ',', ';', 'tab' or '|' (default: detected)")
    parser.add_argument("--decimal", default=None, metavar="CHAR",
                        help="decimal mark: '.' or ',' (default: detected)")


def _delimiter(value: str | None, where: str) -> str | None:
    if value is None:
        return None
    value = "\t" if value in ("tab", "\\t") else value
    if value not in DELIMITERS:
        raise SpindlebenchError(f"{where}: {value!r} is not one of ',', ';', 'tab', '|'")
    return value


def _decimal(value: str | None, where: str) -> str | None:
    if value is not None and value not in DECIMALS:
        raise SpindlebenchError(f"{where}: {value!r} is not '.' or ','")
    return value


def detect_dialect(path: Path, delimiter: str | None = None,
                   decimal: str | None = None, encoding: str | None = None) -> tuple[str, str]:
    """The delimiter and decimal mark of a CSV: as given, or detected from its first lines.

    The delimiter is the candidate that splits the header into the most fields and the first
    data line into as many; a decimal comma is assumed when the delimiter is not a comma and
    the data line has numbers like ``21,5``.
    """
    check_input(path, "recording", max_bytes=MAX_RECORDING_BYTES)  # opening a FIFO would block here
    try:
        with open(path, encoding=check_encoding(encoding), newline="") as handle:
            lines = [handle.readline() for _ in range(2)]
    except (OSError, UnicodeDecodeError, SpindlebenchError):
        return delimiter or ",", decimal or "."  # the reader names the problem
    header, first = lines[0], lines[1]
    try:
        return _detected(path, header, first, delimiter, decimal)
    except csv.Error:  # a field over the csv module's limit: the header reader names it
        return delimiter or ",", decimal or "."


def _detected(path: Path, header: str, first: str, delimiter: str | None,
              decimal: str | None) -> tuple[str, str]:
    if delimiter is None:
        counts = {d: len(next(csv.reader([header], delimiter=d), [])) for d in DELIMITERS}
        agreeing = [d for d in DELIMITERS if counts[d] > 1 and (
            not first.strip() or len(next(csv.reader([first], delimiter=d), [])) == counts[d])]
        delimiter = max(agreeing, key=lambda d: counts[d]) if agreeing else ","
    if decimal is None:
        cells = next(csv.reader([first], delimiter=delimiter), [])
        comma_numbers = [c for c in cells if re.fullmatch(r"\s*-?\d+,\d+\s*", c)]
        decimal = "," if delimiter != "," and comma_numbers else "."
    if delimiter == decimal:
        raise SpindlebenchError(f"recording {path}: the delimiter and the decimal mark are both "
                                f"{delimiter!r}; give --delimiter and --decimal")
    return delimiter, decimal


@functools.lru_cache(maxsize=1024)  # asked once per column and pattern: 15 000 times for
def _pattern(text: str) -> re.Pattern[str]:  # 100 sensors, 0.4 s of a 2 s command uncached
    """A name pattern: ``*`` any run of characters, ``?`` one; everything else literal, so
    ``*[degC]`` means names ending in "[degC]" (not fnmatch's character class)."""
    return re.compile("".join(".*" if c == "*" else "." if c == "?" else re.escape(c)
                              for c in text) + r"\Z", re.DOTALL)


def matches(name: str, patterns: Sequence[str]) -> bool:
    """Whether ``name`` is one of ``patterns`` or matches one (``*``, ``?`` wildcards)."""
    return any(name == p or _pattern(p).match(name) for p in patterns)


def looks_like_time(name: str) -> bool:
    return bool(_TIME.search(name.strip()))


def looks_like_temperature(name: str) -> bool:
    return bool(_TEMPERATURE.search(name.strip()))


def choose(header: Sequence[str], target: str, roles: ColumnRoles,
           where: str) -> RoleChoice:
    """Apply ``roles`` to a recording's header: the time column and the sensors.

    ``where`` names the recording in messages. Errors: a given time column or a sensor
    pattern that matches no column, a target that is also a sensor, no sensor left.
    """
    header = [str(name) for name in header]
    if target not in header:
        raise SpindlebenchError(f"recording {where}: target column {target!r} not found "
                                f"({columns_hint(header, target)})")
    time_column = roles.time_column or TIME_COLUMN
    if roles.time_column is not None and roles.time_column not in header:
        raise SpindlebenchError(f"recording {where}: --time-column {roles.time_column!r} not "
                                f"found ({columns_hint(header, roles.time_column)})")
    if time_column not in header:
        time_column = None
    if time_column is not None and time_column == target:
        raise SpindlebenchError(f"recording {where}: the target {target!r} is also the time "
                                "column; name the time axis with --time-column")
    for pattern in roles.exclude:
        if not any(matches(name, [pattern]) for name in header):
            raise SpindlebenchError(f"recording {where}: --exclude {pattern!r} matches no "
                                    f"column ({columns_hint(header, pattern)})")
    skipped: list[tuple[str, str]] = []
    if roles.sensors is not None:
        sensors: list[str] = []
        names = set(header)
        for pattern in roles.sensors:
            if not any(c in pattern for c in "*?"):  # a name matches only itself: no scan
                matched = [pattern] if pattern in names else []  # (100 names: 0.1 s)
            else:
                matched = [n for n in header if matches(n, [pattern])]
            found = [n for n in matched if n not in sensors]
            if not matched:
                what = ("sensor pattern matches no column" if any(c in pattern for c in "*?")
                        else "sensor column(s) not found")
                raise SpindlebenchError(f"recording {where}: {what}: {pattern} "
                                        f"({columns_hint(header, pattern)})")
            sensors += found
        for name in list(sensors):
            if name == target:
                raise SpindlebenchError(f"recording {where}: the target {target!r} is also "
                                        "listed as a sensor")
            if name == time_column and name in roles.sensors:  # named, not matched by a pattern
                raise SpindlebenchError(f"recording {where}: --sensors names the time column "
                                        f"{name!r}; a time is not a temperature sensor")
            if name == time_column or matches(name, roles.exclude):
                sensors.remove(name)
                skipped.append((name, "time column" if name == time_column else "--exclude"))
        by_rule = False
    else:
        sensors = []
        by_rule = True
        for name in header:
            if name == target:
                skipped.append((name, "target"))
            elif name == time_column:
                skipped.append((name, "time column"))
            elif name == roles.speed_column:
                skipped.append((name, "--speed-column"))
            elif matches(name, roles.exclude):
                skipped.append((name, "--exclude"))
            elif looks_like_time(name):
                skipped.append((name, "looks like time; --time-column names the time axis"))
            else:
                reason = not_sensor_reason(name)
                if reason is None and looks_like_temperature(name):
                    sensors.append(name)
                else:
                    skipped.append((name, reason or "does not look like a temperature; "
                                    "name it in --sensors to use it"))
    if not sensors:
        shown = "; ".join(f"{quoted_name(n)}: {why}" for n, why in skipped[:3])
        more = f"; and {len(skipped) - 3} more" if len(skipped) > 3 else ""
        raise SpindlebenchError(f"recording {where}: no sensor columns ({shown}{more}); "
                                "pass --sensors")
    return RoleChoice(time_column, sensors, skipped, by_rule)


def refuse_target_copies(frame: pd.DataFrame | RecordingTable, target: str,
                         sensors: Sequence[str], where: str, allow: bool) -> None:
    """Refuse a sensor whose |r| with the target exceeds :data:`COPY_R`: a target that leaks
    into the model gives ψ = 1 and R² = 1 and predicts nothing on a real machine."""
    if allow:
        return
    y = np.asarray(frame[target], dtype=float)
    for name in _possible_copies(frame, y, sensors):
        x = np.asarray(frame[name], dtype=float)
        keep = np.isfinite(x) & np.isfinite(y)
        if keep.sum() < 3 or np.ptp(x[keep]) == 0 or np.ptp(y[keep]) == 0:
            continue
        r = float(np.corrcoef(x[keep], y[keep])[0, 1])
        if abs(r) > COPY_R:
            raise SpindlebenchError(
                f"recording {where}: sensor {name!r} follows the target {target!r} with |r| = "
                f"{abs(r):.4f} > {COPY_R}: likely a copy of the target (another displacement "
                f"channel?); --exclude it, or pass --allow-target-copy")


#: |r| below which ``_possible_copies`` clears a sensor without the exact check: the two
#: computations of r differ by rounding (~1e-15), far less than this margin.
_CLEARLY_NO_COPY = COPY_R - 1e-6


def _possible_copies(frame: pd.DataFrame | RecordingTable, y: np.ndarray,
                     sensors: Sequence[str]) -> list[str]:
    """The sensors that may follow the target, in order: all of them, except, where every
    value is finite, those whose |r| (all sensors at once) is clearly below ``COPY_R``; the
    caller checks the rest one by one as before (one np.corrcoef per sensor: 10 ms of
    ``evaluate`` for 100 sensors)."""
    names = list(sensors)
    if not names or not np.isfinite(y).all():
        return names
    X = np.column_stack([np.asarray(frame[name], dtype=float) for name in names])
    if not np.isfinite(X).all():
        return names
    with np.errstate(all="ignore"):
        xc = X - X.mean(axis=0)
        yc = y - y.mean()
        r = (yc @ xc) / np.sqrt((xc * xc).sum(axis=0) * (yc @ yc))
    return [name for name, value in zip(names, r, strict=True)
            if not abs(value) < _CLEARLY_NO_COPY]  # NaN: checked one by one


def require_time(choice: RoleChoice, where: str, why: str) -> str:
    """The time column, or an error for a command that needs one (plots, resampling)."""
    if choice.time_column is None:
        raise SpindlebenchError(f"recording {where}: no time column {TIME_COLUMN!r}; {why} "
                                "needs one: name it with --time-column (or time_column)")
    return choice.time_column


def parse_delimiter(value: str | None, where: str) -> str | None:
    """A delimiter as given by a user (``tab`` for a tab), checked."""
    return _delimiter(value, where)


def parse_decimal(value: str | None, where: str) -> str | None:
    """A decimal mark as given by a user, checked."""
    return _decimal(value, where)


#: Values a temperature sensor cannot read (°C): below absolute zero, or a logger's error
#: sentinel (9.9e37, 1e10); -273.15 itself is also a common "no value" code.
PLAUSIBLE_C = (-KELVIN_OFFSET, 1.0e4)


def refuse_implausible_temperatures(frame: pd.DataFrame | RecordingTable,
                                    sensors: Sequence[str], where: str) -> None:
    """A temperature-looking sensor with a value no thermometer reads is one line naming the
    file, line and column (one 9.9e37 cell made every other sensor look constant)."""
    low, high = PLAUSIBLE_C
    for name in sensors:
        if not looks_like_temperature(name):
            continue
        values = np.asarray(frame[name], dtype=float)
        bad = np.flatnonzero(~((values > low) & (values < high)) & ~np.isnan(values))
        if bad.size:
            row = int(bad[0])
            line = row + 2 if isinstance(frame, RecordingTable) else _line(frame, row)
            raise SpindlebenchError(
                f"recording {where}, line {line}, column {name!r}: {values[row]:g} is not a "
                f"plausible temperature ({low:g}..{high:g} °C; a logger's error value?); "
                f"{bad.size} such cell(s); remove those samples or --exclude the column")


def _line(frame: pd.DataFrame, row: int) -> int:
    """The file line of a frame's ``row``-th sample (header = line 1)."""
    import pandas as pd

    return int(frame.index[row]) + 2 if isinstance(frame.index, pd.RangeIndex) else row + 2


def read_with_roles(path: Path, target: str, roles: ColumnRoles, *,
                    allow_missing: bool = False,
                    extra: Sequence[str] = ()) -> tuple[pd.DataFrame, RoleChoice]:
    """Read a user recording under ``roles``: dialect, time column, sensors, checks.

    Only the target, the time column, the sensors and those of ``extra`` the file has (a
    plot's driver inputs) are read and checked. The time column
    is renamed to ``time_s`` in the frame (so downstream code has one name), the sensors are
    checked for implausible temperatures and (unless allowed) copies of the target.
    """
    table, choice = read_table_with_roles(path, target, roles, allow_missing=allow_missing,
                                          extra=extra, engine="pandas")
    return table.frame(), choice


def read_table_with_roles(path: Path, target: str, roles: ColumnRoles, *,
                          allow_missing: bool = False, extra: Sequence[str] = (),
                          engine: str = "numpy") -> tuple[RecordingTable, RoleChoice]:
    """``read_with_roles`` as a ``RecordingTable`` (no pandas with ``engine="numpy"``; see
    ``recording.ENGINES``): the same columns, checks, values and messages."""
    delimiter, decimal = detect_dialect(path, roles.delimiter, roles.decimal, roles.encoding)
    header = read_header(path, delimiter, roles.encoding)
    choice = choose(header, target, roles, str(path))
    speed = roles.speed_column
    if speed is not None and speed not in header:
        raise SpindlebenchError(f"recording {path}: --speed-column {speed!r} not found "
                                f"(columns are: {', '.join(header)})")
    if speed is not None and (speed in choice.sensors or speed in (target, choice.time_column)):
        raise SpindlebenchError(f"recording {path}: --speed-column {speed!r} is also the "
                                "target, the time column or a sensor; name another column")
    dates = (_date_times(path, choice.time_column, header, delimiter, roles.encoding)
             if choice.time_column else None)
    wanted = [target, *choice.sensors] + (
        [choice.time_column] if choice.time_column and dates is None else []) \
        + [name for name in (*extra, *([speed] if speed else [])) if name in header]
    table = read_table(path, allow_missing=allow_missing, columns=wanted,
                       delimiter=delimiter, decimal=decimal, engine=engine,
                       encoding=roles.encoding)
    if dates is not None:
        table = _with_time_s(table, dates, choice.time_column)
        choice.time_note = f"{choice.time_column!r} read as dates/times, seconds since the first"
    elif choice.time_column:
        table, choice.time_note = timed(table, choice.time_column, path, roles.time_unit)
    elif roles.time_unit is not None:
        raise SpindlebenchError(f"recording {path}: --time-unit {roles.time_unit} but no time "
                                f"column {TIME_COLUMN!r}; name it with --time-column")
    if speed is not None and speed != SPEED_COLUMN:
        table = table.renamed(speed, SPEED_COLUMN)
    refuse_implausible_temperatures(table, choice.sensors, str(path))
    return table, choice


#: What ``--speed-column`` is read as: the testbench's speed input, ``recording.SPEED_COLUMN``.


def _date_times(path: Path, column: str, header: Sequence[str], delimiter: str,
                encoding: str | None) -> np.ndarray | None:
    """Seconds since the first row when ``column`` holds dates/times, else None."""
    from spindlebench.formats.time_axis import parse_datetimes

    position = list(header).index(column)
    try:
        with open(path, encoding=check_encoding(encoding), newline="") as handle:
            rows = csv.reader(handle, delimiter=delimiter)
            next(rows, None)
            first = next(rows, None)
            if first is None or position >= len(first) or not _is_date(first[position]):
                return None
            cells = [first[position]] + [row[position] if position < len(row) else ""
                                         for row in rows if row]
    except (OSError, UnicodeDecodeError):
        return None  # the table reader names the problem
    return parse_datetimes(cells, column, str(path))


def _is_date(cell: str) -> bool:
    return bool(re.match(r"\s*\d{4}-\d{2}-\d{2}", cell))


def _with_time_s(table: RecordingTable, seconds: np.ndarray, column: str) -> RecordingTable:
    """``table`` with ``seconds`` as its ``time_s`` column, first (a date column's values)."""
    if len(seconds) != len(table):
        raise SpindlebenchError(f"recording {table.path}: the time column {column!r} has "
                                f"{len(seconds)} rows, the others {len(table)}")
    keep = [i for i, name in enumerate(table.columns) if name != TIME_COLUMN]
    values = np.column_stack([seconds, table.values[:, keep]])
    table = RecordingTable(table.path, table.header,
                           (TIME_COLUMN, *(table.columns[i] for i in keep)), values)
    _check_increasing(table, Path(table.path))
    return table


def timed(frame: pd.DataFrame | RecordingTable, time_column: str, path: Path,
          unit: str | None = None) -> tuple[pd.DataFrame | RecordingTable, str | None]:
    """``as_time_s`` and the note that says how the time column was read (None: seconds)."""
    seconds, note = time_axis_seconds(np.asarray(frame[time_column], dtype=float),
                                      time_column, unit, str(path))
    frame = _renamed_time(frame, time_column, path)
    if note is not None:
        if isinstance(frame, RecordingTable):
            values = frame.values.copy()
            values[:, frame.columns.index(TIME_COLUMN)] = seconds
            frame = RecordingTable(frame.path, frame.header, frame.columns, values)
        else:
            frame = frame.assign(**{TIME_COLUMN: seconds})
    return frame, note


def as_time_s(frame: pd.DataFrame | RecordingTable, time_column: str,
              path: Path, unit: str | None = None) -> pd.DataFrame | RecordingTable:
    """``frame`` with its time axis ``time_column`` named ``time_s`` (downstream code has one
    name), checked to increase; ``read_recording`` keeps a ``time_s`` column whenever the
    file has one, so a named time axis replaces it. ``unit`` (``--time-unit``) or the unit
    in the column's name converts it to seconds (``formats.time_axis``)."""
    if unit is not None or (time_column != TIME_COLUMN and unit_from_name(time_column)):
        return timed(frame, time_column, path, unit)[0]
    return _renamed_time(frame, time_column, path)


def _renamed_time(frame: pd.DataFrame | RecordingTable, time_column: str,
                  path: Path) -> pd.DataFrame | RecordingTable:
    if time_column == TIME_COLUMN:
        return frame
    if isinstance(frame, RecordingTable):
        frame = frame.renamed(time_column, TIME_COLUMN)
    else:
        frame = frame.drop(columns=[TIME_COLUMN], errors="ignore").rename(
            columns={time_column: TIME_COLUMN})
    _check_increasing(frame, path)
    return frame


def _check_increasing(frame: pd.DataFrame | RecordingTable, path: Path) -> None:
    steps = np.diff(np.asarray(frame[TIME_COLUMN], dtype=float))
    bad = np.flatnonzero(~(steps > 0))
    if bad.size:
        raise SpindlebenchError(f"recording {path}, line {bad[0] + 3}: the time column does not "
                                "increase (--time-column names the time axis in seconds)")
