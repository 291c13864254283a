"""The recording format: one CSV per run plus its JSON sidecar, and every column-name rule.

A newcomer who renames or adds a recording column edits this module only.

**Columns.** ``time_s``; the measured sensors ``T1`` … ``T20``; the measured thermal error
``drift_um``; the driver inputs; then the noise-free FMU outputs, each as ``true_<output>``:
sensors (``true_T1_C``), drift (``true_drift_um``), the temperature field
(``true_node_<node>_C``) and heat flows (``true_Q_<part>_W``); the outputs of the five-probe
model and of a spindle mechanism that is off are left out (``recorded_outputs``).
``default_sensors`` says which columns of any recording (also a real one) count as sensors
when none are named.

**Reading** (synthetic or real recordings, one CSV per experiment). A canonical recording
is a CSV with a header line and one numeric row per sample: ``time_s``, sensor temperatures,
the measured thermal error, optionally drivers and ``true_*`` columns.
``read_recording`` refuses anything it would otherwise have to guess about, with a one-line
``SpindlebenchError`` naming the file, line and column: a missing file, an empty file, repeated
or empty column names, rows with the wrong number of fields, empty/NaN/non-numeric/infinite
cells, fewer than 2 samples, or a ``time_s`` that does not strictly increase. Missing values
are never interpolated: whoever made the file knows better how to fill them. A leading UTF-8
byte-order mark (Excel's "CSV UTF-8") is ignored.

``read_recording(path, allow_missing=True)`` is the one opt-in exception: empty and ``NaN``
cells (the testbench's sensor dropout) are read as NaN so that a consumer can drop the
incomplete samples, as ``selection.evaluate(..., missing="drop-rows")`` does, with a warning.
Only those two spellings count as missing; text, ``inf``, booleans, rows with fewer fields than
the header and a missing ``time_s`` stay errors. Nothing is filled in either way.

``read_recording(path, columns=[...])`` reads and checks only those columns (and ``time_s``):
a caller that names the columns it uses (``evaluate --sensors``, the paper study) is not
stopped by a gap or a note in a column it ignores.

**Writing** the CSV and its JSON sidecar, each atomically, as a checkable pair. A recording
is only useful with its provenance, so both files are written in full first and
then moved into place one right after the other, the CSV first: a crash never leaves a half
file, and a failed CSV move never leaves a new sidecar describing a CSV that is not there.
Two renames cannot be one atomic step (a crash between them leaves a new CSV beside the old
sidecar), so the sidecar also carries the CSV's SHA-256 (``recording_sha256``): a reader can
tell a pair that does not belong together (see ``sidecar_mismatch``).

**Sidecar.** The JSON beside the CSV: provenance, ``recording_sha256`` (see
``sidecar_mismatch``) and ``end_state.states_K``, the state a ``continue`` run starts from
(``read_end_state``).
"""

from __future__ import annotations

import codecs
import csv
import functools
import io
import itertools
import json
import os
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from spindlebench.core.atomic import atomic_file
from spindlebench.core.errors import SpindlebenchError, columns_hint, quoted_name
from spindlebench.core.files import MAX_RECORDING_BYTES, check_input
from spindlebench.core.names import SENSORS
from spindlebench.core.paths import file_kind, refuse_shipped
from spindlebench.core.provenance import sha256_written
from spindlebench.formats.json_text import indented_json

if TYPE_CHECKING:  # pandas is imported where a DataFrame is made: ``evaluate`` needs none
    import pandas as pd

# --------------------------------------------------------------------------- column names

TIME_COLUMN = "time_s"
#: The measured thermal error (the probe's reading), µm.
DRIFT_COLUMN = "drift_um"
#: The driver inputs: the FMU's input names and their recording columns (rev/min, mm/min, °C).
SPEED_COLUMN = "spindle_speed_rpm"
FEED_X_COLUMN = "feed_x_mm_per_min"
FEED_Y_COLUMN = "feed_y_mm_per_min"
AMBIENT_COLUMN = "ambient_C"
#: The driver columns in the FMU's input order.
DRIVER_COLUMNS: tuple[str, ...] = (SPEED_COLUMN, FEED_X_COLUMN, FEED_Y_COLUMN, AMBIENT_COLUMN)
#: Prefix of a noise-free FMU output's column.
TRUE_PREFIX = "true_"
#: FMU outputs: a sensor ``T1`` is output ``T1_C``; a field node ``housing_3`` is output
#: ``node_housing_3_C``; a heat flow is ``Q_<part>_W``.
TEMPERATURE_SUFFIX = "_C"
NODE_PREFIX = "node_"
HEAT_FLOW_PREFIX = "Q_"
#: The paper's sensors as FMU outputs.
SENSOR_OUTPUTS: tuple[str, ...] = tuple(f"{name}{TEMPERATURE_SUFFIX}" for name in SENSORS)


#: The five-probe outputs (ISO 230-3 set-up: radial probes X1, X2, Y1, Y2 at two heights
#: ``probe_l`` apart, axial probe Z on the end face; drifts of the end face; tilts A, B in
#: µrad). ``probe_Z_um`` is ``drift_um`` under its probe's name.
PROBE_OUTPUTS: tuple[str, ...] = (
    "probe_X1_um", "probe_X2_um", "probe_Y1_um", "probe_Y2_um", "probe_Z_um",
    "drift_x_um", "drift_y_um", "tilt_a_urad", "tilt_b_urad",
)
#: The thermal-error columns a recording can carry, each a study's possible target
#: (``[study] targets``): the axial drift, then the measured five-probe channels (``probe_Z_um``
#: is ``drift_um``), the latter with ``[outputs] probes = true`` only.
ERROR_COLUMNS: tuple[str, ...] = (DRIFT_COLUMN, *(name for name in PROBE_OUTPUTS
                                                  if name != "probe_Z_um"))
