"""The FMI Cross-Check layout for the FMU: ``spindlebench build --cross-check DIR``.

Writes, for both interfaces of the FMU (``me`` and ``cs``), the folder the FMI Cross-Check
rules ask of an exporting tool::

    DIR/fmus/3.0/{me,cs}/<platform>/spindlebench/<version>/SpindleBench/
        SpindleBench.fmu  SpindleBench_in.csv  SpindleBench_ref.csv  SpindleBench_ref.opt
        ReadMe.md  provenance.json

The experiment is the paper's experiment 1 (``scenarios/paper/exp1.toml``: 4 000 rpm, both
axes at 1 500 mm/min, the January ambient rising from 5.3 to 10.4 °C over 6 h) as inputs
(``_in.csv``, every 60 s, interpolated linearly by the importer as the rules say). A
cross-check importer sets no start values, so the machine starts where the FMU's defaults put
it: every node at 20 °C (``T_start``'s default; the paper's run starts cold at the 5.3 °C air,
which needs a start value). The reference (``_ref.csv``: drift and the 20 sensors every
60 s) is FMPy's CVode on model exchange at a relative tolerance of 1e-10, started so;
FMPy's cross-check validator (``fmpy.cross_check.validate_vendor_repo.validate_test_fmu``)
checks the folders in the tests, which also simulate the ``cs`` folder through FMPy's
co-simulation loop and compare it with the reference (``fmpy.cross_check.validate_result``).
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np

from spindlebench.core import atomic
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import FMU_NAME
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.formats.recording import DRIFT_COLUMN

#: Exporting tool name and version in the layout (the package's).
TOOL = "spindlebench"
INPUT_INTERVAL_S = 60.0
OUTPUT_INTERVAL_S = 60.0
#: CVode's tolerance for the reference: at 1e-8 FMPy's CVode is still 6.0e-3 K off its own
#: 1e-10 solution on this experiment (T10_C; bench/bench_cosim.py, docs/fmu.md).
REFERENCE_RTOL = 1e-10
#: Options of the reference: the importer's communication step and tolerance.
STEP_SIZE_S = 1.0
REL_TOL = 1e-6
REFERENCE_OUTPUTS = (DRIFT_COLUMN, *(f"T{i}_C" for i in range(1, 21)))


def _version() -> str:
    from importlib import metadata

    try:
        return metadata.version("spindlebench")
    except metadata.PackageNotFoundError:
        return "0.0.0"


def experiment_inputs(scenario_path: Path) -> tuple[np.ndarray, float]:
    """The scenario's inputs every ``INPUT_INTERVAL_S`` as a structured array, and its end."""
    from spindlebench.testbench.drivers import INPUT_NAMES, drive
    from spindlebench.testbench.scenario import load_scenario

    scenario = load_scenario(scenario_path)
    every = round(INPUT_INTERVAL_S / scenario.step_s)
    signals = drive(scenario)
    rows = np.arange(0, len(signals.time_s), every)
    table = np.zeros(len(rows), dtype=[("time", float)] + [(n, float) for n in INPUT_NAMES])
    table["time"] = signals.time_s[rows]
    for name in INPUT_NAMES:
        table[name] = getattr(signals, name)[rows]
    return table, scenario.duration_s


def reference(fmu_path: Path, inputs: np.ndarray, stop_s: float) -> np.ndarray:
    """FMPy CVode on model exchange from the FMU's default start values, tight tolerance,
    stopped at every communication point (``STEP_SIZE_S``), kept every ``OUTPUT_INTERVAL_S``."""
    from fmpy import simulate_fmu

    result = simulate_fmu(str(fmu_path), fmi_type="ModelExchange", stop_time=stop_s,
                          input=inputs, output_interval=STEP_SIZE_S,
                          relative_tolerance=REFERENCE_RTOL, output=list(REFERENCE_OUTPUTS))
    every = round(OUTPUT_INTERVAL_S / STEP_SIZE_S)
    return result[::every]


def _csv_text(table: np.ndarray) -> str:
    """The cross-check CSV: quoted names, shortest round-trip numbers."""
    names = table.dtype.names
    lines = [",".join(f'"{n}"' for n in names)]
    lines += [",".join(repr(float(row[n])) for n in names) for row in table]
    return "\n".join(lines) + "\n"


def write_cross_check(fmu_path: str | Path, out_dir: str | Path,
                      scenario_path: str | Path) -> list[Path]:
    """Write the cross-check folders for ``fmu_path`` under ``out_dir``; return them."""
    from fmpy import platform_tuple, read_model_description

    fmu_path, out_dir = Path(fmu_path), Path(out_dir)
    md = read_model_description(str(fmu_path))
    kinds = [k for k, present in (("me", md.modelExchange), ("cs", md.coSimulation)) if present]
    if not kinds:
        raise SpindlebenchError(f"{fmu_path}: neither model exchange nor co-simulation")
    inputs, stop_s = experiment_inputs(Path(scenario_path))
    ref = reference(fmu_path, inputs, stop_s)
    table = np.zeros(len(ref), dtype=[("time", float)] + [(n, float) for n in REFERENCE_OUTPUTS])
    for name in table.dtype.names:
        table[name] = ref[name]
    options = (f"StartTime,0.0\nStopTime,{stop_s!r}\nStepSize,{STEP_SIZE_S!r}\n"
               f"RelTol,{REL_TOL!r}\n")
    readme = (f"# {FMU_NAME}\n\nThermal network of a vertical machining centre (spindlebench). "
              "Experiment: inputs of Xu et al. (2023) experiment 1 (4000 rpm, feeds 1500 mm/min, "
              "ambient 5.3-10.4 degC over 6 h) from the FMU's default start (every node at "
              f"20 degC). Reference: FMPy CVode, model exchange, rtol {REFERENCE_RTOL:g}, "
              f"outputs every {OUTPUT_INTERVAL_S:g} s.\n")
    written = []
    for kind in kinds:
        folder = out_dir / "fmus" / md.fmiVersion / kind / platform_tuple / TOOL / _version() \
            / FMU_NAME
        folder.mkdir(parents=True, exist_ok=True)
        with atomic.atomic_path(folder / f"{FMU_NAME}.fmu") as tmp:
            shutil.copyfile(fmu_path, tmp)
        atomic.write_text(folder / f"{FMU_NAME}_in.csv", _csv_text(inputs))
        atomic.write_text(folder / f"{FMU_NAME}_ref.csv", _csv_text(table))
        atomic.write_text(folder / f"{FMU_NAME}_ref.opt", options)
        atomic.write_text(folder / "ReadMe.md", readme)
        record = provenance(command="spindlebench build --cross-check", fmu=file_entry(fmu_path),
                            scenario=file_entry(scenario_path), interface=kind,
                            reference=f"FMPy CVode, model exchange, rtol {REFERENCE_RTOL:g}")
        atomic.write_text(folder / "provenance.json", json.dumps(record, indent=1) + "\n")
        written.append(folder)
    return written
