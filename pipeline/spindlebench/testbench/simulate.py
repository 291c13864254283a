"""Scenario → recording (frame + JSON sidecar), the library half of ``spindlebench simulate``.

``simulate_scenario`` is the Python entry point (``commands.simulate`` and the demo use it and
``record``; ``testbench.batch`` plans several): it loads
and validates the scenario, co-simulates it with the FMU, applies the sensor model and writes
the recording atomically. Any problem surfaces as one ``SpindlebenchError`` line before
anything is written.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.formats.recording import (
    DRIFT_COLUMN,
    SENSOR_OUTPUTS,
    EndState,
    recording_frame,
    sensor_of_output,
    write_recording,
)
from spindlebench.formats.recording import sidecar_record as recording_sidecar
from spindlebench.testbench.drivers import INPUT_NAMES
from spindlebench.testbench.runner import Simulation, check_physical, co_simulate, inspect_fmu
from spindlebench.testbench.scenario import (
    MeasuredAmbient,
    Scenario,
    load_scenario,
    resolve_initial,
    start_state,
)
from spindlebench.testbench.sensors import measure, measure_probes
from spindlebench.testbench.soak import soak_provenance, soak_start, soak_state


def simulation_sidecar(scenario: Scenario, fmu_path: Path, seed: int,
                   simulation: Simulation) -> dict[str, Any]:
    """The sidecar of one simulated recording: its provenance (scenario, machine, FMU, seed,
    start) around ``formats.recording.sidecar_record``, which owns the sidecar's layout."""
    extra: dict[str, Any] = {}
    if isinstance(scenario.ambient, MeasuredAmbient):
        extra["ambient_file"] = file_entry(scenario.ambient.file)
    if scenario.initial.kind == "continue":
        extra["initial_state_from"] = file_entry(scenario.initial.from_file)
    if scenario.initial.kind == "soak":
        extra["initial_state_soak"] = soak_provenance(scenario, fmu_path)
    return recording_sidecar(
        provenance=provenance(
            kind="spindlebench synthetic recording",
            scenario=file_entry(scenario.path),
            machine=scenario.machine.provenance(),
            fmu=file_entry(fmu_path),
            seed=seed,
            **extra,
            scenario_parsed=scenario.to_dict(),
            parameters=dict(simulation.parameters),
            solver=dict(simulation.solver),
        ),
        initial_state_K=simulation.initial_state_K,
        end_time_s=scenario.duration_s,
        end_state_K=simulation.end_state_K,
    )


def run_start(scenario: Scenario, fmu_path: Path) -> EndState | dict[str, float] | None:
    """What the runner starts from, handed to it (it reads no files and computes no soak): the
    soak history's end state for ``initial.kind = "soak"``, the recording's end state it
    continues for ``"continue"``, else None (a cold start, made by the runner)."""
    if scenario.initial.kind == "soak":
        return soak_state(scenario, fmu_path)
    return start_state(scenario)


def run_start_with_state(scenario: Scenario, fmu_path: Path,
                         ) -> tuple[EndState | dict[str, float] | None, bytes | None]:
    """``run_start``, plus for a soak the FMU's saved state at the soak's end when the FMU
    saves states (``soak.soak_start``): the runner restores it into the run, one warm state
    forked into every run of the same soak, with the same bytes as the temperatures set by
    name."""
    if scenario.initial.kind == "soak" and inspect_fmu(fmu_path).saves_states:
        return soak_start(scenario, fmu_path)
    return run_start(scenario, fmu_path), None


