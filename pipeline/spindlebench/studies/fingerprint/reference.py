"""The default machine's paper experiments, as the reference a fingerprint is compared with.

``spindlebench fingerprint`` puts a user's recordings next to the five paper experiments
(``scenarios/paper/exp1..5.toml``) simulated on the default machine. They come from one of two
places:

- ``--reference DIR``: any folder of recordings, e.g. ``results/paper`` from ``make run``
  (every ``*.csv`` in it is used, with ``drift_um`` as the error);
- otherwise a cache, ``fingerprint_reference/`` in the per-user cache
  (``paths.user_cache_dir()``, never the current folder; ``.../<machine>/`` with
  ``--machine``): the five experiments simulated with
  the committed FMU the first time they are needed (a few seconds each), reused while the
  FMU, the scenario files (``scenarios/paper/*.toml`` and ``scenarios/machines/*.toml``
  when present), the testbench's source and the package versions have the hashes recorded in
  its ``reference.json``. Anything else (a changed
  FMU or scenario, a missing or damaged file) resimulates. ``reference.json`` is written
  last, so an interrupted simulation is never taken for a complete cache.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from spindlebench.core import atomic
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.listflags import expand_folders
from spindlebench.core.paths import DATA_ROOT, DEFAULT_FMU, SCENARIOS_DIR, shown, user_cache_dir
from spindlebench.core.provenance import sha256_file, source_sha256
from spindlebench.formats.recording import DRIFT_COLUMN, write_recording
from spindlebench.machines.variants import load_machine
from spindlebench.testbench.batch import check_batch, plan_batch
from spindlebench.testbench.simulate import record

PAPER_SCENARIOS = SCENARIOS_DIR / "paper"
MACHINES = SCENARIOS_DIR / "machines"
def default_cache() -> Path:
    """The reference's cache folder: ``fingerprint_reference/`` in the per-user cache."""
    return user_cache_dir() / "fingerprint_reference"


KEY_FILE = "reference.json"
#: The code that turns scenarios into recordings: a change in it (or in a tracked package's
#: version) resimulates the reference, as a changed FMU or scenario does.
REFERENCE_CODE = ("spindlebench.formats.recording", *(
    f"spindlebench.testbench.{name}" for name in (
        "drivers", "runner", "scenario", "sensors", "simulate", "soak")))
#: The error column of a synthetic recording.
REFERENCE_TARGET = DRIFT_COLUMN


@dataclass(frozen=True)
class Reference:
    """Where the reference recordings are and what made them (for provenance)."""

    recordings: list[Path]
    source: dict[str, Any]


def inputs_key(fmu: Path = DEFAULT_FMU, scenarios: Path = PAPER_SCENARIOS,
               machines: Path = MACHINES) -> dict[str, Any]:
    """The hashes that decide whether a cached reference is still the default machine's."""
    files = sorted(scenarios.glob("*.toml")) + sorted(machines.glob("*.toml"))
    return {
        "code_sha256": source_sha256(*REFERENCE_CODE),
        "fmu": {"path": str(fmu), "sha256": sha256_file(fmu)},
        "scenarios": {str(path.relative_to(DATA_ROOT) if path.is_relative_to(DATA_ROOT)
                          else path): sha256_file(path) for path in files},
    }


def explicit_reference(folder: Path) -> Reference:
    """``--reference DIR``: its ``*.csv`` recordings, or one error line."""
    if not folder.is_dir():
        raise SpindlebenchError(f"--reference {folder}: no such folder (give a folder of "
                                "recordings, e.g. results/paper from 'make run')")
    try:
        recordings = expand_folders([folder], ".csv", "recording")
    except SpindlebenchError as exc:
        raise SpindlebenchError(f"--reference {exc}") from None
    return Reference(recordings, {"kind": "folder", "path": str(folder)})


def cached_reference(cache: Path | None = None, fmu: Path = DEFAULT_FMU,
                     scenarios: Path = PAPER_SCENARIOS, machines: Path = MACHINES,
                     say=print, machine: str | None = None) -> Reference:
    """The paper experiments on the default machine (or on ``machine``, a name or a .toml
    file, in ``cache/<its name>/``), simulated once into ``cache``."""
    cache = default_cache() if cache is None else cache
    label = "default"
    machine_entry: dict[str, Any] = {}
    if machine is not None:
        variant = load_machine(machine)
        label = variant.name
        machine_entry = {"machine": variant.provenance()}
        cache = cache / variant.name
    if not fmu.is_file():
        raise SpindlebenchError(f"reference: FMU {fmu} not found (run 'spindlebench build', "
                                "or pass --reference DIR)")
    files = sorted(scenarios.glob("*.toml"))
    if not files:
        raise SpindlebenchError(f"reference: no scenario in {scenarios} (pass --reference DIR)")
    key = {**inputs_key(fmu, scenarios, machines), **machine_entry}
    targets = [cache / f"{path.stem}.csv" for path in files]
    if _cache_matches(cache / KEY_FILE, key) and all(path.is_file() for path in targets):
        return Reference(targets, {"kind": "cache", "path": str(cache), **key})
    say(f"simulating the {label} machine's {len(files)} paper experiments ({shown(scenarios)}, "
        f"{shown(fmu)}) into {cache} once")
    plan = plan_batch(files, targets, machine)
    check_batch(plan, fmu)
    (cache / KEY_FILE).unlink(missing_ok=True)
    for i in plan.order:
        frame, sidecar = record(plan.scenarios[i], fmu)
        write_recording(targets[i], frame, sidecar)
    atomic.write_text(cache / KEY_FILE, json.dumps(key, indent=2, sort_keys=True) + "\n")
    return Reference(targets, {"kind": "cache", "path": str(cache), **key})


def _cache_matches(path: Path, key: dict[str, Any]) -> bool:
    try:
        return json.loads(path.read_text(encoding="utf-8")) == key
    except (OSError, ValueError):
        return False
