"""The simulation phase every study shares (``sweep`` and ``place``).

Claim the results folder (pin the study's content and the FMU, or check them on resume),
simulate every (replica, experiment) run whose recording is not on disk yet, and store each
outcome as it arrives: the recording with its sidecar, or the error in its place, so an
interrupted study resumes and a failed simulation is retried by the next run. The command
line every study shares is ``commands.arguments.register_study_command``.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

from spindlebench.core.provenance import sha256_file
from spindlebench.studies.family.experiments import Experiment, replicas, scenario_for
from spindlebench.studies.family.family_file import SweepStudy, pinned_content
from spindlebench.studies.running.executor import Outcome, Task
from spindlebench.studies.running.jobs import simulate_job
from spindlebench.studies.running.store import ResultStore
from spindlebench.testbench.scenario import MeasuredAmbient, Scenario


def run_dir(replica: int) -> str:
    return f"runs/r{replica:03d}"


def recording_path(replica: int, experiment: Experiment) -> str:
    return f"{run_dir(replica)}/{experiment.id}.csv"


def failure_path(replica: int, experiment: Experiment) -> str:
    return f"{run_dir(replica)}/{experiment.id}.error.json"


def on_any_worker(scenario: Scenario,
                  resolve: Callable[[Path], Path] = Path.resolve) -> Scenario:
    """``scenario`` with every file it names made absolute here (by ``resolve``), before it
    is submitted: a Dask worker started in another folder read ``scenarios/studies/x.toml``
    relative to its own folder and every simulation failed with ``FileNotFoundError``. The
    same for the local pool, so a recording's sidecar reads the same on every backend."""
    if isinstance(scenario.ambient, MeasuredAmbient):
        scenario = replace(scenario, ambient=replace(scenario.ambient,
                                                     file=resolve(scenario.ambient.file)))
    if scenario.initial.from_file is not None:
        scenario = replace(scenario, initial=replace(
            scenario.initial, from_file=resolve(scenario.initial.from_file)))
    return replace(scenario, path=resolve(Path(scenario.path)))


class Simulations:
    """The runs of one study in one results folder: what is done, what failed, the tasks."""

    def __init__(self, store: ResultStore, study: SweepStudy, family: list[Experiment],
                 fmu: Path, command: str) -> None:
        self.store = store
        self.command = command
        self.study = study
        self.family = family
        self.fmu = fmu
        self._keys: dict[str, tuple[int, Experiment]] = {}
        #: the files the study's scenarios name (the study's, a measured ambient's) and the
        #: FMU, resolved at their first task: each of a thousand tasks resolved them again,
        #: a ``stat`` per part of each path
        self._resolve = functools.cache(Path.resolve)

    def claim(self) -> bool:
        """Pin the study's content and the FMU (True: resuming a folder pinned to them)."""
        return self.store.claim(pinned_content(self.study), {"fmu_sha256": sha256_file(self.fmu)},
                                command=self.command)

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
        scenario = on_any_worker(scenario_for(self.study, replica, experiment), self._resolve)
        return Task(key, simulate_job, (scenario, self._resolve(self.fmu)), kind="simulation")

    def store_outcome(self, outcome: Outcome) -> tuple[int, Experiment]:
        """Write a simulation's recording (or its error); return which run it was."""
        replica, experiment = self._keys[outcome.task.key]
        if outcome.ok:
            frame, sidecar = outcome.value
            self.store.write_recording(recording_path(replica, experiment), frame, sidecar)
            self.store.remove(failure_path(replica, experiment))
        else:
            self.store.write_json(failure_path(replica, experiment),
                                  {"error": outcome.error, "detail": outcome.detail})
        return replica, experiment




