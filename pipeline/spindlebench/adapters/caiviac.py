"""Cut the CAIVIAC FL_THERMAL 46-hour recording into its runs and write canonical recordings.

The source is one continuous logger file (15 s steps) following a speed schedule: an idle
baseline, five constant-speed cycles (4 h spindle on, 4 h off) and a stepped-speed block.
Runs are found from ``spindle_rpm`` alone: a run starts where the spindle switches on after
standing still, its heating phase lasts while the spindle turns, and its cooling phase is the
idle stretch up to the next switch-on (or the end of the file). A heating phase with one speed
is a constant-speed cycle; one with several speeds is the stepped block. A spindle-on block
shorter than ``MIN_RUN_SAMPLES`` (10 samples) is a jog, not a run: it is skipped, with one
warning line naming its source rows (not rejected: one jog should not make a 46-hour file
unusable). A source without a constant-speed run to train on and another run to predict is
an error, and nothing is written. Non-finite cells (``inf``) are errors naming line and column.

Two ways to cut (``phase``):
- ``heating`` (default): only the spindle-on part of each run. This is the analogue of the
  paper's experiments, which are warm-up runs with the machine running; temperature rises and
  the error are taken relative to the run's first sample, as in the paper.
- ``cycle``: heating plus the following cool-down. A harder test the paper never made: a static
  regression has to follow the error back down while parts cool at different rates.

Canonical output per run (``<name>.csv``): ``time_s`` from 0, ``spindle_speed_rpm``,
``t1_C`` … ``t16_C`` (absolute °C, as measured) and ``ch1_um`` … ``ch5_um`` re-zeroed at the
run's first sample, like a displacement probe zeroed at the start of an experiment (the offsets
subtracted are in the sidecar, so the source values are recoverable). ``<name>.json`` carries the
provenance: source file and SHA-256, 0-based row range, speeds. ``paper_study.toml`` beside
them configures ``spindlebench paper`` for these runs (see ``study_config_text``), and
``iso230_3_map.toml`` maps all five displacement channels for ``spindlebench iso230-3
--recording`` (``DISPLACEMENT_CHANNELS`` says what each channel is as far as the data tell).
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from spindlebench.core import atomic
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import DEFAULT_SIMILARITY
from spindlebench.core.paths import shared_recordings_dir
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.formats.recording import (
    SPEED_COLUMN,
    TIME_COLUMN,
    check_recording_targets,
    write_recording,
)

if TYPE_CHECKING:  # pandas is imported where a recording is read: ``adapt --help`` is cheap
    import pandas as pd

DATASET = "caiviac-fl-thermal"
TEMPERATURES = tuple(f"t{i}_C" for i in range(1, 17))
DISPLACEMENTS = tuple(f"ch{i}_um" for i in range(1, 6))
SOURCE_COLUMNS = (TIME_COLUMN, "spindle_rpm", *DISPLACEMENTS, *TEMPERATURES)
AXIAL_TARGET = "ch3_um"
#: What each displacement channel is, as far as the data tell (the source documents neither
#: direction nor position; the names stay the source's channel numbers, in µm). The pairs are
#: read from the data: on the 5000 rpm cycle ch1/ch2 correlate at r = 0.997 and ch3/ch4 at
#: 1.000, the pattern of two radial probes at two heights in one direction each; ch5 is alone.
DISPLACEMENT_CHANNELS: dict[str, str] = {
    "ch1_um": "displacement (um), zeroed at the run's start; with ch2_um a pair: one radial "
              "direction at two heights (direction and position undocumented)",
    "ch2_um": "displacement (um); the partner of ch1_um",
    "ch3_um": "displacement (um); with ch4_um a pair, the largest heating response (to -70 "
              "um): the other radial direction at two heights, or the axial drift "
              "(SOURCE.md's reading); used as the axial target by the paper comparison",
    "ch4_um": "displacement (um); the partner of ch3_um",
    "ch5_um": "displacement (um), alone: the axial (Z) probe if ch3/ch4 are a radial pair; "
              "drifts slowly and rises in the cool-downs",
}
#: The ``iso230-3 --recording`` map beside the runs: the five channels as two radial pairs
#: and an axial probe (the reading of ``DISPLACEMENT_CHANNELS``).
ISO_MAP_FILE = "iso230_3_map.toml"
ISO_MAP_TEXT = """\
# ISO 230-3 map of the caiviac-fl-thermal runs, written by `spindlebench adapt caiviac`.
# Use: spindlebench iso230-3 spindle --recording <run>.csv --map <this file>
# (a cycle-phase run, `adapt caiviac --phase cycle`, is a spindle test: 4 h on, 4 h off).
# The source documents no probe directions, positions or geometry: the pairs below are read
# from the data (ch1/ch2 and ch3/ch4 move together, r >= 0.997), ch5 is taken as the axial
# probe, which of a pair is the upper probe and the distance l between them are ASSUMED, so
# the tilts are (ch1 - ch2)/l and (ch3 - ch4)/l with l = 0.1 m, good to their sign and order
# of magnitude only.
speed = "spindle_speed_rpm"
probe_l_m = 0.1
temperatures = ["t5_C", "t9_C", "t4_C", "t1_C", "t16_C", "t6_C"]

