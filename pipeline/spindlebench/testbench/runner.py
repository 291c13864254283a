"""Co-simulation of a scenario with the SpindleBench FMU (FMI 3.0 model exchange) via FMPy.

The loop follows FMPy's own ``simulateME``: instantiate, set parameters and the initial state
by name, initialise, then integrate with FMPy's CVode wrapper from one stop to the next.
Two input modes (``Scenario.inputs``, scenarios/README.md says why continuous is the default):

- ``continuous``: the ambient is set at the solver's time inside the right-hand side (FMPy's
  ``set_time`` hook); speed and feed are piecewise constant. CVode stops only at output
  points and input jumps, never steps past the next jump (``CVodeSetStopTime``) and has no
  step cap.
- ``hold``: every input is held over each communication step (zero-order hold), set at its
  start, and CVode is stopped exactly at its end, so it never integrates past a point where
  an input changes.

In both, where a programmed input jumps (a speed or feed step) the solver is re-initialised,
so its step-size history does not straddle the jump; between two stops Python runs (a
pending Ctrl-C is acted on there: FMPy's CVode callbacks swallow KeyboardInterrupt).

Per-stop Python work is kept small: the driver values for all steps are computed up front, the
value references are turned into ctypes arrays once, inputs are set and outputs read with one
``fmi3SetFloat64`` / ``fmi3GetFloat64`` call each, straight from and into numpy rows.
"""

from __future__ import annotations

import ctypes
import dataclasses
import difflib
import json
import multiprocessing.util
import os
import shutil
import sys
import tempfile
import zipfile
import zlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from fmpy import extract, platform_tuple, read_model_description, sharedLibraryExtension
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Model, fmi3Float64, fmi3ValueReference
from fmpy.model_description import ModelDescription, ScalarVariable, ValidationError

from spindlebench.core import interrupts
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.files import check_input
from spindlebench.core.names import KELVIN_OFFSET
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.formats.recording import (
    AMBIENT_COLUMN,
    DRIFT_COLUMN,
    FEED_X_COLUMN,
    FEED_Y_COLUMN,
    MECHANISM_SWITCHES,
    SENSOR_OUTPUTS,
    SPEED_COLUMN,
    EndState,
    recorded_outputs,
)
from spindlebench.machines.variants import Machine
from spindlebench.testbench import fmu_archive, native_cvode
from spindlebench.testbench.drivers import INPUT_NAMES, DriverSignals, drive
from spindlebench.testbench.scenario import Scenario, step_count_problem

#: What a run that is not a cold start starts from, handed over by the caller: a previous
#: run's parsed end state (``continue``) or a soak history's end state in kelvin (``soak``).
Start = EndState | Mapping[str, float] | None

#: CVode's relative tolerance per input mode; absolute tolerance = nominal × this (K for
#: temperatures). Without the 1 s step cap the solver's own error control sets the accuracy,
#: so the continuous mode asks for 10× more (it still takes ~100× fewer steps); the hold keeps
#: the tolerance it always had.
RELATIVE_TOLERANCE = {"continuous": 1e-7, "hold": 1e-6}
#: Cooling settings of the scenario map onto these FMU parameters.
COOLING_PARAMETERS = ("cooling_enabled", "cooling_follows_ambient", "cooling_setpoint_C")


@dataclass(frozen=True)
class FmuInterface:
    """What the runner needs to know about an FMU, looked up once by name."""

    path: Path
    model_description: ModelDescription
    input_vrs: tuple[int, ...]
    output_names: tuple[str, ...]
    output_vrs: tuple[int, ...]
    state_names: tuple[str, ...]
    state_vrs: tuple[int, ...]
    parameters: Mapping[str, ScalarVariable] = field(repr=False)
    #: ``<ModelExchange canGetAndSetFMUState canSerializeFMUState>`` (FMPy's FMI 3 reader
    #: keeps neither flag, so they are read from the XML here)
    saves_states: bool = False
    #: The inputs by name (``INPUT_NAMES``), with the ``min``/``max`` the FMU declares.
    inputs: Mapping[str, ScalarVariable] = field(repr=False, default_factory=dict)


#: FMUs already read and checked in this process, by (resolved path, size, mtime): a sweep
#: simulates the same FMU thousands of times, and reading, CRC-checking and parsing it costs
#: ~23 ms each time. A rebuilt or replaced file has a new size or mtime and is read again.
_INSPECTED: dict[tuple[str, int, int], FmuInterface] = {}


def inspect_fmu(fmu_path: str | Path) -> FmuInterface:
    """Read an FMU's model description and check it offers the contract's interface (once
    per process and file version)."""
    fmu_path = Path(fmu_path)
    check_input(fmu_path, "FMU (.fmu)", max_bytes=None)
    if not fmu_path.is_file():
        hint = " (build it with `spindlebench build`)" if fmu_path == DEFAULT_FMU else ""
        raise SpindlebenchError(f"{fmu_path}: no such FMU{hint}")
    stat = fmu_path.stat()
    key = (str(fmu_path.resolve()), stat.st_size, stat.st_mtime_ns)
    if key not in _INSPECTED:
        if len(_INSPECTED) >= 16:
            _INSPECTED.clear()
        _INSPECTED[key] = _read_and_check(fmu_path)
    return dataclasses.replace(_INSPECTED[key], path=fmu_path)  # messages name the path given