#: Field nodes of the five-probe model (the '+' halves of the column's and the headstock's
#: sections), recorded with the probe outputs only.
PROBE_NODES: tuple[str, ...] = ("column_front", "column_right", "housing_front", "housing_right")


def is_probe_output(output_name: str) -> bool:
    """Whether an FMU output belongs to the five-probe model (recorded only when a scenario
    asks with ``[outputs] probes = true``, so older scenarios keep their columns)."""
    return output_name in PROBE_OUTPUTS or node_of_output(output_name) in PROBE_NODES


#: Issue 20's spindle-driven mechanisms: each FMU output only one of them makes, and the FMU
#: parameter that switches that mechanism on (off at 0). With its switch at 0 such an output
#: says nothing (a heat flow or preload of 0, the coolant temperatures of a jacket that is not
#: there), so a run records it only when its switch is non-zero in that run: a machine with a
#: mechanism off keeps the columns it had before the mechanism existed (``ambient-following``,
#: every mechanism off, keeps the columns and bytes of its recordings from before version 3).
MECHANISM_SWITCHES: dict[str, str] = {
    "Q_bearing_air_W": "G_bearing_air_ref",       # air stream through the front bearing
    "Q_rotor_W": "rotor_loss_fraction",           # built-in motor: losses in the rotor
    "Q_jacket_W": "jacket_enabled",               # chiller jacket
    "jacket_inlet_C": "jacket_enabled",
    "jacket_outlet_C": "jacket_enabled",
    "front_preload_thermal_N": "front_preload_N_per_K",  # thermally induced preload
}


def recorded_outputs(output_names: Iterable[str], *, probes: bool,
                     switches: Mapping[str, float]) -> tuple[str, ...]:
    """The FMU outputs a run records (FMU order): the five-probe model's only with
    ``probes`` (a scenario's ``[outputs] probes = true``), a mechanism's (``MECHANISM_SWITCHES``)
    only when ``switches`` (its switch parameters' values in the run) has it non-zero. An
    output whose switch is not in ``switches`` (an FMU without that parameter) is recorded."""
    def recorded(name: str) -> bool:
        if is_probe_output(name):
            return probes
        switch = MECHANISM_SWITCHES.get(name)
        return switch is None or switches.get(switch, 1.0) != 0.0

    return tuple(name for name in output_names if recorded(name))


def true_column(output_name: str) -> str:
    """Recording column of a noise-free FMU output: ``T1_C`` → ``true_T1_C``."""
    return f"{TRUE_PREFIX}{output_name}"


def sensor_of_output(output_name: str) -> str:
    """The sensor an FMU output measures: ``T1_C`` → ``T1``."""
    return output_name.removesuffix(TEMPERATURE_SUFFIX)


def node_output(node: str) -> str:
    """FMU output of a field node's temperature: ``housing_3`` → ``node_housing_3_C``."""
    return f"{NODE_PREFIX}{node}{TEMPERATURE_SUFFIX}"


def node_of_output(output_name: str) -> str | None:
    """The field node of an FMU output (``node_housing_3_C`` → ``housing_3``), or None."""
    if output_name.startswith(NODE_PREFIX) and output_name.endswith(TEMPERATURE_SUFFIX):
        return output_name[len(NODE_PREFIX):-len(TEMPERATURE_SUFFIX)]
    return None


def node_column(node: str) -> str:
    """Recording column of a node's true temperature: ``true_node_<node>_C``."""
    return true_column(node_output(node))


#: The noise-free thermal error's column (``true_drift_um``).
TRUE_DRIFT_COLUMN = true_column(DRIFT_COLUMN)
#: The noise-free sensor temperatures' columns (``true_T1_C`` ...), in ``SENSORS`` order.
TRUE_SENSOR_COLUMNS: tuple[str, ...] = tuple(true_column(o) for o in SENSOR_OUTPUTS)
#: Truth columns a study's evaluation needs from a recording.
TRUTH_COLUMNS: tuple[str, ...] = (TIME_COLUMN, *(true_column(o) for o in SENSOR_OUTPUTS),
                                  true_column(DRIFT_COLUMN))
#: The driver columns a study keeps beside its truth, for the dynamic regressors that read
#: the speed programme and the room (``selection.dynamic``).
STUDY_DRIVER_COLUMNS: tuple[str, ...] = (SPEED_COLUMN, AMBIENT_COLUMN)


def _output_order(name: str) -> int:
    """Sensors, drift, nodes, heat flows, anything else; FMU order within a group."""
    for rank, prefix in enumerate(("T", DRIFT_COLUMN, NODE_PREFIX, HEAT_FLOW_PREFIX)):
        if name.startswith(prefix):
            return rank
    return 4


#: Columns that are never sensors by default, with the reason (first match wins): the
#: synthetic testbench's noise-free truth and driver inputs, and, on any recording, thermal
#: errors/displacements (``*_um``, ``[µm]``), speeds, feed rates and heat flows. ``ambient_C``
#: is the testbench's ambient *driver*; the measured ambient sensor is a T column. Used by
#: ``default_sensors`` and by the column roles of user recordings (``formats.roles``).
NOT_SENSOR: tuple[tuple[re.Pattern[str], str], ...] = (
    (re.compile(r"^true_"), "noise-free truth"),
    (re.compile(r"_um$|_urad$|\[um\]|\[µm\]|µm|displacement", re.IGNORECASE),
     "displacement/thermal error"),
    (re.compile(r"_rpm$|\[rpm\]|speed|feed|_mm_per_min$|_W$", re.IGNORECASE),
     "driver/command input"),
    (re.compile(r"^ambient_C$"), "the testbench's ambient driver"),
)


