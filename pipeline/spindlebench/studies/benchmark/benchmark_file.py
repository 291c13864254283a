"""The benchmark suite file: ``benchmarks/<suite>.toml``.

A suite fixes what numbers mean: its tasks (synthetic families, real recordings, with their
folds), the sensor budget ``k``, the band of "within +-band" and the seed. Its ``version`` is
written by hand and bumped whenever a task changes; ``tasks_sha256`` is computed from the
tasks' content (the suite's task tables, the budget, the band, the seed; for a synthetic
task the parsed content of its study and climate files, its machines' parameter values and
the FMU's SHA-256 (comments do not count, a rebuilt model does); for a real
one the source file's SHA-256), so a result always says which tasks made it, and two
results with the same hash are comparable. The methods a suite lists are only the default
entrants: they are not part of the hash.

Format::

    [suite]
    name = "default"
    version = "1.0"
    description = "..."
    k = 3                 # sensors (candidates) every selection method keeps
    band_um = 5.0         # "share of time within +-band_um"
    seed = 0              # seed of the seeded methods
    methods = ["closure", "lasso", ...]   # default entrants (spindlebench methods)

    [[task]]
    name = "synthetic"
    kind = "synthetic"    # a sweep study file's family, simulated with the FMU
    study = "studies/synthetic-default.toml"   # relative to the suite file

    [[task]]
    name = "iso230-3-spindle"
    kind = "scenarios"    # scenario files simulated with the FMU, as they are written
    train = ["../scenarios/heating/room20_4000.toml"]   # each trains once (one fold each)
    predict = ["../scenarios/iso230-3/spindle.toml"]    # predicted in every fold
    others = false        # the other train scenarios are predicted too (default true)
    targets = ["drift_um", "drift_y_um"]   # one task per target (default ["drift_um"])
    probes = true         # record the five-probe channels in every run (default false)
    machine = "default"   # the machine variant every run simulates

    [[task]]
    name = "caiviac-heating"
    kind = "caiviac"      # the CAIVIAC FL_THERMAL runs (read in place)
    phase = "heating"     # or "cycle"
    source = "caiviac-fl-thermal/data.csv"  # under the shared recordings folder
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import BENCHMARKS_DIR
from spindlebench.formats.toml import Table, in_range, load_toml, one_of, positive

#: Where suites live: ``benchmarks/`` of the checkout (a wheel's copy when installed).
SUITES_DIR = BENCHMARKS_DIR
DEFAULT_SUITE = "default"
TASK_KINDS = ("synthetic", "scenarios", "caiviac")
PHASES = ("heating", "cycle")


@dataclass(frozen=True)
class TaskSpec:
    """One task of a suite as its file defines it."""

    name: str
    kind: str
    study: Path | None = None
    #: ``scenarios`` kind: the scenario files that train (one fold each), the ones predicted
    #: in every fold, whether the other training files are predicted too, the targets, the
    #: five-probe outputs, the machine.
    train: tuple[Path, ...] = ()
    predict: tuple[Path, ...] = ()
    others: bool = True
    targets: tuple[str, ...] = ()
    probes: bool = False
    machine: str = "default"
    phase: str = "heating"
    source: str = "caiviac-fl-thermal/data.csv"
    description: str = ""
    #: The one-line error of a real task whose recording is not there ("" when it is).
    missing: str = ""
    #: The content the hash covers (the task table as written, plus a study's content).
    content: dict[str, Any] = field(default_factory=dict, compare=False)


@dataclass(frozen=True)
class Suite:
    """A checked suite file."""

    path: Path
    name: str
    version: str
    description: str
    k: int
    band_um: float
    seed: int
    methods: tuple[str, ...]
    tasks: tuple[TaskSpec, ...]

    @property
    def tasks_sha256(self) -> str:
        """SHA-256 of the tasks' content (canonical JSON): what a result's numbers mean."""
        content = {"k": self.k, "band_um": self.band_um, "seed": self.seed,
                   "tasks": [task.content for task in self.tasks]}
        text = json.dumps(content, sort_keys=True, separators=(",", ":"), default=str)
        return hashlib.sha256(text.encode()).hexdigest()

    def describe(self) -> dict[str, Any]:
        """The suite's identity for every output."""
        return {"name": self.name, "version": self.version, "tasks_sha256": self.tasks_sha256,
                "file": str(self.path), "k": self.k, "band_um": self.band_um,
                "seed": self.seed, "tasks": [task.name for task in self.tasks]}


