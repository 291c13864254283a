"""One recording read with its column roles and fingerprinted (``statistics.fingerprint``).

``spindlebench fingerprint`` (``commands.fingerprint``) runs this per recording; the figure
(``figure``) draws the results.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from spindlebench.core.errors import SpindlebenchError, columns_hint
from spindlebench.formats.recording import DRIFT_COLUMN, TIME_COLUMN, read_header, sidecar_path
from spindlebench.formats.roles import (
    SPEED_COLUMN,
    ColumnRoles,
    RoleChoice,
    detect_dialect,
    read_with_roles,
    refuse_target_copies,
    require_time,
)
from spindlebench.studies.fingerprint.statistics import KEYS, fingerprint

#: The error column of a recording that has it and no ``--target`` is given.
DEFAULT_TARGET = DRIFT_COLUMN


@dataclass(frozen=True)
class Fingerprinted:
    """One recording's fingerprint and the columns it was computed from."""

    path: Path
    target: str
    time_column: str
    sensors: list[str]
    time: np.ndarray
    rises: np.ndarray  # n x m sensor rises (K)
    error: np.ndarray  # n error rise
    stats: dict[str, float]
    #: The spindle-speed programme (``spindle_speed_rpm`` or ``--speed-column``), or None.
    programme: list[dict[str, float]] | None = None

    def row(self) -> dict[str, Any]:
        """The JSON row: which file and columns, then the statistics (NaN as null)."""
        return {"recording": str(self.path), "target": self.target,
                "time_column": self.time_column, "sensors": list(self.sensors),
                "samples": int(self.time.size), "programme": self.programme,
                **json_stats(self.stats)}


#: A programme with more speed changes than this is summarised by its first ones.
MAX_PROGRAMME_STEPS = 50


def programme(time_s: np.ndarray, speed_rpm: np.ndarray) -> list[dict[str, float]]:
    """The speed programme as steps ``{"start_h", "rpm"}``: one per change of speed."""
    speed = np.asarray(speed_rpm, dtype=float)
    starts = [0] + [int(i) + 1 for i in np.flatnonzero(np.diff(speed) != 0)]
    return [{"start_h": round(float(time_s[i]) / 3600.0, 6), "rpm": float(speed[i])}
            for i in starts[:MAX_PROGRAMME_STEPS] if np.isfinite(speed[i])]


def json_stats(stats: dict[str, float]) -> dict[str, float | None]:
    """Statistics for JSON: a value that is undefined for the recording (NaN) is null."""
    return {key: (None if not math.isfinite(stats[key]) else float(stats[key])) for key in KEYS}


def median_stats(rows: list[dict[str, float]]) -> dict[str, float]:
    """Per statistic, the median over recordings where it is defined (NaN if nowhere)."""
    out = {}
    for key in KEYS:
        values = [row[key] for row in rows if math.isfinite(row[key])]
        out[key] = float(np.median(values)) if values else math.nan
    return out


def fingerprint_recording(path: Path, target: str | None = None,
                          roles: ColumnRoles | None = None
                          ) -> tuple[Fingerprinted, RoleChoice]:
    """Read one recording under the column ``roles`` and compute its fingerprint, or raise
    one error line. The time column is required (t63 is a time); a sensor that copies the
    target (|r| > 0.999) is refused unless the roles allow it (it would give ψ = 1)."""
    roles = roles or ColumnRoles()
    delimiter, _ = detect_dialect(path, roles.delimiter, roles.decimal, roles.encoding)
    target = target or _default_target(path, read_header(path, delimiter, roles.encoding))
    frame, choice = read_with_roles(path, target, roles, extra=(SPEED_COLUMN,))
    require_time(choice, str(path), "the fingerprint (t63 is a time)")
    refuse_target_copies(frame, target, choice.sensors, str(path), roles.allow_target_copy)
    time = frame[TIME_COLUMN].to_numpy(dtype=float)
    temps = frame[choice.sensors].to_numpy(dtype=float)
    error = frame[target].to_numpy(dtype=float)
    if np.ptp(error) == 0:
        raise SpindlebenchError(f"recording {path}: target column {target!r} is constant "
                                f"({error[0]:g}): no thermal error to fingerprint; name the "
                                "error column with --target")
    steps = (programme(time, frame[SPEED_COLUMN].to_numpy(dtype=float))
             if SPEED_COLUMN in frame else None)
    try:
        stats = fingerprint(time, temps, error)
    except SpindlebenchError as exc:
        raise SpindlebenchError(f"recording {path}: {exc}") from exc
    return Fingerprinted(path, target, str(choice.time_column), list(choice.sensors), time,
                         temps - temps[0], error - error[0], stats, steps), choice


def _default_target(path: Path, header: list[str]) -> str:
    """``drift_um`` if present, else the sidecar's ``axial_target``, else one error line."""
    if DEFAULT_TARGET in header:
        return DEFAULT_TARGET
    named = _sidecar_target(path)
    if named is not None and named in header:
        return named
    raise SpindlebenchError(
        f"recording {path}: no --target given, no '{DEFAULT_TARGET}' column and no "
        f"axial_target in {sidecar_path(path).name} ({columns_hint(header, DEFAULT_TARGET)})")


def _sidecar_target(path: Path) -> str | None:
    """The ``axial_target`` a recording's JSON sidecar names, if it has one."""
    try:
        named = json.loads(sidecar_path(path).read_text(encoding="utf-8")).get("axial_target")
    except (OSError, ValueError, AttributeError):
        return None
    return named if isinstance(named, str) else None