def _read_and_check(fmu_path: Path) -> FmuInterface:
    try:  # names, encryption, compression and sizes, before a byte is decompressed
        with zipfile.ZipFile(fmu_path) as archive:
            unsafe = fmu_archive.member_problem(archive)
    except (zipfile.BadZipFile, OSError):
        unsafe = None  # not a zip, unreadable: said below
    if unsafe:
        raise SpindlebenchError(f"{fmu_path}: unsafe FMU: {unsafe}; not unpacked")
    damaged = _damaged_member(fmu_path)
    if damaged:
        raise SpindlebenchError(f"{fmu_path}: damaged FMU: {damaged} (rebuild it with "
                                "`spindlebench build` or copy it again)")
    try:
        md = read_model_description(str(fmu_path))
    except ValidationError as exc:
        first = str(exc).splitlines()[1:2] or [str(exc)]
        raise SpindlebenchError(f"{fmu_path}: invalid modelDescription.xml: "
                                f"{first[0].lstrip('- ')}") from None
    except Exception as exc:  # not a zip, no modelDescription.xml, bad XML
        raise SpindlebenchError(f"{fmu_path}: not a readable FMU: {exc}") from None
    if not md.fmiVersion.startswith("3.") or md.modelExchange is None:
        raise SpindlebenchError(f"{fmu_path}: need an FMI 3.0 model-exchange FMU, got FMI "
                                f"{md.fmiVersion}{'' if md.modelExchange else ' without ME'}")
    with zipfile.ZipFile(fmu_path) as archive:  # before anything is unpacked or loaded
        problem = fmu_archive.binary_problem(archive, md.modelExchange.modelIdentifier)
        if problem is None and str(md.generationTool or "").startswith("spindlebench"):
            problem = fmu_archive.token_problem(archive, md.guid,
                                                 md.modelExchange.modelIdentifier)
    if problem:
        raise SpindlebenchError(f"{fmu_path}: unsafe or mismatched FMU: {problem}")
    by_name = {v.name: v for v in md.modelVariables}
    inputs = []
    for name in INPUT_NAMES:
        var = by_name.get(name)
        if var is None or var.causality != "input" or var.type != "Float64":
            raise SpindlebenchError(f"{fmu_path}: no Float64 input {name!r}")
        inputs.append(var)
    outputs = [v for v in md.modelVariables if v.causality == "output" and v.type == "Float64"]
    names = {v.name for v in outputs}
    for required in (*SENSOR_OUTPUTS, DRIFT_COLUMN):
        if required not in names:
            raise SpindlebenchError(f"{fmu_path}: no output {required!r}")
    states = [d.variable.derivative for d in md.derivatives]
    parameters = {v.name: v for v in md.modelVariables
                  if v.causality == "parameter" and v.variability in ("fixed", "tunable")}
    return FmuInterface(
        path=fmu_path,
        model_description=md,
        input_vrs=tuple(v.valueReference for v in inputs),
        output_names=tuple(v.name for v in outputs),
        output_vrs=tuple(v.valueReference for v in outputs),
        state_names=tuple(v.name for v in states),
        state_vrs=tuple(v.valueReference for v in states),
        parameters=parameters,
        saves_states=_declares_saved_states(fmu_path),
        inputs={v.name: v for v in inputs},
    )


def _declares_saved_states(fmu_path: Path) -> bool:
    """Whether the FMU's ``<ModelExchange>`` can get, set and serialise its state."""
    import xml.etree.ElementTree as ET

    with zipfile.ZipFile(fmu_path) as archive:
        me = ET.fromstring(archive.read("modelDescription.xml")).find("ModelExchange")
    return me is not None and all(me.get(flag) == "true" for flag in
                                  ("canGetAndSetFMUState", "canSerializeFMUState"))


def _damaged_member(fmu_path: Path) -> str | None:
    """What is wrong with the FMU's zip container (None when every member checks out).

    Checked up front (CRC of every member, and a shared library must not be empty) so a
    damaged file is one line before anything runs, not a ``BadZipFile`` or "file too short"
    traceback from the middle of extracting or loading it.
    """
    try:
        with zipfile.ZipFile(fmu_path) as archive:
            for info in archive.infolist():
                if info.filename.startswith("binaries/") and not info.is_dir() \
                        and info.file_size == 0:
                    return f"member {info.filename} is empty (0 bytes)"
                try:
                    with archive.open(info) as member:
                        while member.read(1 << 20):
                            pass
                except (zipfile.BadZipFile, zlib.error, EOFError) as exc:
                    return f"member {info.filename} is corrupt ({exc})"
    except zipfile.BadZipFile:
        return None  # not a zip at all: reading its model description says so
    except OSError as exc:
        return f"cannot read the archive ({exc.strerror or exc})"
    return None


def extract_fmu(fmu: FmuInterface, prefix: str = "spindlebench-fmu-") -> Path:
    """Unzip the FMU into a new temporary folder; on any failure the folder is removed."""
    unzip_dir = Path(tempfile.mkdtemp(prefix=prefix))
    try:
        extract(str(fmu.path), unzipdir=str(unzip_dir))
    except (zipfile.BadZipFile, OSError, EOFError, zlib.error) as exc:
        shutil.rmtree(unzip_dir, ignore_errors=True)
        raise SpindlebenchError(f"{fmu.path}: cannot unpack the FMU: {exc}") from None
    except BaseException:
        shutil.rmtree(unzip_dir, ignore_errors=True)
        raise
    return unzip_dir


#: Folders this process unpacked FMUs into, by (process id, resolved path, size, mtime): a
#: sweep simulates one FMU thousands of times, and unzipping it costs ~20 ms (10 % of a 6 h
#: run) each time. The process id keeps a forked child from sharing its parent's folder.
_EXTRACTED: dict[tuple[int, str, int, int], Path] = {}
#: Name of a cached extraction: the owning process's id follows, so a process can tell the
#: folders of processes that died without cleaning up (a worker ended by SIGTERM).
_CACHE_PREFIX = "spindlebench-fmu-cache-"