[directions]
X = { upper = "ch1_um", lower = "ch2_um" }
Y = { upper = "ch3_um", lower = "ch4_um" }
Z = "ch5_um"
"""
SAMPLE_STEP_S = 15.0
#: A spindle-on block shorter than this (2.5 min at 15 s) is a jog, not a run: it is skipped
#: with a warning (the readers need 2 samples, a regression at k = 4 more than 4).
MIN_RUN_SAMPLES = 10
#: The logger's precision (micrometres and degrees to 6 places), kept in the canonical CSVs.
SOURCE_FLOAT_FORMAT = "%.6f"

Phase = Literal["heating", "cycle"]
PHASES: tuple[str, ...] = ("heating", "cycle")


def default_source() -> Path:
    """Where the recording lives: ``../shared/recordings/caiviac-fl-thermal/data.csv``."""
    return shared_recordings_dir() / DATASET / "data.csv"


@dataclass(frozen=True)
class Run:
    """One run of the schedule as 0-based, half-open source row ranges.

    ``start:heating_stop`` is the spindle-on phase, ``heating_stop:stop`` the idle cool-down.
    """

    name: str
    kind: Literal["constant", "stepped"]
    start: int
    heating_stop: int
    stop: int
    speeds_rpm: tuple[float, ...]

    def rows(self, phase: Phase) -> range:
        """Source rows of this run for the given phase."""
        return range(self.start, self.heating_stop if phase == "heating" else self.stop)


@dataclass(frozen=True)
class Schedule:
    """The whole file cut up: the idle baseline before the first run, then the runs."""

    n_rows: int
    baseline: range
    runs: tuple[Run, ...]


def read_source(path: str | Path) -> pd.DataFrame:
    """Read and check the source CSV; every problem is one line naming the file."""
    import pandas as pd

    path = Path(path)
    if not path.is_file():
        raise SpindlebenchError(f"{path}: caiviac source file not found")
    try:
        frame = pd.read_csv(path)
    except (pd.errors.ParserError, UnicodeDecodeError, pd.errors.EmptyDataError) as exc:
        raise SpindlebenchError(f"{path}: not a readable CSV ({str(exc).strip()})") from exc
    missing = [c for c in SOURCE_COLUMNS if c not in frame.columns]
    if missing:
        raise SpindlebenchError(f"{path}: missing column(s) {', '.join(missing)}")
    frame = frame[list(SOURCE_COLUMNS)]
    for column in SOURCE_COLUMNS:
        values = pd.to_numeric(frame[column], errors="coerce")
        bad = np.flatnonzero(values.isna().to_numpy())
        if bad.size:
            # +2: one header line, 1-based line numbers.
            raise SpindlebenchError(
                f"{path}: line {bad[0] + 2}, column {column}: missing or non-numeric value"
            )
        bad = np.flatnonzero(~np.isfinite(values.to_numpy(dtype=float)))
        if bad.size:  # 'inf' parses as a number, but no recording reader accepts it
            raise SpindlebenchError(
                f"{path}: line {bad[0] + 2}, column {column}: non-finite value "
                f"'{frame[column].iloc[bad[0]]}'"
            )
        frame[column] = values.astype(float)
    if len(frame) < 2:
        raise SpindlebenchError(f"{path}: fewer than two data rows")
    steps = np.diff(frame[TIME_COLUMN].to_numpy())
    bad = np.flatnonzero((steps <= 0) | ~np.isclose(steps, steps[0]))
    if bad.size:
        raise SpindlebenchError(
            f"{path}: line {bad[0] + 3}: time_s does not advance by a constant step"
        )
    return frame


def _blocks(mask: np.ndarray) -> list[tuple[int, int]]:
    """Maximal half-open index ranges where ``mask`` is true."""
    padded = np.concatenate([[False], mask, [False]]).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


def find_schedule(spindle_rpm: np.ndarray) -> Schedule:
    """Cut the file at every switch-on of the spindle; see the module docstring."""
    rpm = np.asarray(spindle_rpm, dtype=float)
    on_blocks = _blocks(rpm > 0)
    if not on_blocks:
        raise SpindlebenchError("spindle_rpm: the spindle never turns, no run to cut")
    runs: list[Run] = []
    for number, (start, heating_stop) in enumerate(on_blocks, start=1):
        stop = on_blocks[number][0] if number < len(on_blocks) else rpm.size
        speeds = tuple(dict.fromkeys(rpm[start:heating_stop].tolist()))
        if len(speeds) == 1:
            kind: Literal["constant", "stepped"] = "constant"
            name = f"run{number}_{speeds[0]:g}rpm"
        else:
            kind = "stepped"
            name = f"run{number}_stepped"
        runs.append(Run(name, kind, start, heating_stop, stop, speeds))
    return Schedule(n_rows=rpm.size, baseline=range(0, on_blocks[0][0]), runs=tuple(runs))


def canonical_run(source: pd.DataFrame, run: Run, phase: Phase) -> tuple[pd.DataFrame, dict]:
    """The canonical table of one run and the zero offsets subtracted from the channels."""
    import pandas as pd

    rows = source.iloc[run.rows(phase).start : run.rows(phase).stop]
    table = pd.DataFrame({TIME_COLUMN: rows[TIME_COLUMN].to_numpy() - rows[TIME_COLUMN].iloc[0]})
    table[SPEED_COLUMN] = rows["spindle_rpm"].to_numpy()
    for column in TEMPERATURES:
        table[column] = rows[column].to_numpy()
    offsets = {column: float(rows[column].iloc[0]) for column in DISPLACEMENTS}
    for column in DISPLACEMENTS:
        table[column] = rows[column].to_numpy() - offsets[column]
    return table, offsets


STUDY_FILE = "paper_study.toml"


def study_config_text(schedule: Schedule, phase: Phase) -> str:
    """A ``spindlebench paper --config`` file for these runs.

    Training run: the constant-speed run with the highest speed, the analogue of the paper's
    experiment 1 (its fastest set-up), so the other runs are predicted inside the trained range
    of heat input. Predicted: every other run, the stepped block included. Six sensors: the
    target-free ``auto`` rule (locations are not documented, so no choice by location).
    """
    constant = [run for run in schedule.runs if run.kind == "constant"]
    if not constant or len(schedule.runs) < 2:
        raise SpindlebenchError(
            f"spindle_rpm: {len(constant)} constant-speed run(s) among {len(schedule.runs)} "
            "usable run(s); the paper comparison needs a constant-speed run to train on and "
            "another run to predict"
        )
    train = max(constant, key=lambda run: run.speeds_rpm[0]).name
    tests = [run.name for run in schedule.runs if run.name != train]

    def names(items: list[str] | tuple[str, ...]) -> str:
        return "[" + ", ".join(f'"{item}"' for item in items) + "]"

    return "\n".join([
        f"# Paper comparison on the {DATASET} runs ({phase} phase), written by",
        "# `spindlebench adapt caiviac`. Use: spindlebench paper --recordings <this folder>",
        f"#   --config <this folder>/{STUDY_FILE}",
        f'title = "{DATASET}, {phase} runs"',
        f'target = "{AXIAL_TARGET}"',
        f'train = "{train}"',
        f"tests = {names(tests)}",
        f"sensors_all = {names(TEMPERATURES)}",
        'six = "auto"',
        "clusters = [2, 3, 4]",
        f'similarity = "{DEFAULT_SIMILARITY}"',
        "",
    ])


def usable_runs(schedule: Schedule, source_path: Path | str = "source") -> Schedule:
    """``schedule`` without the runs whose spindle-on part is shorter than
    ``MIN_RUN_SAMPLES`` (a jog, not a run), each skipped one warned with its source rows."""
    kept = []
    for run in schedule.runs:
        length = run.heating_stop - run.start
        if length < MIN_RUN_SAMPLES:
            warnings.warn(
                f"{source_path}: skipped {run.name} (rows {run.start}-{run.heating_stop - 1}): "
                f"the spindle turns for {length} sample(s), a run needs at least "
                f"{MIN_RUN_SAMPLES}", stacklevel=2)
            continue
        kept.append(run)
    return Schedule(n_rows=schedule.n_rows, baseline=schedule.baseline, runs=tuple(kept))


def run_summary(source_path: str | Path | None = None) -> list[dict[str, Any]]:
    """Each usable run of the source as the adapter cuts it: its speeds, 0-based source rows
    of both phases, and the axial error re-zeroed at the run's start (its range over the
    heating phase, its value at the end of heating and of the cycle), in µm. What
    ``docs/validation.md``'s table of the runs shows; the calibration's validation script
    records it (``calibration.validation``)."""
    source_path = Path(source_path) if source_path is not None else default_source()
    source = read_source(source_path)
    schedule = usable_runs(find_schedule(source["spindle_rpm"].to_numpy()), source_path)
    error = source[AXIAL_TARGET].to_numpy()
    rows = []
    for run in schedule.runs:
        zero = error[run.start]
        heating = error[run.start:run.heating_stop] - zero
        rows.append({
            "run": run.name, "speeds_rpm": list(run.speeds_rpm),
            "heating_rows": [run.start, run.heating_stop - 1],
            "cycle_rows": [run.start, run.stop - 1],
            "heating_min_um": float(heating.min()), "heating_max_um": float(heating.max()),
            "end_of_heating_um": float(heating[-1]),
            "end_of_cycle_um": float(error[run.stop - 1] - zero),
        })
    return rows


def write_runs(
    out_dir: str | Path, source_path: str | Path | None = None, phase: Phase = "heating"
) -> list[Path]:
    """Write every run as ``<out_dir>/<name>.csv`` + ``<name>.json``, and a study config
    (``paper_study.toml``) for ``spindlebench paper``; return the CSV paths.

    Every run's table and sidecar is made, and every target checked, before the first file
    is written, so a source the adapter cannot cut (no constant-speed run, nothing to
    predict) writes nothing. The recordings go through ``formats.recording.write_recording``
    like simulated ones.
    """
    if phase not in PHASES:
        raise SpindlebenchError(f"phase: {phase!r} is not one of {', '.join(PHASES)}")
    source_path = Path(source_path) if source_path is not None else default_source()
    source = read_source(source_path)
    schedule = usable_runs(find_schedule(source["spindle_rpm"].to_numpy()), source_path)
    try:
        config_text = study_config_text(schedule, phase)
    except SpindlebenchError as exc:
        raise SpindlebenchError(f"{source_path}: {exc}") from None
    source_entry = file_entry(source_path)
    out_dir = Path(out_dir)
    recordings: list[tuple[Path, pd.DataFrame, dict]] = []
    for run in schedule.runs:
        table, offsets = canonical_run(source, run, phase)
        rows = run.rows(phase)
        record = provenance(
            dataset=DATASET,
            adapter="spindlebench.adapters.caiviac",
            source=source_entry,
            phase=phase,
            run=asdict(run),
            source_rows={"first": rows.start, "last": rows.stop - 1, "count": len(rows)},
            source_time_s={
                "first": float(source[TIME_COLUMN].iloc[rows.start]),
                "last": float(source[TIME_COLUMN].iloc[rows.stop - 1]),
            },
            speeds_rpm=list(run.speeds_rpm),
            axial_target=AXIAL_TARGET,
            displacement_channels=DISPLACEMENT_CHANNELS,
            displacement_zero_offsets_um=offsets,
            license="MIT (c) 2024 CAIVIAC, see LICENSE-MIT-CAIVIAC.txt beside the source",
            recording_sha256=None,  # its place; write_recording fills in the CSV's hash
        )
        recordings.append((out_dir / f"{run.name}.csv", table, record))
    config_path = out_dir / STUDY_FILE
    if config_path.is_dir():
        raise SpindlebenchError(f"{config_path}: is a folder, where the adapter writes a file")
    for path, _, _ in recordings:
        check_recording_targets(path)
    for path, table, record in recordings:
        write_recording(path, table, record, float_format=SOURCE_FLOAT_FORMAT)
    atomic.write_text(config_path, config_text)
    atomic.write_text(out_dir / ISO_MAP_FILE, ISO_MAP_TEXT)
    return [path for path, _, _ in recordings]