def not_sensor_reason(name: str) -> str | None:
    """Why a column is never a sensor by default, or None."""
    return next((why for rule, why in NOT_SENSOR if rule.search(name)), None)


def is_default_sensor(name: str) -> bool:
    """Whether a column counts as a sensor when none are named (see ``default_sensors``)."""
    return name != TIME_COLUMN and not_sensor_reason(name) is None


# --------------------------------------------------------------------------- reading

#: UTF-8, with a leading byte-order mark (Excel's "CSV UTF-8" export) dropped: kept, it would
#: glue itself to the first column name ("\ufefftime_s") and time_s would become a sensor.
ENCODING = "utf-8-sig"

#: Cell spellings ``allow_missing`` reads as NaN (compared after stripping, case-insensitive).
MISSING_SPELLINGS = ("", "nan")
#: The exact strings the fast path hands to pandas as NaN; other casings take the slow path.
_FAST_NA_VALUES = ["", "nan", "NaN", "NAN"]


class MissingValueError(SpindlebenchError):
    """An empty or NaN cell in a recording read without ``allow_missing``: the one bad-input
    case a caller can opt out of, so callers can point to their option."""


#: How ``read_table`` turns text into numbers. ``"pandas"``: its C tokenizer (2-3x faster
#: per file than NumPy's, for callers that build a DataFrame anyway); what it cannot take
#: goes to the text path, which names the first bad cell. ``"numpy"``: ``np.loadtxt`` on a
#: plain file first (no pandas import, half a second of a short command's start-up); a file
#: it does not take exactly as pandas would (same values to the last bit, tested) goes on
#: to pandas' way. The rules and the values do not depend on the engine.
ENGINES = ("numpy", "pandas")


@dataclass(frozen=True)
class RecordingTable:
    """A recording as read and checked: the kept columns' values in one float64 array.

    ``read_table`` returns it, ``read_recording`` builds its DataFrame from it. A table is
    what a command needs that only computes on the columns (``spindlebench evaluate``):
    no pandas. ``table[name]`` is a column (a view of ``values``); row ``i`` is line
    ``i + 2`` of the file."""

    path: str
    header: FileHeader  #: every column name of the file, also those not kept
    columns: tuple[str, ...]  #: the kept columns, in file order
    values: np.ndarray  #: (samples, len(columns)) float64

    def __len__(self) -> int:
        return self.values.shape[0]

    def __contains__(self, name: object) -> bool:
        return name in self.columns

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.values[:, self.columns.index(name)]
        except ValueError:
            raise KeyError(name) from None

    def renamed(self, old: str, new: str) -> RecordingTable:
        """The table with column ``old`` named ``new``, an existing ``new`` column dropped
        (a named time axis replaces ``time_s``)."""
        keep = [i for i, name in enumerate(self.columns) if name != new]
        names = tuple(new if self.columns[i] == old else self.columns[i] for i in keep)
        values = self.values if len(keep) == len(self.columns) else self.values[:, keep]
        return RecordingTable(self.path, self.header, names, values)

    def frame(self) -> pd.DataFrame:
        """The table as the DataFrame ``read_recording`` returns (``attrs`` ``path`` and
        ``header``)."""
        import pandas as pd

        frame = pd.DataFrame(self.values, columns=list(self.columns))
        frame.attrs["path"] = self.path
        frame.attrs["header"] = self.header
        return frame


def read_recording(
    path: str | os.PathLike[str],
    *,
    allow_missing: bool = False,
    columns: Iterable[str] | None = None,
    delimiter: str = ",",
    decimal: str = ".",
    encoding: str | None = None,
) -> pd.DataFrame:
    """Read and validate one recording; all columns become float64.

    ``allow_missing`` reads empty and NaN cells (not in ``time_s``) as NaN instead of raising
    ``MissingValueError``; see the module docstring. ``columns`` keeps only those columns (plus
    ``time_s``) and checks only their cells, so a gap or a note in a column the caller does
    not use cannot reject the file; names not in the header are left out (the caller says
    what it missed, ``require_columns`` lists the whole header); every line must still have
    all its fields. ``frame.attrs["path"]`` keeps the file name for later messages,
    ``frame.attrs["header"]`` every column name of the file. ``delimiter`` and ``decimal``
    give the CSV dialect (``formats.roles.detect_dialect`` finds them); a file that reads
    as one column whose name holds another delimiter is refused saying so.

    The DataFrame of ``read_table(..., engine="pandas")``: the same checks and values.
    """
    return read_table(path, allow_missing=allow_missing, columns=columns,
                      delimiter=delimiter, decimal=decimal, engine="pandas",
                      encoding=encoding).frame()


