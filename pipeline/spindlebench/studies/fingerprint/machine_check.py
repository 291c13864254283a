"""Check a machine variant against its file's fingerprint targets.

The paper's five experiments (``scenarios/paper/exp*.toml``) are simulated noise-free with the
FMU and the machine's parameters (FMPy, CVode, a cold start through ``T_start``), the other runs
its targets name (``heating/room20_4000``, ``examples/realistic_day``: scenarios under
``scenarios/``) with the testbench's runner (its noise-free outputs, soak included), and the
fingerprint of each run (``spindlebench.studies.fingerprint.statistics``: sensors T1-T20,
error ``drift_um``) is compared with the machine's ``[[targets]]``. This is what the tests run
and what the numbers in ``docs/model.md`` come from::

    python -m spindlebench.studies.fingerprint.machine_check  # every shipped machine
    python -m spindlebench.studies.fingerprint.machine_check default --hours 6
    # no-load ambient sensitivity (um/K):
    python -m spindlebench.studies.fingerprint.machine_check --ambient-step
    # each issue-20 mechanism off alone:
    python -m spindlebench.studies.fingerprint.machine_check --mechanisms
    # bearing rises, column time constant:
    python -m spindlebench.studies.fingerprint.machine_check --levels
    # all of it for every machine, as the docs' model page reads it (make docs):
    python -m spindlebench.studies.fingerprint.machine_check --json results/docs/machines.json
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from spindlebench.core.names import KELVIN_OFFSET
from spindlebench.core.paths import DEFAULT_FMU, SCENARIOS_DIR
from spindlebench.formats.recording import (
    AMBIENT_COLUMN,
    DRIFT_COLUMN,
    SENSOR_OUTPUTS,
    TIME_COLUMN,
    node_output,
)
from spindlebench.machines.variants import (
    PAPER_RUNS,
    Machine,
    load_machine,
    machine_names,
    run_scenario_path,
    target_problems,
    target_runs,
)
from spindlebench.studies.fingerprint.statistics import KEYS, fingerprint
from spindlebench.testbench.drivers import INPUT_NAMES, drive
from spindlebench.testbench.scenario import load_scenario

PAPER_DIR = SCENARIOS_DIR / "paper"
SAMPLE_S = 60.0
ERROR = DRIFT_COLUMN


def simulate_run(machine: Machine, run: str, fmu_path: str | Path = DEFAULT_FMU,
                 hours: float | None = None) -> dict[str, np.ndarray]:
    """Noise-free outputs (``time_s``, ``T1_C`` … ``T20_C``, ``drift_um``) of one paper run."""
    from fmpy import simulate_fmu

    scenario = load_scenario(PAPER_DIR / f"{run}.toml")
    stop_s = scenario.duration_s if hours is None else min(hours * 3600.0, scenario.duration_s)
    grid = np.arange(0.0, stop_s + SAMPLE_S / 2, SAMPLE_S)
    signals = drive(scenario, grid)
    inputs = np.zeros(grid.size, dtype=[("time", float)] + [(n, float) for n in INPUT_NAMES])
    inputs["time"] = grid
    for name in INPUT_NAMES:
        inputs[name] = getattr(signals, name)
    start = {
        **machine.parameters,
        "T_start": float(signals.ambient_C[0]) + KELVIN_OFFSET,
        "cooling_enabled": 0.0 if scenario.cooling.mode == "off" else 1.0,
    }
    outputs = [*SENSOR_OUTPUTS, ERROR]
    result = simulate_fmu(str(fmu_path), start_values=start, input=inputs, stop_time=stop_s,
                          output_interval=SAMPLE_S, output=outputs, relative_tolerance=1e-6,
                          fmi_type="ModelExchange")  # CVode (FMPy would pick co-simulation)
    frame = {name: np.asarray(result[name], dtype=float) for name in outputs}
    frame[TIME_COLUMN] = np.asarray(result["time"], dtype=float)
    return frame


def simulate_scenario_run(machine: Machine, run: str, fmu_path: str | Path = DEFAULT_FMU,
                          extra: tuple[str, ...] = ()) -> dict[str, np.ndarray]:
    """Noise-free outputs of a non-paper run (a scenario under ``scenarios/``) on ``machine``,
    from the testbench's runner (so a soak or continued start is what ``simulate`` does): the
    sensors, the error and those of the ``extra`` outputs the FMU has."""
    from dataclasses import replace

    from spindlebench.testbench.runner import co_simulate
    from spindlebench.testbench.simulate import run_start

    scenario = replace(load_scenario(run_scenario_path(run)), machine=machine)
    simulation = co_simulate(scenario, fmu_path, start=run_start(scenario, Path(fmu_path)))
    names = [*SENSOR_OUTPUTS, ERROR, *(n for n in extra if n in simulation.outputs)]
    frame = {name: np.asarray(simulation.outputs[name], dtype=float) for name in names}
    frame[TIME_COLUMN] = np.asarray(simulation.time_s, dtype=float)
    return frame


def run_fingerprint(frame: Mapping[str, np.ndarray]) -> dict[str, float]:
    """The fingerprint of one simulated run."""
    temps = np.column_stack([frame[o] for o in SENSOR_OUTPUTS])
    return fingerprint(frame[TIME_COLUMN], temps, frame[ERROR])


def paper_fingerprints(machine: Machine, fmu_path: str | Path = DEFAULT_FMU,
                       runs: tuple[str, ...] = PAPER_RUNS,
                       hours: float | None = None) -> dict[str, dict[str, float]]:
    """Fingerprint of each paper run of ``machine`` (run name → statistics)."""
    return {run: run_fingerprint(simulate_run(machine, run, fmu_path, hours)) for run in runs}


def machine_fingerprints(machine: Machine, fmu_path: str | Path = DEFAULT_FMU,
                         hours: float | None = None) -> dict[str, dict[str, float]]:
    """Fingerprint of every run the machine's targets name (paper runs first, all five)."""
    runs = [run for run in target_runs(machine) if run not in PAPER_RUNS]
    stats = paper_fingerprints(machine, fmu_path, hours=hours)
    for run in runs:
        stats[run] = run_fingerprint(simulate_scenario_run(machine, run, fmu_path))
    return stats


