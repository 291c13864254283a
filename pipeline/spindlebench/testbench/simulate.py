"""``spindlebench simulate``: scenario file(s) → recording(s) (CSV + JSON sidecar).

``simulate_scenario`` is the Python entry point (used by ``spindlebench demo`` too): it loads
and validates the scenario, co-simulates it with the FMU, applies the sensor model and writes
the recording atomically. Any problem surfaces as one ``SpindlebenchError`` line before
anything is written.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from spindlebench.errors import SpindlebenchError
from spindlebench.formats.recording import (
    DRIFT_COLUMN,
    SENSOR_OUTPUTS,
    recording_frame,
    sensor_of_output,
    write_recording,
)
from spindlebench.formats.recording import sidecar_record as recording_sidecar
from spindlebench.listflags import expand_folders
from spindlebench.machines import add_machine_argument
from spindlebench.paths import DEFAULT_FMU
from spindlebench.provenance import file_entry, provenance
from spindlebench.testbench.drivers import INPUT_NAMES
from spindlebench.testbench.runner import (
    Simulation,
    check_physical,
    check_scenario,
    co_simulate,
    inspect_fmu,
)
from spindlebench.testbench.scenario import (
    MeasuredAmbient,
    Scenario,
    load_scenario,
    resolve_initial,
    start_state,
    with_machine,
)
from spindlebench.testbench.sensors import measure, measure_probes
from spindlebench.testbench.soak import soak_provenance


def sidecar_record(scenario: Scenario, fmu_path: Path, seed: int,
                   simulation: Simulation) -> dict[str, Any]:
    """Provenance and end state of one simulated recording."""
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


def record(scenario: Scenario, fmu_path: str | Path | None = None, seed: int | None = None,
           progress: bool = False) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Co-simulate a loaded scenario and measure it: the recording frame and its sidecar.

    ``seed`` overrides the scenario's seed; ``fmu_path`` defaults to ``fmus/SpindleBench.fmu``.
    Nothing is written, so a study can keep recordings in memory.
    """
    fmu = Path(DEFAULT_FMU if fmu_path is None else fmu_path)
    seed = scenario.seed if seed is None else seed
    simulation = co_simulate(scenario, fmu, progress=progress, start=start_state(scenario))
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
    return frame, sidecar_record(scenario, fmu, seed, simulation)


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
    if name in simulation.parameters:
        return float(simulation.parameters[name])
    variable = inspect_fmu(fmu).parameters.get(name)
    if variable is None or variable.start is None:
        raise SpindlebenchError(f"{scenario.path}: key 'outputs.probes': the FMU {fmu} has no "
                                f"five-probe parameter {name!r} (rebuild it)")
    return float(variable.start)


def _columns(truth: Mapping[str, np.ndarray], names: tuple[str, ...]) -> np.ndarray:
    return np.column_stack([truth[name] for name in names])


# --------------------------------------------------------------------------- command line


def _scenario_files(arguments: list[str]) -> list[Path]:
    return expand_folders(arguments, ".toml", "scenario")


@dataclass(frozen=True)
class BatchPlan:
    """A validated batch: each scenario loaded once, and the order to run them in."""

    order: list[int]  # indices into the batch, each after the run it continues from
    scenarios: list[Scenario]  # loaded, with sibling references resolved to files
    state_from_batch: list[bool]  # whether a run's start state is written by an earlier run


def plan_batch(files: list[Path], targets: list[Path], machine: str | None = None) -> BatchPlan:
    """Validate a batch and order it so a run comes after the run it continues from.

    ``targets[i]`` is the CSV that ``files[i]`` will be written to. A scenario whose
    ``initial.from`` is the sidecar of another target (by sibling name or by path) runs after
    it; otherwise the given (alphabetical) order is kept. ``machine`` (``--machine``) replaces
    every scenario's machine. A reference that no run of the batch
    writes and that does not exist yet, or a circle of continuations, is one error line naming
    the file and key, before anything is simulated.
    """
    seen: dict[Path, int] = {}
    for i, target in enumerate(targets):
        key = target.resolve()
        if key in seen:
            raise SpindlebenchError(f"{files[i]}: writes {target} like {files[seen[key]]}; "
                                    "rename one of the two scenario files")
        seen[key] = i
    producers = {target.with_suffix(".json").resolve(): i for i, target in enumerate(targets)}
    scenarios = [resolve_initial(with_machine(load_scenario(path), machine), target.parent)
                 for path, target in zip(files, targets, strict=True)]
    after: list[int | None] = []
    for path, scenario in zip(files, scenarios, strict=True):
        source = scenario.initial.from_file
        if scenario.initial.kind != "continue" or source is None:
            after.append(None)
            continue
        producer = producers.get(source.resolve())
        if producer is None and not source.is_file():
            sibling = scenario.initial.from_scenario
            what = (f"no scenario {sibling!r} in this batch and no recording {source}"
                    if sibling is not None else f"no such file {source}")
            raise SpindlebenchError(f"{path}: key 'initial.from': {what} (simulate the "
                                    "previous run first, or together with this one)")
        after.append(producer)
    order: list[int] = []
    state: dict[int, str] = {}  # "open" while its chain is being followed, then "done"

    def visit(i: int, chain: list[int]) -> None:
        if state.get(i) == "done":
            return
        if state.get(i) == "open":
            loop = [*chain[chain.index(i):], i]
            names = " continues from ".join(files[j].stem for j in loop)
            raise SpindlebenchError(f"{files[i]}: key 'initial.from': circular continuation: "
                                    f"{names}")
        state[i] = "open"
        producer = after[i]
        if producer is not None:
            visit(producer, [*chain, i])
        state[i] = "done"
        order.append(i)

    for i in range(len(files)):
        visit(i, [])
    return BatchPlan(order=order, scenarios=scenarios,
                     state_from_batch=[producer is not None for producer in after])


