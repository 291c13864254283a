"""Run the paper's comparison: three sensor groups x several cluster counts, train on one
experiment, predict the others (Xu et al. 2023, section 3).

Groups, in the paper's words: reference group 1 = all raw sensors, reference group 2 = six raw
sensors, reconstructed group = those six plus their pairwise differences. Every number comes
from ``spindlebench.selection`` (the method lives there, not here); this module only arranges
the runs and keeps what the tables and figures need.

With ``missing = "drop-rows"`` the recordings are read with their gaps (NaN) and every cell's
``evaluate`` drops the incomplete samples it would use (warned); a cell's predictions are put
back on the recording's full time axis with NaN at the dropped samples, so figures show the
gap. The ``six = "auto"`` rule uses the training samples where every raw sensor is present.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import ALL_RAW, DEFAULT_METHOD, GROUPS, SIX_DIFF
from spindlebench.core.paths import file_kind
from spindlebench.formats.recording import TIME_COLUMN, MissingValueError, read_header
from spindlebench.formats.roles import (
    ColumnRoles,
    detect_dialect,
    read_with_roles,
    refuse_target_copies,
    require_time,
)
from spindlebench.selection import SelectionWarning, evaluate
from spindlebench.selection.clustering import cluster_candidates
from spindlebench.selection.registry import parse_method
from spindlebench.selection.similarity import constant_columns
from spindlebench.studies.paper.config import AUTO_SIX, CONFIG_NAME, StudyConfig

AUTO_SIX_RULE = (
    "six = auto: the fuzzy equivalence hierarchy (same similarity, t(R)) of all raw sensors on "
    "the training experiment cut into 6 clusters; from each cluster the sensor with the largest "
    "temperature range (max - min) on the training experiment. The thermal error is not used."
)


@dataclass
class Cell:
    """One model of the comparison: a group at one number of clusters."""

    group: str
    k: int
    sensors: list[str]
    differences: bool
    selected: list[str]
    psi: list[float]
    eta: float
    clusters: list[list[str]]
    coefficients: dict[str, float]
    r2: float
    rmse_um: dict[str, float]
    mean_rmse_um: float
    predictions_um: dict[str, np.ndarray] = field(repr=False)
    evaluation: dict = field(repr=False)
    closure_names: list[str] = field(repr=False)
    closure: np.ndarray = field(repr=False)


@dataclass
class MethodCell:
    """One method (label) on one group at one k: the held-out scores, or why it failed."""

    method: str
    group: str
    k: int
    selected: list[str]
    rmse_um: dict[str, float]
    error: str = ""

    @property
    def mean_rmse_um(self) -> float:
        return float(np.mean(list(self.rmse_um.values()))) if self.rmse_um else float("nan")

    @property
    def spread_um(self) -> float:
        """Standard deviation of the per-run RMSE across the held-out runs."""
        values = list(self.rmse_um.values())
        return float(np.std(values)) if values else float("nan")

    @property
    def worst_um(self) -> float:
        return float(max(self.rmse_um.values())) if self.rmse_um else float("nan")


@dataclass
class StudyResult:
    """All cells plus what they were computed from."""

    config: StudyConfig
    six: tuple[str, ...]
    six_rule: str
    frames: dict[str, pd.DataFrame] = field(repr=False)
    paths: dict[str, Path]
    cells: list[Cell]
    groups: tuple[str, ...] = GROUPS
    #: Every method of ``config.methods`` on every group and k (the paper's from ``cells``).
    method_cells: list[MethodCell] = field(default_factory=list)

    def cell(self, group: str, k: int) -> Cell:
        """The cell of ``group`` at ``k`` clusters."""
        for cell in self.cells:
            if cell.group == group and cell.k == k:
                return cell
        raise KeyError((group, k))

    def group_sensors(self, group: str) -> tuple[list[str], bool]:
        """(raw sensors, with differences?) of a group."""
        if group == ALL_RAW:
            return list(self.config.sensors_all), False
        return list(self.six), group == SIX_DIFF

    def closure(self, group: str) -> tuple[list[str], np.ndarray]:
        """Candidate names and t(R) of a group on the training experiment (the same at every
        k; constant candidates left out)."""
        cell = next(c for c in self.cells if c.group == group)
        return cell.closure_names, cell.closure


def load_experiments(directory: str | Path, config: StudyConfig) -> tuple[dict, dict]:
    """Read ``<directory>/<name>.csv`` for every experiment: only the columns the study uses
    (target, ``sensors_all``, ``time_s``) are read and checked, others are ignored."""
    directory = Path(directory)
    if not directory.is_dir():
        raise SpindlebenchError(f"{directory}: " + (
            f"is {file_kind(directory)}, not a recordings folder" if directory.exists()
            else "recordings folder not found"))
    frames: dict[str, pd.DataFrame] = {}
    paths: dict[str, Path] = {}
    needed = [config.target, *config.sensors_all]
    for name in config.experiments:
        path = directory / f"{name}.csv"
        if path.exists() and not path.is_file():
            raise SpindlebenchError(f"{path}: experiment {name!r} is a folder, not a "
                                    "recording CSV")
        if not path.is_file():
            found = ", ".join(sorted(p.stem for p in directory.glob("*.csv")
                                     if p.is_file())) or "none"
            hint = ""
            own = directory / CONFIG_NAME
            if own.is_file() and not _uses(config, own):
                hint = f"; {own} describes this folder: pass --config {own}"
            raise SpindlebenchError(
                f"{path}: experiment {name!r} not found (the folder has: {found}){hint}"
            )
        delimiter, decimal = detect_dialect(path, config.delimiter, config.decimal)
        header = read_header(path, delimiter)
        missing = [column for column in needed if column not in header]
        if missing:
            raise SpindlebenchError(f"{path}: missing column(s) {', '.join(missing)}")
        given_time = None if config.time_column == TIME_COLUMN else config.time_column
        roles = ColumnRoles(time_column=given_time, sensors=tuple(config.sensors_all),
                            delimiter=delimiter, decimal=decimal)
        try:
            frame, choice = read_with_roles(path, config.target, roles,
                                            allow_missing=config.missing == "drop-rows")
        except MissingValueError as exc:
            raise SpindlebenchError(
                f"{exc}; missing = \"drop-rows\" (--missing drop-rows) drops incomplete samples"
            ) from exc
        require_time(choice, str(path), "the paper's figures plot against time and")
        if name == config.train:
            refuse_target_copies(frame, config.target, choice.sensors, str(path),
                                 config.allow_target_copy)
        frames[name] = frame
        paths[name] = path
    return frames, paths


def _uses(config: StudyConfig, path: Path) -> bool:
    """Whether ``config`` was read from ``path``."""
    return any(Path(part) == path for part in config.source.split(" + "))


def choose_six(frame: pd.DataFrame, sensors: Sequence[str], similarity: str) -> tuple[str, ...]:
    """The target-free six-sensor rule (``AUTO_SIX_RULE``), in ``sensors`` order, on the
    samples where every one of ``sensors`` is present."""
    raw = frame.loc[:, list(sensors)].astype(float).dropna()
    if len(raw) < 2:
        raise SpindlebenchError(
            "six = auto: fewer than 2 training samples have every sensor of sensors_all"
        )
    constant = constant_columns(raw.to_numpy())
    varying = [name for name, fixed in zip(sensors, constant, strict=True) if not fixed]
    if len(varying) < 6:
        raise SpindlebenchError(f"six = auto needs 6 varying sensors, have {len(varying)}")
    clusters = cluster_candidates(raw[varying].to_numpy(), 6, DEFAULT_METHOD, similarity)
    ranges = (raw[varying].max() - raw[varying].min()).to_numpy()
    picks = {varying[int(members[np.argmax(ranges[members])])] for members in clusters}
    return tuple(name for name in sensors if name in picks)


def _cell(
    config: StudyConfig,
    frames: Mapping[str, pd.DataFrame],
    group: str,
    k: int,
    sensors: list[str],
    differences: bool,
) -> Cell:
    try:
        result = evaluate(
            frames[config.train],
            {name: frames[name] for name in config.tests},
            target=config.target,
            sensors=sensors,
            k=k,
            differences=differences,
            similarity=config.similarity,
            missing=config.missing,
        )
    except SpindlebenchError as exc:
        raise SpindlebenchError(f"group {group}, k = {k}: {exc}") from exc
    record = result.to_dict()
    return Cell(
        group=group,
        k=k,
        sensors=sensors,
        differences=differences,
        selected=list(record["selected"]),
        psi=[float(v) for v in record["psi"]],
        eta=float(record["eta"]),
        clusters=[list(c) for c in record["clusters"]],
        coefficients=dict(record["coefficients"]),
        r2=float(result.fit.r2),
        rmse_um={name: float(record["rmse_um"][name]) for name in config.tests},
        mean_rmse_um=float(record["mean_rmse_um"]),
        predictions_um={
            name: _on_full_axis(len(frames[name]), result.test_rows[name], values)
            for name, values in result.predictions.items()
        },
        evaluation=record,
        closure_names=[result.candidates[i] for i in result.selection.kept],
        closure=result.selection.closure,
    )


def _on_full_axis(length: int, rows: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``values`` at sample positions ``rows`` of a ``length``-sample recording, NaN elsewhere."""
    out = np.full(length, np.nan)
    out[rows] = values
    return out


