"""The folds of every benchmark task: which recording trains, which are predicted.

- ``synthetic``: a sweep study file's family, simulated with the FMU (a few seconds; nothing
  is cached, the simulation is deterministic). One task per machine x measuring condition
  (noise level x fault); its folds are the study's replicas (each re-draws the day's weather
  and the sensor noise). In every fold the study's training run (measured healthy) trains and
  every other run of the family, measured under the condition (a fault appears after
  training), is predicted: the season sweep's protocol (``studies.jobs.measured_frame``).
- ``caiviac``: the CAIVIAC runs cut by ``adapters.caiviac`` (``heating`` or ``cycle``
  phase), read in place; one fold per constant-speed run: it trains, every other run (the
  stepped block included) is predicted. Target ``ch3_um``, sensors ``t1_C`` ... ``t16_C``.
- ``own``: the user's recordings (``--recordings``): each trains in turn, the others are
  predicted.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import SENSORS
from spindlebench.formats.recording import TIME_COLUMN
from spindlebench.studies.benchmark.benchmark_file import TaskSpec

TIME = TIME_COLUMN


@dataclass
class Fold:
    """One training recording and the recordings it predicts (frames with ``time_s``)."""

    name: str
    train_name: str
    train: pd.DataFrame
    tests: dict[str, pd.DataFrame]


@dataclass
class Task:
    """A task ready to score: its folds, target and sensors."""

    name: str
    kind: str
    description: str
    target: str
    sensors: tuple[str, ...]
    folds: list[Fold]
    provenance: dict[str, Any] = field(default_factory=dict)


def build_tasks(spec: TaskSpec) -> list[Task]:
    """The task(s) of one suite entry (a synthetic entry gives one per machine x condition)."""
    if spec.missing:
        raise SpindlebenchError(spec.missing)
    if spec.kind == "synthetic":
        return synthetic_tasks(spec)
    return [caiviac_task(spec)]


def synthetic_tasks(spec: TaskSpec) -> list[Task]:
    from spindlebench.formats.recording import DRIFT_COLUMN, TRUTH_COLUMNS
    from spindlebench.studies.family.experiments import (
        conditions,
        experiments,
        replicas,
        scenario_for,
        sensor_seed,
        training_experiments,
    )
    from spindlebench.studies.family.family_file import load_study
    from spindlebench.studies.running.jobs import EvaluationJob, measured_frame, simulate_job

    assert spec.study is not None
    base = load_study(spec.study)
    machines = list(base.machines) or [None]
    tasks: list[Task] = []
    for machine in machines:
        study = load_study(spec.study, machine=machine) if machine else base
        family = experiments(study)
        trains = training_experiments(study, family)
        if len(trains) != 1:
            raise SpindlebenchError(f"{spec.study}: a benchmark family needs exactly one "
                                    f"training experiment ([training] rule 'one')")
        train = trains[0]
        truths: dict[int, dict[str, pd.DataFrame]] = {}
        for replica in replicas(study):
            truths[replica] = {}
            for experiment in family:
                frame, _ = simulate_job(scenario_for(study, replica, experiment), study.fmu)
                truths[replica][experiment.id] = frame.loc[:, list(TRUTH_COLUMNS)].copy()
        for condition in conditions(study):
            folds = []
            for replica in replicas(study):
                job = EvaluationJob(
                    replica=replica, condition=condition, trains=(train,),
                    experiments=tuple(family), truths=truths[replica], failures={},
                    seeds={e.id: sensor_seed(study, replica, e) for e in family},
                    duration_s=study.duration_s, specs=(), similarity="abs-pearson")
                train_frame = measured_frame(job, train, held_out=False)
                tests = {e.id: measured_frame(job, e) for e in family if e != train}
                folds.append(Fold(f"replica {replica}", train.id, train_frame, tests))
            label = machine or study.machine.name
            tasks.append(Task(
                name=f"{spec.name}/{label}/{condition.id}", kind="synthetic",
                description=(spec.description or study.description)
                + f" (machine {label}, {condition.id})",
                target=DRIFT_COLUMN, sensors=SENSORS, folds=folds,
                provenance={"study": str(spec.study), "machine": label,
                            "condition": condition.id, "replicas": study.replicas,
                            "train": train.id, "tests": [e.id for e in family if e != train]}))
    return tasks


def caiviac_task(spec: TaskSpec) -> Task:
    from spindlebench.adapters import caiviac
    from spindlebench.core.provenance import file_entry

    source = caiviac.read_source(spec.source)
    schedule = caiviac.usable_runs(caiviac.find_schedule(source["spindle_rpm"].to_numpy()),
                                   spec.source)
    frames = {run.name: caiviac.canonical_run(source, run, spec.phase)[0]
              for run in schedule.runs}
    folds = []
    for run in schedule.runs:
        if run.kind != "constant":
            continue
        tests = {name: frame for name, frame in frames.items() if name != run.name}
        folds.append(Fold(f"train {run.name}", run.name, frames[run.name], tests))
    return Task(name=spec.name, kind="caiviac",
                description=spec.description or f"CAIVIAC FL_THERMAL, {spec.phase} runs",
                target=caiviac.AXIAL_TARGET, sensors=caiviac.TEMPERATURES, folds=folds,
                provenance={"source": file_entry(spec.source), "phase": spec.phase,
                            "runs": list(frames)})


def own_task(paths: Sequence[Path], target: str, roles=None, name: str = "own") -> Task:
    """The user's recordings as a task: each trains in turn, the others are predicted.

    Read as ``evaluate`` reads them (``formats.columns``: the time column, the sensors by
    name, pattern or the temperature rule, the CSV dialect; ``roles`` from the command's
    flags); every file must have the first file's sensors and a time column (the replay
    baseline needs the time since the start)."""
    import dataclasses

    from spindlebench.core.provenance import file_entry
    from spindlebench.formats.roles import ColumnRoles, read_with_roles, require_time

    roles = roles if roles is not None else ColumnRoles()
    if len(paths) < 2:
        raise SpindlebenchError("--recordings: give at least 2 recordings (one trains, the "
                                "others are predicted)")
    frames: dict[str, pd.DataFrame] = {}
    sensors: tuple[str, ...] = ()
    for path in paths:
        frame, choice = read_with_roles(Path(path), target, roles)
        require_time(choice, str(path), "the replay baseline")
        if not sensors:
            sensors = tuple(choice.sensors)
            roles = dataclasses.replace(roles, sensors=sensors, exclude=())
        frames[Path(path).stem] = frame
    if len(frames) < len(paths):
        raise SpindlebenchError("--recordings: two recordings share a file name")
    folds = [Fold(f"train {name}", name, frame,
                  {other: f for other, f in frames.items() if other != name})
             for name, frame in frames.items()]
    return Task(name=name, kind="own", description="the user's recordings (--recordings)",
                target=target, sensors=sensors, folds=folds,
                provenance={"recordings": [file_entry(p) for p in paths]})
