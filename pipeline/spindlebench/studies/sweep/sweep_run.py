"""The season stress test of the selection methods (``spindlebench sweep STUDY.toml``, whose
command is ``commands.sweep``).

Simulates every experiment of the study on every replica's day (through the FMU, in worker
processes or on a Dask cluster), then, per replica, measurement condition and training
experiment, trains every method and scores it on all held-out experiments. Each finished
simulation and evaluation is on disk at once, so an interrupted sweep resumes where it
stopped; a failed simulation is recorded with its error and the sweep carries on.

The results folder holds ``results.csv`` (tidy: one row per replica × condition × method × k
× held-out experiment), ``summary.csv``, box plots, ``README.md`` (the findings, computed from
the data) and ``provenance.json``.

A study with several ``[study] targets`` (issue 21) is laid out as ``place`` lays it out: the
simulations once in the folder, each target's sweep (the same files as that target alone)
in ``<out>/<target>/``, and the joint selections of all targets (``studies.sweep.joint``) in
``<out>/joint.csv`` and ``<out>/README.md``. One target: the folder as it always was.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from spindlebench.core.atomic import write_text
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.progress import Stages
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.formats.recording import (
    DRIFT_COLUMN,
    STUDY_DRIVER_COLUMNS,
    TRUTH_COLUMNS,
    read_back,
    read_recording,
)
from spindlebench.studies.family.experiments import (
    Condition,
    Experiment,
    conditions,
    experiments,
    one_target_readme,
    probe_geometry_m,
    replicas,
    sensor_seed,
    target_truth_columns,
    training_experiments,
)
from spindlebench.studies.family.family_file import (
    SweepStudy,
    check_fmu,
    describe,
    load_study,
    pinned_content,
)
from spindlebench.studies.family.methods import method_specs
from spindlebench.studies.running.executor import Outcome, RunStats, Task, TaskRunner
from spindlebench.studies.running.jobs import (
    NOISE_FREE,
    EvaluationJob,
    JobResult,
    evaluate_job,
    evaluate_jobs,
)
from spindlebench.studies.running.simulations import (
    Simulations,
    failure_path,
    recording_path,
)
from spindlebench.studies.running.store import ResultStore, content_sha256

RESULT_COLUMNS = (
    "replica", "data", "noise", "fault", "train_experiment", "test_experiment", "test_month",
    "test_season", "test_speed_rpm", "test_programme", "test_cooling", "method", "k",
    "rmse_um", "rmse_true_um", "selected", "error",
)


@dataclass
class SweepOutcome:
    """What a sweep did: counts of work done now, the results table and the output folder."""

    out_dir: Path
    results: pd.DataFrame
    stats: RunStats
    resumed: bool
    skipped: dict[str, int] = field(default_factory=dict)
    #: (replica, condition, training run) evaluations done now; ``stats`` counts their tasks
    #: (one per replica: its conditions' jobs, ``evaluate_jobs``)
    evaluated: int = 0
    #: Several targets: the study's folder (its README has the joint selections), while
    #: ``out_dir`` is the first target's; None for one target.
    study_dir: Path | None = None


def condition_id(condition: Condition | None) -> str:
    return condition.id if condition is not None else NOISE_FREE


def task_jobs(task: Task) -> tuple[EvaluationJob, ...]:
    """The evaluation jobs of a sweep's evaluation task: one (``evaluate_job``) or one
    replica's (``evaluate_jobs``)."""
    return task.args[0] if task.fn is evaluate_jobs else (task.args[0],)


def evaluation_path(replica: int, condition: Condition | None, train: Experiment) -> str:
    return f"evals/r{replica:03d}/{condition_id(condition)}/{train.id}.csv"


def error_path(relative: str) -> str:
    """Where a failed unit's error is kept (beside the file it did not produce)."""
    return relative.removesuffix(".csv") + ".error.csv"