def read_table(
    path: str | os.PathLike[str],
    *,
    allow_missing: bool = False,
    columns: Iterable[str] | None = None,
    delimiter: str = ",",
    decimal: str = ".",
    engine: str = "numpy",
    encoding: str | None = None,
) -> RecordingTable:
    """Read and validate one recording as arrays (see ``read_recording`` for the rules and
    ``ENGINES`` for ``engine``; the rules and the values do not depend on it).
    ``encoding``: the file's text encoding (default UTF-8, a BOM allowed; ``--encoding``)."""
    if engine not in ENGINES:
        raise ValueError(f"engine must be one of {ENGINES}, got {engine!r}")
    path = Path(path)
    if not path.exists():
        raise SpindlebenchError(f"recording {path}: file not found")
    check_input(path, "recording", max_bytes=MAX_RECORDING_BYTES)
    if not path.is_file():
        raise SpindlebenchError(f"recording {path}: is {file_kind(path)}, not a file")
    dialect = _Dialect(delimiter, decimal, check_encoding(encoding))
    header = _read_header(path, dialect)
    keep = header if columns is None else _kept(header, columns)
    values = None
    if engine == "numpy" and dialect.encoding == ENCODING:  # it reads the bytes as UTF-8
        values = _parse_with_numpy(path, header, allow_missing, keep, dialect)
    if values is None:  # not a plain file: what pandas' tokenizer reads
        values = _parse_with_pandas(path, header, allow_missing, keep, dialect)
    if values is None:  # something is wrong: read as text to say exactly what and where
        values = _read_diagnosing(path, header, allow_missing, keep, dialect)
    if len(values) < 2:
        raise SpindlebenchError(
            f"recording {path}: has {len(values)} data row(s); an experiment needs at least 2"
        )
    if TIME_COLUMN in keep:
        time_s = values[:, keep.index(TIME_COLUMN)]
        bad = np.flatnonzero(np.diff(time_s) <= 0)
        if bad.size:
            raise SpindlebenchError(
                f"recording {path}, line {bad[0] + 3}: '{TIME_COLUMN}' does not increase "
                f"({time_s[bad[0]]:g} -> {time_s[bad[0] + 1]:g})"
            )
    return RecordingTable(str(path), FileHeader(header), tuple(keep), values)


class FileHeader(list):
    """Every column name of a recording's file, as read (``frame.attrs["header"]``; not
    changed after reading). pandas deep-copies ``attrs`` into every column and frame derived
    from a frame: this copy is the list itself, so selecting a column costs no copy of a
    100-name header (that was ~20 % of ``evaluate`` on two 100-sensor recordings)."""

    def __deepcopy__(self, memo: dict) -> FileHeader:
        return self


@dataclass(frozen=True)
class _Dialect:
    delimiter: str = ","
    decimal: str = "."
    encoding: str = ENCODING


def _kept(header: list[str], columns: Iterable[str]) -> list[str]:
    """The header's names among ``columns``, plus ``time_s``, in file order."""
    wanted = {str(name) for name in columns} | {TIME_COLUMN}
    return [name for name in header if name in wanted]


def _checked_values(values: np.ndarray, keep: list[str], allow_missing: bool) -> bool:
    """Whether parsed ``values`` of the ``keep`` columns pass: finite, or NaN where
    ``allow_missing`` permits it (never in ``time_s``)."""
    if not allow_missing:
        return bool(np.isfinite(values).all())
    if np.isinf(values).any():
        return False
    return not (TIME_COLUMN in keep and np.isnan(values[:, keep.index(TIME_COLUMN)]).any())


def _parse_with_pandas(
    path: Path, header: list[str], allow_missing: bool, keep: list[str], dialect: _Dialect
) -> np.ndarray | None:
    """Fast path: the ``keep`` columns parse as finite floats throughout (or NaN where
    ``allow_missing`` permits it), and every line has all its fields; or None."""
    import pandas as pd

    na = {"keep_default_na": False, "na_values": _FAST_NA_VALUES} if allow_missing else {}
    try:
        frame = pd.read_csv(
            path, skip_blank_lines=False, engine="c", encoding=dialect.encoding,
            sep=dialect.delimiter, decimal=dialect.decimal, **na
        )
    except (pd.errors.ParserError, UnicodeDecodeError, ValueError):
        return None
    if frame.shape[1] != len(header):
        return None
    # pandas pads short rows and blank lines with NaN: where a NaN is not an error (an ignored
    # column, or allow_missing), every line must be checked to have all its fields.
    if frame.isna().to_numpy().any() and (allow_missing or len(keep) < len(header)) \
            and not _all_fields_fast(path, len(frame), len(header), dialect.delimiter):
        return None
    frame = frame.set_axis(header, axis=1).loc[:, keep]
    numeric = all(
        pd.api.types.is_float_dtype(dtype) or pd.api.types.is_integer_dtype(dtype)
        for dtype in frame.dtypes
    )
    if not numeric:
        return None
    values = frame.to_numpy(dtype=float)
    return values if _checked_values(values, keep, allow_missing) else None


#: A NaN spelling with a sign, which ``float`` reads but the rules do not count as missing.
_SIGNED_NAN = re.compile(rb"[+-]nan", re.IGNORECASE)


