"""Writing a recording: the CSV and its JSON sidecar, each atomically, as a checkable pair.

A recording is only useful with its provenance, so both files are written in full first and
then moved into place one right after the other, the CSV first: a crash never leaves a half
file, and a failed CSV move never leaves a new sidecar describing a CSV that is not there.
Two renames cannot be one atomic step (a crash between them leaves a new CSV beside the old
sidecar), so the sidecar also carries the CSV's SHA-256 (``recording_sha256``): a reader can
tell a pair that does not belong together (see ``spindlebench.provenance.sidecar_mismatch``).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from spindlebench.atomic import atomic_path
from spindlebench.errors import SpindlebenchError
from spindlebench.provenance import sha256_file

#: Text format of every float in the CSV: shortest round-trip repr (bit-exact, stable).
FLOAT_FORMAT = None


def sidecar_path(csv_path: str | os.PathLike[str]) -> Path:
    """The JSON sidecar that belongs to a recording CSV: same name, ``.json`` suffix."""
    return Path(csv_path).with_suffix(".json")


def write_recording(csv_path: str | os.PathLike[str], frame: pd.DataFrame,
                    sidecar: dict[str, Any]) -> Path:
    """Write ``frame`` as CSV and ``sidecar`` as JSON beside it; return the CSV path."""
    csv_path = Path(csv_path)
    if csv_path.suffix.lower() != ".csv":
        raise SpindlebenchError(f"{csv_path}: a recording must be written to a .csv file")
    json_path = sidecar_path(csv_path)
    for path in (csv_path, json_path):
        if path.is_dir():
            raise SpindlebenchError(f"{path}: is a directory, cannot write a recording there")
    # the JSON context is the outer one, so the CSV is moved into place first: if that move
    # fails, the sidecar is not replaced either (no new sidecar beside an old CSV)
    with atomic_path(json_path) as tmp_json, atomic_path(csv_path) as tmp_csv:
        frame.to_csv(tmp_csv, index=False, float_format=FLOAT_FORMAT, lineterminator="\n")
        paired = {**sidecar, "recording_sha256": sha256_file(tmp_csv)}
        text = json.dumps(paired, indent=2, ensure_ascii=False, allow_nan=False) + "\n"
        tmp_json.write_text(text, encoding="utf-8")
    return csv_path


def read_sidecar(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Load a recording's sidecar (given the JSON or the CSV path)."""
    path = Path(path)
    if path.suffix == ".csv":
        path = sidecar_path(path)
    return json.loads(path.read_text(encoding="utf-8"))


def true_column(output_name: str) -> str:
    """Recording column of a noise-free FMU output: ``T1_C`` → ``true_T1_C``."""
    return f"true_{output_name}"


def _output_order(name: str) -> int:
    """Sensors, drift, nodes, heat flows, anything else; FMU order within a group."""
    for rank, prefix in enumerate(("T", "drift_um", "node_", "Q_")):
        if name.startswith(prefix):
            return rank
    return 4


def recording_frame(
    time_s: np.ndarray,
    measured_C: np.ndarray,
    measured_drift_um: np.ndarray,
    drivers: Mapping[str, np.ndarray],
    truth: Mapping[str, np.ndarray],
) -> pd.DataFrame:
    """The canonical recording table (column order fixed by the contract)."""
    columns: dict[str, np.ndarray] = {"time_s": time_s}
    for i in range(measured_C.shape[1]):
        columns[f"T{i + 1}"] = measured_C[:, i]
    columns["drift_um"] = measured_drift_um
    columns.update(drivers)
    for name in sorted(truth, key=_output_order):  # stable sort keeps FMU order in a group
        columns[true_column(name)] = truth[name]
    return pd.DataFrame(columns)