def _output_targets(files: list[Path], out: Path) -> list[Path]:
    """The CSV each scenario is written to, or one error line about ``-o``.

    ``simulate SCENARIO.toml -o OUT.csv`` names the recording; any other ``-o`` is a folder
    that gets ``<scenario>.csv`` per scenario. A folder name with a suffix (``-o x.txt``) is
    taken for a mistyped file name unless that folder already exists.
    """
    suffix = out.suffix.lower()
    single = len(files) == 1 and suffix == ".csv"
    if not single and suffix == ".csv":
        raise SpindlebenchError(f"{out}: several scenarios need an output directory, not a "
                                ".csv file")
    if not single and (out.is_file() or (suffix and not out.is_dir())):
        raise SpindlebenchError(f"{out}: -o must be a .csv file (one scenario) or a directory "
                                f"(a name without a suffix), not a {suffix or 'plain'} file")
    targets = [out if single else out / f"{scenario.stem}.csv" for scenario in files]
    for target in targets:
        for path in (target, target.with_suffix(".json")):
            if path.is_dir():
                raise SpindlebenchError(f"{path}: is a directory; the recording needs it as "
                                        "a file name (choose another -o)")
    return targets


def check_batch(plan: BatchPlan, fmu_path: str | Path | None) -> None:
    """Check every scenario of a planned batch against the FMU before any is simulated.

    Parameter names, step count and continue-from sidecars are checked here, so a batch is
    all or nothing. A state that an earlier run of the batch writes can only be checked to
    come from the batch (``plan_batch`` did that).
    """
    fmu = inspect_fmu(DEFAULT_FMU if fmu_path is None else fmu_path)
    for i in plan.order:
        scenario = plan.scenarios[i]
        start = None if plan.state_from_batch[i] else start_state(scenario)
        check_scenario(scenario, fmu, start=start)


def run(args: argparse.Namespace) -> int:
    """Simulate every scenario given; one file → ``-o`` is the CSV, several → a directory."""
    if args.seed is not None and args.seed < 0:
        raise SpindlebenchError(f"--seed: must be >= 0, got {args.seed}")
    files = _scenario_files(args.scenarios)
    targets = _output_targets(files, Path(args.output))
    if args.plot:
        for target in targets:
            if target.with_suffix(".png").is_dir():
                raise SpindlebenchError(f"{target.with_suffix('.png')}: is a directory; "
                                        "--plot writes the figure there (choose another -o)")
    # validate all first: a typo in the last file should cost nothing
    plan = plan_batch(files, targets, args.machine)
    check_batch(plan, args.fmu)
    show_progress = not args.quiet and sys.stderr.isatty()
    for i in plan.order:
        frame, sidecar = record(plan.scenarios[i], args.fmu, args.seed, show_progress)
        written = write_recording(targets[i], frame, sidecar)
        extras = [written.with_suffix(".json").name]
        if args.plot:
            from spindlebench.testbench.overview import plot_recording  # matplotlib: only here

            frame.attrs["path"] = str(written)
            plot_recording(frame, written.with_suffix(".png"), files[i].stem)
            extras.append(written.with_suffix(".png").name)
        if not args.quiet:
            print(f"{files[i]} -> {written} (+ {', '.join(extras)})")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``simulate`` sub-command."""
    parser = subparsers.add_parser(
        "simulate",
        help="co-simulate scenario(s) with the FMU into recording(s)",
        description="Co-simulate scenario TOML files with the SpindleBench FMU and write "
        "recordings: a CSV (measured T1..T20, drift_um, drivers, noise-free truth) and a "
        "JSON sidecar with provenance and the end state.",
    )
    parser.add_argument("scenarios", nargs="+", metavar="SCENARIO",
                        help="scenario .toml file(s) or directories of them")
    parser.add_argument("-o", "--output", required=True, metavar="OUT",
                        help="output .csv for one scenario, else an output directory")
    parser.add_argument("--fmu", type=Path, default=None,
                        help=f"FMU to simulate (default: {DEFAULT_FMU.name} in fmus/)")
    parser.add_argument("--seed", type=int, default=None,
                        help="random seed of the sensor model (default: the scenario's)")
    add_machine_argument(parser, "machine variant for every scenario",
                         "each scenario's machine key, else 'default'")
    parser.add_argument("--plot", action="store_true",
                        help="also draw each recording (as `spindlebench plot`) into "
                        "<recording>.png beside it")
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no progress bar, no summary")
    parser.set_defaults(func=run)
