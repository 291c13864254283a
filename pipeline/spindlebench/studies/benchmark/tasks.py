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
    if spec.kind == "scenarios":
        return scenario_tasks(spec)
    return [caiviac_task(spec)]


def synthetic_tasks(spec: TaskSpec) -> list[Task]:
    from spindlebench.formats.recording import DRIFT_COLUMN, SPEED_COLUMN, TRUTH_COLUMNS
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
    tasks: list[Task] = []
    for label, study in family_studies(base, spec.study):
        family = experiments(study)
        trains = training_experiments(study, family)
        if len(trains) != 1:
            raise SpindlebenchError(f"{spec.study}: a benchmark family needs exactly one "
                                    f"training experiment ([training] rule 'one')")
        train = trains[0]
        truths: dict[int, dict[str, pd.DataFrame]] = {}
        speeds: dict[tuple[int, str], pd.Series] = {}  # the dynamic models' input
        for replica in replicas(study):
            truths[replica] = {}
            for experiment in family:
                frame, _ = simulate_job(scenario_for(study, replica, experiment), study.fmu)
                truths[replica][experiment.id] = frame.loc[:, list(TRUTH_COLUMNS)].copy()
                speeds[(replica, experiment.id)] = frame[SPEED_COLUMN].to_numpy(float)
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
                for experiment, frame in [(train, train_frame),
                                          *((e, tests[e.id]) for e in family if e != train)]:
                    frame[SPEED_COLUMN] = speeds[(replica, experiment.id)]
                folds.append(Fold(f"replica {replica}", train.id, train_frame, tests))
            tasks.append(Task(
                name=f"{spec.name}/{label}/{condition.id}", kind="synthetic",
                description=(spec.description or study.description)
                + f" (machine {label}, {condition.id})",
                target=DRIFT_COLUMN, sensors=SENSORS, folds=folds,
                provenance={"study": str(spec.study), "machine": label,
                            "condition": condition.id, "replicas": study.replicas,
                            "train": train.id, "tests": [e.id for e in family if e != train]}))
    return tasks


def family_studies(base, path: Path) -> list[tuple[str, Any]]:
    """(machine label, study) of every machine of a synthetic family: the study's own
    machine, each of ``[axes] machines``, or each machine of its population drawn in memory
    (``studies.family.population.draw_parameters``: the same parameters a sweep's machine
    files hold; no fingerprint is simulated and nothing is written)."""
    import dataclasses

    from spindlebench.studies.family.family_file import load_study

    if base.population is not None:
        return [(machine.name, dataclasses.replace(base, machine=machine, population=None))
                for machine in population_machines(base)]
    if base.machines:
        return [(name, load_study(path, machine=name)) for name in base.machines]
    return [(base.machine.name, base)]


def population_machines(study) -> list:
    """The machines of ``study``'s population (``keep = "all"`` only: keeping by targets
    would simulate every draw's fingerprint)."""
    from spindlebench.machines.variants import Machine, load_machine
    from spindlebench.studies.family.population import draw_parameters, machine_name
    from spindlebench.testbench.runner import inspect_fmu

    population = study.population
    if population.keep != "all":
        raise SpindlebenchError(f"{study.path}: key 'axes.machines.keep': a benchmark task "
                                "draws its population with keep = \"all\"")
    base = load_machine(population.base, source=population.source)
    known = inspect_fmu(study.fmu).parameters
    out = []
    for index in range(1, population.size + 1):
        name = machine_name(population, base, index)
        out.append(Machine(name=name, description=f"machine {index} of a population around "
                           f"{base.name}", path=base.path, sha256=base.sha256,
                           parameters=draw_parameters(population, base, known, index)))
    return out


def scenario_tasks(spec: TaskSpec) -> list[Task]:
    """Scenario files simulated with the FMU as written (their own sensors, noise and seed;
    the task's machine; the five-probe outputs if ``probes``): each training scenario trains
    once, the prediction scenarios (and, with ``others``, the other training ones) are
    predicted; one task per target."""
    import dataclasses

    from spindlebench.core.paths import DEFAULT_FMU
    from spindlebench.machines.variants import load_machine
    from spindlebench.testbench.scenario import load_scenario
    from spindlebench.testbench.simulate import record

    machine = load_machine(spec.machine)
    frames: dict[str, pd.DataFrame] = {}
    names: dict[Path, str] = {}
    for path in (*spec.train, *spec.predict):
        scenario = load_scenario(path)
        scenario = dataclasses.replace(scenario, machine=machine,
                                       probes=spec.probes or scenario.probes)
        frame, _ = record(scenario, DEFAULT_FMU)
        names[path] = scenario.name
        frames[scenario.name] = frame
    tasks = []
    for target in spec.targets:
        for path, name in names.items():
            if target not in frames[name]:
                raise SpindlebenchError(f"task {spec.name}: scenario {path} records no "
                                        f"{target!r} (probes = true gives the five-probe "
                                        "channels)")
        folds = []
        for path in spec.train:
            tests = [p for p in (*spec.train, *spec.predict) if p != path
                     and (spec.others or p in spec.predict)]
            folds.append(Fold(f"train {names[path]}", names[path], frames[names[path]],
                              {names[p]: frames[names[p]] for p in tests}))
        tasks.append(Task(
            name=spec.name if len(spec.targets) == 1 else f"{spec.name}/{target}",
            kind="scenarios", description=(spec.description or "scenario files")
            + f" (machine {machine.name}, target {target})",
            target=target, sensors=SENSORS, folds=folds,
            provenance={"scenarios": [str(p) for p in names], "machine": machine.name,
                        "target": target, "probes": spec.probes}))
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
