"""The two kinds of work a sweep sends to its workers, as plain picklable functions.

``simulate_job``: one experiment on one replica's day through the FMU → a canonical recording
(frame + sidecar), returned to the coordinating process, which writes it. Returning data
instead of writing in the worker keeps Dask workers on other machines free of any shared
file system.

``evaluate_job``: one (replica, condition) and its training experiments: re-measure every
experiment's noise-free truth with the condition's instruments (once for all training runs),
train every method on each training run and score it on all the others → tidy result rows
per training run. ``evaluate_jobs``: the jobs of one replica's conditions in one task, so
the conditions that measure a training run alike train its models once.
"""

from __future__ import annotations

import dataclasses
import functools
import weakref
from collections.abc import Mapping
from dataclasses import dataclass
from operator import itemgetter
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from threadpoolctl import ThreadpoolController

try:  # pandas 3: a frame from its blocks as they are (``_frame``)
    from pandas.api.internals import create_dataframe_from_blocks as _from_blocks
except ImportError:  # pragma: no cover - pandas before 3
    _from_blocks = None

from spindlebench.core.console import one_line_error
from spindlebench.core.names import SENSORS
from spindlebench.formats.recording import (
    DRIFT_COLUMN,
    STUDY_DRIVER_COLUMNS,
    TIME_COLUMN,
    TRUTH_COLUMNS,
    recording_name,
    true_column,
)
from spindlebench.selection.evaluate import CheckedRecording
from spindlebench.studies.family.experiments import (
    Condition,
    Experiment,
    measured_target,
    sensor_model,
)
from spindlebench.studies.family.methods import TARGET, TRUTH, MethodSpec, SharedRuns, score_all
from spindlebench.testbench.scenario import Scenario
from spindlebench.testbench.sensors import measure
from spindlebench.testbench.simulate import record

#: Pseudo-condition of the ground-truth rows.
NOISE_FREE = "noise-free"
#: Columns of the frames the methods see (``measured_frame``).
MEASURED_COLUMNS = (TIME_COLUMN, *SENSORS, TARGET, TRUTH)