STEP_K = 5.0
STEP_HOURS = (1.0, 3.0, 6.0, 12.0, 24.0, 48.0, 96.0)


def ambient_step_response(machine: Machine, fmu_path: str | Path = DEFAULT_FMU,
                          hours: tuple[float, ...] = STEP_HOURS) -> dict[float, float]:
    """Drift per kelvin (um/K) at ``hours`` after a 5 K ambient step of the idle machine.

    Spindle off, axes idle; the response is the difference of a run with the step and one
    without (the idle servo losses cancel; the model is linear at standstill), divided by the
    step. At long times it is the machine's uniform ambient sensitivity.
    """
    from fmpy import simulate_fmu

    stop_s = max(hours) * 3600.0
    drift = []
    for ambient_C in (20.0, 20.0 + STEP_K):
        start = {**machine.parameters, "T_start": 20.0 + KELVIN_OFFSET, AMBIENT_COLUMN: ambient_C}
        result = simulate_fmu(str(fmu_path), start_values=start, stop_time=stop_s,
                              output_interval=600.0, output=[ERROR], relative_tolerance=1e-8,
                              fmi_type="ModelExchange")
        drift.append(np.interp([h * 3600.0 for h in hours], result["time"], result[ERROR]))
    response = (drift[1] - drift[0]) / STEP_K
    return dict(zip(hours, (float(v) for v in response), strict=True))


#: Issue 20's mechanisms: the parameter values that switch each one off on a machine where it is
#: on (``MECHANISM_RUN`` says which heating run shows it), so its effect can be shown alone.
MECHANISMS: dict[str, dict[str, dict[str, float]]] = {
    "default": {
        "thermally induced preload": {"front_preload_N_per_K": 0.0},
        "air through the front bearing": {"G_bearing_air_ref": 0.0},
        "column heated by the headstock and motor": {"headstock_column_G": 5.0,
                                                     "motor_column_G": 0.0},
        "column time constant (earlier 12 m2, 1600 kg)": {"A_column": 12.0,
                                                          "column_C": 736000.0},
        "test mandrel in the loop": {"tool_L": 0.0},
    },
    "motor-spindle": {
        "rotor losses on the shaft": {"rotor_loss_fraction": 0.0},
        "chiller jacket": {"jacket_enabled": 0.0},
        "stator seated in the housing": {"stator_housing_G": 0.0, "motor_housing_G": 2.0},
        "thermally induced preload": {"front_preload_N_per_K": 0.0},
        "air through the front bearing": {"G_bearing_air_ref": 0.0},
    },
}
MECHANISM_RUN = {"default": "heating/room20_4000", "motor-spindle": "heating/room20_12000"}


def mechanism_fingerprints(name: str, fmu_path: str | Path = DEFAULT_FMU
                           ) -> dict[str, dict[str, float]]:
    """Fingerprint of machine ``name``'s heating run with everything on, then with each of its
    mechanisms off alone (row label → statistics)."""
    from dataclasses import replace

    machine = load_machine(name)
    run = MECHANISM_RUN[name]
    rows = {"all on": run_fingerprint(simulate_scenario_run(machine, run, fmu_path))}
    for mechanism, off in MECHANISMS[name].items():
        variant = replace(machine, parameters={**machine.parameters, **off})
        rows[f"{mechanism} off"] = run_fingerprint(simulate_scenario_run(variant, run, fmu_path))
    return rows


