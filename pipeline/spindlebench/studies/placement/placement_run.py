"""Virtual sensor placement over a season study (``spindlebench place STUDY.toml``, whose
command is ``commands.place``).

1. Simulate every experiment of the study on every replica's day through the FMU (the
   sweep's executor: worker processes or a Dask cluster; each recording is stored as soon as
   it is done, so an interrupted study resumes).
2. On the design replica, find placements for every budget m with each method (fuzzy
   clustering on the training run, greedy forward selection, exhaustive search).
3. Score every placement on every replica (refit on its training run, predict the others)
   and write the results folder: ``placements.csv``, ``scores.csv``, plots, schematic
   drawings, ``README.md`` and ``provenance.json``, all atomically.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from spindlebench.core.atomic import write_text
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.progress import Stages
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.formats.recording import read_recording
from spindlebench.selection import rmse
from spindlebench.selection.registry import methods_record
from spindlebench.studies.family.experiments import (
    experiments,
    one_target_readme,
    replicas,
    sensor_seed,
    training_experiments,
)
from spindlebench.studies.family.family_file import check_fmu, pinned_content
from spindlebench.studies.placement.candidates import TARGET, Run, node_seed, prepare_run
from spindlebench.studies.placement.placement_file import (
    METHODS,
    PlacementStudy,
    describe,
    load_placement_study,
)
from spindlebench.studies.placement.placements import (
    Placement,
    find_placements,
    placements_table,
    score_all,
)
from spindlebench.studies.running.executor import Outcome, RunStats, Task, TaskRunner
from spindlebench.studies.running.simulations import (
    Simulations,
    failure_path,
    recording_path,
)
from spindlebench.studies.running.store import ResultStore, content_sha256


@dataclass
class PlacementOutcome:
    """What ``place`` did: the tables, the output folder and the work counts."""

    out_dir: Path
    placements: list[Placement]
    table: pd.DataFrame
    scores: pd.DataFrame
    stats: RunStats
    resumed: bool
    failures: dict[str, str]
    search_seconds: float
    no_model_rmse_um: float  # mean RMSE of predicting no drift at all, on the scored test runs
    target: str = TARGET
    #: The scored runs per replica: (training runs, held-out runs) of the target.
    runs: dict[int, tuple[list[Run], list[Run]]] = field(default_factory=dict)


class PlacementStudyRun:
    """Simulations (resumable, through the sweep's store and executor) and their runs."""

    def __init__(self, study: PlacementStudy, out_dir: Path) -> None:
        self.study = study
        self.store = ResultStore(out_dir)
        self.family = experiments(study.family)
        self.trains = training_experiments(study.family, self.family)
        self.fmu = check_fmu(study.family)
        self.simulations = Simulations(self.store, study.family, self.family, self.fmu,
                                       "place")

    def simulate(self, runner: TaskRunner) -> tuple[RunStats, bool]:
        resumed = self.simulations.claim()
        tasks = [self.simulations.task(r, e)
                 for r, exps in self.simulations.pending().items() for e in exps]

        def on_outcome(outcome: Outcome) -> Iterable[Task]:
            self.simulations.store_outcome(outcome)
            return ()

        return runner.run(tasks, on_outcome), resumed

    def failures(self) -> dict[str, str]:
        """``r<replica> <experiment>`` → error of every simulation that failed."""
        return {f"r{r} {e.id}": self.simulations.error(r, e) for r, e in self.simulations.failed()}

    def failure_summary(self) -> str:
        """The failures in a few words: how many, the first error once, where it is kept.

        One line however many runs failed: the same cause (a bad FMU, a bad parameter)
        usually fails every run, and repeating it per run made a line of thousands of
        characters.
        """
        runs, failed = self.simulations.runs(), self.simulations.failed()
        if not failed:  # a recording neither stored nor failed: name it, do not say "none"
            missing = [f"r{r} {e.id}" for r, e in runs
                       if not self.store.has_recording(recording_path(r, e))]
            return (f"no simulation failed, but {len(missing)} of {len(runs)} have no stored "
                    f"recording, first {missing[0]}" if missing else "no simulation failed")
        errors = [self.simulations.error(r, e) for r, e in failed]
        replica, experiment = failed[0]
        others = len(set(errors)) - 1
        return (f"{len(failed)} of {len(runs)} simulations failed; first, r{replica} "
                f"{experiment.id}: {errors[0]}"
                + (f" ({others} other distinct error(s))" if others else "")
                + f"; see {self.store.path(failure_path(replica, experiment))}")

    def runs(self, replica: int, target: str = TARGET) -> tuple[list[Run], list[Run]] | None:
        """(training runs, held-out runs) of a replica for ``target``; None if a training
        run is missing."""
        loaded: dict[str, Run] = {}
        for experiment in self.family:
            if self.store.has_recording(recording_path(replica, experiment)):
                frame = read_recording(self.store.path(recording_path(replica, experiment)))
                loaded[experiment.id] = prepare_run(self.study, replica, experiment, frame,
                                                    target)
        if any(train.id not in loaded for train in self.trains):
            return None
        train_ids = {train.id for train in self.trains}
        return ([loaded[t.id] for t in self.trains],
                [run for key, run in loaded.items() if key not in train_ids])


def run_placement(study_path: str | Path, out_dir: str | Path, workers: int | None = None,
                  dask_address: str | None = None, progress: bool = True,
                  machine: str | None = None) -> PlacementOutcome:
    """Run (or resume) a placement study and write every output; return what was done.
    ``machine`` replaces the study's machine variant."""
    stages = Stages(Path(study_path).stem, enabled=progress)  # timed from the start
    study = load_placement_study(study_path, machine)
    stages.label = study.name
    work = PlacementStudyRun(study, Path(out_dir))
    runner = TaskRunner(workers=workers, dask_address=dask_address, progress=progress,
                        desc=study.name, unit="run")
    # an unreachable scheduler fails before the folder is made (and locked)
    with runner.connected(), work.store.locked():
        stats, resumed = work.simulate(runner)
        targets = study.family.targets
        if len(targets) == 1:  # one target: the study's folder as it always was
            return _place(work, runner, stats, resumed, stages, targets[0])
        outcomes = {target: _place(work, runner, stats, resumed, stages, target,
                                   ResultStore(work.store.root / target))
                    for target in targets}
        from spindlebench.studies.placement.joint import write_joint

        stages("joint placements: one sensor set for every target")
        write_joint(work, outcomes)
        return outcomes[targets[0]]


def _place(work: PlacementStudyRun, runner: TaskRunner, stats: RunStats,
           resumed: bool, say: Callable[[str], None] = lambda _: None,
           target: str = TARGET, store: ResultStore | None = None) -> PlacementOutcome:
    """Search, score and write the placements of simulated runs for ``target`` into
    ``store`` (default: the study's folder; ``say`` hears each step: the searches and figures
    come after the simulations' progress bar)."""
    study = work.study
    say("reading the simulated runs" + ("" if store is None else f" for {target}"))
    failures = work.failures()
    runs: dict[int, tuple[list[Run], list[Run]]] = {}
    for replica in replicas(study.family):
        split = work.runs(replica, target)
        if split is not None and split[1]:
            runs[replica] = split
    if study.design_replica not in runs:
        raise SpindlebenchError(f"{study.path}: the design replica's training or held-out runs "
                                f"failed to simulate ({work.failure_summary()})")
    start = time.perf_counter()
    train_runs, valid_runs = runs[study.design_replica]
    say(f"searching placements: {len(study.methods)} method(s) x {len(study.budgets)} "
        f"budget(s) over {len(study.nodes)} candidate nodes")
    placements = find_placements(study, train_runs, valid_runs)
    search_seconds = time.perf_counter() - start
    say(f"scoring {len(placements)} placement(s) on {len(runs)} replica(s)")
    scores = score_all(study, placements, runs)
    table = placements_table(study, placements, scores)
    tested = [run for r in study.test_replicas if r in runs for run in runs[r][1]]
    no_model = float(np.mean([rmse(run.drift_um, np.zeros_like(run.drift_um))
                              for run in tested]))
    outcome = PlacementOutcome((store or work.store).root, placements, table, scores, stats,
                               resumed, failures, search_seconds, no_model, target, runs)
    say("writing tables, figures, schematic drawings and README")
    write_outputs(work, outcome, runner, sorted(runs), store)
    return outcome


def write_outputs(work: PlacementStudyRun, outcome: PlacementOutcome, runner: TaskRunner,
                  scored_replicas: list[int], store: ResultStore | None = None) -> None:
    """Tables, figures, README and provenance (each written atomically) into ``store``
    (default: the study's folder; one folder per target when the study has several)."""
    from spindlebench.studies.placement import placement_plots as plots
    from spindlebench.studies.placement import placement_report as report
    from spindlebench.studies.placement import schematic

    store, study = store or work.store, work.study
    store.write_frame("placements.csv", outcome.table)
    store.write_frame("scores.csv", outcome.scores)
    references = {"probe noise σ": study.family.noise[0].value.probe_noise_um}
    figures = {"comparison": plots.comparison(
        outcome.table, store.path("comparison.png"), references,
        note=f"predicting no drift at all: {outcome.no_model_rmse_um:.1f} µm")}
    figures.update(schematic.placement_figures(study, outcome.placements, outcome.table,
                                               store.path("schematic")))
    seeds = {f"r{r}": {e.id: {"sensors": sensor_seed(study.family, r, e),
                              "nodes": node_seed(study, r, e)} for e in work.family}
             for r in replicas(study.family)}
    record_ = provenance(
        kind="spindlebench sensor placement",
        study=file_entry(study.path),
        study_content_sha256=content_sha256(pinned_content(study.family)),
        climate=file_entry(study.family.climate.path),
        machine=study.family.machine.provenance(),
        fmu=file_entry(work.fmu),
        study_seed=study.family.seed,
        seeds=seeds,
        settings=describe(study),
        # the labels that are selection methods (not the study's own fuzzy, greedy and
        # exhaustive searches), a user's class with its code's package, version and hash
        methods=methods_record([m for m in study.methods if m not in METHODS]),
        training=[e.id for e in work.trains],
        scored_replicas=scored_replicas,
        executor=runner.describe(),
        no_model_rmse_um=outcome.no_model_rmse_um,
        **({} if store is work.store else {"target": outcome.target}),
    )
    store.write_json("provenance.json", record_)
    text = report.readme(study, outcome, figures, record_, work.trains, scored_replicas)
    if store is not work.store:  # one of several targets: say which, under the title
        text = one_target_readme(text, outcome.target, "study", "joint placements")
    write_text(store.path("README.md"), text)


# --------------------------------------------------------------------------- command line


def search_times(placements: list[Placement]) -> str:
    """Search time per method on this machine: printed (the log), never written to the
    results, which are the same bytes for the same study and seed."""
    seconds: dict[str, float] = {}
    for placement in placements:
        if placement.found:  # greedy's budgets share one path: count its time once
            seen = seconds.get(placement.label)
            shared = placement.method == "greedy" and seen is not None
            seconds[placement.label] = (seen or 0.0) + (0.0 if shared else placement.seconds)
    return "search time: " + (", ".join(f"{label} {s:.2f} s" for label, s in seconds.items())
                              or "none")


def report_best(table: pd.DataFrame) -> str:
    """One line per budget: the placement with the lowest mean test RMSE."""
    lines = []
    ok = table[table["test_mean_rmse_um"].notna()]
    for m, at in ok.groupby("m"):
        best = at.loc[at["test_mean_rmse_um"].idxmin()]
        lines.append(f"  m = {m}: best {best['label']} ({best['test_mean_rmse_um']:.2f} um): "
                     f"{best['variables']}")
    return "\n".join(lines)
