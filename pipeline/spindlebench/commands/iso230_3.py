"""``spindlebench iso230-3 TEST``: run an ISO 230-3 thermal test on a machine variant (or
evaluate a real recording through a map) and write the report: figure, JSON, CSV.

``TEST`` is ``etve``, ``spindle``, ``spectrum`` or ``axis`` (``scenarios/iso230-3/``). With
``--machine NAME`` the test's scenario is simulated on that machine (the axis test once per
target of ``AXIS_TARGETS_M``); with ``--recording R.csv --map MAP.toml`` a recording is read
instead (``channels`` describes the map). Outputs in ``-o DIR`` (default
``iso230-3_<test>``): ``<test>.png``, ``<test>.json`` (numbers and provenance),
``<test>_series.csv`` (the series the figure shows) and, for a simulation, the recording(s).

With ``--compensate PROVENANCE.json [--model NAME]`` a model trained by ``spindlebench
compensate`` predicts the Z drift from the test's temperatures and the residual is reported
beside it (``iso230_3.compensation``).
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from spindlebench.core import atomic
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import DEFAULT_FMU, SCENARIOS_DIR
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.formats.recording import SPEED_COLUMN, read_recording, write_recording
from spindlebench.formats.table_csv import write_table
from spindlebench.machines.variants import add_machine_argument
from spindlebench.studies.iso230_3 import evaluation
from spindlebench.studies.iso230_3.channels import TestData, from_map, load_map, synthetic
from spindlebench.studies.iso230_3.compensation import LinearModel, load_model
from spindlebench.studies.iso230_3.figure import draw

if TYPE_CHECKING:
    import pandas as pd

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "run an ISO 230-3 thermal test and write its report"

ISO_SCENARIOS = SCENARIOS_DIR / "iso230-3"
#: The axis test's two targets near the ends of the X stroke (m from the fixed bearing).
AXIS_TARGETS_M = (0.05, 0.80)
#: Numbers in the JSON report are rounded to this many decimals (stable bytes).
DECIMALS = 4


@dataclass(frozen=True)
class Test:
    """One ISO 230-3 test: its scenario and what the report evaluates."""

    scenario: str
    title: str


TESTS: dict[str, Test] = {
    "etve": Test("etve.toml", "environmental temperature variation error (ETVE)"),
    "spindle": Test("spindle.toml", "thermal distortion caused by a rotating spindle"),
    "spectrum": Test("spectrum.toml", "rotating spindle, speed spectrum"),
    "axis": Test("axis.toml", "thermal distortion caused by moving linear axis X"),
}


def _rounded(value: Any) -> Any:
    if isinstance(value, float):
        return round(value, DECIMALS)
    if isinstance(value, dict):
        return {k: _rounded(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_rounded(v) for v in value]
    return value


def simulate_test(test: str, machine: str, out_dir: Path, fmu: Path = DEFAULT_FMU
                  ) -> tuple[TestData, list[dict[str, Any]], pd.DataFrame]:
    """Simulate ``test`` on ``machine``, write its recording(s) into ``out_dir``, and return
    the report's series (the axis test's X at both targets), the recordings' entries and the
    (first) recording's frame."""
    from spindlebench.testbench.scenario import load_scenario, with_machine
    from spindlebench.testbench.simulate import record

    scenario = with_machine(load_scenario(ISO_SCENARIOS / TESTS[test].scenario), machine)
    if test != "axis":
        frame, sidecar = record(scenario, fmu)
        path = write_recording(out_dir / f"{test}_recording.csv", frame, sidecar)
        return synthetic(frame), [file_entry(path)], frame
    runs, entries, frames = [], [], []
    for target in AXIS_TARGETS_M:
        at_target = dataclasses.replace(
            scenario, parameters={**scenario.parameters, "x_target_m": target})
        frame, sidecar = record(at_target, fmu)
        path = write_recording(out_dir / f"axis_recording_x{target:g}m.csv", frame, sidecar)
        runs.append(synthetic(frame))
        entries.append(file_entry(path))
        frames.append(frame)
    near, far = runs
    linear = {f"X at {AXIS_TARGETS_M[0]:g} m": near.linear["X"],
              f"X at {AXIS_TARGETS_M[1]:g} m": far.linear["X"],
              "X far - near": far.linear["X"] - near.linear["X"],
              "Y": near.linear["Y"], "Z": near.linear["Z"]}
    return dataclasses.replace(near, linear=linear, sources={}), entries, frames[0]


