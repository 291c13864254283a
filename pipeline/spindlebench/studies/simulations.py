"""The simulation phase every study shares (``sweep`` and ``place``).

Claim the results folder (pin the study's content and the FMU, or check them on resume),
simulate every (replica, experiment) run whose recording is not on disk yet, and store each
outcome as it arrives: the recording with its sidecar, or the error in its place, so an
interrupted study resumes and a failed simulation is retried by the next run. The command
line every study shares (``register_study_command``) lives here too.
"""

from __future__ import annotations

import argparse
import functools
from collections.abc import Callable
from pathlib import Path

from spindlebench.formats.recording import write_recording
from spindlebench.provenance import sha256_file
from spindlebench.studies.executor import Outcome, Task, add_study_arguments, results_folder
from spindlebench.studies.experiments import Experiment, replicas, scenario_for
from spindlebench.studies.jobs import simulate_job
from spindlebench.studies.population import Member, Population, draw_population
from spindlebench.studies.store import ResultStore
from spindlebench.studies.study import SweepStudy, machine_runs, pinned_content


def run_dir(replica: int) -> str:
    return f"runs/r{replica:03d}"


def recording_path(replica: int, experiment: Experiment) -> str:
    return f"{run_dir(replica)}/{experiment.id}.csv"


def failure_path(replica: int, experiment: Experiment) -> str:
    return f"{run_dir(replica)}/{experiment.id}.error.json"


class Simulations:
    """The runs of one study in one results folder: what is done, what failed, the tasks."""

    def __init__(self, store: ResultStore, study: SweepStudy, family: list[Experiment],
                 fmu: Path) -> None:
        self.store = store
        self.study = study
        self.family = family
        self.fmu = fmu
        self._keys: dict[str, tuple[int, Experiment]] = {}

    def claim(self) -> bool:
        """Pin the study's content and the FMU (True: resuming a folder pinned to them)."""
        return self.store.claim(pinned_content(self.study), {"fmu_sha256": sha256_file(self.fmu)})

    def runs(self) -> list[tuple[int, Experiment]]:
        """Every (replica, experiment) run of the study."""
        return [(r, e) for r in replicas(self.study) for e in self.family]

    def pending(self) -> dict[int, list[Experiment]]:
        """Per replica, the experiments without a recording yet."""
        return {r: [e for e in self.family if not self.store.has_recording(recording_path(r, e))]
                for r in replicas(self.study)}

    def failed(self) -> list[tuple[int, Experiment]]:
        """The runs whose simulation failed (an error file is kept instead of the recording)."""
        return [(r, e) for r, e in self.runs() if self.store.exists(failure_path(r, e))]

    def error(self, replica: int, experiment: Experiment) -> str:
        """The error of a failed run."""
        return self.store.read_json(failure_path(replica, experiment))["error"]

    def task(self, replica: int, experiment: Experiment) -> Task:
        """The task that simulates one run (in a worker; the result comes back here)."""
        key = f"simulate r{replica} {experiment.id}"
        self._keys[key] = (replica, experiment)
        scenario = scenario_for(self.study, replica, experiment)
        return Task(key, simulate_job, (scenario, self.fmu), kind="simulation")

    def store_outcome(self, outcome: Outcome) -> tuple[int, Experiment]:
        """Write a simulation's recording (or its error); return which run it was."""
        replica, experiment = self._keys[outcome.task.key]
        if outcome.ok:
            frame, sidecar = outcome.value
            write_recording(self.store.path(recording_path(replica, experiment)), frame, sidecar)
            self.store.remove(failure_path(replica, experiment))
        else:
            self.store.write_json(failure_path(replica, experiment),
                                  {"error": outcome.error, "detail": outcome.detail})
        return replica, experiment


#: What a study kind writes over a population's machines once each has run (None: the
#: machines' own folders and ``population.csv`` only).
PopulationReport = Callable[[Path, Population, list[Member], Path, Path], str]


def register_study_command(subparsers: argparse._SubParsersAction, name: str, *, help: str,
                           description: str, example: str,
                           load_family: Callable[[Path], SweepStudy],
                           run_one: Callable[[argparse.Namespace, Path, str | None], None],
                           population_report: PopulationReport | None = None) -> None:
    """Add a study sub-command with the options every study shares.

    ``load_family`` loads (and checks) the study file and gives its experiment family;
    ``run_one`` runs the study on one machine into one results folder;
    ``population_report`` sums up a population's machines (``studies.population``)."""
    parser = subparsers.add_parser(name, help=help, description=description)
    add_study_arguments(parser, example)
    parser.set_defaults(func=functools.partial(run_study_command, load_family=load_family,
                                               run_one=run_one,
                                               population_report=population_report))


def run_study_command(args: argparse.Namespace, *, load_family: Callable[[Path], SweepStudy],
                      run_one: Callable[[argparse.Namespace, Path, str | None], None],
                      population_report: PopulationReport | None = None) -> int:
    """A study command: its results folder, then one run per machine (``machine_runs``, or
    every kept machine of the study's population)."""
    out = results_folder(args, lambda study: load_family(study).name)
    study = load_family(args.study)
    members: list[Member] | None = None
    if args.machine is None and study.population is not None:
        from spindlebench.testbench.runner import inspect_fmu

        print(f"population: {study.population.describe()}")
        members = draw_population(study.population, inspect_fmu(study.fmu).parameters,
                                  study.fmu, out, study.name)
        runs: list[tuple[str | None, Path]] = [(str(m.path), out / m.name)
                                               for m in members if m.kept]
    else:
        runs = machine_runs(study, args.machine, out)
    for machine, folder in runs:
        if machine is not None and folder != out:
            print(f"machine {Path(machine).stem if machine.endswith('.toml') else machine}:")
        run_one(args, folder, machine)
    if members is not None and population_report is not None:
        population_report(out, study.population, members, Path(args.study), study.fmu)
        print(f"population summary: {out / 'README.md'}")
    return 0