class Sweep:
    """One sweep of one study into one results folder (plans, runs and collects), for one
    ``target``: the study's first by default. The simulations are in ``store`` (the study's
    folder); the evaluations and outputs in ``results``: the same folder for a study of one
    target, ``<out>/<target>/`` for one of several."""

    def __init__(self, study: SweepStudy, out_dir: Path, target: str | None = None,
                 store: ResultStore | None = None) -> None:
        self.study = study
        self.target = study.targets[0] if target is None else target
        # one store (and lock) of the folder shared by the sweeps of a study's targets
        self.store = ResultStore(out_dir) if store is None else store
        self.results = self.store if len(study.targets) == 1 else \
            ResultStore(Path(out_dir) / self.target)
        self.truth_columns = (*TRUTH_COLUMNS, *STUDY_DRIVER_COLUMNS,
                              *target_truth_columns(self.target))
        self._geometry: tuple[float, float] | None = None
        self.family = experiments(study)
        self.trains = training_experiments(study, self.family)
        self.conditions: list[Condition | None] = list(conditions(study))
        if study.methods.ground_truth:
            self.conditions.append(None)
        self.specs = tuple(method_specs(study.methods))
        self.fmu = check_fmu(study)
        self.simulations = Simulations(self.store, study, self.family, self.fmu,
                                       "sweep")
        self._truths: dict[tuple[int, str], pd.DataFrame] = {}

    # ----------------------------------------------------------------- planning

    def evaluation_keys(self, replica: int) -> list[tuple[Condition | None, Experiment]]:
        return [(c, t) for c in self.conditions for t in self.trains]

    def simulation_task(self, replica: int, experiment: Experiment) -> Task:
        """The task that simulates one run (a seam: tests break a run here)."""
        return self.simulations.task(replica, experiment)

    def evaluation_task(self, replica: int, condition: Condition | None,
                        trains: Sequence[Experiment]) -> Task:
        """The task that evaluates training runs ``trains`` of one (replica, condition): one
        job for all of them measures and checks every run once (a seam: tests break one
        here)."""
        truths: dict[str, pd.DataFrame] = {}
        failures: dict[str, str] = {}
        for experiment in self.family:
            if self.store.exists(failure_path(replica, experiment)):
                failures[experiment.id] = self.simulations.error(replica, experiment)
            else:
                truths[experiment.id] = self.truth(replica, experiment)
        job = EvaluationJob(
            replica=replica, condition=condition, trains=tuple(trains),
            experiments=tuple(self.family), truths=truths, failures=failures,
            seeds={e.id: sensor_seed(self.study, replica, e) for e in self.family},
            duration_s=self.study.duration_s, specs=self.specs,
            similarity=self.study.methods.similarity, target=self.target,
            probe_geometry_m=self.probe_geometry())
        key = f"evaluate r{replica} {condition_id(condition)}"
        if list(trains) != self.trains:
            key += " " + " ".join(train.id for train in trains)
        return Task(key, evaluate_job, (job,), kind="evaluation")

    def truth(self, replica: int, experiment: Experiment) -> pd.DataFrame:
        """The run's truth columns as read from its recording (kept from the write when the
        recording was simulated now: ``read_back``)."""
        key = (replica, experiment.id)
        if key not in self._truths:
            frame = read_recording(self.store.path(recording_path(replica, experiment)))
            missing = [c for c in self.truth_columns if c not in frame.columns]
            if missing:
                raise SpindlebenchError(
                    f"{self.store.path(recording_path(replica, experiment))}: lacks "
                    f"{missing[0]} for the target {self.target}: was it simulated without "
                    "the probes?")
            self._truths[key] = frame.loc[:, list(self.truth_columns)].copy()
        return self._truths[key]

    def target_stores(self) -> list[ResultStore]:
        """The evaluations' folder of every target of the study (this one's is ``results``)."""
        if len(self.study.targets) == 1:
            return [self.results]
        return [self.results if t == self.target else ResultStore(self.store.root / t)
                for t in self.study.targets]

    def probe_geometry(self) -> tuple[float, float] | None:
        """(l, end-face offset) in m of the runs' five probes; None for the axial drift."""
        if self.target == DRIFT_COLUMN:
            return None
        if self._geometry is None:
            self._geometry = probe_geometry_m(self.study, self.fmu)
        return self._geometry

    # ----------------------------------------------------------------- running

    def run(self, runner: TaskRunner) -> SweepOutcome:
        """Simulate and evaluate what is not done yet, holding the folder's lock."""
        with self.store.locked():
            return self._run(runner)

    def _run(self, runner: TaskRunner) -> SweepOutcome:
        resumed = self.simulations.claim()
        pending = self.simulations.pending()
        waiting = {r: {e.id for e in exps} for r, exps in pending.items()}
        tasks: list[Task] = []
        skipped = {"simulation": 0, "evaluation": 0}
        for replica, exps in pending.items():
            skipped["simulation"] += len(self.family) - len(exps)
            if exps:
                # Its recordings change: evaluations made from the old set are stale.
                for condition, train in self.evaluation_keys(replica):
                    for results in self.target_stores():  # every target's are stale
                        results.remove(evaluation_path(replica, condition, train))
                        results.remove(error_path(evaluation_path(replica, condition, train)))
                tasks.extend(self.simulation_task(replica, e) for e in exps)
            else:
                todo = self._evaluations_to_do(replica)
                skipped["evaluation"] += len(self.evaluation_keys(replica)) - sum(
                    len(job.trains) for task in todo for job in task_jobs(task))
                tasks.extend(todo)

        evaluated = [0]  # training-run evaluations written (a job holds several)

        def on_outcome(outcome: Outcome) -> Iterable[Task]:
            if outcome.task.kind == "simulation":
                return self._record_simulation(outcome, waiting)
            self._record_evaluation(outcome)
            evaluated[0] += sum(len(job.trains) for job in task_jobs(outcome.task))
            return ()

        follow_ups = sum(1 for exps in pending.values() if exps)  # a task per replica
        stats = runner.run(tasks, on_outcome, expected_follow_ups=follow_ups)
        results = self.collect()
        return SweepOutcome(self.results.root, results, stats, resumed, skipped, evaluated[0])

    def _evaluations_to_do(self, replica: int) -> list[Task]:
        """The evaluations of ``replica``'s training runs without a result file (a run whose
        file is lost is redone, the others are kept): one job per condition
        (``evaluation_task``), all in one task (``evaluate_jobs``: the conditions that measure
        a training run alike then train its models once)."""
        tasks = []
        for condition in self.conditions:
            missing = [train for train in self.trains
                       if not self.results.exists(evaluation_path(replica, condition, train))]
            if missing:
                tasks.append(self.evaluation_task(replica, condition, missing))
        for experiment in self.family:  # the jobs hold their data now: free the cache
            self._truths.pop((replica, experiment.id), None)
        jobs = [task for task in tasks if task.fn is evaluate_job]
        if len(jobs) < 2:
            return tasks
        joined = Task(f"evaluate r{replica}", evaluate_jobs,
                      (tuple(task.args[0] for task in jobs),), kind="evaluation")
        return [joined, *(task for task in tasks if task.fn is not evaluate_job)]

    def _record_evaluation(self, outcome: Outcome) -> None:
        """Write each training run's rows, or its error file (kept apart so that the next run
        retries it): a task that raised fails all its training runs, a job that raised all
        of its own, a training run whose evaluation raised only itself. One manifest save
        records them all."""
        jobs = task_jobs(outcome.task)
        if not outcome.ok:
            results: list[JobResult] = [str(outcome.error)] * len(jobs)
        elif outcome.task.fn is evaluate_jobs:
            results = list(outcome.value)
        else:
            results = [outcome.value]
        with self.results.one_manifest_save():
            for job, result in zip(jobs, results, strict=True):
                self._record_job(job, result)

    def _record_job(self, job: EvaluationJob, result: JobResult) -> None:
        """Write the rows or error file of each training run of ``job`` (``result``: its
        results, or the one-line error that failed it)."""
        condition = job.condition
        for train in job.trains:
            path = evaluation_path(job.replica, condition, train)
            value = result if isinstance(result, str) else result[train.id]
            if isinstance(value, pd.DataFrame):
                self.results.write_frame(path, value)
                self.results.remove(error_path(path))
                continue
            self.results.write_frame(error_path(path), pd.DataFrame([{
                "replica": job.replica, "data": "measured" if condition else NOISE_FREE,
                "noise": condition.noise.name if condition else NOISE_FREE,
                "fault": condition.fault_name if condition else "none",
                "train_experiment": train.id,
                "error": f"evaluation failed: {value}"}]))

    def _record_simulation(self, outcome: Outcome, waiting: dict[int, set[str]]) -> list[Task]:
        replica, experiment = self.simulations.store_outcome(outcome)
        if outcome.ok:  # its truth as the file reads back, without reading it
            truth = read_back(self.store.path(recording_path(replica, experiment)),
                              outcome.value[0], self.truth_columns)
            if truth is not None:
                self._truths[(replica, experiment.id)] = truth
        waiting[replica].discard(experiment.id)
        return self._evaluations_to_do(replica) if not waiting[replica] else []

    # ----------------------------------------------------------------- collecting

    def collect(self) -> pd.DataFrame:
        """All evaluation files as one tidy table, in a stable order."""
        found = []
        for replica in replicas(self.study):
            for condition, train in self.evaluation_keys(replica):
                relative = evaluation_path(replica, condition, train)
                for candidate in (relative, error_path(relative)):
                    if self.results.exists(candidate):
                        found.append(candidate)
                        break
        if not found:
            return pd.DataFrame(columns=list(RESULT_COLUMNS))
        results = self.results.read_frames(found)
        for column in RESULT_COLUMNS:
            if column not in results:
                results[column] = pd.NA
        results = results.loc[:, list(RESULT_COLUMNS)]
        results["k"] = results["k"].astype("Int64")
        for column in ("error", "selected"):  # an all-empty column reads back as float NaN
            results[column] = results[column].astype(object).where(results[column].notna(), "")
            results[column] = results[column].astype(str)
        return results.reset_index(drop=True)