def compensated(data: TestData, frame: pd.DataFrame, model: LinearModel) -> TestData:
    """``data`` with the residual of ``model``'s Z compensation as one more direction."""
    missing = [s for s in model.sensors if s not in frame]
    if missing:
        raise SpindlebenchError(f"{model.source}: model {model.name!r} reads sensor(s) "
                                f"{', '.join(missing)}, which the test's recording has not")
    prediction = model.predict({s: frame[s].to_numpy(float) for s in model.sensors})
    linear = dict(data.linear)
    linear[f"Z residual ({model.name})"] = data.linear["Z"] - prediction
    return dataclasses.replace(data, linear=linear)


def evaluate(test: str, data: TestData) -> dict[str, Any]:
    """The report's numbers for ``test`` (see ``evaluation``)."""
    t = data.time_s
    report: dict[str, Any] = {
        "duration_h": float(t[-1] - t[0]) / 3600.0,
        "samples": int(t.size),
        "range_um": evaluation.ranges(t, data.linear),
        "range_urad": evaluation.ranges(t, data.tilts),
        "temperature_range_K": {k: float(v.max() - v.min())
                                for k, v in data.temperatures.items()},
        "channels": dict(data.sources),
    }
    if test == "etve":
        report["etve_um"] = {k: v["range"] for k, v in report["range_um"].items()}
        report["etve_urad"] = {k: v["range"] for k, v in report["range_urad"].items()}
        if data.air is not None:
            report["air_range_K"] = report["temperature_range_K"][data.air]
    if test in ("spindle", "spectrum"):
        end = evaluation.spindle_on_end_s(t, data.speed_rpm)
        heating = slice(0, int(np.searchsorted(t, end)) + 1)
        report["spindle_on_end_h"] = end / 3600.0
        report["heating_range_um"] = evaluation.ranges(t, data.linear, heating)
        report["heating_range_urad"] = evaluation.ranges(t, data.tilts, heating)
        if test == "spindle":
            directions = {k: v for k, v in data.linear.items() if k in evaluation.LINEAR}
            report["stability"] = evaluation.stability(t, directions, end).to_dict()
    if test == "spectrum" and data.speed_rpm is not None:
        steps = []
        change = np.flatnonzero(np.diff(data.speed_rpm) != 0) + 1
        bounds = [0, *change.tolist(), t.size]
        for start, stop in itertools.pairwise(bounds):
            last = stop - 1
            steps.append({"speed_rpm": float(data.speed_rpm[start]),
                          "from_h": float(t[start] / 3600.0), "to_h": float(t[last] / 3600.0),
                          "end_um": {k: float(v[last]) for k, v in data.linear.items()},
                          "end_urad": {k: float(v[last]) for k, v in data.tilts.items()}})
        report["steps"] = steps
    return report