def _parse_with_numpy(
    path: Path, header: list[str], allow_missing: bool, keep: list[str], dialect: _Dialect
) -> np.ndarray | None:
    """Fast path without pandas, for the plain files a logger or the testbench writes: ASCII
    data lines, no quotes, every line with exactly the header's number of fields, every
    ``keep`` cell a number ``float`` reads (empty or NaN where ``allow_missing`` permits
    it), no "-0" in a column of integers; or None. ``np.loadtxt`` converts with Python's
    correctly rounded ``float``, which is what pandas' parser gives on such cells (tested);
    it reads the bytes as a file (a third faster than line by line)."""
    data = path.read_bytes()
    data = data.removeprefix(codecs.BOM_UTF8)
    newline = data.find(b"\n")
    if newline < 0 or b'"' in data or data.count(b"\r") != data.count(b"\r\n"):
        return None  # no data line, quoting, or a line break other than \n and \r\n
    body = data[newline + 1:].removesuffix(b"\n")  # without the last line's newline
    if not body.isascii():
        return None
    if not body:
        return np.empty((0, len(keep)))
    rows = body.count(b"\n") + 1
    delimiter = dialect.delimiter.encode()
    every_column = len(keep) == len(header)
    # every line must have all its fields: np.loadtxt checks that itself when it reads every
    # column (a line with another count is an error, a blank line is skipped: rows differ)
    if not every_column and any(line.count(delimiter) != len(header) - 1
                                for line in body.split(b"\n")):
        return None  # a short, long or blank line: the text path names it
    if dialect.decimal == ",":  # the delimiter is not a comma (detect_dialect)
        body = body.replace(b",", b".")
    if allow_missing:
        body = _empty_field(dialect.delimiter).sub(b"nan", body)
    positions = [header.index(name) for name in keep]
    try:
        values = np.loadtxt(io.BytesIO(body), delimiter=dialect.delimiter, comments=None,
                            quotechar=None, usecols=None if every_column else positions,
                            ndmin=2, dtype=float)
    except ValueError:
        return None
    if values.shape != (rows, len(keep)) or not _checked_values(values, keep, allow_missing):
        return None
    if allow_missing and np.isnan(values).any() and _SIGNED_NAN.search(body):
        return None  # "-nan" is not a missing-value spelling
    if _integer_negative_zero(values, body.split(b"\n"), positions, delimiter):
        return None
    return values


#: A cell pandas reads as an integer (a column of them becomes int64, "-0" the integer 0).
_INTEGER = re.compile(rb"\s*[+-]?\d+\s*|\s*nan\s*", re.IGNORECASE)


def _integer_negative_zero(values: np.ndarray, lines: list[bytes], positions: list[int],
                           delimiter: bytes) -> bool:
    """Whether a column with a -0.0 has only integer (or missing) cells: pandas reads those
    as integers, so its -0 is +0.0 there (a column with a decimal point keeps -0.0)."""
    negative_zero = (values == 0) & np.signbit(values)
    for j in np.flatnonzero(negative_zero.any(axis=0)):
        cells = (line.split(delimiter)[positions[j]] for line in lines)
        if all(_INTEGER.fullmatch(cell) for cell in cells):
            return True
    return False


@functools.lru_cache(maxsize=8)
def _empty_field(delimiter: str) -> re.Pattern[bytes]:
    """Where a line has an empty field: at its start or after a delimiter, before the next
    delimiter or its end (a trailing carriage return is not empty: the text path)."""
    d = re.escape(delimiter).encode()
    return re.compile(rb"(?m)(?:^|(?<=" + d + rb"))(?=" + d + rb"|$)")


def _all_fields_fast(path: Path, rows: int, width: int, delimiter: str = ",") -> bool:
    """Whether the file has one delimiter fewer than columns on every line (no quoting),
    cheaply; False sends the caller to the slow path, which checks line by line."""
    return path.read_bytes().count(delimiter.encode()) == (rows + 1) * (width - 1)


def _read_diagnosing(
    path: Path, header: list[str], allow_missing: bool, keep: list[str], dialect: _Dialect
) -> np.ndarray:
    """Slow path: read every cell as text, raise naming the first bad cell of ``keep``, or
    return their values."""
    import pandas as pd

    try:
        raw = pd.read_csv(
            path, dtype=str, keep_default_na=False, skip_blank_lines=False, engine="c",
            encoding=dialect.encoding, sep=dialect.delimiter,
        )
    except UnicodeDecodeError as exc:
        line = path.read_bytes()[: exc.start].count(b"\n") + 1
        raise SpindlebenchError(f"recording {path}, line {line}: not {_encoding_name(dialect)} "
                                f"text (byte {exc.start}); save it as UTF-8 or give its "
                                "encoding with --encoding (e.g. latin-1)") from exc
    except (pd.errors.ParserError, ValueError) as exc:
        detail = " ".join(str(exc).split())
        fields = re.search(r"Expected (\d+) fields in line (\d+), saw (\d+)", detail)
        if fields:
            expected, line, saw = fields.groups()
            raise SpindlebenchError(f"recording {path}, line {line}: {saw} field(s), the "
                                    f"header has {expected}") from exc
        raise SpindlebenchError(f"recording {path}: cannot parse CSV: {detail}") from exc
    if raw.shape[1] != len(header):
        raise SpindlebenchError(f"recording {path}: header and data have different widths")
    raw.columns = header  # names stripped of surrounding spaces
    raw = _drop_trailing_blank_rows(raw)
    if allow_missing or len(keep) < len(header):
        # pandas pads short rows with empty cells: those are not missing values
        _check_field_counts(path, len(header), len(raw), dialect.delimiter, dialect.encoding)
    values = np.empty((len(raw), len(keep)))
    for i, name in enumerate(keep):
        values[:, i] = _numeric_column(path, name, raw[name], allow_missing, dialect.decimal)
    return values


def read_header(path: str | os.PathLike[str], delimiter: str = ",",
                encoding: str | None = None) -> list[str]:
    """A recording's column names (stripped), checked like ``read_recording`` checks them."""
    path = Path(path)
    check_input(path, "recording", max_bytes=MAX_RECORDING_BYTES)
    if not path.is_file():
        raise SpindlebenchError(f"recording {path}: " + (
            f"is {file_kind(path)}, not a file" if path.exists() else "file not found"))
    return _read_header(path, _Dialect(delimiter, encoding=check_encoding(encoding)))


