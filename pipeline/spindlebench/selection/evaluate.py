"""The whole protocol on recordings: select on one experiment, fit, predict the others.

``evaluate`` is what ``spindlebench evaluate`` and the paper comparison call. Candidates are
the sensors (plus their pairwise differences), as rises relative to each experiment's first
sample; the target (thermal error, um) is used as recorded (canonical recordings zero it at the
first sample, like a displacement probe).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from spindlebench.recordings import (
    default_sensors,
    read_recording,
    recording_name,
)
from spindlebench.selection.differences import difference_names, pair_indices
from spindlebench.selection.errors import SelectionError
from spindlebench.selection.regression import LinearFit, fit_ols, rises, rmse
from spindlebench.selection.select import Selection, select_sensitive_points

RecordingLike = str | os.PathLike[str] | pd.DataFrame


@dataclass(frozen=True)
class CandidateSet:
    """Raw sensors plus (optionally) their pairwise differences, as rises, any subset of columns."""

    sensors: tuple[str, ...]
    differences: bool

    @property
    def names(self) -> list[str]:
        """Candidate names: sensors, then ``A-B`` differences."""
        names = list(self.sensors)
        return names + difference_names(names) if self.differences else names

    def matrix(self, frame: pd.DataFrame, columns: Sequence[int] | None = None) -> np.ndarray:
        """Candidate values (rises) of ``frame``; only ``columns`` if given."""
        raw = rises(frame.loc[:, list(self.sensors)].to_numpy(dtype=float))
        n = raw.shape[1]
        wanted = np.arange(len(self.names)) if columns is None else np.asarray(columns, int)
        if wanted.size and (wanted.min() < 0 or wanted.max() >= len(self.names)):
            raise SelectionError(f"candidate index out of range 0..{len(self.names) - 1}")
        is_raw = wanted < n
        pair = wanted[~is_raw] - n  # index into the pair list
        first, second = pair_indices(n)
        out = np.empty((raw.shape[0], wanted.size))
        out[:, is_raw] = raw[:, wanted[is_raw]]
        out[:, ~is_raw] = raw[:, first[pair]] - raw[:, second[pair]]
        return out


@dataclass(frozen=True)
class Evaluation:
    """Result of ``evaluate``; ``to_dict()`` is the ``spindlebench evaluate --json`` shape."""

    train: str
    target: str
    sensors: list[str]
    candidates: list[str]
    selection: Selection
    fit: LinearFit
    predictions: dict[str, np.ndarray]
    measured: dict[str, np.ndarray]
    rmse_um: dict[str, float]

    @property
    def selected(self) -> list[str]:
        """Selected candidate names, one per cluster."""
        return [self.candidates[i] for i in self.selection.selected]

    @property
    def psi(self) -> list[float]:
        """psi (signed correlation with the error) of each selected candidate."""
        return [float(value) for value in self.selection.selected_psi]

    @property
    def clusters(self) -> list[list[str]]:
        """Candidate names of each cluster."""
        return [[self.candidates[i] for i in members] for members in self.selection.clusters]

    @property
    def coefficients(self) -> dict[str, float]:
        """Intercept, then one coefficient per selected candidate (um per K)."""
        out = {"intercept": float(self.fit.intercept)}
        out.update(zip(self.selected, map(float, self.fit.coefficients), strict=True))
        return out

    @property
    def mean_rmse_um(self) -> float:
        """Mean of the per-experiment RMSE."""
        return float(np.mean(list(self.rmse_um.values())))

    def to_dict(self) -> dict[str, Any]:
        """The JSON shape of ``spindlebench evaluate --json`` (without provenance)."""
        return {
            "selected": self.selected,
            "psi": self.psi,
            "eta": float(self.selection.eta),
            "clusters": self.clusters,
            "coefficients": self.coefficients,
            "r2": _finite_or_none(self.fit.r2),
            "rmse_um": {name: float(value) for name, value in self.rmse_um.items()},
            "mean_rmse_um": self.mean_rmse_um,
        }

    def summary(self) -> str:
        """A readable multi-line report."""
        lines = [
            f"train: {self.train}   target: {self.target}   "
            f"candidates: {len(self.candidates)} ({len(self.selection.dropped)} constant dropped)",
            f"clusters: {len(self.selection.clusters)} at eta = {self.selection.eta:.6f}",
        ]
        for number, (members, chosen, psi) in enumerate(
            zip(self.clusters, self.selected, self.psi, strict=True), start=1
        ):
            shown = ", ".join(members[:8]) + (f", ... ({len(members)})" if len(members) > 8 else "")
            lines.append(f"  {number}: keep {chosen} (psi = {psi:+.4f}) from [{shown}]")
        terms = " ".join(
            f"{value:+.4g}*d({name})" for name, value in list(self.coefficients.items())[1:]
        )
        lines.append(f"model: {self.target} = {self.fit.intercept:.4g} {terms}")
        lines.append(f"training R2: {self.fit.r2:.4f}")
        lines.append("RMSE on the other experiments (um):")
        width = max(len(name) for name in self.rmse_um)
        for name, value in self.rmse_um.items():
            lines.append(f"  {name:<{width}}  {value:8.3f}")
        lines.append(f"  {'mean':<{width}}  {self.mean_rmse_um:8.3f}")
        return "\n".join(lines)


def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _load(recording: RecordingLike, fallback: str) -> tuple[str, pd.DataFrame]:
    if isinstance(recording, pd.DataFrame):
        return recording_name(recording, fallback), recording
    return str(recording), read_recording(Path(recording))


def _check_finite(name: str, frame: pd.DataFrame, columns: Sequence[str]) -> None:
    """Frames handed in directly skip ``read_recording``: check the columns used."""
    if len(frame) < 2:
        raise SelectionError(
            f"recording {name}: has {len(frame)} row(s); an experiment needs at least 2"
        )
    for column in columns:
        values = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=float)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise SelectionError(
                f"recording {name}, row {bad[0]}, column '{column}': missing, NaN, infinite "
                f"or non-numeric value"
            )


def resolve_sensors(
    train_name: str,
    train: pd.DataFrame,
    tests: Mapping[str, pd.DataFrame],
    target: str,
    sensors: Sequence[str] | None,
) -> list[str]:
    """The sensor list, checked against every recording."""
    for name, frame in [(train_name, train), *tests.items()]:
        if target not in frame.columns:
            raise SelectionError(f"recording {name}: target column '{target}' not found")
    if sensors is not None:
        sensors = [str(sensor) for sensor in sensors]
        if not sensors:
            raise SelectionError("the sensor list is empty")
        repeated = sorted({s for s in sensors if sensors.count(s) > 1})
        if repeated:
            raise SelectionError(f"sensor(s) listed twice: {', '.join(repeated)}")
        if target in sensors:
            raise SelectionError(f"the target '{target}' is also listed as a sensor")
        for name, frame in [(train_name, train), *tests.items()]:
            missing = [sensor for sensor in sensors if sensor not in frame.columns]
            if missing:
                raise SelectionError(
                    f"recording {name}: sensor column(s) not found: {', '.join(missing)}"
                )
        return sensors
    chosen = default_sensors(train, target)
    if not chosen:
        raise SelectionError(f"recording {train_name}: no sensor columns found; pass --sensors")
    for name, frame in tests.items():
        theirs = default_sensors(frame, target)
        if theirs != chosen:
            missing = [s for s in chosen if s not in theirs]
            extra = [s for s in theirs if s not in chosen]
            raise SelectionError(
                f"recording {name}: sensor columns differ from the training file {train_name} "
                f"(missing: {missing or 'none'}; extra: {extra or 'none'}); pass --sensors"
            )
    return chosen


def evaluate(
    train: RecordingLike,
    tests: Sequence[RecordingLike] | Mapping[str, RecordingLike],
    target: str,
    sensors: Sequence[str] | None = None,
    k: int = 2,
    differences: bool = False,
    similarity: str = "abs-pearson",
    closure: str = "fast",
) -> Evaluation:
    """Select ``k`` points on ``train``, fit the rise model, and score it on every test.

    Recordings are paths (read with ``read_recording``) or DataFrames; ``tests`` may be a
    mapping from display name to recording (default names: the paths). ``sensors`` None means
    ``default_sensors`` of the training file, and every test file must then have exactly the
    same sensor columns; with explicit ``sensors`` the files only need to contain them.
    Warnings (``SelectionWarning``): constant candidates dropped, ties in the cut.
    Errors (``SelectionError``, one line naming the file): missing target or sensor columns,
    differing sensor sets, non-finite values, fewer than 2 rows, k < 1 or k > candidates.
    """
    train_name, train_frame = _load(train, "train")
    items = tests.items() if isinstance(tests, Mapping) else enumerate(tests, start=1)
    test_frames: dict[str, pd.DataFrame] = {}
    for key, recording in items:
        name, frame = _load(recording, f"test{key}" if isinstance(key, int) else str(key))
        name = str(key) if isinstance(tests, Mapping) else name
        if name in test_frames:
            raise SelectionError(f"test recording {name} given twice")
        test_frames[name] = frame
    if not test_frames:
        raise SelectionError("at least one test recording is needed")
    chosen = resolve_sensors(train_name, train_frame, test_frames, target, sensors)
    for name, frame in [(train_name, train_frame), *test_frames.items()]:
        _check_finite(name, frame, [*chosen, target])

    candidates = CandidateSet(tuple(chosen), differences)
    names = candidates.names
    y_train = train_frame[target].to_numpy(dtype=float)
    selection = select_sensitive_points(
        candidates.matrix(train_frame), y_train, k, similarity, closure, names=names
    )
    fit = fit_ols(candidates.matrix(train_frame, selection.selected), y_train)
    predictions, measured, errors = {}, {}, {}
    for name, frame in test_frames.items():
        measured[name] = frame[target].to_numpy(dtype=float)
        predictions[name] = fit.predict(candidates.matrix(frame, selection.selected))
        errors[name] = rmse(measured[name], predictions[name])
    return Evaluation(
        train=train_name,
        target=target,
        sensors=chosen,
        candidates=names,
        selection=selection,
        fit=fit,
        predictions=predictions,
        measured=measured,
        rmse_um=errors,
    )