def extracted_fmu(fmu: FmuInterface) -> Path:
    """The FMU unpacked once per process and file version, removed when the process exits.

    Safe under multiprocessing: each worker unpacks its own copy, and the clean-up is a
    ``multiprocessing.util.Finalize``, which runs at the exit of the main process (atexit)
    and of a worker process (which skips atexit), and never in another process than the one
    that registered it. Folders of processes killed before their clean-up are removed by
    the next process that unpacks.
    """
    stat = fmu.path.stat()
    key = (os.getpid(), str(fmu.path.resolve()), stat.st_size, stat.st_mtime_ns)
    folder = _EXTRACTED.get(key)
    if folder is not None and folder.is_dir():
        return folder
    if not _EXTRACTED:
        _remove_orphaned_extractions()
    folder = extract_fmu(fmu, prefix=f"{_CACHE_PREFIX}{os.getpid()}-")
    _EXTRACTED[key] = folder
    multiprocessing.util.Finalize(None, shutil.rmtree, args=(str(folder),),
                                  kwargs={"ignore_errors": True}, exitpriority=10)
    return folder


def forget_extracted(fmu: FmuInterface) -> None:
    """Remove this process's unpacked copy of ``fmu`` (it turned out unusable)."""
    for key in [k for k in _EXTRACTED if k[0] == os.getpid() and k[1] == str(fmu.path.resolve())]:
        folder = _EXTRACTED.pop(key)
        for loaded in [k for k in _LOADED if k[1] == str(folder)]:
            del _LOADED[loaded]
        shutil.rmtree(folder, ignore_errors=True)


#: FMU binaries loaded in this process, by (pid, unpacked folder, GUID): FMPy's FMU3Model
#: loads the library and binds its ~75 FMI functions (an ``inspect.signature`` each) on
#: construction, 4.4 ms of a 6 h run's ~105 ms; a run instantiates and frees its own
#: instance of the loaded model, so nothing of one run's instance reaches the next.
_LOADED: dict[tuple[int, str, str], FMU3Model] = {}


def _loaded_model(md: ModelDescription, unzip_dir: Path) -> FMU3Model:
    """The FMU's binary loaded once per process and unpacked folder (see ``_LOADED``)."""
    key = (os.getpid(), str(unzip_dir), md.guid)
    if key not in _LOADED:
        _LOADED[key] = FMU3Model(guid=md.guid, unzipDirectory=str(unzip_dir),
                                 modelIdentifier=md.modelExchange.modelIdentifier,
                                 instanceName="spindlebench")
    return _LOADED[key]


def _remove_orphaned_extractions() -> None:
    """Remove cached extractions whose process no longer exists."""
    for folder in Path(tempfile.gettempdir()).glob(f"{_CACHE_PREFIX}*"):
        pid = folder.name[len(_CACHE_PREFIX):].split("-", 1)[0]
        if pid.isdigit() and int(pid) != os.getpid() and not _process_exists(int(pid)):
            shutil.rmtree(folder, ignore_errors=True)