def check_encoding(encoding: str | None) -> str:
    """A text encoding a user named (``--encoding``), checked; None is UTF-8 (BOM allowed)."""
    if encoding is None:
        return ENCODING
    try:
        name = codecs.lookup(encoding).name
    except LookupError:
        raise SpindlebenchError(f"--encoding {encoding}: not a known text encoding (e.g. "
                                "utf-8, latin-1, cp1252)") from None
    return ENCODING if name == "utf-8" else name


def _encoding_name(dialect: _Dialect) -> str:
    return "UTF-8" if dialect.encoding == ENCODING else dialect.encoding


def _read_header(path: Path, dialect: _Dialect = _Dialect()) -> list[str]:
    try:
        with open(path, newline="", encoding=dialect.encoding) as handle:
            header = next(csv.reader(handle, delimiter=dialect.delimiter), None)
    except csv.Error as exc:  # a field over the csv module's limit (131 072 characters)
        raise SpindlebenchError(f"recording {path}, line 1: not a header of column names "
                                f"({exc})") from None
    except UnicodeDecodeError as exc:
        raise SpindlebenchError(f"recording {path}: not {_encoding_name(dialect)} text; save "
                                "it as UTF-8 or give its encoding with --encoding (e.g. "
                                "latin-1)") from exc
    if not header:
        raise SpindlebenchError(f"recording {path}: empty file (no header line)")
    names = [name.strip() for name in header]
    if len(names) == 1:
        for other in (",", ";", "\t", "|"):
            if other != dialect.delimiter and other in names[0]:
                shown = "tab" if other == "\t" else other
                raise SpindlebenchError(
                    f"recording {path}, line 1: read as one column {names[0][:40]!r} with "
                    f"delimiter {dialect.delimiter!r}; the fields look separated by "
                    f"{shown!r} (pass --delimiter '{shown}')")
    for number, name in enumerate(names, start=1):
        if not name:
            raise SpindlebenchError(f"recording {path}, line 1: column {number} has no name")
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise SpindlebenchError(f"recording {path}, line 1: repeated column(s) {repeated}")
    return names


def _check_field_counts(path: Path, width: int, rows: int, delimiter: str = ",",
                        encoding: str = ENCODING) -> None:
    """Raise naming the first of the first ``rows`` data lines without ``width`` fields."""
    with open(path, newline="", encoding=encoding) as handle:
        lines = csv.reader(handle, delimiter=delimiter)
        next(lines, None)
        for number, fields in enumerate(itertools.islice(lines, rows), start=2):
            if len(fields) != width:
                raise SpindlebenchError(
                    f"recording {path}, line {number}: {len(fields)} field(s), the header has "
                    f"{width} (a truncated or blank line is not a missing value)"
                )


def _drop_trailing_blank_rows(raw: pd.DataFrame) -> pd.DataFrame:
    blank = raw.isna() | (raw == "")
    filled = np.flatnonzero(~blank.all(axis=1).to_numpy())
    return raw.iloc[: filled[-1] + 1] if filled.size else raw.iloc[:0]


def _numeric_column(path: Path, name: str, cells: pd.Series, allow_missing: bool,
                    decimal: str = ".") -> np.ndarray:
    """One column as float64, or an error naming the first bad line (header = line 1).

    Empty and NaN cells raise ``MissingValueError`` (or pass as NaN with ``allow_missing``),
    except in ``time_s``, which must be complete.
    """
    import pandas as pd

    optional = name != TIME_COLUMN
    stripped = cells.str.strip()
    as_numbers = stripped.str.replace(",", ".", regex=False) if decimal == "," else stripped
    values = pd.to_numeric(as_numbers, errors="coerce").astype(float)
    bad_mask = ~np.isfinite(values.to_numpy())
    if allow_missing and optional:
        bad_mask &= ~stripped.str.lower().isin(MISSING_SPELLINGS).to_numpy(dtype=bool)
    bad = np.flatnonzero(bad_mask)
    if not bad.size:
        return values.to_numpy()
    row = int(bad[0])
    cell = cells.iloc[row]
    text = "" if pd.isna(cell) else str(cell).strip()
    error: type[SpindlebenchError] = SpindlebenchError
    if text.lower() in MISSING_SPELLINGS:
        what = "missing value" if not text else f"NaN value {cell!r}"
        if optional:
            error = MissingValueError
        else:
            what += f" ('{TIME_COLUMN}' must be complete)"
    elif text.lower() in {"na", "n/a", "null", "none"}:
        what = f"NaN value {cell!r}"
    elif np.isinf(values.iloc[row]):
        what = f"infinite value {cell!r}"
    else:
        what = f"non-numeric value {quoted_name(str(cell))}"
    raise error(
        f"recording {path}, line {row + 2}, column '{name}': {what} "
        f"({bad.size} bad cell(s) in this column)"
    )


def recording_name(frame: pd.DataFrame | RecordingTable, fallback: str = "<data frame>") -> str:
    """The file a frame (or a table) was read from, for messages."""
    if isinstance(frame, RecordingTable):
        return frame.path
    return str(frame.attrs.get("path", fallback))


