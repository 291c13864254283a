"""Initial state from a soak history: the machine standing idle for days before a run.

A cold start puts every node, floor slab included, at the morning air; a real workshop machine
has lived through the previous days' cycle, so its slow parts (bed, column, slab) lag the air
and sit near the daily mean. ``initial.kind = "soak"`` simulates ``days`` days of the climate's
daily cycle with the spindle and the feed axes standing and the cooling unit off, starting
from a cold soak at the cycle's first temperature, and starts the run from the end state.
Idle is standstill as the FMU models it, not power off: the servo motors' holding losses
(``P_x_motor_idle``, ``P_y_motor_idle``) stay on, as they do in a machine left powered; the
scenario's ``[parameters]`` apply to the history as to the run. The history
ends at the run's clock time (``start_hour``), so a 08:00 run starts from a morning state.

The daily cycle is ``initial.soak_ambient`` or the run's own ambient without its random
weather (a season or an indoor ambient; a constant ambient soaks to that constant; a measured
series has no cycle to repeat and is refused). Weather is left out on purpose: the soak then
depends only on the FMU, the parameters, the cycle and the number of days, so every run of one
month of a sweep (each speed, programme, replica) shares one soak.

Soaks are cached twice: in memory for the process, and as JSON files in the folder
``SPINDLEBENCH_SOAK_CACHE`` (default ``soak/`` in ``paths.user_cache_dir()``), named by a
SHA-256 of everything the soak depends on (the FMU's hash, the runner's source and the package
versions included), written atomically, so parallel workers and later runs reuse them and a
stale entry cannot be hit. Beside each JSON file, ``<key>.fmustate`` holds the FMU's serialised
state at the soak's end (``fmi3SerializeFMUState``), for an FMU that saves states: the runner
restores it into every run of the same soak (``soak_start``), one warm state forked into many
scenarios.
A JSON file carries its key and the SHA-256 of its states (and of its ``.fmustate``) and is
used only when they match: an edited, copied or damaged entry is named in a warning and
recomputed.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

from spindlebench.core import atomic
from spindlebench.core.errors import SpindlebenchError, StaleCacheWarning
from spindlebench.core.paths import user_cache_folder
from spindlebench.core.provenance import sha256_file, source_sha256
from spindlebench.testbench.runner import co_simulate
from spindlebench.testbench.scenario import (
    ConstantFeed,
    ConstantSpeed,
    Cooling,
    IndoorAmbient,
    InitialState,
    MeasuredAmbient,
    Scenario,
    SensorModel,
)

#: Communication step (s) of the soak: the machine is idle and the air changes over hours.
SOAK_STEP_S = 300.0
#: The runner's input mode of every soak, whatever the run's: a soak shared by runs in either
#: mode (and its cache file) must be one computation.
SOAK_INPUTS = "continuous"
CACHE_ENV = "SPINDLEBENCH_SOAK_CACHE"
#: Bumped when the soak's recipe changes, so old cache files are not reused.
RECIPE = 2
#: The modules whose source (with the package versions) is part of the cache key: a changed
#: runner or driver computes another soak.
SOAK_CODE = ("spindlebench.testbench.runner", "spindlebench.testbench.drivers",
             "spindlebench.testbench.soak")

_memory: dict[str, dict[str, float]] = {}
_memory_fmu_state: dict[str, bytes] = {}
#: The first bytes of a serialised SpindleBench FMU state (``fmu_extensions.c``): a cache file
#: that does not start so is redone, never handed to the FMU.
FMU_STATE_MAGIC = b"SBFMUST\x00"


def cache_dir() -> Path:
    """Where soak states are kept: ``$SPINDLEBENCH_SOAK_CACHE``, else ``soak/`` in the
    per-user cache (``paths.user_cache_dir``), never the current folder."""
    return user_cache_folder("soak", CACHE_ENV)


def soak_scenario(scenario: Scenario) -> Scenario:
    """The idle history before ``scenario``: ``days`` of its daily cycle, machine standing."""
    initial = scenario.initial
    cycle = initial.soak_ambient or scenario.ambient
    if isinstance(cycle, MeasuredAmbient):
        raise SpindlebenchError(f"{scenario.path}: key 'initial.kind': a soak repeats a daily "
                                "cycle; a measured ambient series has none (give "
                                "initial.soak_ambient, or use kind = \"cold\")")
    if isinstance(cycle, IndoorAmbient):  # the cycle without weather: no seed matters
        cycle = replace(cycle, weather_sd_K=0.0, weather_seed=0)
    duration_s = initial.days * 86400.0
    return replace(
        scenario,
        name=f"{scenario.name} soak",
        duration_s=duration_s,
        step_s=SOAK_STEP_S,
        sample_interval_s=duration_s,
        speed=ConstantSpeed(rpm=0.0),
        feed=ConstantFeed(0.0, 0.0),
        ambient=cycle,
        cooling=Cooling(),
        sensors=SensorModel(),
        initial=InitialState(),
        inputs=SOAK_INPUTS,
    )


def soak_key(history: Scenario, fmu_path: Path) -> str:
    """SHA-256 of everything the soak's end state depends on."""
    what: dict[str, Any] = {
        "recipe": RECIPE,
        "code_sha256": source_sha256(*SOAK_CODE),
        "fmu_sha256": sha256_file(fmu_path),
        "duration_s": history.duration_s,
        "step_s": history.step_s,
        "inputs": history.inputs,
        "ambient": history.to_dict()["ambient"],
        "parameters": dict(sorted(history.parameters.items())),
        "machine_parameters": dict(sorted(history.machine.parameters.items())),
    }
    text = json.dumps(what, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def soak_provenance(scenario: Scenario, fmu_path: str | Path) -> dict[str, Any]:
    """What a soaked recording's sidecar says about its start: the history and its cache key."""
    history = soak_scenario(scenario)
    return {"days": scenario.initial.days, "step_s": history.step_s,
            "ambient": history.to_dict()["ambient"],
            "soak_key": soak_key(history, Path(fmu_path))}


def soak_state(scenario: Scenario, fmu_path: str | Path) -> dict[str, float]:
    """The end state (K by state name) of the soak before ``scenario``; cached."""
    fmu_path = Path(fmu_path)
    history = soak_scenario(scenario)
    key = soak_key(history, fmu_path)
    if key in _memory:
        return dict(_memory[key])
    file = cache_dir() / f"{key}.json"
    states = _read_cached(file, key)
    if states is None:
        states = dict(co_simulate(history, fmu_path).end_state_K)
        record = {"soak_key": key, "days": scenario.initial.days,
                  "ambient": history.to_dict()["ambient"], "fmu": str(fmu_path),
                  "states_K": states, "states_sha256": states_sha256(states)}
        with contextlib.suppress(OSError):  # an unwritable cache costs time, not correctness
            atomic.write_text(file, json.dumps(record, indent=1, sort_keys=True) + "\n")
    _memory[key] = dict(states)
    return dict(states)


def soak_start(scenario: Scenario, fmu_path: str | Path) -> tuple[dict[str, float], bytes]:
    """The soak's end temperatures (K by state name) and the FMU's serialised state there.

    Needs an FMU that saves states (``FmuInterface.saves_states``); the caller hands both to
    the runner (``simulate.run_start_with_state``). Cached like ``soak_state``; a JSON entry
    without its state file (written before states were saved, or damaged) is computed again.
    """
    fmu_path = Path(fmu_path)
    history = soak_scenario(scenario)
    key = soak_key(history, fmu_path)
    if key in _memory_fmu_state:
        return dict(_memory[key]), _memory_fmu_state[key]
    file = cache_dir() / f"{key}.json"
    state_file = file.with_suffix(".fmustate")
    states, saved = _read_cached(file, key), _read_state(state_file)
    if saved is not None and states is not None:
        recorded = _recorded_state_sha256(file)
        if recorded != hashlib.sha256(saved).hexdigest():
            if recorded is not None:
                _stale(state_file, "FMU state does not match its checksum (edited or damaged)")
            saved = None
    if states is None or saved is None:
        simulation = co_simulate(history, fmu_path, save_end_state=True)
        states, saved = dict(simulation.end_state_K), simulation.end_fmu_state
        assert saved is not None
        record = {"soak_key": key, "days": scenario.initial.days,
                  "ambient": history.to_dict()["ambient"], "fmu": str(fmu_path),
                  "states_K": states, "states_sha256": states_sha256(states),
                  "fmu_state_sha256": hashlib.sha256(saved).hexdigest()}
        with contextlib.suppress(OSError):
            atomic.write_bytes(state_file, saved)
            atomic.write_text(file, json.dumps(record, indent=1, sort_keys=True) + "\n")
    _memory[key], _memory_fmu_state[key] = dict(states), saved
    return dict(states), saved


def _read_state(file: Path) -> bytes | None:
    """A cached serialised FMU state, or None when missing or not one (then it is redone)."""
    try:
        data = file.read_bytes()
    except OSError:
        return None
    return data if data.startswith(FMU_STATE_MAGIC) else None


def _recorded_state_sha256(file: Path) -> str | None:
    """The SHA-256 of the FMU state file that the JSON entry ``file`` records, if any."""
    try:
        value = json.loads(file.read_text(encoding="utf-8")).get("fmu_state_sha256")
    except (OSError, ValueError, AttributeError):
        return None
    return value if isinstance(value, str) else None


def states_sha256(states: dict[str, float]) -> str:
    """SHA-256 of a soak's end state (sorted names, each value's shortest repr)."""
    text = json.dumps({str(k): float(v) for k, v in states.items()}, sort_keys=True,
                      separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _read_cached(file: Path, key: str) -> dict[str, float] | None:
    """A cache file's states, or None when it is missing or damaged (then it is redone).

    The file must carry the key of the inputs it was computed from (its name can be copied
    or renamed) and the checksum of its states: a hand-edited state (a machine started at
    -23 °C in a 5-12 °C room) is named in a warning and recomputed, not used."""
    try:
        record = json.loads(file.read_text(encoding="utf-8"))
        states = record["states_K"]
    except FileNotFoundError:
        return None
    except (OSError, ValueError, KeyError, TypeError):
        return _stale(file, "unreadable")
    if not isinstance(states, dict) or not all(
            isinstance(v, float) and 200.0 <= v <= 600.0 for v in states.values()):
        return _stale(file, "its states are not temperatures in kelvin")
    if "states_sha256" not in record:  # written before files had checksums: recompute
        return None
    if record.get("soak_key") != key:
        return _stale(file, "computed from other inputs (its soak_key differs)")
    if record.get("states_sha256") != states_sha256(states):
        return _stale(file, "its states do not match their checksum (edited or damaged)")
    return {str(k): float(v) for k, v in states.items()}


def _stale(file: Path, why: str) -> None:
    warnings.warn(f"{file}: soak cache {why}; recomputing it", StaleCacheWarning, stacklevel=3)
    return None