def record(scenario: Scenario, fmu_path: str | Path | None = None, seed: int | None = None,
           progress: bool = False) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Co-simulate a loaded scenario and measure it: the recording frame and its sidecar.

    ``seed`` overrides the scenario's seed; ``fmu_path`` defaults to ``fmus/SpindleBench.fmu``.
    Nothing is written, so a study can keep recordings in memory.
    """
    frame, sidecar, _ = record_run(scenario, fmu_path, seed, progress)
    return frame, sidecar


def record_run(scenario: Scenario, fmu_path: str | Path | None = None,
               seed: int | None = None, progress: bool = False, *,
               start_fmu_state: bytes | None = None, save_end_state: bool = False,
               ) -> tuple[pd.DataFrame, dict[str, Any], bytes | None]:
    """``record``, plus the saved FMU states a batch hands from a run to the one continuing
    it: ``start_fmu_state`` (the end state of the run a ``continue`` scenario continues,
    restored instead of its end temperatures set by name: the same bytes) and, with
    ``save_end_state``, this run's serialised end state (else None)."""
    fmu = Path(DEFAULT_FMU if fmu_path is None else fmu_path)
    seed = scenario.seed if seed is None else seed
    start, warm = run_start_with_state(scenario, fmu)
    if scenario.initial.kind == "continue" and start_fmu_state is not None:
        warm = start_fmu_state
    simulation = co_simulate(scenario, fmu, progress=progress, start=start,
                             start_fmu_state=warm, save_end_state=save_end_state)
    check_physical(simulation, scenario)
    truth = simulation.outputs
    measured_C, measured_drift = measure(
        scenario.sensors,
        simulation.time_s,
        _columns(truth, SENSOR_OUTPUTS),
        truth[DRIFT_COLUMN],
        tuple(sensor_of_output(name) for name in SENSOR_OUTPUTS),
        seed,
    )
    drivers = {name: getattr(simulation.drivers, name) for name in INPUT_NAMES}
    probes = None
    if scenario.probes:
        probes = measure_probes(scenario.sensors, simulation.time_s, truth,
                                _parameter(simulation, fmu, scenario, "probe_l"),
                                _parameter(simulation, fmu, scenario, "probe_end_offset"),
                                measured_drift, seed)
    frame = recording_frame(simulation.time_s, measured_C, measured_drift, drivers, truth,
                            probes)
    sidecar = simulation_sidecar(scenario, fmu, seed, simulation)
    return frame, sidecar, simulation.end_fmu_state


def simulate_scenario(scenario_path: str | Path, out_csv: str | Path,
                      fmu_path: str | Path | None = None, seed: int | None = None,
                      progress: bool = False) -> Path:
    """Simulate one scenario file into ``out_csv`` (+ ``.json`` sidecar); return the CSV path.

    ``seed`` overrides the scenario's seed; ``fmu_path`` defaults to ``fmus/SpindleBench.fmu``.
    A scenario that continues from a sibling (``initial.from = "day1_warmup"``) starts from
    that scenario's recording next to ``out_csv``.
    """
    out_csv = Path(out_csv)
    if out_csv.suffix.lower() != ".csv":
        raise SpindlebenchError(f"{out_csv}: output must be a .csv file")
    scenario = resolve_initial(load_scenario(scenario_path), out_csv.parent)
    frame, sidecar = record(scenario, fmu_path, seed, progress)
    return write_recording(out_csv, frame, sidecar)


def _parameter(simulation: Simulation, fmu: Path, scenario: Scenario, name: str) -> float:
    """A parameter's value in a run: the one given, else the FMU's default."""
    return run_parameter(simulation.parameters, fmu, name, scenario.path)


def run_parameter(parameters: Mapping[str, Any], fmu: Path, name: str, where: Any) -> float:
    """A parameter's value in a run whose set parameters are ``parameters`` (a sidecar's
    ``parameters``): the one given, else the FMU's default (``where`` names the file that
    asked for it in the error)."""
    if name in parameters:
        return float(parameters[name])
    variable = inspect_fmu(fmu).parameters.get(name)
    if variable is None or variable.start is None:
        raise SpindlebenchError(f"{where}: key 'outputs.probes': the FMU {fmu} has no "
                                f"five-probe parameter {name!r} (rebuild it)")
    return float(variable.start)


def _columns(truth: Mapping[str, np.ndarray], names: tuple[str, ...]) -> np.ndarray:
    return np.column_stack([truth[name] for name in names])