LEVEL_RUNS = ("heating/room20_2000", "heating/room20_4000", "heating/room20_8000",
              "heating/room20_12000")
#: FMU outputs of the issue-20 mechanisms whose course docs/model.md describes on the heating
#: runs (the thermally induced preload, the air through the front bearing, the column, the
#: motor spindle's jacket): ``heating_outputs`` keeps each one's peak, when, and end.
MECHANISM_OUTPUTS = ("front_preload_thermal_N", "Q_bearing_air_W", "column_growth_um",
                     "Q_jacket_W", "jacket_inlet_C", "jacket_outlet_C")


def heating_outputs(frame: Mapping[str, np.ndarray]) -> dict[str, dict[str, float]]:
    """The error's and each mechanism output's start, peak, the peak's time (h) and end value
    on one heating run (the outputs the FMU has)."""
    hours = np.asarray(frame[TIME_COLUMN]) / 3600.0
    out = {}
    for name in (ERROR, *MECHANISM_OUTPUTS):
        if name not in frame:
            continue
        values = np.asarray(frame[name], dtype=float)
        peak = int(np.argmax(values))
        out[name] = {"start": float(values[0]), "peak": float(values[peak]),
                     "peak_h": float(hours[peak]), "end": float(values[-1])}
    return out


def levels(machine: Machine, fmu_path: str | Path = DEFAULT_FMU) -> dict[str, float]:
    """Rises after the 8 h heating runs (K: T1 on the bearing cap, the front bearing rings) and
    the column's time constant to the room (h: t63 of its mean temperature after an idle 5 K
    ambient step)."""
    from dataclasses import replace

    from fmpy import simulate_fmu

    from spindlebench.studies.fingerprint.statistics import t63
    from spindlebench.testbench.runner import co_simulate
    from spindlebench.testbench.simulate import run_start

    out: dict[str, float] = {}
    for run in LEVEL_RUNS:
        scenario = replace(load_scenario(run_scenario_path(run)), machine=machine)
        outputs = co_simulate(scenario, fmu_path, start=run_start(scenario, Path(fmu_path))).outputs
        rpm = run.rsplit("_", 1)[1]
        for name, column in (("T1", SENSOR_OUTPUTS[0]), ("rings", node_output("front_bearing"))):
            values = np.asarray(outputs[column], dtype=float)
            out[f"{name} rise at {rpm} rpm (K)"] = float(values[-1] - values[0])
    columns = [node_output(f"column_{i}") for i in range(1, 13)]
    start = {**machine.parameters, "T_start": 20.0 + KELVIN_OFFSET, AMBIENT_COLUMN: 20.0 + STEP_K}
    result = simulate_fmu(str(fmu_path), start_values=start, stop_time=96 * 3600.0,
                          output_interval=120.0, output=columns, relative_tolerance=1e-8,
                          fmi_type="ModelExchange")
    mean = np.mean([np.asarray(result[c]) for c in columns], axis=0) - 20.0
    out["column time constant to the room (h)"] = t63(np.asarray(result["time"]), mean) / 3600.0
    return out


def table(fingerprints: Mapping[str, Mapping[str, float]]) -> str:
    """A Markdown table: one row per run plus the median of the paper runs."""
    lines = ["| run | " + " | ".join(KEYS) + " |", "|---|" + "---|" * len(KEYS)]
    paper = [stats for run, stats in fingerprints.items() if run in PAPER_RUNS]
    rows = {run: stats for run, stats in fingerprints.items() if run in PAPER_RUNS}
    if paper:
        rows["paper median"] = {k: float(np.median([r[k] for r in paper])) for k in KEYS}
    rows.update({run: stats for run, stats in fingerprints.items() if run not in PAPER_RUNS})
    for run, stats in rows.items():
        lines.append(f"| {run} | " + " | ".join(f"{stats[k]:.3f}" for k in KEYS) + " |")
    return "\n".join(lines)