def _process_exists(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process: it exists
        return True
    return True


@dataclass(frozen=True)
class Simulation:
    """Noise-free result of a co-simulation, sampled at the scenario's interval."""

    time_s: np.ndarray
    outputs: Mapping[str, np.ndarray]  # FMU output name -> samples
    drivers: DriverSignals  # driver values at the sample times
    initial_state_K: Mapping[str, float]  # noqa: N815
    end_state_K: Mapping[str, float]  # noqa: N815
    parameters: Mapping[str, float]  # every parameter value the FMU was given
    solver: Mapping[str, Any]
    #: The FMU's serialised state at the end (``fmi3SerializeFMUState``), when asked for
    #: (``co_simulate(..., save_end_state=True)``): a soak's warm start for many runs.
    end_fmu_state: bytes | None = None


# --------------------------------------------------------------------------- set-up helpers


def declared_bounds(variable: ScalarVariable) -> tuple[float | None, float | None]:
    """The ``min`` and ``max`` the model description declares for a variable (None: none)."""
    def number(text: Any) -> float | None:
        return None if text is None else float(text)

    return number(variable.min), number(variable.max)


def bound_problem(variable: ScalarVariable, value: float) -> str | None:
    """Why ``value`` lies outside the FMU's declared ``min``/``max`` of ``variable`` (None
    when inside): the FMI way to keep a parameter physical (capacities > 0, conductances
    >= 0), declared once in the Modelica source and read here from the FMU."""
    low, high = declared_bounds(variable)
    if low is not None and not value >= low:
        return f"must be ≥ {low:g}, got {value:g}"
    if high is not None and not value <= high:
        return f"must be ≤ {high:g}, got {value:g}"
    return None


#: Sensor outputs outside this range (°C) mean the simulation left physics: a machine tool
#: does not reach 1000 °C nor fall below -100 °C.
PHYSICAL_RANGE_C = (-100.0, 1000.0)


def check_physical(simulation: Simulation, scenario: Scenario) -> None:
    """Refuse a simulation whose temperatures left the physical range, naming the scenario and
    the parameters it changed from the model's defaults (the likely cause)."""
    low, high = PHYSICAL_RANGE_C
    for name in SENSOR_OUTPUTS:
        values = np.asarray(simulation.outputs[name])
        outside = np.flatnonzero(~((values >= low) & (values <= high)))
        if outside.size:
            i = int(outside[0])
            changed = ", ".join(f"{k} = {v:g}" for k, v in scenario.parameters.items())
            likely = (f"; likely the parameters it changes: {changed}" if changed
                      else "; it changes no parameter (check the drivers and the FMU)")
            raise SpindlebenchError(
                f"{scenario.path}: the simulation diverged: {name} = {values[i]:g} °C at "
                f"t = {simulation.time_s[i]:g} s is outside {low:g}..{high:g} °C{likely}")


def check_parameter(name: str, value: float, known: Mapping[str, ScalarVariable],
                    fmu_name: str, source: str | Path) -> None:
    """One ``[parameters]`` entry of a machine or scenario file (``source``): a parameter of
    the FMU (``known``: name -> variable), within its declared bounds, and not a cooling
    setting (a scenario's ``[cooling]`` table sets those); one line naming file and key."""
    where = f"{source}: key 'parameters.{name}'"
    if name in COOLING_PARAMETERS:
        raise SpindlebenchError(f"{where}: a cooling setting; set it in a scenario's "
                                "[cooling] table (mode, setpoint_C)")
    if name not in known:
        near = difflib.get_close_matches(name, list(known), n=1)
        hint = f" (did you mean {near[0]!r}?)" if near else ""
        raise SpindlebenchError(f"{where}: the FMU {fmu_name} has no parameter {name!r}{hint}")
    problem = bound_problem(known[name], value)
    if problem:
        raise SpindlebenchError(f"{where}: {problem}")


def check_machine(machine: Machine, known: Mapping[str, ScalarVariable], fmu_name: str) -> None:
    """A machine file's parameters, each checked by ``check_parameter``. Studies call it at
    load time, so a bad machine fails before any worker simulates."""
    for name, value in machine.parameters.items():
        check_parameter(name, value, known, fmu_name, machine.path)


def parameter_values(scenario: Scenario, fmu: FmuInterface) -> dict[str, float]:
    """Scenario parameters and cooling settings as FMU parameter values; unknown names fail."""
    check_machine(scenario.machine, fmu.parameters, fmu.path.name)
    values: dict[str, float] = dict(scenario.machine.parameters)  # the scenario's on top
    for name, value in scenario.parameters.items():
        check_parameter(name, value, fmu.parameters, fmu.path.name, scenario.path)
        values[name] = value
    cooling = scenario.cooling
    wanted = {
        "cooling_enabled": 0.0 if cooling.mode == "off" else 1.0,
        "cooling_follows_ambient": 1.0 if cooling.mode == "follow_ambient" else 0.0,
        "cooling_setpoint_C": cooling.setpoint_C,
    }
    for name, value in wanted.items():
        if name in fmu.parameters:
            values[name] = value
        elif cooling.mode != "off":
            raise SpindlebenchError(f"{scenario.path}: key 'cooling.mode': the FMU "
                                    f"{fmu.path.name} has no parameter {name!r}")
    return values


#: A saved state temperature outside this range (K) is not a machine in a workshop (-73 to
#: 327 °C): a corrupted or foreign sidecar, or kelvin and celsius mixed up.
STATE_RANGE_K = (200.0, 600.0)


def initial_state(scenario: Scenario, fmu: FmuInterface, ambient0_C: float,
                  start: Start = None) -> dict[str, float]:
    """Initial value (K) of every state: a cold soak, or the start the caller hands over like
    every other start, never computed here: a soak history's end state (``start``, from
    ``testbench.soak.soak_state``) or a previous run's (``start``, parsed by
    ``scenario.start_state``). ``testbench.simulate.run_start`` picks the right one."""
    initial = scenario.initial
    if initial.kind == "cold":
        start_C = ambient0_C if initial.temperature_C is None else initial.temperature_C
        return dict.fromkeys(fmu.state_names, start_C + KELVIN_OFFSET)
    if initial.kind == "soak":
        if start is None or isinstance(start, EndState):
            raise SpindlebenchError(f"{scenario.path}: key 'initial.kind': a soak start is "
                                    "computed by the caller, not the runner: pass start="
                                    "soak_state(scenario, fmu) (testbench.simulate.record does)")
        return dict(start)
    if not isinstance(start, EndState):
        what = (f"the scenario {initial.from_scenario!r}" if initial.from_file is None
                else str(initial.from_file))
        raise SpindlebenchError(f"{scenario.path}: key 'initial.from': names {what}, a previous "
                                "run's end state, which the runner is given, not read: pass "
                                "start=start_state(scenario) (simulate_scenario() does)")
    return saved_state(start, fmu)


def saved_state(start: EndState, fmu: FmuInterface) -> dict[str, float]:
    """The end state a ``continue`` scenario starts from, checked name by name and value by value.

    The sidecar is user-reachable input (any file can be named), so everything about it that
    could break the run later is one line naming the scenario, the key and the sidecar.
    """
    where, source, saved = start.where, start.source, start.states_K
    missing = [n for n in fmu.state_names if n not in saved]
    extra = [n for n in saved if n not in fmu.state_names]
    if missing or extra:
        what = f"lacks state {missing[0]!r}" if missing else f"has unknown state {extra[0]!r}"
        raise SpindlebenchError(f"{where}: {source} {what} of {fmu.path.name} (saved from a "
                                "different model build?)")
    low, high = STATE_RANGE_K
    for name in fmu.state_names:
        value = saved[name]
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise SpindlebenchError(f"{where}: {source}: state {name!r} is not a number "
                                    f"(got {json.dumps(value)})")
        if not low <= value <= high:  # also catches NaN
            raise SpindlebenchError(f"{where}: {source}: state {name!r} = {value:g} K is "
                                    f"outside {low:g}-{high:g} K")
    return {name: float(saved[name]) for name in fmu.state_names}


#: The scenario table that sets each input (what a refusal names).
INPUT_KEYS = {SPEED_COLUMN: "speed", FEED_X_COLUMN: "feed", FEED_Y_COLUMN: "feed",
              AMBIENT_COLUMN: "ambient"}


def check_inputs(scenario: Scenario, fmu: FmuInterface, signals: DriverSignals) -> None:
    """Refuse driver values outside the FMU's declared ``min``/``max`` of each input.

    The FMU's model description is the one home of these limits (declared in the Modelica
    source): a scenario at 35 000 rpm against ``max = 30000`` ran to the end without a word
    (T1 at 65.8 °C in ten minutes), as the model's friction laws are not meant for it."""
    for name in INPUT_NAMES:
        variable = fmu.inputs.get(name)
        if variable is None:
            continue
        low, high = declared_bounds(variable)
        values = np.asarray(getattr(signals, name), dtype=float)
        outside = np.zeros(values.shape, dtype=bool)
        if low is not None:
            outside |= ~(values >= low)
        if high is not None:
            outside |= ~(values <= high)
        hits = np.flatnonzero(outside)
        if hits.size:
            i = int(hits[0])
            unit = f" {variable.unit}" if getattr(variable, "unit", None) else ""
            raise SpindlebenchError(
                f"{scenario.path}: key '{INPUT_KEYS[name]}': input {name} = {values[i]:g}{unit} "
                f"at t = {signals.time_s[i]:g} s is outside the range "
                f"{'-inf' if low is None else f'{low:g}'}..{'inf' if high is None else f'{high:g}'}"
                f"{unit} that {fmu.path.name} declares for it; change the scenario (or use an "
                "FMU built for it)")


def check_scenario(scenario: Scenario, fmu: FmuInterface, *,
                   start: EndState | None = None, signals: DriverSignals | None = None) -> None:
    """Everything about a scenario that needs the FMU, checked without simulating.

    A batch runs this for every scenario before the first simulation, so a bad parameter
    name or continue-from file in its last scenario writes nothing. ``start`` is the parsed
    end state a ``continue`` scenario starts from, checked against the FMU when given (an
    earlier run of the same batch may not have written it yet).
    """
    problem = step_count_problem(scenario.duration_s, scenario.step_s)
    if problem:
        raise SpindlebenchError(f"{scenario.path}: key 'step_s': {problem}")
    parameter_values(scenario, fmu)
    check_inputs(scenario, fmu, drive(scenario) if signals is None else signals)
    if scenario.initial.kind == "continue" and start is not None:
        saved_state(start, fmu)


def _row_pointer(matrix: np.ndarray, row: int) -> Any:
    """Pointer to one row of a C-contiguous float64 matrix, for FMI get/set calls."""
    address = matrix.ctypes.data + row * matrix.strides[0]
    return ctypes.cast(address, ctypes.POINTER(fmi3Float64))


def _progress_bar(total_s: float, enabled: bool, label: str) -> Any:
    if not enabled:
        return None
    from spindlebench.core.progress import tqdm_class

    return tqdm_class()(total=round(total_s), unit=" sim-s", desc=label, delay=2.0, file=sys.stderr,
                leave=False, dynamic_ncols=True)


# --------------------------------------------------------------------------- the loop


@interrupts.deferring  # Ctrl-C inside CVode's ctypes callbacks would be swallowed
def co_simulate(scenario: Scenario, fmu_path: str | Path | None = None, *,
                progress: bool = False, start: Start = None,
                start_fmu_state: bytes | None = None, save_end_state: bool = False,
                native_rhs: bool = True) -> Simulation:
    """Run a scenario through the FMU and return the noise-free sampled outputs.

    A ``continue`` scenario needs ``start``, the parsed end state of the run it continues
    (``scenario.start_state``), a ``soak`` scenario the soak's end state
    (``testbench.soak.soak_state``): the runner reads no recording files and runs no soak
    (``testbench.simulate.run_start`` picks either). With ``start_fmu_state`` as well (a
    serialised FMU state whose states are ``start``'s: the soak's, ``soak.soak_start``, or
    the continued run's), an FMU that saves states restores it (``fmi3SetFMUState``: one warm
    state forked into many runs) instead of setting ``start``'s temperatures by name; the
    bytes are the same (tests/testbench/test_fmu_cosim.py), and the check that the FMU starts from
    ``start`` still applies. ``save_end_state`` keeps the FMU's serialised end state in
    ``Simulation.end_fmu_state``.

    CVode calls the FMU's own C right-hand side when its binary exports one
    (``testbench.native_cvode``: the same bytes, no Python inside the solver); ``native_rhs =
    False``, or an FMU without it, runs FMPy's ``CVodeSolver`` with Python callbacks."""
    fmu_info = inspect_fmu(DEFAULT_FMU if fmu_path is None else fmu_path)
    md = fmu_info.model_description
    problem = step_count_problem(scenario.duration_s, scenario.step_s)
    if problem:  # before drive() makes arrays of that many steps
        raise SpindlebenchError(f"{scenario.path}: key 'step_s': {problem}")
    signals = drive(scenario)
    check_scenario(scenario, fmu_info, signals=signals)  # initial_state() checks the start
    inputs = np.ascontiguousarray(signals.matrix)
    jumps = signals.jumps()
    x0 = initial_state(scenario, fmu_info, float(signals.ambient_C[0]), start)
    warm = start_fmu_state if fmu_info.saves_states and start is not None else None
    params = parameter_values(scenario, fmu_info)

    n_steps, every = scenario.n_steps, scenario.steps_per_sample
    n_samples = n_steps // every + 1
    n_out = len(fmu_info.output_vrs)
    samples = np.empty((n_samples, n_out))

    unzip_dir = extracted_fmu(fmu_info)
    identifier = md.modelExchange.modelIdentifier
    binary = Path(unzip_dir, "binaries", platform_tuple, identifier + sharedLibraryExtension)
    if not binary.is_file():
        forget_extracted(fmu_info)
        raise SpindlebenchError(f"{fmu_info.path}: has no binary for {platform_tuple}; "
                                "rebuild it here with `spindlebench build`")
    try:
        fmu = _loaded_model(md, unzip_dir)
    except OSError as exc:  # a binary that does not load here
        forget_extracted(fmu_info)
        raise SpindlebenchError(f"{fmu_info.path}: cannot load its binary for {platform_tuple} "
                                f"({exc}); rebuild it here with `spindlebench build`") from None
    bar = _progress_bar(scenario.duration_s, progress, scenario.name)
    instantiated = False
    try:
        fmu.instantiate()
        instantiated = True
        if warm is not None:  # states, parameters and flags of the start; ours on top
            restore_state(fmu, warm)
        if params:
            names = list(params)
            fmu.setFloat64([fmu_info.parameters[n].valueReference for n in names],
                           [params[n] for n in names])
        if warm is None:
            fmu.setFloat64(list(fmu_info.state_vrs), [x0[n] for n in fmu_info.state_names])
        fmu.enterInitializationMode(startTime=0.0, stopTime=scenario.duration_s)
        fmu.setFloat64(list(fmu_info.input_vrs), inputs[0].tolist())
        fmu.exitInitializationMode()
        need_update = True
        while need_update:
            need_update, terminate, *_ = fmu.updateDiscreteStates()
            if terminate:
                raise SpindlebenchError(f"{fmu_info.path}: model asked to terminate at start")
        fmu.enterContinuousTimeMode()
        _check_initial_state(fmu, fmu_info, x0)
        stepper = _stepper(fmu, fmu_info, scenario, inputs, native_rhs)
        integrator = stepper.name
        try:
            stepper.outputs_at_start(samples[0])
            stops, segment_ends = solver_stops(jumps, every, n_steps, scenario.inputs)
            _integrate(stepper, fmu_info, scenario, stops, segment_ends, jumps, samples, bar)
        finally:
            stepper.free()
        end_values = fmu.getFloat64(list(fmu_info.state_vrs))
        switches = mechanism_switches(fmu, fmu_info)
        end_fmu_state = save_state(fmu) if save_end_state else None
        fmu.terminate()
    except (RuntimeError, FMICallException) as exc:  # CVode or the FMU gave up
        changed = ", ".join(f"{k} = {v:g}" for k, v in scenario.parameters.items())
        likely = f" (likely the parameters it changes: {changed})" if changed else ""
        raise SpindlebenchError(f"{fmu_info.path}: simulation failed in scenario "
                                f"{scenario.path}{likely}: {exc}") from None
    finally:
        if bar is not None:
            bar.close()
        if instantiated:  # the library stays loaded for the next run (``_loaded_model``)
            fmu.fmi3FreeInstance(fmu.component)

    recorded = set(recorded_outputs(fmu_info.output_names, probes=scenario.probes,
                                    switches=switches))
    sample_rows = np.arange(n_samples) * every
    sampled = DriverSignals(*(getattr(signals, f)[sample_rows]
                              for f in DriverSignals.__dataclass_fields__))
    return Simulation(
        time_s=sampled.time_s,
        outputs={name: samples[:, i] for i, name in enumerate(fmu_info.output_names)
                 if name in recorded},
        drivers=sampled,
        initial_state_K=x0,
        end_state_K=dict(zip(fmu_info.state_names, end_values, strict=True)),
        parameters=params,
        solver={
            "integrator": integrator,
            "relative_tolerance": RELATIVE_TOLERANCE[scenario.inputs],
            "communication_step_s": scenario.step_s,
            "inputs": scenario.inputs,
            "input_hold": INPUT_DESCRIPTIONS[scenario.inputs],
            "solver_stops": int(stops.size),
            "restarts_at_input_jumps": int(jumps.sum()),
            **({"start": "saved FMU state of " + ("the soak" if scenario.initial.kind == "soak"
                                                  else "the run it continues")
                            + " (fmi3SetFMUState)"} if warm else {}),
        },
        end_fmu_state=end_fmu_state,
    )


def mechanism_switches(fmu: Any, info: FmuInterface) -> dict[str, float]:
    """The values in this run of the parameters that switch issue 20's mechanisms on, read
    from the instance (so machine file, scenario, FMU default and a restored start all
    count), for ``recorded_outputs``."""
    names = sorted({name for name in MECHANISM_SWITCHES.values() if name in info.parameters})
    if not names:
        return {}
    values = fmu.getFloat64([info.parameters[name].valueReference for name in names])
    return dict(zip(names, (float(v) for v in values), strict=True))


def save_state(fmu: Any) -> bytes:
    """The instance's state, serialised (``fmi3GetFMUState`` + ``fmi3SerializeFMUState``)."""
    state = fmu.getFMUState()
    try:
        return bytes(fmu.serializeFMUState(state))
    finally:
        fmu.freeFMUState(state)


def restore_state(fmu: Any, data: bytes) -> None:
    """Restore a state saved by ``save_state`` (of the same FMU build) into ``fmu``."""
    state = fmu.deserializeFMUState(data)
    try:
        fmu.setFMUState(state)
    finally:
        fmu.freeFMUState(state)


#: What each ``Scenario.inputs`` mode does, for the recording's provenance.
INPUT_DESCRIPTIONS = {
    "continuous": "ambient evaluated at the solver's time in the right-hand side (linear "
                  "between communication points); speed and feed held between their jumps; "
                  "CVode stopped at output points and jumps only",
    "hold": "zero-order hold, set at the start of each communication step",
}
#: CVode's internal steps allowed per call (FMPy's default of 500 can be too few for a long
#: output interval right after a jump).
MAX_SOLVER_STEPS = 100_000


def solver_stops(jumps: np.ndarray, every: int, n_steps: int,
                 inputs: str) -> tuple[np.ndarray, np.ndarray]:
    """Communication points (step indices) where the loop stops CVode, and for each the end
    of its segment (the next input jump, or the end of the run), past which CVode may not
    step. ``hold`` stops at every point; ``continuous`` at output points and jumps only."""
    if inputs == "hold":
        stops = np.arange(1, n_steps + 1)
        return stops, stops
    stops = np.union1d(np.arange(every, n_steps + 1, every), np.flatnonzero(jumps[1:]) + 1)
    ends = np.append(np.flatnonzero(jumps[1:]) + 1, n_steps)
    return stops, ends[np.searchsorted(ends, stops, side="left")]


def _integrate(stepper: Any, info: FmuInterface, scenario: Scenario, stops: np.ndarray,
               segment_ends: np.ndarray, jumps: np.ndarray, samples: np.ndarray,
               bar: Any) -> None:
    """One solver segment per stop: a stop is an output point or an input jump (every
    communication point with inputs = "hold"); CVode never steps past the segment's end (the
    next jump). Between segments (between chunks of them in the FMU's C loop) Python runs, so
    a pending signal is seen."""
    if isinstance(stepper, _NativeStepper):
        stepper.integrate(stops, segment_ends, jumps, samples, bar)
        return
    step_s, every = scenario.step_s, scenario.steps_per_sample
    report_every = max(1, len(stops) // 200)
    for number, (k, end) in enumerate(zip(stops.tolist(), segment_ends.tolist(), strict=True)):
        t_next = k * step_s
        t = stepper.advance(t_next, end * step_s)
        interrupts.check()  # a Ctrl-C that arrived during the step ends the run here
        if abs(t - t_next) > 1e-9 * max(1.0, t_next):
            raise SpindlebenchError(f"{info.path}: CVode stopped at t={t:g} s "
                                    f"instead of {t_next:g} s")
        stepper.stop(t_next, k, samples[k // every] if k % every == 0 else None)
        if jumps[k]:
            stepper.reset(t_next)
        if bar is not None and (number + 1) % report_every == 0:
            bar.update(round(t_next) - bar.n)


#: CVode's Jacobian on the C path (``native_cvode.JACOBIANS``): its own difference quotients
#: on the C right-hand side ("cvode", the same bytes as FMPy's solver), the FMU's coloured
#: forward derivatives ("forward") or coloured difference quotients ("differences").
NATIVE_JACOBIAN = "cvode"
#: Stops per call of the FMU's C loop: Python runs between calls (a Ctrl-C is acted on, the
#: progress bar moves) about every millisecond of solver work.
NATIVE_CHUNK = 32


def _stepper(fmu: FMU3Model, info: FmuInterface, scenario: Scenario, inputs: np.ndarray,
             native_rhs: bool) -> Any:
    """CVode for this run: on the FMU's C callbacks where it has them, else FMPy's."""
    md = info.model_description
    if native_rhs and not md.modelExchange.needsCompletedIntegratorStep \
            and native_cvode.available(fmu, md.numberOfEventIndicators):
        return _NativeStepper(fmu, info, scenario, inputs)
    return _FmpyStepper(fmu, info, scenario, inputs)


class _NativeStepper:
    """CVode on the FMU's C right-hand side, its loop between output points in C
    (``testbench.native_cvode``)."""

    name = "SUNDIALS CVODE (BDF) of FMPy on the FMU's C right-hand side"

    def __init__(self, fmu: FMU3Model, info: FmuInterface, scenario: Scenario,
                 inputs: np.ndarray):
        self.info, self.scenario, self.inputs, self.fmu = info, scenario, inputs, fmu
        continuous = scenario.inputs == "continuous"
        ambient = INPUT_NAMES.index(AMBIENT_COLUMN)
        self.solver = native_cvode.NativeCVode(
            fmu, info.model_description.numberOfContinuousStates, start_time=0.0,
            relative_tolerance=RELATIVE_TOLERANCE[scenario.inputs],
            max_step=float("inf") if continuous else scenario.step_s,
            max_num_steps=MAX_SOLVER_STEPS,
            table=(info.input_vrs[ambient], inputs[:, ambient], scenario.step_s)
            if continuous else None, jacobian=NATIVE_JACOBIAN)

    def outputs_at_start(self, row: np.ndarray) -> None:
        row[:] = self.fmu.getFloat64(list(self.info.output_vrs))

    def integrate(self, stops: np.ndarray, segment_ends: np.ndarray, jumps: np.ndarray,
                  samples: np.ndarray, bar: Any) -> None:
        plan = native_cvode.Plan(stops, segment_ends, jumps, self.scenario.step_s,
                                 self.scenario.steps_per_sample, self.inputs, samples,
                                 input_vr_list=self.info.input_vrs,
                                 output_vr_list=self.info.output_vrs)
        step_s = self.scenario.step_s
        for first in range(0, stops.size, NATIVE_CHUNK):
            count = min(NATIVE_CHUNK, stops.size - first)
            try:
                self.solver.run(plan, first, count)
            finally:
                interrupts.check()  # a Ctrl-C that arrived in the C loop ends the run here
            if bar is not None:
                bar.update(round(int(stops[first + count - 1]) * step_s) - bar.n)

    def free(self) -> None:
        self.solver.free()


class _FmpyStepper:
    """FMPy's ``CVodeSolver`` with Python callbacks: for an FMU without the C callbacks."""

    name = "FMPy CVodeSolver (SUNDIALS CVODE, BDF)"

    def __init__(self, fmu: FMU3Model, info: FmuInterface, scenario: Scenario,
                 inputs: np.ndarray):
        from fmpy.sundials import CVodeSolver

        md = info.model_description
        self.fmu, self.info, self.inputs = fmu, info, inputs
        self.set_stop_time = _cvode_set_stop_time()
        self.n_in, self.n_out = len(info.input_vrs), len(info.output_vrs)
        self.input_vrs = (fmi3ValueReference * self.n_in)(*info.input_vrs)
        self.output_vrs = (fmi3ValueReference * self.n_out)(*info.output_vrs)
        # fixed ctypes buffers: a row is copied in/out with one memmove, no per-step objects
        self.u_buffer = (fmi3Float64 * self.n_in)()
        self.y_buffer = (fmi3Float64 * self.n_out)()
        self.y_view = np.ctypeslib.as_array(self.y_buffer)
        self.row_bytes, self.inputs_address = inputs.strides[0], inputs.ctypes.data
        self.completed_step = md.modelExchange.needsCompletedIntegratorStep
        step_s = scenario.step_s
        if scenario.inputs == "hold":
            hooks: Any = _HeldInputs(fmu, self.input_vrs, inputs, step_s)
            set_time, max_step = fmu.setTime, step_s
        else:
            hooks = _ContinuousInputs(fmu, info.input_vrs[INPUT_NAMES.index(AMBIENT_COLUMN)],
                                      inputs[:, INPUT_NAMES.index(AMBIENT_COLUMN)], step_s)
            set_time, max_step = hooks.set_time, float("inf")
        self.solver = CVodeSolver(
            nx=md.numberOfContinuousStates, nz=md.numberOfEventIndicators,
            get_x=fmu.getContinuousStates, set_x=fmu.setContinuousStates,
            get_dx=fmu.getContinuousStateDerivatives, get_z=fmu.getEventIndicators,
            get_nominals=fmu.getNominalsOfContinuousStates, set_time=set_time,
            input=hooks, startTime=0.0, maxStep=max_step,
            relativeTolerance=RELATIVE_TOLERANCE[scenario.inputs], maxNumSteps=MAX_SOLVER_STEPS,
        )
        self.t = 0.0

    def outputs_at_start(self, row: np.ndarray) -> None:
        self._outputs(row)

    def _outputs(self, row: np.ndarray) -> None:
        self.fmu.fmi3GetFloat64(self.fmu.component, self.output_vrs, self.n_out, self.y_buffer,
                                self.n_out)
        row[:] = self.y_view

    def advance(self, t_next: float, stop_time: float) -> float:
        self.set_stop_time(self.solver.cvode_mem, stop_time)
        _, _, t = self.solver.step(self.t, t_next)
        return t

    def stop(self, t: float, k: int, row: np.ndarray | None) -> None:
        fmu = self.fmu
        self.t = t
        fmu.setTime(t)
        ctypes.memmove(self.u_buffer, self.inputs_address + k * self.row_bytes, self.row_bytes)
        fmu.fmi3SetFloat64(fmu.component, self.input_vrs, self.n_in, self.u_buffer, self.n_in)
        if self.completed_step:
            _, terminate = fmu.completedIntegratorStep()
            if terminate:
                raise SpindlebenchError(f"{self.info.path}: model terminated at t={t:g} s")
        if row is not None:
            self._outputs(row)

    def reset(self, t: float) -> None:
        self.solver.reset(t)

    def free(self) -> None:
        """FMPy's solver frees its CVode memory when it is collected."""


def _cvode_set_stop_time() -> Any:
    """``CVodeSetStopTime`` from the SUNDIALS library FMPy ships (FMPy binds it only in a comment).

    A stop time makes CVode end each call exactly at the communication point instead of
    stepping past it and interpolating back, so the zero-order hold is exact.
    """
    from fmpy.sundials.libraries import sundials_cvode
    from fmpy.sundials.sundials_types import sunrealtype

    function = sundials_cvode.CVodeSetStopTime
    function.argtypes = [ctypes.c_void_p, sunrealtype]
    function.restype = ctypes.c_int
    return function


class _HeldInputs:
    """FMPy's solver ``input`` hook: applies the zero-order-held inputs valid at time ``t``.

    CVode calls it only for event indicators (root finding), which SpindleBench has none of,
    but it keeps the solver correct for an FMU build that does.
    """

    def __init__(self, fmu: FMU3Model, vrs: ctypes.Array, inputs: np.ndarray, step_s: float):
        self.fmu, self.vrs, self.inputs, self.step_s = fmu, vrs, inputs, step_s

    def apply(self, t: float, **_: Any) -> None:
        row = min(int(np.floor(t / self.step_s + 1e-9)), len(self.inputs) - 1)
        n = len(self.vrs)
        self.fmu.fmi3SetFloat64(self.fmu.component, self.vrs, n, _row_pointer(self.inputs, row),
                                n)


class _ContinuousInputs:
    """The ambient as a continuous-time input: set at the solver's time whenever CVode
    evaluates the right-hand side (FMPy's ``set_time`` hook) or the event indicators (its
    ``input`` hook), linearly interpolated between the communication points' values (the
    season curve is smooth; a measured series is already piecewise linear). Speed and feed
    are piecewise constant and set by the loop at their jumps."""

    def __init__(self, fmu: FMU3Model, ambient_vr: int, ambient_C: np.ndarray,
                 step_s: float):
        self.set_fmu_time, self.set_float = fmu.fmi3SetTime, fmu.fmi3SetFloat64
        self.component = fmu.component
        self.vr = (fmi3ValueReference * 1)(ambient_vr)
        self.value = (fmi3Float64 * 1)()
        self.ambient = ambient_C.tolist()  # at least 2 points: n_steps >= 1
        self.last = len(self.ambient) - 2  # the last interval's start
        self.rate = 1.0 / step_s
        self.varying = bool(np.any(ambient_C != ambient_C[0]))

    def set_time(self, t: float) -> None:
        self.set_fmu_time(self.component, t)
        if self.varying:
            x = t * self.rate
            k = min(int(x), self.last)
            a = self.ambient
            self.value[0] = a[k] + (x - k) * (a[k + 1] - a[k])
            self.set_float(self.component, self.vr, 1, self.value, 1)

    def apply(self, t: float, **_: Any) -> None:
        self.set_time(t)


def _check_initial_state(fmu: FMU3Model, info: FmuInterface, x0: Mapping[str, float]) -> None:
    """Make sure the FMU really starts from the state we set by name (order and values)."""
    n = info.model_description.numberOfContinuousStates
    x = (fmi3Float64 * n)()
    fmu.getContinuousStates(x, n)
    expected = np.array([x0[name] for name in info.state_names])
    if not np.allclose(np.array(x), expected, rtol=0.0, atol=1e-9):
        raise SpindlebenchError(f"{info.path}: the FMU ignored the initial state set by name "
                                "(state start values not applied)")
