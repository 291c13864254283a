"""Reading and validating canonical recordings (synthetic or real), one CSV per experiment.

A canonical recording is a CSV with a header line and one numeric row per sample: ``time_s``,
sensor temperatures, the measured thermal error, optionally drivers and ``true_*`` columns.
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
"""

from __future__ import annotations

import csv
import itertools
import os
import re
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import pandas as pd

from spindlebench.errors import SpindlebenchError

TIME_COLUMN = "time_s"
#: UTF-8, with a leading byte-order mark (Excel's "CSV UTF-8" export) dropped: kept, it would
#: glue itself to the first column name ("\ufefftime_s") and time_s would become a sensor.
ENCODING = "utf-8-sig"

#: Columns that are never sensors by default: the synthetic testbench's driver inputs and
#: noise-free truth, and, on any recording, thermal errors/displacements (``*_um``), speeds
#: (``*_rpm``) and feed rates. ``ambient_C`` is the testbench's ambient *driver*; the measured
#: ambient sensor is a T column.
_NOT_SENSOR = re.compile(r"^(true_.*|.*_um|.*_rpm|feed_.*|.*_mm_per_min|.*_W|ambient_C)$")


#: Cell spellings ``allow_missing`` reads as NaN (compared after stripping, case-insensitive).
MISSING_SPELLINGS = ("", "nan")
#: The exact strings the fast path hands to pandas as NaN; other casings take the slow path.
_FAST_NA_VALUES = ["", "nan", "NaN", "NAN"]


class MissingValueError(SpindlebenchError):
    """An empty or NaN cell in a recording read without ``allow_missing``: the one bad-input
    case a caller can opt out of, so callers can point to their option."""


def read_recording(
    path: str | os.PathLike[str],
    *,
    allow_missing: bool = False,
    columns: Iterable[str] | None = None,
) -> pd.DataFrame:
    """Read and validate one recording; all columns become float64.

    ``allow_missing`` reads empty and NaN cells (not in ``time_s``) as NaN instead of raising
    ``MissingValueError``; see the module docstring. ``columns`` keeps only those columns (plus
    ``time_s``) and checks only their cells, so a gap or a note in a column the caller does
    not use cannot reject the file; names not in the header are left out (the caller says
    what it missed, ``require_columns`` lists the whole header); every line must still have
    all its fields. ``frame.attrs["path"]`` keeps the file name for later messages,
    ``frame.attrs["header"]`` every column name of the file.
    """
    path = Path(path)
    if not path.exists():
        raise SpindlebenchError(f"recording {path}: file not found")
    if not path.is_file():
        raise SpindlebenchError(f"recording {path}: not a file")
    header = _read_header(path)
    keep = header if columns is None else _kept(header, columns)
    frame = _read_clean(path, header, allow_missing, keep)
    if frame is None:  # something is wrong: read as text to say exactly what and where
        frame = _read_diagnosing(path, header, allow_missing, keep)
    if len(frame) < 2:
        raise SpindlebenchError(
            f"recording {path}: has {len(frame)} data row(s); an experiment needs at least 2"
        )
    if TIME_COLUMN in frame:
        steps = np.diff(frame[TIME_COLUMN].to_numpy())
        bad = np.flatnonzero(steps <= 0)
        if bad.size:
            raise SpindlebenchError(
                f"recording {path}, line {bad[0] + 3}: '{TIME_COLUMN}' does not increase "
                f"({frame[TIME_COLUMN].iloc[bad[0]]:g} -> {frame[TIME_COLUMN].iloc[bad[0] + 1]:g})"
            )
    frame.attrs["path"] = str(path)
    frame.attrs["header"] = list(header)
    return frame


def _kept(header: list[str], columns: Iterable[str]) -> list[str]:
    """The header's names among ``columns``, plus ``time_s``, in file order."""
    wanted = {str(name) for name in columns} | {TIME_COLUMN}
    return [name for name in header if name in wanted]


def _read_clean(
    path: Path, header: list[str], allow_missing: bool, keep: list[str]
) -> pd.DataFrame | None:
    """Fast path: the ``keep`` columns parse as finite floats throughout (or NaN where
    ``allow_missing`` permits it), and every line has all its fields; or None."""
    na = {"keep_default_na": False, "na_values": _FAST_NA_VALUES} if allow_missing else {}
    try:
        frame = pd.read_csv(
            path, skip_blank_lines=False, engine="c", encoding=ENCODING, **na
        )
    except (pd.errors.ParserError, UnicodeDecodeError, ValueError):
        return None
    if frame.shape[1] != len(header):
        return None
    # pandas pads short rows and blank lines with NaN: where a NaN is not an error (an ignored
    # column, or allow_missing), every line must be checked to have all its fields.
    if frame.isna().to_numpy().any() and (allow_missing or len(keep) < len(header)) \
            and not _all_fields_fast(path, len(frame), len(header)):
        return None
    frame = frame.set_axis(header, axis=1).loc[:, keep]
    numeric = all(
        pd.api.types.is_float_dtype(dtype) or pd.api.types.is_integer_dtype(dtype)
        for dtype in frame.dtypes
    )
    if not numeric:
        return None
    values = frame.to_numpy(dtype=float)
    if not allow_missing:
        return frame.astype(float) if np.isfinite(values).all() else None
    if np.isinf(values).any():
        return None
    if TIME_COLUMN in keep and np.isnan(values[:, keep.index(TIME_COLUMN)]).any():
        return None  # time_s must be complete
    return frame.astype(float)