def run_study(directory: str | Path, config: StudyConfig) -> StudyResult:
    """Every group at every k; the six-sensor subset resolved first (fixed or by the rule)."""
    frames, paths = load_experiments(directory, config)
    if config.six == AUTO_SIX:
        six = choose_six(frames[config.train], config.sensors_all, config.similarity)
        rule = AUTO_SIX_RULE
    else:
        six = tuple(config.six)
        rule = "six: fixed list from the configuration"
    result = StudyResult(config=config, six=six, six_rule=rule, frames=frames, paths=paths,
                         cells=[])
    for k in config.clusters:
        for group in GROUPS:
            sensors, differences = result.group_sensors(group)
            result.cells.append(_cell(config, frames, group, k, sensors, differences))
    for label in config.methods:
        for k in config.clusters:
            for group in GROUPS:
                result.method_cells.append(_method_cell(result, frames, label, group, k))
    return result


def _method_cell(result: StudyResult, frames: Mapping[str, pd.DataFrame], label: str,
                 group: str, k: int) -> MethodCell:
    """``label`` on ``group`` at ``k``; a method that cannot run there (too few candidates,
    too few samples to split) is recorded with its one-line message, not raised."""
    config = result.config
    if label == DEFAULT_METHOD:
        cell = result.cell(group, k)
        return MethodCell(label, group, k, cell.selected, dict(cell.rmse_um))
    sensors, differences = result.group_sensors(group)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SelectionWarning)  # as the paper's cells warn once
            evaluation = evaluate(frames[config.train],
                                  {name: frames[name] for name in config.tests},
                                  target=config.target, sensors=sensors, k=k,
                                  differences=differences, similarity=config.similarity,
                                  missing=config.missing, method=parse_method(label),
                                  seed=config.seed)
    except SpindlebenchError as exc:
        return MethodCell(label, group, k, [], {}, error=" ".join(str(exc).split()))
    return MethodCell(label, group, k, evaluation.selected,
                      {name: float(v) for name, v in evaluation.rmse_um.items()})