def machine_record(machine: Machine, fmu_path: str | Path = DEFAULT_FMU,
                   fingerprints_only: bool = False) -> dict:
    """Everything the model page shows of one machine: its file (path, SHA-256, parameters),
    the fingerprint of every run its targets name, the targets met or not, and (unless
    ``fingerprints_only``) the idle ambient-step response, the levels and, for a machine with
    issue-20 mechanisms, each mechanism off alone."""
    stats = machine_fingerprints(machine, fmu_path)
    record: dict = {"file": machine.path.name, "sha256": machine.sha256,
                    "parameters": dict(machine.parameters), "fingerprints": stats,
                    "targets": [t.describe() for t in machine.targets],
                    "problems": list(target_problems(machine, stats))}
    if not fingerprints_only:
        record["ambient_step_um_per_K"] = {f"{h:g} h": v for h, v in
                                           ambient_step_response(machine, fmu_path).items()}
        record["levels"] = levels(machine, fmu_path)
        frames = {run: simulate_scenario_run(machine, run, fmu_path, MECHANISM_OUTPUTS)
                  for run in LEVEL_RUNS}
        record["heating_fingerprints"] = {run: run_fingerprint(f) for run, f in frames.items()}
        record["heating_outputs"] = {run: heating_outputs(f) for run, f in frames.items()}
        if machine.name in MECHANISMS and machine.path == load_machine(machine.name).path:
            record["mechanism_run"] = MECHANISM_RUN[machine.name]
            record["mechanisms"] = mechanism_fingerprints(machine.name, fmu_path)
    return record


def write_json(path: Path, names: list[str], fmu_path: Path = DEFAULT_FMU,
               fingerprints_only: bool = False) -> dict:
    """``machine_record`` of every machine named, with provenance (the FMU's and each machine
    file's SHA-256, the command), written atomically to ``path``."""
    from spindlebench.core import atomic, provenance

    machines = {}
    for name in names:
        machine = load_machine(name)
        machines[machine.name] = machine_record(machine, fmu_path, fingerprints_only)
    command = ["python", "-m", "spindlebench.studies.fingerprint.machine_check", *names,
               "--json", str(path)] + (["--fingerprints-only"] if fingerprints_only else [])
    document = {"machines": machines,
                "provenance": provenance.provenance(command=" ".join(command),
                                                    fmu=provenance.file_entry(Path(fmu_path)))}
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic.write_text(path, json.dumps(document, indent=2, allow_nan=False, default=float)
                      + "\n")
    return document


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m spindlebench.studies.fingerprint.machine_check",
        description=__doc__.splitlines()[0])
    parser.add_argument("machines", nargs="*", help="machine names or files (default: all)")
    parser.add_argument("--fmu", type=Path, default=DEFAULT_FMU)
    parser.add_argument("--hours", type=float, default=None,
                        help="simulate only the first HOURS of each run (default: all 6 h)")
    parser.add_argument("--ambient-step", action="store_true",
                        help="print the no-load response to a 5 K ambient step (um/K) instead")
    parser.add_argument("--mechanisms", action="store_true",
                        help="print each issue-20 mechanism's effect on its heating run")
    parser.add_argument("--levels", action="store_true",
                        help="print bearing rises of the heating runs and the column's "
                        "time constant to the room")
    parser.add_argument("--json", type=Path, metavar="OUT.json", default=None,
                        help="write fingerprints, targets, ambient step, levels, the "
                        "heating runs' outputs and mechanisms of every machine named to "
                        "OUT.json (the model page's source) instead of printing")
    parser.add_argument("--fingerprints-only", action="store_true",
                        help="with --json: only the fingerprints and targets (seconds)")
    args = parser.parse_args(argv)
    failed = False
    if args.json is not None:
        names = args.machines or machine_names()
        document = write_json(args.json, names, args.fmu, args.fingerprints_only)
        print(f"wrote {args.json}")
        return 1 if any(m["problems"] for m in document["machines"].values()) else 0
    if args.mechanisms:
        for name in args.machines or list(MECHANISMS):
            print(f"## {name}, {MECHANISM_RUN[name]}\n")
            print(table(mechanism_fingerprints(name, args.fmu)) + "\n")
        return 0
    for name in args.machines or machine_names():
        machine = load_machine(name)
        if args.levels:
            print(f"{machine.name}: " + ", ".join(
                f"{key} {value:.1f}" for key, value in levels(machine, args.fmu).items()))
            continue
        if args.ambient_step:
            response = ambient_step_response(machine, args.fmu)
            print(f"{machine.name}: drift per K after an idle ambient step: " + ", ".join(
                f"{h:g} h {v:+.2f}" for h, v in response.items()))
            continue
        stats = machine_fingerprints(machine, args.fmu, hours=args.hours)
        print(f"## {machine.name} ({machine.path.name}, sha256 {machine.sha256[:12]})\n")
        print(table(stats) + "\n")
        problems = target_problems(machine, stats)
        for target in machine.targets:
            print(f"- target {target.describe()}")
        print("\n" + ("\n".join(f"NOT MET: {p}" for p in problems) or "all targets met") + "\n")
        failed |= bool(problems)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