def suite_path(name_or_path: str | None) -> Path:
    """``default`` -> ``benchmarks/default.toml``; a path stays a path."""
    text = name_or_path or DEFAULT_SUITE
    path = Path(text)
    if path.suffix == ".toml" or path.parent != Path("."):
        return path
    return SUITES_DIR / f"{text}.toml"


def load_suite(name_or_path: str | None = None, recordings_root: Path | None = None) -> Suite:
    """Read and check a suite (one-line errors naming file and key). A real task's source is
    found under ``recordings_root`` (default: ``paths.shared_recordings_dir()``)."""
    from spindlebench.core.paths import shared_recordings_dir

    root_dir = Path(recordings_root) if recordings_root is not None else shared_recordings_dir()
    path = suite_path(name_or_path)
    if not path.is_file():
        known = sorted(p.stem for p in SUITES_DIR.glob("*.toml")) if SUITES_DIR.is_dir() else []
        raise SpindlebenchError(f"{path}: no such suite file"
                                + (f" (suites in {SUITES_DIR}: {', '.join(known)})"
                                   if known else ""))
    root = Table(load_toml(path, "benchmark suite"), path)
    head = root.table("suite")
    name = head.get("name", str, default=path.stem)
    version = head.get("version", str)
    description = head.get("description", str, default="")
    k = head.get("k", int, check=in_range(1, 1000))
    band = head.get("band_um", float, default=5.0, check=positive)
    seed = head.get("seed", int, default=0, check=in_range(0, 2**32 - 1))
    methods = tuple(head.get_list("methods", str, default=[]))
    head.finish()
    from spindlebench.selection.registry import check_labels
    from spindlebench.studies.benchmark.rollout import is_dynamic, parse_dynamic

    where = f"{path}: key 'suite.methods'"
    for label in methods:
        if is_dynamic(label):
            try:
                parse_dynamic(label)
            except SpindlebenchError as exc:
                raise SpindlebenchError(f"{where}: {exc}") from None
    static = check_labels([m for m in methods if not is_dynamic(m)], where)
    dynamic = [m for m in methods if is_dynamic(m)]
    if len(set(dynamic)) < len(dynamic):
        raise SpindlebenchError(f"{where}: a dynamic model is listed twice")
    methods = (*static, *dynamic)
    tasks = []
    for table in root.tables("task"):
        tasks.append(_task(table, path, root_dir))
    root.finish()
    if not tasks:
        raise root.error("task", "a suite needs at least one [[task]]")
    names = [task.name for task in tasks]
    for task_name in names:
        if names.count(task_name) > 1:
            raise root.error("task", f"task name {task_name!r} appears twice")
    return Suite(path=path, name=name, version=version, description=description, k=k,
                 band_um=band, seed=seed, methods=methods, tasks=tuple(tasks))


def _machine_content(machine) -> dict[str, Any]:
    """A machine (``machines.variants.Machine``) as the task hash sees it: its name and
    parameter values."""
    return {"name": machine.name, "parameters": dict(sorted(machine.parameters.items()))}