def simulate_job(scenario: Scenario, fmu_path: Path) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Co-simulate ``scenario``; return its recording frame and sidecar (not yet written)."""
    return record(scenario, fmu_path)


@dataclass(frozen=True)
class EvaluationJob:
    """Everything one evaluation needs, shipped to the worker (no file access there).

    One job is one (replica, condition) and covers its training runs ``trains`` (all of the
    study's, or those whose result files are missing): every run is measured and checked
    once for all of them instead of once per training run. ``condition`` None means the
    noise-free ground truth. ``truths`` maps experiment ids to their truth columns
    (``TRUTH_COLUMNS``); ``failures`` maps the ids of experiments whose simulation failed to
    its error.
    """

    replica: int
    condition: Condition | None
    trains: tuple[Experiment, ...]
    experiments: tuple[Experiment, ...]
    truths: dict[str, pd.DataFrame]
    failures: dict[str, str]
    seeds: dict[str, int]
    duration_s: float
    specs: tuple[MethodSpec, ...]
    similarity: str
    #: The thermal error the methods predict (``[study] targets``); another than the axial
    #: drift is measured from the truths of ``experiments.target_truth_columns(target)`` with
    #: the condition's probes (``experiments.measured_target``) over ``probe_geometry_m`` (l
    #: and the end-face offset, m), and stands in the frames' ``drift_um`` column.
    target: str = DRIFT_COLUMN
    probe_geometry_m: tuple[float, float] | None = None

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        """Pickled with its truths as bare arrays (``_packed_truths``): a job is pickled by
        the study process and unpickled by a worker, once per condition of a replica."""
        fields = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        fields["truths"] = _packed_truths(self.truths)
        return _unpickled_job, (fields,)


def _packed_truths(truths: dict[str, pd.DataFrame]) -> dict[str, Any]:
    """The truth frames as (values, columns) where a frame is one float64 block on a default
    index (the sweep's are), else the frame itself.

    Pickling a frame stores its block manager and unpickling rebuilds it: 1.5 ms for a job's
    24 truths (and 1.1 ms to pickle them), against 0.6 ms to unpickle the arrays and make
    the frames again (0.8 ms to pickle). The frames made again are the same: the same
    values and memory layout (``to_numpy`` is the transposed block, made the block again
    without a copy), the same column Index object (one for all frames with the same
    columns, pickled once).

    A frame's pair is made once while the frame lives (``_packed_frames``): a replica's
    task holds its conditions' seven jobs, which share the truth frames, and pickle stores
    an object met again as a reference only if it is the same object; a pair made anew per
    job stored the replica's truths seven times (5.9 MB a task of the season sweep, 0.8 MB
    with the pairs shared)."""
    packed: dict[str, Any] = {}
    shared: dict[tuple[str, ...], pd.Index] = {}
    for key, frame in truths.items():
        known = _packed_frames.get(id(frame))
        if known is not None and known[0]() is frame and known[1] is frame.columns \
                and getattr(frame._mgr, "is_single_block", False) \
                and frame._mgr.blocks[0].values is known[2]:
            packed[key] = known[3]
            continue
        index = frame.index
        if not (getattr(frame._mgr, "is_single_block", False) and isinstance(index, pd.RangeIndex)
                and index.start == 0 and index.step == 1):
            packed[key] = frame
            continue
        values = frame.to_numpy()
        if values.dtype != np.float64:
            packed[key] = frame
            continue
        names = tuple(frame.columns.tolist())
        packed[key] = (values, shared.setdefault(names, frame.columns))
        if known is None or known[0]() is not frame:  # one finalizer a frame, not a change
            weakref.finalize(frame, _packed_frames.pop, id(frame), None)
        _packed_frames[id(frame)] = (weakref.ref(frame), frame.columns,
                                     frame._mgr.blocks[0].values, packed[key])
    return packed


#: ``_packed_truths``'s pair of each truth frame alive, by the frame's ``id``, with what
#: tells that it still stands for the frame: a weak reference (not a new frame at a reused
#: address), the frame's columns object and its block's array (a column set, added or
#: renamed gives the frame new ones; a value changed in place is in the pair's view too).
#: A frame's entry goes with it.
_packed_frames: dict[int, tuple[weakref.ref[pd.DataFrame], pd.Index, np.ndarray,
                                tuple[np.ndarray, pd.Index]]] = {}


def _unpickled_job(fields: dict[str, Any]) -> EvaluationJob:
    fields["truths"] = {key: truth if isinstance(truth, pd.DataFrame) else
                        pd.DataFrame(truth[0], columns=truth[1], copy=False)
                        for key, truth in fields["truths"].items()}
    return EvaluationJob(**fields)


#: What ``evaluate_job`` gives per training run: its result rows, or the one-line error of
#: an evaluation of that run that raised (the other training runs keep their rows).
TrainingResult = pd.DataFrame | str


class _TruthColumns:
    """A run's truth frame as float arrays from one conversion: looking its columns up in
    pandas, a few times per run, was some 6 % of an evaluation's time. The values are the
    frame's (a frame of float64 columns gives its own column block, column-major).

    The block serves when pandas gives every column as float64 in common: float64 columns
    (or ints and narrower floats beside them, which it converts as ``to_numpy(float)``
    converts each column). Asked of ``to_numpy``'s dtype rather than of ``truth.dtypes``,
    a Series of the column names that pandas builds on each call (a seventh of
    ``measured_frame``'s time)."""

    def __init__(self, truth: pd.DataFrame) -> None:
        self.frame = truth
        block = truth.to_numpy() if truth.columns.is_unique else None
        self.block = block if block is not None and block.dtype == np.float64 else None
        self.position = {column: i for i, column in enumerate(truth.columns.tolist())}

    def __contains__(self, column: str) -> bool:
        return column in self.position

    def column(self, column: str) -> np.ndarray:
        """One column as float64."""
        if self.block is None:
            return self.frame[column].to_numpy(float)
        return self.block[:, self.position[column]]

    def columns(self, columns: list[str]) -> np.ndarray:
        """Several columns side by side, (samples, len(columns)), column-major."""
        if self.block is None:
            return self.frame[columns].to_numpy(float)
        return np.asfortranarray(self.block[:, [self.position[c] for c in columns]])


def measured_frame(job: EvaluationJob, experiment: Experiment,
                   held_out: bool = True) -> pd.DataFrame:
    """The run as the condition's instruments see it (the fault only when ``held_out``:
    a training run is measured healthy, the fault comes after training).

    A sensor that drops out is held at its last good reading, as a compensation controller
    would; the columns are T1..T20 (degC), ``drift_um`` (probe, zeroed at the first sample)
    and the true drift rise for scoring, then the speed and ambient driver columns when the
    truth holds them (the sweep's does: ``STUDY_DRIVER_COLUMNS``). With another
    ``job.target`` the drift columns hold that target's measured reading and true rise (in
    its unit) instead.
    """
    truth = _TruthColumns(job.truths[experiment.id])
    drift = truth.column(TRUTH_COLUMNS[-1])
    time_s = truth.column(TIME_COLUMN)
    drivers = [column for column in STUDY_DRIVER_COLUMNS if column in truth]
    # one float block, filled column group by column group, made a frame once: building it
    # column by column was a third of an evaluation's time. It is laid out as pandas keeps
    # it (a row per column) and given to pandas as it is (``_block_frame``).
    values = np.empty((len(MEASURED_COLUMNS) + len(drivers), len(time_s)))
    values[0] = time_s
    at = len(MEASURED_COLUMNS)  # the drift columns are the two before ``at``
    if job.condition is None:
        values[1:at - 2] = truth.columns(list(TRUTH_COLUMNS[1:-1])).T
        values[at - 2] = drift - drift[0]
    else:
        model, measured_C, measured_drift = _measured_sensors(job, experiment, held_out,
                                                              truth)
        values[1:at - 2] = measured_C.T
        values[at - 2] = measured_drift
        if job.target != DRIFT_COLUMN:
            values[at - 2] = measured_target(job.target, model, time_s, truth.frame,
                                             measured_drift, job.seeds[experiment.id],
                                             job.probe_geometry_m)
    values[at - 1] = drift - drift[0]
    if job.target != DRIFT_COLUMN:
        true_target = truth.column(true_column(job.target))
        values[at - 1] = true_target - true_target[0]
        if job.condition is None:
            values[at - 2] = values[at - 1]
    for i, column in enumerate(drivers):  # the programme, for the dynamic regressors
        values[at + i] = truth.column(column)
    return _block_frame(values, _measured_columns(tuple(drivers)))


def _block_frame(values: np.ndarray, columns: pd.Index) -> pd.DataFrame:
    """``pd.DataFrame(values.T, columns=columns)`` for float ``values`` of one row per
    column, C-contiguous: the block pandas 3 makes of a (samples, columns) array (it copies
    one into that layout), here taken as it is, without the constructor's copy and checks
    (a sixth of ``measured_frame``)."""
    if _from_blocks is None:
        return pd.DataFrame(values.T, columns=columns)
    return _from_blocks([(values, np.arange(len(columns)))], pd.RangeIndex(values.shape[1]),
                        columns)


@functools.cache
def _measured_columns(drivers: tuple[str, ...]) -> pd.Index:
    """The column index of ``measured_frame`` with ``drivers``, made once and shared by its
    frames (an Index cannot be changed): pandas inferring it from the names again for
    every frame was a fifth of ``measured_frame``'s time."""
    return pd.Index([*MEASURED_COLUMNS, *drivers])


def _measured_sensors(job: EvaluationJob, experiment: Experiment, held_out: bool,
                      truth: _TruthColumns | None = None) -> tuple[Any, np.ndarray, np.ndarray]:
    """(sensor model, measured T1..T20 with a dropout held at its last good reading,
    measured axial drift) of the run under ``job``'s measured condition (``truth``: its
    truth columns, if made already)."""
    truth = _TruthColumns(job.truths[experiment.id]) if truth is None else truth
    fault = job.condition.fault if held_out else None
    model = sensor_model(job.condition.noise, fault)
    measured_C, measured_drift = measure(
        model, truth.column(TIME_COLUMN), truth.columns(list(TRUTH_COLUMNS[1:-1])),
        truth.column(TRUTH_COLUMNS[-1]), SENSORS, job.seeds[experiment.id])
    if np.isnan(measured_C).any():  # a dropout: hold the last good reading
        measured_C = pd.DataFrame(measured_C).ffill().bfill().to_numpy()
    return model, measured_C, measured_drift


def measured_targets(jobs: Mapping[str, EvaluationJob], experiment: Experiment,
                     held_out: bool = True) -> pd.DataFrame:
    """``time_s``, T1..T20 and every target's measured reading (a column named by the
    target) of the run, for one job per target of the same (replica, measured condition):
    the columns ``measured_frame`` of each target's job gives, with the sensors measured
    once instead of once per target (the same seed, truth and readings in every job)."""
    first = next(iter(jobs.values()))
    if first.condition is None:
        raise ValueError("measured_targets needs a measured condition, not the noise-free one")
    model, measured_C, measured_drift = _measured_sensors(first, experiment, held_out)
    time_s = first.truths[experiment.id][TIME_COLUMN].to_numpy(float)
    values = np.empty((len(time_s), 1 + len(SENSORS)))
    values[:, 0] = time_s
    values[:, 1:] = measured_C
    out = pd.DataFrame(values, columns=[TIME_COLUMN, *SENSORS])
    for target, job in jobs.items():
        out[target] = measured_target(target, model, time_s, job.truths[experiment.id],
                                      measured_drift, job.seeds[experiment.id],
                                      job.probe_geometry_m)
    return out


def evaluate_job(job: EvaluationJob) -> dict[str, TrainingResult]:
    """Per training run (by id): tidy rows, one per method × k × held-out experiment (failed
    ones carry the error), or the one-line error if that run's evaluation raised.

    BLAS runs single-threaded here: the matrices are small (hundreds of samples × at most
    210 candidates), where threads only cost; measured, an SVD of the ridge baseline took
    250 ms with OpenBLAS threads on a busy 2-core machine and 9 ms without.
    """
    with _thread_pools().limit(limits=1):
        return _evaluate(job, {})


#: The training recordings of one task's jobs, by content (``_training_recording``).
TrainingRecordings = dict[tuple[Any, ...], CheckedRecording]


#: What ``evaluate_jobs`` gives per job: ``evaluate_job``'s results, or the one-line error of
#: that job if it raised (the other jobs keep theirs).
JobResult = dict[str, TrainingResult] | str


def evaluate_jobs(jobs: tuple[EvaluationJob, ...]) -> list[JobResult]:
    """``evaluate_job`` of each of ``jobs`` (one replica's conditions), in one task: per job
    its results, or its one-line error if it raised, as a task of its own reports it.

    Why one task: the fault conditions of a noise level measure each training run healthy,
    into the same frame, and the first of their jobs in the task trains the models that the
    others reuse (``_training_recording``); as tasks of their own they are spread over the
    workers, each of which trains them again."""
    results: list[JobResult] = []
    kept: TrainingRecordings = {}
    noise: str | None = None
    with _thread_pools().limit(limits=1):
        for job in jobs:
            # only a job of the same noise level can measure a training run alike: the
            # recordings of another one are let go (with what they hold of their jobs)
            level = job.condition.noise.name if job.condition is not None else NOISE_FREE
            if level != noise:
                kept.clear()
                noise = level
            try:
                results.append(_evaluate(job, kept))
            except Exception as exc:  # failure isolation per job, as one task each had
                results.append(one_line_error(exc))
    return results


@functools.cache
def _thread_pools() -> ThreadpoolController:
    """The process's BLAS and OpenMP libraries, found once: ``threadpool_limits`` looks them
    up again on every call (2.4 ms, a tenth of an evaluation); a controller made once
    limits the same libraries in microseconds. Made at the first job, when NumPy's,
    SciPy's and scikit-learn's libraries are loaded (this module imports them)."""
    return ThreadpoolController()


def _evaluate(job: EvaluationJob, kept: TrainingRecordings) -> dict[str, TrainingResult]:
    # Every run as a held-out run, measured once for all training runs: same seed, so the
    # same frame whichever run trains (one job per training run measured it once each).
    held_out = {e.id: measured_frame(job, e) for e in job.experiments
                if e.id not in job.failures}
    runs = SharedRuns(held_out)
    results: dict[str, TrainingResult] = {}
    for train in job.trains:
        try:
            results[train.id] = _evaluate_training_run(job, train, runs, kept)
        except Exception as exc:  # failure isolation per training run, as one job each had
            results[train.id] = one_line_error(exc)
    return results


def _evaluate_training_run(job: EvaluationJob, train: Experiment, runs: SharedRuns,
                           kept: TrainingRecordings) -> pd.DataFrame:
    tests = [e for e in job.experiments if e != train]
    rows: list[dict[str, Any]] = []
    if train.id in job.failures:
        message = f"training experiment failed: {job.failures[train.id]}"
        rows = [{"method": s.name, "k": s.k, "test_experiment": e.id, "rmse_um": np.nan,
                 "rmse_true_um": np.nan, "selected": "", "error": message}
                for s in job.specs for e in tests]
    else:
        healthy = job.condition is None or job.condition.fault is None
        # without a fault the training run's frame is its held-out frame (same measurement)
        train_frame = runs.frames[train.id] if healthy else \
            measured_frame(job, train, held_out=False)
        ids = [e.id for e in tests]  # (an id is formatted anew at each ask)
        available = {i: runs.frames[i] for i in ids if i not in job.failures}
        if available:
            rows = score_all(list(job.specs), train_frame, available, job.similarity, runs,
                             _training_recording(train_frame, kept))
        failed = [i for i in ids if i in job.failures]
        rows += [{"method": s.name, "k": s.k, "test_experiment": i, "rmse_um": np.nan,
                  "rmse_true_um": np.nan, "selected": "",
                  "error": f"simulation failed: {job.failures[i]}"}
                 for s in job.specs for i in failed]
    return _result_frame(job, train, tests, rows)


def _training_recording(frame: pd.DataFrame, kept: TrainingRecordings) -> CheckedRecording:
    """The checked recording of training frame ``frame``: the one an earlier job of the same
    task made of a frame of the same content (kept in ``kept``), else a new one, kept there.

    Why: a training run is measured healthy, so the three fault conditions of one noise
    level measure it into the same frame, bit for bit (same truth, seed and sensor model);
    the recording keeps every model trained on it (the groups' selections and fits, the
    top-k fits, the ridge penalty and fit, ``score_all``), so the jobs after the first train
    nothing again and score the same models (the same values: computed once from the same
    bits). Matched by content (the names, the values' bytes), so a frame that differs in any
    bit is a recording of its own (and one with attributes or another index, which its
    messages may name, is not kept). Kept for one task only (``evaluate_jobs``: a
    replica's) and one noise level, as the recordings hold what their jobs' held-out runs
    made for them (some 40 MB for a noise level's three jobs of the season sweep). The
    frames are ``measured_frame``'s, which nothing changes after."""
    values = frame.to_numpy()
    index = frame.index
    if values.dtype != np.float64 or not frame.columns.is_unique or frame.attrs or not (
            isinstance(index, pd.RangeIndex) and index.start == 0 and index.step == 1):
        return CheckedRecording(recording_name(frame, "train"), frame)
    key = (tuple(frame.columns.tolist()), values.shape, values.tobytes())
    if key not in kept:
        kept[key] = CheckedRecording(recording_name(frame, "train"), frame)
    return kept[key]


#: The keys of a result row (``score_all``'s and a failed run's), in the order
#: ``_result_frame`` takes them apart.
_ROW_KEYS = ("method", "k", "test_experiment", "rmse_um", "rmse_true_um", "selected", "error")


def _result_frame(job: EvaluationJob, train: Experiment, tests: list[Experiment],
                  rows: list[dict[str, Any]]) -> pd.DataFrame:
    """The rows of one training run with the columns that say which case each is, built in
    one go (a frame grown column by column was a twentieth of an evaluation), each column
    made in the dtype pandas would infer for it (text: ``_text_dtype``), so inferring it
    from the values, per column and frame, is skipped.

    The rows are taken apart into columns in one pass (``zip``) and each held-out run's
    descriptive columns looked up once per run, not once per row; the frame is made from
    its columns as they are (``_frame``). A list per column, ``pd.array`` per text column,
    ``pd.array(..., "Int64")`` (inspecting every element) and ``pd.DataFrame`` checking
    every column again took 1.2 ms per training run of the season sweep, this 0.65 ms
    (issue 26)."""
    n = len(rows)
    method, k, test_id, rmse, rmse_true, selected, error = \
        zip(*map(itemgetter(*_ROW_KEYS), rows), strict=True) if n else ((),) * len(_ROW_KEYS)
    described = {e.id: (e.month, e.season, e.speed_rpm, e.programme, e.cooling) for e in tests}
    month, season, speed, programme, cooling = \
        zip(*map(described.__getitem__, test_id), strict=True) if n else ((),) * 5
    condition = job.condition

    def same_text(value: str) -> Any:
        return _text(np.full(n, value, dtype=object))

    def floats(values: tuple[Any, ...]) -> np.ndarray:
        return np.array(values, dtype=np.float64)

    return _frame({
        "replica": np.full(n, job.replica, dtype=np.int64),
        "data": same_text("measured" if condition else NOISE_FREE),
        "noise": same_text(condition.noise.name if condition else NOISE_FREE),
        "fault": same_text(condition.fault_name if condition else "none"),
        "train_experiment": same_text(train.id),
        "method": _text(method),
        "k": _nullable_ints(k),
        "test_experiment": _text(test_id),
        "rmse_um": floats(rmse),
        "rmse_true_um": floats(rmse_true),
        "selected": _text(selected),
        "error": _text(error),
        "test_month": _text(month),
        "test_season": _text(season),
        "test_speed_rpm": floats(speed),
        "test_programme": _text(programme),
        "test_cooling": _text(cooling),
    }, n)


def _text(values: tuple[Any, ...] | np.ndarray) -> Any:
    """A text column as ``pd.array(values, dtype=_text_dtype())`` makes it: through the
    dtype's array type directly where it has one (pandas 3's ``str``), as ``pd.array``
    does, without its dispatch (half the time of a column)."""
    values = np.asarray(values, dtype=object) if isinstance(values, tuple) else values
    array_type = _text_array_type()
    if array_type is None:
        return pd.array(values, dtype=_text_dtype())
    return array_type._from_sequence(values, dtype=_text_dtype())


@functools.cache
def _text_array_type() -> Any:
    """The extension array type of ``_text_dtype`` (looked up once: pandas imports it at
    each ask), None where text is a NumPy object column (pandas before 3)."""
    dtype = _text_dtype()
    return dtype.construct_array_type() if isinstance(dtype, pd.api.extensions.ExtensionDtype) \
        else None


def _nullable_ints(values: tuple[int | None, ...]) -> Any:
    """``values`` (ints, None for a method without a k) as the ``Int64`` array
    ``pd.array(values, dtype="Int64")`` makes (the same values, NA where None), from one
    object array and its mask."""
    boxed = np.array(values, dtype=object)
    missing = np.equal(boxed, None)
    boxed[missing] = 0
    return pd.arrays.IntegerArray(boxed.astype(np.int64), missing)


def _frame(columns: dict[str, Any], n: int) -> pd.DataFrame:
    """``pd.DataFrame(columns, copy=False)`` for columns already in their final dtypes and
    of length ``n``: made from one block per column, in column order, as that constructor
    makes it, without checking and converting every column again; the constructor itself
    where pandas has no ``create_dataframe_from_blocks`` (before 3)."""
    if _from_blocks is None:
        return pd.DataFrame(columns, copy=False)
    blocks = [(values.reshape(1, n) if isinstance(values, np.ndarray) else values,
               np.array([i]))
              for i, values in enumerate(columns.values())]
    return _from_blocks(blocks, pd.RangeIndex(n), _column_index(tuple(columns)))


@functools.cache
def _column_index(names: tuple[str, ...]) -> pd.Index:
    """The column index of frames with ``names``, made once and shared (an Index cannot be
    changed), as ``_measured_columns``."""
    return pd.Index(names)


@functools.cache
def _text_dtype() -> Any:
    """The dtype pandas infers for a column of text (``str`` in pandas 3, object before)."""
    return pd.Series(["text"]).dtype