def require_columns(frame: pd.DataFrame, columns: Iterable[str], what: str) -> None:
    """Raise naming the recording and the ``what`` columns it lacks (listing every column of
    the file, also those ``read_recording(columns=...)`` left out)."""
    missing = [name for name in columns if name not in frame.columns]
    if missing:
        raise SpindlebenchError(
            f"recording {recording_name(frame)}: {what} column(s) not found: "
            f"{', '.join(missing)} ("
            f"{columns_hint(list(map(str, frame.attrs.get('header', frame.columns))), missing[0])})"
        )


def default_sensors(frame: pd.DataFrame | RecordingTable, target: str) -> list[str]:
    """Sensor columns when none are given: every numeric column except the target,
    ``time_s``, ``true_*`` truth, driver/command columns (``ambient_C``, ``feed_*``,
    ``*_rpm``, ``*_mm_per_min``, heat flows ``*_W``) and other thermal-error or displacement
    channels (``*_um``), which are outputs, not temperatures. (A table's columns are all
    numeric.)
    """
    names = [str(name) for name in frame.columns
             if name != target and is_default_sensor(str(name))]
    if isinstance(frame, RecordingTable):
        return names
    import pandas as pd

    return [name for name in names if pd.api.types.is_numeric_dtype(frame[name])]


# --------------------------------------------------------------------------- writing

#: Text format of every float in the CSV: shortest round-trip repr (bit-exact, stable).
FLOAT_FORMAT = None


def sidecar_path(csv_path: str | os.PathLike[str]) -> Path:
    """The JSON sidecar that belongs to a recording CSV: same name, ``.json`` suffix."""
    return Path(csv_path).with_suffix(".json")


def check_recording_targets(csv_path: str | os.PathLike[str]) -> tuple[Path, Path]:
    """(CSV, JSON) paths of a recording, or one line: not a .csv name, or a folder there."""
    csv_path = Path(csv_path)
    if csv_path.suffix.lower() != ".csv":
        raise SpindlebenchError(f"{csv_path}: a recording must be written to a .csv file")
    json_path = sidecar_path(csv_path)
    for path in (csv_path, json_path):
        if path.is_dir():
            raise SpindlebenchError(f"{path}: is a directory, cannot write a recording there")
        refuse_shipped(path)  # never a shipped file (the CSV named first)
    return csv_path, json_path


def write_recording(csv_path: str | os.PathLike[str], frame: pd.DataFrame,
                    sidecar: dict[str, Any], float_format: str | None = FLOAT_FORMAT) -> Path:
    """Write ``frame`` as CSV and ``sidecar`` as JSON beside it; return the CSV path.

    The one writer of recordings (simulated and adapted). The sidecar gets
    ``recording_sha256``, the hash of the CSV as written (newlines ``\n`` on every
    platform); a sidecar that already holds the key (``None`` reserves its place) keeps it
    there, with the writer's value. ``float_format`` is the CSV's number format: the
    shortest round trip by default; an adapter of measured data keeps the source's
    precision (``"%.6f"``).
    """
    csv_path, json_path = check_recording_targets(csv_path)
    # the JSON context is the outer one, so the CSV is moved into place first: if that move
    # fails, the sidecar is not replaced either (no new sidecar beside an old CSV)
    with atomic_file(json_path) as part_json, atomic_file(csv_path) as part_csv:
        data = csv_bytes(frame, float_format)
        if data is None:  # pandas writes it
            part_csv.close()
            write_csv(part_csv.path, frame, float_format)
        else:
            part_csv.write(data)
        paired = {**sidecar, "recording_sha256": sha256_written(part_csv.path, data)}
        text = indented_json(paired, allow_nan=False) + "\n"  # json.dumps' text
        part_json.write(text.encode("utf-8"))
    return csv_path


def write_csv(path: str | os.PathLike[str], frame: pd.DataFrame,
              float_format: str | None = FLOAT_FORMAT) -> bytes | None:
    """``frame.to_csv(path, index=False, float_format=..., lineterminator="\\n")``, the same
    bytes (tested): in the shortest round trip through ``table_csv.write_table``, 2-3x
    faster for the all-float frames the testbench writes (each value Python's ``repr``, what
    pandas writes without a float format). A sweep writes a thousand recordings of ~27 000
    values in its one coordinating process, where pandas' writer was a third of its CPU per
    run; ``float_text`` writes the values at a tenth of ``repr``'s CPU."""
    if float_format is None:
        from spindlebench.formats.table_csv import write_table

        return write_table(path, frame)
    frame.to_csv(path, index=False, float_format=float_format, lineterminator="\n")
    return None


def csv_bytes(frame: pd.DataFrame, float_format: str | None = FLOAT_FORMAT) -> bytes | None:
    """The bytes ``write_csv`` writes, or None where pandas is left to write them."""
    if float_format is not None:
        return None
    from spindlebench.formats.table_csv import table_bytes

    return table_bytes(frame)