def _scenarios_task(table: Table, suite_file: Path, name: str, description: str,
                    content: dict[str, Any]) -> TaskSpec:
    """A ``scenarios`` task: its files checked (each loads as a scenario), their bytes'
    SHA-256, the machine's parameter values and the FMU's SHA-256 in the hash."""
    from spindlebench.core.paths import DEFAULT_FMU
    from spindlebench.core.provenance import sha256_file
    from spindlebench.formats.recording import DRIFT_COLUMN
    from spindlebench.machines.variants import load_machine
    from spindlebench.testbench.scenario import load_scenario

    folder = suite_file.resolve().parent
    files = {}
    for key in ("train", "predict"):
        listed = table.get_list(key, str, default=[]) if key == "predict" else \
            table.get_list(key, str)
        files[key] = tuple((folder / p).resolve() for p in listed)
        for path in files[key]:
            if not path.is_file():
                raise table.error(key, f"no such scenario file: {path}")
            try:
                load_scenario(path)
            except SpindlebenchError as exc:
                raise table.error(key, str(exc)) from None
    others = table.get("others", bool, default=True)
    targets = tuple(table.get_list("targets", str, default=[DRIFT_COLUMN]))
    probes = table.get("probes", bool, default=False)
    machine_name = table.get("machine", str, default="default")
    table.finish()
    if not files["train"]:
        raise table.error("train", "give at least one training scenario")
    every = [*files["train"], *files["predict"]]
    if len(set(every)) < len(every):
        raise table.error("predict", "a scenario is listed twice")
    if len(files["train"]) < 2 and not files["predict"]:
        raise table.error("predict", "one training scenario and nothing to predict")
    try:
        machine = load_machine(machine_name, source=suite_file)
    except SpindlebenchError as exc:
        raise table.error("machine", str(exc)) from None
    content["scenario_sha256"] = {p.name: sha256_file(p) for p in every}
    content["machine_content"] = _machine_content(machine)
    content["fmu_sha256"] = sha256_file(DEFAULT_FMU)
    return TaskSpec(name, "scenarios", train=files["train"], predict=files["predict"],
                    others=others, targets=targets, probes=probes, machine=machine_name,
                    description=description, content=content)


def _task(table: Table, suite_file: Path, recordings_root: Path) -> TaskSpec:
    content = dict(table.data)
    name = table.get("name", str)
    kind = table.get("kind", str, check=lambda v: one_of(v, TASK_KINDS))
    description = table.get("description", str, default="")
    if kind == "synthetic":
        study = (suite_file.resolve().parent / table.get("study", str)).resolve()
        table.finish()
        if not study.is_file():
            raise table.error("study", f"no such study file: {study}")
        from spindlebench.core.provenance import sha256_file
        from spindlebench.studies.family.family_file import load_study, pinned_content

        loaded = load_study(study)
        # parsed content only: a comment edited in a machine file (its bytes' SHA-256) must
        # not make the same tasks look different
        from spindlebench.machines.variants import load_machine

        content["study"] = {**pinned_content(loaded), "machine": _machine_content(loaded.machine)}
        content["machines"] = [_machine_content(load_machine(m, source=study))
                               for m in loaded.machines]
        content["fmu_sha256"] = sha256_file(loaded.fmu)  # another model: other task data
        if loaded.population is not None:  # the draw also depends on the base machine
            content["population_base"] = _machine_content(
                load_machine(loaded.population.base, source=loaded.population.source))
        return TaskSpec(name, kind, study=study, description=description, content=content)
    if kind == "scenarios":
        return _scenarios_task(table, suite_file, name, description, content)
    phase = table.get("phase", str, default="heating", check=lambda v: one_of(v, PHASES))
    source = table.get("source", str, default="caiviac-fl-thermal/data.csv")
    table.finish()
    source_path = recordings_root / source
    from spindlebench.core.provenance import sha256_file

    content.setdefault("phase", phase)
    content.setdefault("source", source)
    # a missing recording is an error only when its task runs (--tasks may leave it out);
    # the hash then says "missing", so it cannot pass for the complete suite's
    content["source_sha256"] = sha256_file(source_path) if source_path.is_file() else "missing"
    missing = "" if source_path.is_file() else table.error(
        "source", f"no such recording {source_path} (real recordings are read in place; "
                  "--recordings-root names their folder)").args[0]
    return TaskSpec(name, kind, phase=phase, source=str(source_path), description=description,
                    content=content, missing=missing)