def write_report(test: str, data: TestData, numbers: dict[str, Any], source: dict[str, Any],
                 out_dir: Path, title: str) -> list[Path]:
    """Write ``<test>.png``, ``<test>_series.csv`` and ``<test>.json`` into ``out_dir``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    stable = numbers.get("stability", {}).get("met_at_h")
    phase_end = numbers.get("spindle_on_end_h")
    figure = draw(data, title, out_dir / f"{test}.png",
                  phase_end_s=None if phase_end is None else phase_end * 3600.0,
                  stable_at_s=None if stable is None else stable * 3600.0)
    columns: dict[str, np.ndarray] = {"time_h": data.time_s / 3600.0}
    columns.update({f"{k}_um": v for k, v in data.linear.items()})
    columns.update({f"tilt_{k}_urad": v for k, v in data.tilts.items()})
    columns.update({f"{k}" if k.endswith("_um") else f"{k}_um": v
                    for k, v in data.others.items()})
    columns.update({f"{k}_C" if not k.endswith("_C") else k: v
                    for k, v in data.temperatures.items()})
    if data.speed_rpm is not None:
        columns[SPEED_COLUMN] = data.speed_rpm
    series = out_dir / f"{test}_series.csv"
    import pandas as pd  # here only: ``iso230-3 --help`` does not pay for pandas

    with atomic.atomic_path(series) as tmp:
        write_table(tmp, pd.DataFrame(columns))
    report = {
        "test": test,
        "title": title,
        **_rounded(numbers),
        "provenance": provenance(kind="spindlebench ISO 230-3 report", **source,
                                 figure=file_entry(figure), series=file_entry(series)),
    }
    path = out_dir / f"{test}.json"
    atomic.write_text(path, json.dumps(report, indent=2, ensure_ascii=False,
                                       allow_nan=False) + "\n")
    return [figure, series, path]


def _summary(test: str, numbers: dict[str, Any]) -> str:
    lines = []
    for unit, key in (("um", "range_um"), ("urad", "range_urad")):
        for name, entry in numbers[key].items():
            lines.append(f"  {name:>14}: range {entry['range']:8.2f} {unit}  (max "
                         f"{entry['max']:.2f} at {entry['at_max_h']:.2f} h, final "
                         f"{entry['final']:.2f})")
    if "stability" in numbers:
        s = numbers["stability"]
        met = f"met at {s['met_at_h']:.2f} h" if s["met"] else "not met"
        lines.append(f"  stability criterion: {met} (time limit {s['time_limit_h']:.2f} h)")
        alone = ", ".join(f"{k} {'-' if v is None else format(v, '.2f') + ' h'}"
                          for k, v in s["per_direction_met_at_h"].items())
        lines.append(f"  each direction alone: {alone}")
    if "air_range_K" in numbers:
        lines.append(f"  air temperature range: {numbers['air_range_K']:.2f} K")
    return "\n".join(lines)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "iso230-3", help=HELP,
        description="Run an ISO 230-3 thermal test (etve, spindle, spectrum, axis) on a "
        "machine variant, or evaluate a real recording through a MAP.toml, and write the "
        "report: figure, JSON and CSV with provenance.")
    parser.add_argument("test", choices=sorted(TESTS), help="the test")
    add_machine_argument(parser, "the machine to test", "default")
    parser.add_argument("--recording", type=Path, help="evaluate this recording instead")
    parser.add_argument("--map", type=Path, help="MAP.toml of the recording's channels")
    parser.add_argument("--fmu", type=Path, default=DEFAULT_FMU, help="the FMU to simulate")
    parser.add_argument("--compensate", type=Path, metavar="PROVENANCE.json",
                        help="a compensate run's provenance.json: its trained model predicts "
                        "Z, the report adds the residual")
    parser.add_argument("--model", help="which model of --compensate (default: its first)")
    parser.add_argument("-o", "--out", type=Path, help="output folder (default iso230-3_TEST)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    out_dir = args.out or Path(f"iso230-3_{args.test}")
    title = f"ISO 230-3 {TESTS[args.test].title}"
    if args.model is not None and args.compensate is None:
        raise SpindlebenchError("--model belongs to --compensate")
    model = None if args.compensate is None else load_model(args.compensate, args.model)
    if args.recording is not None:
        if args.map is None:
            raise SpindlebenchError("--recording needs --map MAP.toml (which channel is which)")
        if args.machine is not None:
            raise SpindlebenchError("--recording and --machine exclude each other")
        mapping = load_map(args.map)
        wanted = mapping.columns() + ([] if model is None else model.sensors)
        frame = read_recording(args.recording, columns=list(dict.fromkeys(wanted)))
        data = from_map(frame, mapping, args.recording)
        source = {"recording": file_entry(args.recording), "map": file_entry(args.map)}
        title += f": {args.recording.name}"
    else:
        if args.map is not None:
            raise SpindlebenchError("--map belongs to --recording")
        machine = args.machine or "default"
        out_dir.mkdir(parents=True, exist_ok=True)
        data, recordings, frame = simulate_test(args.test, machine, out_dir, args.fmu)
        source = {"machine": machine, "scenario": file_entry(ISO_SCENARIOS /
                                                              TESTS[args.test].scenario),
                  "fmu": file_entry(args.fmu), "recordings": recordings}
        title += f": machine {machine}"
    if model is not None:
        if "Z" not in data.linear:
            raise SpindlebenchError("--compensate needs a Z direction to compensate")
        data = compensated(data, frame, model)
        source["compensation"] = {"model": model.name, "inputs": list(model.inputs),
                                  "coefficients": [model.intercept, *model.coefficients],
                                  "file": file_entry(model.source)}
        title += f", compensated by {model.name}"
    numbers = evaluate(args.test, data)
    paths = write_report(args.test, data, numbers, source, out_dir, title)
    print(f"{title}\n{_summary(args.test, numbers)}")
    for path in paths:
        print(f"wrote {path}")
    return 0
