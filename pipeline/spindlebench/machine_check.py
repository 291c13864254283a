"""Check a machine variant against its file's fingerprint targets.

The paper's five experiments (``scenarios/paper/exp*.toml``) are simulated noise-free with the
FMU and the machine's parameters (FMPy, CVode, a cold start through ``T_start``), and the
fingerprint of each run (``spindlebench.fingerprint``: sensors T1-T20, error ``drift_um``) is
compared with the machine's ``[[targets]]``. This is what the tests run and what the numbers in
``docs/model.md`` come from::

    python -m spindlebench.machine_check                 # every shipped machine
    python -m spindlebench.machine_check default --hours 6
    python -m spindlebench.machine_check --ambient-step  # no-load ambient sensitivity (um/K)
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from spindlebench.fingerprint import KEYS, fingerprint
from spindlebench.machines import (
    PAPER_RUNS,
    Machine,
    load_machine,
    machine_names,
    target_problems,
)
from spindlebench.names import KELVIN_OFFSET, SENSORS
from spindlebench.paths import DEFAULT_FMU, SCENARIOS_DIR
from spindlebench.testbench.drivers import INPUT_NAMES, drive
from spindlebench.testbench.scenario import load_scenario

PAPER_DIR = SCENARIOS_DIR / "paper"
SAMPLE_S = 60.0
ERROR = "drift_um"


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
    outputs = [f"{s}_C" for s in SENSORS] + [ERROR]
    result = simulate_fmu(str(fmu_path), start_values=start, input=inputs, stop_time=stop_s,
                          output_interval=SAMPLE_S, output=outputs, relative_tolerance=1e-6)
    frame = {name: np.asarray(result[name], dtype=float) for name in outputs}
    frame["time_s"] = np.asarray(result["time"], dtype=float)
    return frame


def run_fingerprint(frame: Mapping[str, np.ndarray]) -> dict[str, float]:
    """The fingerprint of one simulated run."""
    temps = np.column_stack([frame[f"{s}_C"] for s in SENSORS])
    return fingerprint(frame["time_s"], temps, frame[ERROR])


def paper_fingerprints(machine: Machine, fmu_path: str | Path = DEFAULT_FMU,
                       runs: tuple[str, ...] = PAPER_RUNS,
                       hours: float | None = None) -> dict[str, dict[str, float]]:
    """Fingerprint of each paper run of ``machine`` (run name → statistics)."""
    return {run: run_fingerprint(simulate_run(machine, run, fmu_path, hours)) for run in runs}


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
        start = {**machine.parameters, "T_start": 20.0 + KELVIN_OFFSET, "ambient_C": ambient_C}
        result = simulate_fmu(str(fmu_path), start_values=start, stop_time=stop_s,
                              output_interval=600.0, output=[ERROR], relative_tolerance=1e-8)
        drift.append(np.interp([h * 3600.0 for h in hours], result["time"], result[ERROR]))
    response = (drift[1] - drift[0]) / STEP_K
    return dict(zip(hours, (float(v) for v in response), strict=True))


def table(fingerprints: Mapping[str, Mapping[str, float]]) -> str:
    """A Markdown table: one row per run plus the median."""
    lines = ["| run | " + " | ".join(KEYS) + " |", "|---|" + "---|" * len(KEYS)]
    rows = dict(fingerprints)
    rows["median"] = {k: float(np.median([r[k] for r in fingerprints.values()])) for k in KEYS}
    for run, stats in rows.items():
        lines.append(f"| {run} | " + " | ".join(f"{stats[k]:.3f}" for k in KEYS) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m spindlebench.machine_check",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("machines", nargs="*", help="machine names or files (default: all)")
    parser.add_argument("--fmu", type=Path, default=DEFAULT_FMU)
    parser.add_argument("--hours", type=float, default=None,
                        help="simulate only the first HOURS of each run (default: all 6 h)")
    parser.add_argument("--ambient-step", action="store_true",
                        help="print the no-load response to a 5 K ambient step (um/K) instead")
    args = parser.parse_args(argv)
    failed = False
    for name in args.machines or machine_names():
        machine = load_machine(name)
        if args.ambient_step:
            response = ambient_step_response(machine, args.fmu)
            print(f"{machine.name}: drift per K after an idle ambient step: " + ", ".join(
                f"{h:g} h {v:+.2f}" for h, v in response.items()))
            continue
        stats = paper_fingerprints(machine, args.fmu, hours=args.hours)
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