def run_sweep(study_path: str | Path, out_dir: str | Path, workers: int | None = None,
              dask_address: str | None = None, progress: bool = True,
              machine: str | None = None) -> SweepOutcome:
    """Run (or resume) a sweep and write every output; return what was done. ``machine``
    replaces the study's machine variant."""
    stages = Stages(Path(study_path).stem, enabled=progress)  # timed from the start
    study = load_study(study_path, machine=machine)
    stages.label = study.name
    sweeps = [Sweep(study, Path(out_dir), study.targets[0])]
    sweeps += [Sweep(study, Path(out_dir), target, sweeps[0].store)
               for target in study.targets[1:]]
    runner = TaskRunner(workers=workers, dask_address=dask_address, progress=progress,
                        desc=study.name, unit="job")
    # an unreachable scheduler fails before the folder is made (and locked)
    with runner.connected(), sweeps[0].store.locked():
        outcomes = []
        for sweep in sweeps:  # the first simulates; the others find the recordings done
            if len(sweeps) > 1:
                stages(f"target {sweep.target}: evaluating into {sweep.results.root}")
            outcomes.append(sweep.run(runner))
            write_outputs(sweep, outcomes[-1], runner, stages)
        if len(sweeps) > 1:
            from spindlebench.studies.sweep.joint import write_joint

            stages("joint selections: one sensor set for every target")
            write_joint(sweeps, runner)
            outcomes[0].study_dir = sweeps[0].store.root
    return outcomes[0]