def _all_fields_fast(path: Path, rows: int, width: int) -> bool:
    """Whether the file has one comma fewer than columns on every line (no quoting), cheaply;
    False sends the caller to the slow path, which checks line by line."""
    return path.read_bytes().count(b",") == (rows + 1) * (width - 1)


def _read_diagnosing(
    path: Path, header: list[str], allow_missing: bool, keep: list[str]
) -> pd.DataFrame:
    """Slow path: read every cell as text, raise naming the first bad cell of ``keep``."""
    try:
        raw = pd.read_csv(
            path, dtype=str, keep_default_na=False, skip_blank_lines=False, engine="c",
            encoding=ENCODING,
        )
    except (pd.errors.ParserError, UnicodeDecodeError, ValueError) as exc:
        detail = " ".join(str(exc).split())
        raise SpindlebenchError(f"recording {path}: cannot parse CSV: {detail}") from exc
    if raw.shape[1] != len(header):
        raise SpindlebenchError(f"recording {path}: header and data have different widths")
    raw.columns = header  # names stripped of surrounding spaces
    raw = _drop_trailing_blank_rows(raw)
    if allow_missing or len(keep) < len(header):
        # pandas pads short rows with empty cells: those are not missing values
        _check_field_counts(path, len(header), len(raw))
    return pd.DataFrame(
        {
            name: _numeric_column(path, name, raw[name], allow_missing)
            for name in keep
        },
        index=raw.index,
    )


def _read_header(path: Path) -> list[str]:
    try:
        with open(path, newline="", encoding=ENCODING) as handle:
            header = next(csv.reader(handle), None)
    except UnicodeDecodeError as exc:
        raise SpindlebenchError(f"recording {path}: not UTF-8 text") from exc
    if not header:
        raise SpindlebenchError(f"recording {path}: empty file (no header line)")
    names = [name.strip() for name in header]
    for number, name in enumerate(names, start=1):
        if not name:
            raise SpindlebenchError(f"recording {path}, line 1: column {number} has no name")
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise SpindlebenchError(f"recording {path}, line 1: repeated column(s) {repeated}")
    return names


def _check_field_counts(path: Path, width: int, rows: int) -> None:
    """Raise naming the first of the first ``rows`` data lines without ``width`` fields."""
    with open(path, newline="", encoding=ENCODING) as handle:
        lines = csv.reader(handle)
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


def _numeric_column(path: Path, name: str, cells: pd.Series, allow_missing: bool) -> pd.Series:
    """One column as float64, or an error naming the first bad line (header = line 1).

    Empty and NaN cells raise ``MissingValueError`` (or pass as NaN with ``allow_missing``),
    except in ``time_s``, which must be complete.
    """
    optional = name != TIME_COLUMN
    stripped = cells.str.strip()
    values = pd.to_numeric(stripped, errors="coerce").astype(float)
    bad_mask = ~np.isfinite(values.to_numpy())
    if allow_missing and optional:
        bad_mask &= ~stripped.str.lower().isin(MISSING_SPELLINGS).to_numpy(dtype=bool)
    bad = np.flatnonzero(bad_mask)
    if not bad.size:
        return values
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
        what = f"non-numeric value {cell!r}"
    raise error(
        f"recording {path}, line {row + 2}, column '{name}': {what} "
        f"({bad.size} bad cell(s) in this column)"
    )


def recording_name(frame: pd.DataFrame, fallback: str = "<data frame>") -> str:
    """The file a frame was read from, for messages."""
    return str(frame.attrs.get("path", fallback))


def require_columns(frame: pd.DataFrame, columns: Iterable[str], what: str) -> None:
    """Raise naming the recording and the ``what`` columns it lacks (listing every column of
    the file, also those ``read_recording(columns=...)`` left out)."""
    missing = [name for name in columns if name not in frame.columns]
    if missing:
        raise SpindlebenchError(
            f"recording {recording_name(frame)}: {what} column(s) not found: "
            f"{', '.join(missing)} (columns are: "
            f"{', '.join(map(str, frame.attrs.get('header', frame.columns)))})"
        )


def is_default_sensor(name: str) -> bool:
    """Whether a column counts as a sensor when none are named (see ``default_sensors``)."""
    return name != TIME_COLUMN and not _NOT_SENSOR.match(name)


def default_sensors(frame: pd.DataFrame, target: str) -> list[str]:
    """Sensor columns when none are given: every numeric column except the target,
    ``time_s``, ``true_*`` truth, driver/command columns (``ambient_C``, ``feed_*``,
    ``*_rpm``, ``*_mm_per_min``, heat flows ``*_W``) and other thermal-error or displacement
    channels (``*_um``), which are outputs, not temperatures.
    """
    return [
        str(name)
        for name in frame.columns
        if name != target
        and is_default_sensor(str(name))
        and pd.api.types.is_numeric_dtype(frame[name])
    ]