def read_back(csv_path: str | os.PathLike[str], frame: pd.DataFrame,
              columns: Iterable[str]) -> pd.DataFrame | None:
    """``read_recording(csv_path).loc[:, columns]`` after ``write_recording(csv_path, frame,
    ...)``, without reading the file; None where the equality is not certain (the caller
    reads the file then).

    A sweep hands each recording's truth to its evaluations as a resumed sweep reads it from
    disk; reading back every recording just written was 40 % of its coordinating process.
    The values are the same bits: the writer writes each float as its ``repr``, which
    round-trips exactly, and the reader's parsers round correctly (both tested on a
    simulated recording and on edge values). Certain only where ``read_recording`` would
    take the file as written: the writer's own float path, unique names without
    surrounding spaces, at least 2 rows, every value finite (a NaN or inf is a read error)
    and ``time_s`` strictly increasing.
    """
    import pandas as pd

    from spindlebench.formats.table_csv import floats_only

    names = list(map(str, frame.columns.tolist()))
    wanted = [str(name) for name in columns]
    values = frame.to_numpy()
    place = {name: number for number, name in enumerate(names)}
    if FLOAT_FORMAT is not None or not floats_only(frame) or len(frame) < 2 \
            or len(place) < len(names) or any(name != name.strip() for name in names) \
            or not set(wanted) <= set(names) or not np.isfinite(values).all():
        return None
    if TIME_COLUMN in place and not (np.diff(values[:, place[TIME_COLUMN]]) > 0).all():
        return None
    # one block, as read_recording's frame (building it column by column cost 10x more)
    out = pd.DataFrame(values[:, [place[name] for name in wanted]], columns=wanted)
    out.attrs = {"path": str(Path(csv_path)), "header": FileHeader(names)}
    return out


def read_sidecar(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Load a recording's sidecar (given the JSON or the CSV path)."""
    path = Path(path)
    if path.suffix == ".csv":
        path = sidecar_path(path)
    return json.loads(path.read_text(encoding="utf-8"))


def recording_frame(
    time_s: np.ndarray,
    measured_C: np.ndarray,
    measured_drift_um: np.ndarray,
    drivers: Mapping[str, np.ndarray],
    truth: Mapping[str, np.ndarray],
    probes: Mapping[str, np.ndarray] | None = None,
) -> pd.DataFrame:
    """The canonical recording table (column order fixed by the contract); ``probes``, the
    measured five-probe channels (``PROBE_OUTPUTS`` but ``probe_Z_um``, which is
    ``drift_um``), follow the drift when a scenario asks for them."""
    import pandas as pd

    columns: dict[str, np.ndarray] = {TIME_COLUMN: time_s}
    for i in range(measured_C.shape[1]):
        columns[SENSORS[i]] = measured_C[:, i]
    columns[DRIFT_COLUMN] = measured_drift_um
    for name in PROBE_OUTPUTS if probes is not None else ():
        if name != "probe_Z_um":
            columns[name] = probes[name]
    columns.update(drivers)
    for name in sorted(truth, key=_output_order):  # stable sort keeps FMU order in a group
        columns[true_column(name)] = truth[name]
    return pd.DataFrame(columns)


# --------------------------------------------------------------------------- sidecar

def sidecar_mismatch(csv_sha256: str, sidecar: dict[str, Any]) -> str | None:
    """Why a sidecar does not describe the CSV with hash ``csv_sha256`` (None when it does).

    A sidecar written by spindlebench names its CSV's hash; an older one without the field is
    taken on trust.
    """
    recorded = sidecar.get("recording_sha256")
    if recorded is None or recorded == csv_sha256:
        return None
    return (f"its recording_sha256 {str(recorded)[:12]}… is not the CSV's "
            f"{csv_sha256[:12]}… (the pair was not written together)")


def sidecar_record(*, provenance: dict[str, Any], initial_state_K: Mapping[str, float],
                   end_time_s: float, end_state_K: Mapping[str, float]) -> dict[str, Any]:
    """A synthetic recording's sidecar: its provenance plus the start and end states, under
    the keys ``read_end_state`` reads back (``end_state.states_K``, kelvin by state name)."""
    return {**provenance,
            "initial_state": {"time_s": 0.0, "states_K": dict(initial_state_K)},
            "end_state": {"time_s": end_time_s, "states_K": dict(end_state_K)}}


@dataclass(frozen=True)
class EndState:
    """A previous run's end state as its sidecar holds it, parsed: what a ``continue``
    scenario starts from. The runner gets this, never the file, and checks the states and
    values against its model; ``source`` and ``where`` (the key that named the file) make
    its messages one line naming both."""

    states_K: Mapping[str, Any]  # noqa: N815  (as written: values not checked yet)
    source: str
    where: str


def read_end_state(source: str | os.PathLike[str], where: str,
                   missing: str | None = None) -> EndState:
    """The ``end_state.states_K`` table of a recording's sidecar, as written (values unchecked:
    the caller knows which states and values its model accepts).

    The sidecar is user-reachable input (any file can be named), so everything about it that
    could break a run later is one line starting with ``where``; ``missing`` replaces the
    text after it for a file that is not there.
    """
    try:
        check_input(source, "sidecar (.json)")
        text = Path(source).read_text(encoding="utf-8")
    except FileNotFoundError:
        missing = missing or f"no such file {source} (simulate the previous run first)"
        raise SpindlebenchError(f"{where}: {missing}") from None
    except UnicodeDecodeError as exc:
        raise SpindlebenchError(f"{where}: {source} is not UTF-8 text (byte {exc.start}), "
                                "not a recording sidecar") from None
    except OSError as exc:  # a directory, no permission
        raise SpindlebenchError(f"{where}: cannot read {source}: "
                                f"{exc.strerror or exc}") from None
    try:
        saved = json.loads(text)["end_state"]["states_K"]
    except (json.JSONDecodeError, KeyError, TypeError):
        raise SpindlebenchError(f"{where}: {source} is not a recording sidecar with an "
                                "end_state") from None
    if not isinstance(saved, dict):
        raise SpindlebenchError(f"{where}: {source}: end_state.states_K must map state names "
                                f"to kelvin, got a {type(saved).__name__}")
    return EndState(states_K=saved, source=str(source), where=where)