def write_outputs(sweep: Sweep, outcome: SweepOutcome, runner: TaskRunner,
                  say: Callable[[str], None] = lambda _: None) -> None:
    """results.csv, summary, plots, README and provenance (all atomic); ``say`` hears each
    step (a third of a sweep's wall time comes after its progress bar)."""
    from spindlebench.studies.sweep import summary
    from spindlebench.studies.sweep import sweep_plots as plots
    from spindlebench.studies.sweep import sweep_report as report

    store, study = sweep.results, sweep.study
    results = outcome.results
    say(f"writing results.csv ({len(results)} rows)")
    store.write_frame("results.csv", results)
    if not results["rmse_um"].notna().any():
        raise nothing_to_summarise(sweep, results)
    say("summarising the results per method, season and condition")
    scored = summary.Scored(results)  # coded once for the tables and the plots
    tables = summary.summarise(results, scored)
    for name, table in tables.items():
        store.write_frame(f"summary/{name}.csv", table)
    say("drawing the box plots")
    figures = plots.box_plots(results, store.path("plots"), scored)
    say("writing provenance.json and README.md")
    seeds = {f"r{r}": {e.id: sensor_seed(study, r, e) for e in sweep.family}
             for r in replicas(study)}
    record = provenance(
        kind="spindlebench season sweep",
        study=file_entry(study.path),
        study_content_sha256=content_sha256(pinned_content(study)),
        climate=file_entry(study.climate.path),
        machine=study.machine.provenance(),
        fmu=file_entry(sweep.fmu),
        study_seed=study.seed,
        seeds=seeds,
        axes=describe(study),
        executor=runner.describe(),
        **({} if store is sweep.store else {"target": sweep.target}),
    )
    store.write_json("provenance.json", record)
    text = report.readme(study, results, tables, figures, record, sweep.trains)
    if store is not sweep.store:  # one of several targets: say which, under the title
        text = one_target_readme(text, sweep.target, "sweep", "joint selections")
    write_text(store.path("README.md"), text)


def nothing_to_summarise(sweep: Sweep, results: pd.DataFrame) -> SpindlebenchError:
    """Write a README that says why there are no findings; return the one-line error.

    When every simulation (or every evaluation) failed there is nothing to summarise, plot or
    judge; results.csv (written before) keeps every row with its error, and the README and
    the error line point at the first cause instead of a crash in the summary.
    """
    store, study = sweep.results, sweep.study
    runs, failed = sweep.simulations.runs(), sweep.simulations.failed()
    if failed:
        where = failure_path(*failed[0])
        first = sweep.simulations.error(*failed[0])
    else:
        with_error = results[results["error"] != ""]
        first = with_error["error"].iloc[0] if len(with_error) else "no result rows"
        where = "results.csv"
    if len(failed) == len(runs):
        what = f"all {len(runs)} simulations failed"
    else:
        what = (f"no evaluation produced an RMSE ({len(results)} result rows, "
                f"{len(failed)} of {len(runs)} simulations failed)")
    write_text(store.path("README.md"), "\n".join([
        f"# {study.name}: no findings", "",
        f"Nothing to summarise: {what} ({len(sweep.family)} experiments × "
        f"{study.replicas} replica(s)).", "",
        f"First error (`{where}`):", "", f"    {first}", "",
        "`results.csv` lists every result row with its error. Fix the cause and run the same "
        "command again: finished work is kept and failed simulations and evaluations are "
        "retried.", ""]))
    home = sweep.store if failed else store  # the simulations' folder, or the target's
    return SpindlebenchError(f"sweep: {what}; first: {first}; see {home.path(where)}")


# --------------------------------------------------------------------- command line
