"""The docs' tables, generated from the files the commands write, each with its source beside it.

A page under ``docs/`` asks for a table with a line of its own::

    <!-- generate: fingerprints default -->

and ``expand`` (called by the MkDocs hook ``generate.py`` for every page) replaces it with the
table, preceded by a marker naming what made it and from which file, and a visible line with
that file's provenance::

    <!-- table by=fingerprints source=results/docs/machines.json key=default -->

    *From `results/docs/machines.json`, written by `python -m ...` (FMU sha256 1a2b3c4d5e6f).*

    | run | best_raw_psi | ...

``tests/repo/test_docs_tables.py`` finds every table of every page, reads its marker and calls
``regenerate(by, source, key)``, which must give the same table from that file: a table typed
by hand has no marker and must be listed there with the reason it is typed.

A number in a sentence is read the same way, inline: ``<!-- value: FILE PATH [FORMAT] -->``
(``VALUE``: one field of a JSON file) becomes the formatted field with a marker naming file
and key, and the same test reads each again; ``tests/repo/test_docs_prose_numbers.py`` keeps
typed numbers with units out of the prose.

Sources (``Sources``, the checkout's by default):

- ``bench/results/*.json`` (``bench/results.py record()``: machine, load, date and commit once
  per file): every file is rendered, known scripts with chosen columns, others key by key;
- ``results/docs/machines.json``, written by ``machine_check --json`` from
  ``scenarios/machines/*.toml`` and the FMU (fingerprints, targets, ambient step, levels,
  mechanisms). It is stale when a machine file or the FMU changed since: ``make docs``
  (``SPINDLEBENCH_DOCS_RUN=1``) reruns it then, a plain ``mkdocs build`` shows a placeholder
  naming the command;
- ``scenarios/machines/*.toml`` and the FMU's model description (the parameters table);
- the stable-room studies' CSVs under ``results/`` (or their committed copies under
  ``docs/snapshots/`` when the study has not been run in this checkout: the population runs
  take half an hour, too long for ``make docs``; the marker names which file was read, and
  the snapshot's ``provenance.json`` sits beside it);
- what ``make run`` writes under ``results/paper_study/`` and ``results/caiviac_study/``
  (``run-table FOLDER/FILE[@N]``: the N-th table of that file as written; ``paper-summary
  FOLDER``: the mean RMSE per k and group of its ``table6_rmse.csv``), or their committed
  copies under ``docs/snapshots/`` in a checkout where ``make run`` has not been run;
- the season sweeps' ``summary/by_method.csv`` (``sweep-groups FOLDER[@iqr]``: the paper's
  groups, the baselines and the oracle per k; ``sweep-methods FOLDER@GROUP``: every method on
  one group's candidates) and the year placement's ``placements.csv`` (``placement-year``,
  ``placement-year-af``), from ``results/`` or their snapshots (the runs take minutes, longer
  than ``make docs``; ``make docs-snapshots`` copies them);
- a multi-target compensation's ``README.md`` (``compensation-targets FOLDER[@RULE]``: its
  per-target residual table, the rows of one retraining rule);
- the ISO 230-3 reports ``spindlebench iso230-3 TEST ... -o DIR`` writes as ``DIR/TEST.json``
  (``iso230-3-comparison TEST``: the default machine's spindle-on phase beside CAIVIAC run
  3's, from ``results/iso230-3/`` or its snapshot; ``iso230-3-report TEST[@steps]``: one
  report of the default machine, per direction and tilt, or the speed spectrum's steps);
- ``results/caiviac_identification/*/caiviac.json`` (or their snapshots), written by
  ``python -m spindlebench.identification.validation --splits ... --out ...``
  (``identification-split C``: that split's table, as the script prints it;
  ``twin summary``: the means of every split);
- ``results/discretisation/discretisation.json`` (or its snapshot), written by ``python -m
  spindlebench.model.discretisation --out ...`` (``discretisation``: the drift rise per segment
  count; its provenance line says when the model source has changed since);
- ``results/cold_start/cold_start.json`` (or its snapshot), written by ``python -m
  spindlebench.model.cold_start --json ...`` (``cold-start``: the sensors' and the drift's
  rises of the cold-start runs; its provenance line says when the FMU has changed since);
- ``evaluate --json`` runs of one comparison at several k (``evaluate-runs NAME``: a folder of
  ``kN.json``, from ``results/NAME`` or its snapshot; the commands in ``EVALUATE_RUNS``);
- a benchmark run's ``leaderboard.json`` (``leaderboard benchmark/mine``: the run's suite and
  command, the overall table and one table per task, as ``leaderboard.md`` has them), from
  ``results/`` or its snapshot;
- ``results/caiviac_calibration/caiviac_calibration.json`` (or its snapshot), written by
  ``python -m spindlebench.calibration.validation`` (``calibration heldout|variants|runs``:
  the calibration table, the fit-set variants, the runs as the adapter cut them);
- ``results/twin/*.json`` (or ``docs/snapshots/twin/``), written by the same script's
  ``--synthetic``, ``--evidence``, ``--room-proxy`` and ``--evaluate`` with ``--out
  results/twin`` (``twin synthetic``, ``twin superposition``, ``twin evidence``, ``twin
  room-proxy``, ``twin every-split``, ``twin evaluate@RUN``), rendered by the script's own
  ``*_markdown``.
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
MACHINE_CHECK = "python -m spindlebench.studies.fingerprint.machine_check"
#: ``make docs`` sets it: run the cheap commands whose output is missing or stale.
RUN_ENV = "SPINDLEBENCH_DOCS_RUN"
PLACEHOLDER = re.compile(r"^<!-- generate: (\S+)(?: (\S+))? -->$", re.MULTILINE)
MARKER = re.compile(r"<!-- table by=(\S+) source=(\S+)(?: key=(\S+))? -->")
#: A result page copies a README the command wrote: all its tables come from that file.
COPIED = re.compile(r"<!-- tables copied from (\S+) -->")


@dataclass(frozen=True)
class Sources:
    """Where the generating files are (the checkout's, or a test's copies)."""

    root: Path = ROOT
    bench: Path = ROOT / "bench" / "results"
    machines: Path = ROOT / "scenarios" / "machines"
    machines_json: Path = ROOT / "results" / "docs" / "machines.json"
    results: Path = ROOT / "results"
    snapshots: Path = ROOT / "docs" / "snapshots"
    fmu: Path = ROOT / "fmus" / "SpindleBench.fmu"
    run: bool = field(default_factory=lambda: os.environ.get(RUN_ENV) == "1")

    def name(self, path: Path) -> str:
        """``path`` as the marker writes it: relative to the checkout where it is inside."""
        try:
            return str(path.resolve().relative_to(self.root.resolve()))
        except ValueError:
            return str(path)

    def path(self, name: str) -> Path:
        return Path(name) if Path(name).is_absolute() else self.root / name


# --------------------------------------------------------------------------- formatting

def number(value: Any) -> str:
    """One cell: floats with 4 significant digits, lists joined, None as a dash."""
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if not math.isfinite(value):
            return "n/a"
        return f"{value:.4g}" if abs(value) < 1e5 else f"{value:.6g}"
    if isinstance(value, list | tuple):
        return " ".join(number(v) for v in value)
    return str(value).replace("|", "\\|").replace("\n", " ")


def markdown_table(header: list[str], rows: list[list[Any]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(number(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def block(by: str, source: str, key: str | None, provenance: str, table: str) -> str:
    """A table with its marker and its visible provenance line."""
    marker = f"<!-- table by={by} source={source}" + (f" key={key}" if key else "") + " -->"
    return f"{marker}\n\n*{provenance}*\n\n{table}\n"


def placeholder(what: str, command: str) -> str:
    return f"*({what} is not in this build: `{command}` writes it; `make docs` runs it.)*\n"


# --------------------------------------------------------------------------- bench results

#: Known bench scripts: (columns of each row: key, header) in the order shown.
BENCH_COLUMNS: dict[str, list[tuple[str, str]]] = {
    "bench_startup": [("command", "command"), ("cpu_s_median", "CPU s (median)"),
                      ("cpu_s_min", "CPU s (min)"), ("runs", "runs"),
                      ("goal_cpu_s", "goal CPU s"), ("met", "met")],
    "bench_runner": [("scenario", "scenario"), ("inputs", "inputs"),
                     ("solver_stops", "stops"), ("python_cpu_ms_min", "Python callbacks CPU-ms"),
                     ("c_cpu_ms_min", "C right-hand side CPU-ms"), ("speed_up", "ratio"),
                     ("same_bytes", "same bytes"),
                     ("c_forward_cpu_ms_min", "C, forward Jacobian CPU-ms"),
                     ("c_forward_max_abs_difference", "its largest difference"),
                     ("c_differences_cpu_ms_min", "C, coloured differences CPU-ms"),
                     ("c_differences_max_abs_difference", "its largest difference")],
    "bench_placement": [("step", "step"), ("s", "s"), ("cpu_s", "CPU s"),
                        ("baseline", "naive baseline in the same process"),
                        ("baseline_s", "baseline s"), ("baseline_cpu_s", "its CPU s"),
                        ("ratio", "ratio (CPU)"), ("same", "same result")],
    "bench_placement_fields": [("nodes", "field nodes"), ("candidates", "candidates"),
                               ("s", "`place`'s fuzzy selection, m = 2..6, s"),
                               ("cpu_s", "CPU s"), ("peak_MB", "peak MB"), ("goal", "goal"),
                               ("met", "met"),
                               ("matrix_s", "before (full design matrix from DataFrames) s"),
                               ("matrix_cpu_s", "its CPU s"),
                               ("matrix_peak_MB", "its peak MB"), ("matrix", "before")],
    "bench_placement_methods": [("method", "method"), ("differences", "differences"),
                                ("candidates", "candidates"), ("cpu_s", "CPU s (median)"),
                                ("ratio_to_fuzzy", "× fuzzy"), ("met", "within 3×"),
                                ("note", "where not: why")],
    "bench_dask": [("row", "row"), ("executor", "executor"), ("workers", "workers"),
                   ("cpu_s", "CPU s (cluster started and stopped)"),
                   ("over_local", "÷ local"),
                   ("running_cluster_cpu_s", "CPU s (cluster running)"),
                   ("running_over_local", "÷ local"), ("command_cpu_s", "command CPU s"),
                   ("scheduler_cpu_s", "scheduler"), ("nanny_cpu_s", "nanny"),
                   ("workers_cpu_s", "Dask workers"), ("command_wall_s", "command wall s"),
                   ("wall_s", "idle wall s"), ("cores_busy", "idle cores busy")],
    "bench_sweep": [("executor", "executor"), ("workers", "workers"),
                    ("simulations", "simulations"), ("wall_s", "wall s"),
                    ("ms_per_simulation", "ms per simulation"),
                    ("experiments_per_s", "experiments/s"),
                    ("s_per_evaluation_job", "s per evaluation job")],
}

#: ``bench_sweep.py``'s goal row: the 1 008-experiment sweep's CPU by part.
BENCH_COLUMNS["bench_sweep_goal"] = [
    ("experiments", "experiments"), ("workers", "workers"), ("cpu_s", "CPU s in all"),
    ("simulation_cpu_s", "simulations"), ("evaluation_cpu_s", "evaluations"),
    ("workers_outside_tasks_cpu_s", "workers outside tasks"),
    ("coordinator_cpu_s", "coordinator"), ("outputs_cpu_s", "of which outputs"),
    ("over_floor", "× simulations"), ("goal_over_floor", "goal ×"), ("wall_s", "wall s")]
#: ``bench_dask.py --example`` writes the same rows for the example sweep itself.
BENCH_COLUMNS["bench_dask_example"] = BENCH_COLUMNS["bench_dask"]


def bench_provenance(document: Mapping[str, Any], source: str) -> str:
    machine = document.get("machine", {})
    load = document.get("load_average") or []
    commit = document.get("git_commit") or "unknown"
    probe = document.get("speed_probe_ms") or {}
    speed = (f", speed probe {probe['start']:.0f} / {probe['end']:.0f} ms at the start / end "
             f"(CPU time of {probe.get('additions', 0):,} Python additions: lower is faster)"
             if "start" in probe and "end" in probe else "")
    return (f"From `{source}`: measured {document.get('date_utc', 'at an unknown date')} on "
            f"{machine.get('nproc', '?')} cores ({machine.get('cpu_model', 'unknown CPU')}), "
            f"load average {' / '.join(f'{v:.1f}' for v in load) or 'unknown'}{speed}, commit "
            f"`{commit[:12]}{'+dirty' if commit.endswith('+dirty') else ''}`")


def bench_table(path: Path, key: str | None = None) -> str:
    """The rows of one bench file: chosen columns for a known script, else every scalar key
    (``key = "goals"``: its goals, key by key)."""
    document = json.loads(path.read_text(encoding="utf-8"))
    if key == "goals":
        goals = document.get("goals") or {}
        return markdown_table(["goal", "value"], [[k, v] for k, v in sorted(goals.items())])
    rows = document.get("rows") or []
    columns = BENCH_COLUMNS.get(path.stem)  # a script's second file has its own keys
    if columns is None:
        keys: list[str] = []
        for row in rows:
            keys += [k for k, v in row.items() if k not in keys and not isinstance(v, dict)]
        columns = [(k, k) for k in keys]
    return markdown_table([h for _, h in columns], [[row.get(k) for k, _ in columns]
                                                    for row in rows])


def bench_section(script: str | None, sources: Sources) -> str:
    """``<!-- generate: bench SCRIPT -->`` on another page than the speed page: the rows of
    ``bench/results/SCRIPT.json`` with its machine, load and date."""
    if script is None:
        raise ValueError("<!-- generate: bench -->: needs the script (e.g. bench_cosim)")
    path = sources.bench / f"{script}.json"
    if not path.is_file():
        return placeholder(f"`bench/results/{script}.json`", f"python bench/{script}.py")
    source = sources.name(path)
    document = json.loads(path.read_text(encoding="utf-8"))
    return block("bench", source, None, bench_provenance(document, source), bench_table(path))


def speed_section(sources: Sources) -> str:
    """Every ``bench/results/*.json``: a heading, its provenance once, its goals and rows."""
    files = sorted(sources.bench.glob("*.json"))
    if not files:
        return placeholder("No benchmark result", "make bench")
    parts = []
    for path in files:
        document = json.loads(path.read_text(encoding="utf-8"))
        source = sources.name(path)
        script = document.get("script", path.stem)
        parts.append(f"### `bench/{script}.py`\n\n{bench_provenance(document, source)}.\n")
        if document.get("goals"):
            parts.append(block("bench", source, "goals", "Its goals", bench_table(path, "goals")))
        parts.append(block("bench", source, None, "Its rows", bench_table(path)))
    return "\n".join(parts)


# --------------------------------------------------------------------------- machines

def machines_document(sources: Sources) -> dict | None:
    """``machines.json`` if it is up to date with the machine files and the FMU; rerun when
    ``sources.run`` (``make docs``) and it is missing or stale; else None."""
    document = _read_json(sources.machines_json)
    if document is not None and not stale(document, sources):
        return document
    if not sources.run:
        return None
    from spindlebench.studies.fingerprint.machine_check import write_json

    shipped = sources.machines.resolve() == (ROOT / "scenarios" / "machines").resolve()
    names = [p.stem if shipped else str(p) for p in sorted(sources.machines.glob("*.toml"))]
    return write_json(sources.machines_json, names, sources.fmu)


def _read_json(path: Path) -> dict | None:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def stale(document: Mapping[str, Any], sources: Sources) -> bool:
    """A machine file added, removed or changed, or another FMU, since the file was written."""
    from spindlebench.core.provenance import sha256_file

    files = {p.stem: sha256_file(p) for p in sources.machines.glob("*.toml")}
    recorded = {Path(m["file"]).stem: m["sha256"] for m in document["machines"].values()}
    fmu = document.get("provenance", {}).get("fmu", {}).get("sha256")
    return files != recorded or fmu != sha256_file(sources.fmu)


def machines_provenance(document: Mapping[str, Any], source: str) -> str:
    prov = document["provenance"]
    return (f"From `{source}`, written by `{prov['command']}` (FMU sha256 "
            f"{prov['fmu']['sha256'][:12]}; machine files as of their sha256 in the file)")


def _machine(document: Mapping[str, Any], key: str) -> Mapping[str, Any]:
    return document["machines"][key]


def fingerprints_table(document: Mapping[str, Any], key: str) -> str:
    from spindlebench.studies.fingerprint.machine_check import table

    return table(_machine(document, key)["fingerprints"])


def mechanisms_table(document: Mapping[str, Any], key: str) -> str:
    from spindlebench.studies.fingerprint.statistics import KEYS

    rows = _machine(document, key)["mechanisms"]
    return markdown_table([f"`{key}`", *KEYS], [[label, *[f"{s[k]:.3f}" for k in KEYS]]
                                                 for label, s in rows.items()])


def heating_table(document: Mapping[str, Any], key: str | None = None) -> str:
    """Every machine's constant-room heating runs (2000 to 12 000 rpm, 8 h, noise-free)."""
    from spindlebench.studies.fingerprint.statistics import KEYS

    rows = [[f"`{name}`", run, *[f"{stats[k]:.3f}" for k in KEYS]]
            for name, m in document["machines"].items()
            for run, stats in m.get("heating_fingerprints", {}).items()]
    return markdown_table(["machine", "run", *KEYS], rows)


def targets_table(document: Mapping[str, Any], key: str | None = None) -> str:
    rows = []
    for name, m in document["machines"].items():
        rows.append([f"`{name}`", "; ".join(m["targets"]) or "none",
                     "all met" if not m["problems"] else "NOT MET: " + "; ".join(m["problems"])])
    return markdown_table(["machine", "targets", "result"], rows)


def levels_table(document: Mapping[str, Any], key: str | None = None) -> str:
    with_levels = {n: m["levels"] for n, m in document["machines"].items() if "levels" in m}
    keys = list(next(iter(with_levels.values()))) if with_levels else []
    return markdown_table(["machine", *keys], [[f"`{n}`", *[f"{lv[k]:.1f}" for k in keys]]
                                               for n, lv in with_levels.items()])


def ambient_step_table(document: Mapping[str, Any], key: str | None = None) -> str:
    steps = {n: m["ambient_step_um_per_K"] for n, m in document["machines"].items()
             if "ambient_step_um_per_K" in m}
    hours = list(next(iter(steps.values()))) if steps else []
    return markdown_table(["machine (µm/K)", *hours], [[f"`{n}`", *[f"{s[h]:+.2f}"
                                                                    for h in hours]]
                                                       for n, s in steps.items()])


#: The heating runs' outputs docs/model.md quotes: (output, what of it, header).
HEATING_OUTPUT_COLUMNS = (
    ("drift_um", "peak", "drift peak (µm, when)"), ("drift_um", "end", "drift at 8 h (µm)"),
    ("column_growth_um", "end", "column growth at 8 h (µm)"),
    ("front_preload_thermal_N", "peak", "induced preload peak (N, when)"),
    ("front_preload_thermal_N", "end", "at 8 h (N)"),
    ("Q_bearing_air_W", "end", "bearing air at 8 h (W)"),
    ("Q_jacket_W", "end", "jacket at 8 h (W)"),
    ("jacket_outlet_C", "rise", "jacket outlet − inlet at 8 h (K)"))


def _heating_cell(outputs: Mapping[str, Any], name: str, what: str) -> str:
    if what == "rise":
        inlet, outlet = outputs.get("jacket_inlet_C"), outputs.get(name)
        return "" if inlet is None or outlet is None else f"{outlet['end'] - inlet['end']:.1f}"
    value = outputs.get(name)
    if value is None:
        return ""
    if what == "peak":
        return f"{value['peak']:.1f} at {value['peak_h']:.2f} h"
    return f"{value['end']:.1f}"


def heating_outputs_table(document: Mapping[str, Any], key: str | None = None) -> str:
    """Every machine's heating runs (8 h at constant speed in a 20 °C room): the drift's peak
    and end, and the issue-20 mechanisms' outputs (``machine_check``'s ``heating_outputs``;
    an empty cell: the machine has no such output or it stays 0)."""
    rows = []
    for name, machine in document["machines"].items():
        for run, outputs in machine.get("heating_outputs", {}).items():
            rows.append([f"`{name}`", run, *[_heating_cell(outputs, o, w)
                                            for o, w, _ in HEATING_OUTPUT_COLUMNS]])
    return markdown_table(["machine", "run", *[h for _, _, h in HEATING_OUTPUT_COLUMNS]], rows)


MACHINE_TABLES: dict[str, tuple[Callable[[Mapping[str, Any], Any], str], str]] = {
    "fingerprints": (fingerprints_table, "fingerprints"),
    "mechanisms": (mechanisms_table, "mechanisms"),
    "targets": (targets_table, "fingerprints"),
    "heating": (heating_table, "heating_fingerprints"),
    "heating-outputs": (heating_outputs_table, "heating_outputs"),
    "levels": (levels_table, "levels"),
    "ambient-step": (ambient_step_table, "ambient_step_um_per_K"),
}


def machine_section(by: str, key: str | None, sources: Sources) -> str:
    document = machines_document(sources)
    command = f"{MACHINE_CHECK} --json {sources.name(sources.machines_json)}"
    function, needs = MACHINE_TABLES[by]
    if document is None or (key is not None and key not in document["machines"]) or \
            not any(needs in m for m in document["machines"].values()):
        return placeholder(f"The {by} table", command)
    source = sources.name(sources.machines_json)
    return block(by, source, key, machines_provenance(document, source),
                 function(document, key))


def parameters_table(machines: Path, fmu: Path) -> str:
    """Every parameter a machine file sets: unit, the FMU's default, each machine's value and
    the model's description (which cites its source by key, docs/model.md)."""
    from spindlebench.machines.variants import load_machine
    from spindlebench.testbench.runner import inspect_fmu

    files = sorted(machines.glob("*.toml"))
    loaded = [load_machine(str(p)) for p in files]
    known = inspect_fmu(fmu).parameters
    names = sorted({n for m in loaded for n in m.parameters})
    rows = []
    for name in names:
        variable = known.get(name)
        start = None if variable is None or variable.start is None else float(variable.start)
        rows.append([f"`{name}`", getattr(variable, "unit", None) or "", start,
                     *[m.parameters.get(name, "") for m in loaded],
                     _short(getattr(variable, "description", None) or "")])
    return markdown_table(["parameter", "unit", "FMU default",
                           *[f"`{m.name}`" for m in loaded], "model description"], rows)


def machine_parameters_table(path: Path, key: str | None = None) -> str:
    """One machine file's ``[parameters]``, as the machines page shows it."""
    from spindlebench.machines.variants import load_machine

    machine = load_machine(str(path))
    return markdown_table(["parameter", "value"], [[f"`{k}`", f"{v:g}"]
                                                   for k, v in machine.parameters.items()])


def machine_parameters_section(path: Path, sources: Sources | None = None) -> str:
    sources = sources or Sources()
    source = sources.name(path)
    return block("machine-parameters", source, None, f"From `{source}`",
                 machine_parameters_table(path))


def _short(text: str, limit: int = 80) -> str:
    """A model description cut at ``limit`` characters (the full text is the FMU's)."""
    return text if len(text) <= limit else text[:limit].rsplit(" ", 1)[0] + " …"


def parameters_section(sources: Sources) -> str:
    from spindlebench.core.provenance import sha256_file

    source = sources.name(sources.machines)
    provenance = (f"From the machine files `{source}/*.toml` and the FMU's model description "
                  f"(`{sources.name(sources.fmu)}`, sha256 {sha256_file(sources.fmu)[:12]}); "
                  "an empty cell: the machine keeps the FMU's default; descriptions cut at 80 "
                  "characters")
    return block("parameters", source, None, provenance,
                 parameters_table(sources.machines, sources.fmu))


# --------------------------------------------------------------------------- stable-room studies

#: Study result tables: by → (results folder under results/, file, table function).
STUDY_FILES = {
    "placement-population": ("placement-stable-room/population", "population_placements.csv"),
    "placement-default": ("placement-stable-room/default", "placements.csv"),
    "compensation-population": ("compensate-stable-room/population",
                                "population_compensation.csv"),
    "compensation-default": ("compensate-stable-room/default", "summary.csv"),
    "placement-year": ("placement", "placements.csv"),
    "placement-year-af": ("af-placement", "placements.csv"),
    "placement-methods": ("placement-methods", "placements.csv"),
    "compensation-month": ("compensate-month", "summary.csv"),
    "compensation-month-short": ("compensate-month", "summary.csv"),
    "compensation-month-cold": ("compensate-month-cold", "summary.csv"),
}
STUDY_COMMANDS = {
    "placement-population": "spindlebench place scenarios/studies/placement_stable_room.toml "
                            "-o results/placement-stable-room/population",
    "placement-default": "spindlebench place scenarios/studies/placement_stable_room.toml "
                         "--machine default -o results/placement-stable-room/default",
    "compensation-population": "spindlebench compensate "
                               "scenarios/studies/compensate_stable_room.toml "
                               "-o results/compensate-stable-room/population",
    "compensation-default": "spindlebench compensate "
                            "scenarios/studies/compensate_stable_room.toml --machine default "
                            "-o results/compensate-stable-room/default",
    "placement-year": "spindlebench place scenarios/studies/placement.toml -o results/placement "
                      "--workers 1",
    "placement-year-af": "spindlebench place scenarios/studies/placement.toml "
                         "-o results/af-placement --machine ambient-following --workers 1",
    "placement-methods": "spindlebench place scenarios/studies/placement_methods.toml "
                         "-o results/placement-methods --workers 1",
    "compensation-month": "spindlebench compensate scenarios/studies/compensate_month.toml "
                          "-o results/compensate-month",
    "compensation-month-short": "spindlebench compensate "
                                "scenarios/studies/compensate_month.toml "
                                "-o results/compensate-month",
    "compensation-month-cold": "spindlebench compensate "
                               "scenarios/studies/compensate_month.toml "
                               "-o results/compensate-month-cold --days cold-starts",
}


def study_file(by: str, sources: Sources) -> Path | None:
    """The study's file in ``results/`` if it was run here, else its committed snapshot."""
    folder, name = STUDY_FILES[by]
    for base in (sources.results, sources.snapshots):
        if (base / folder / name).is_file():
            return base / folder / name
    return None


def _csv(path: Path) -> list[dict[str, str]]:
    import csv

    with path.open(encoding="utf-8", newline="") as handle:
        return list(csv.DictReader(handle))


def _share(count: int, total: int) -> str:
    return f"{count} of {total} ({100.0 * count / total:.0f} %)" if total else "none"


def _quartiles(values: list[float]) -> tuple[float, float, float]:
    import numpy as np

    q1, median, q3 = np.quantile(np.asarray(values, dtype=float), [0.25, 0.5, 0.75])
    return float(q1), float(median), float(q3)


def placement_population_table(path: Path, key: str | None = None) -> str:
    groups: dict[tuple[str, int], list[dict[str, str]]] = {}
    for row in _csv(path):
        if row["gain_um"] not in ("", "nan"):
            groups.setdefault((row["method"], int(row["m"])), []).append(row)
    rows = []
    for (method, m), at in sorted(groups.items()):
        helps = sum(r["diff_helps"] == "True" for r in at)
        q1, median, q3 = _quartiles([float(r["gain_um"]) for r in at])
        rows.append([method, m, _share(helps, len(at)), f"{median:.2f}",
                     f"{q1:.2f} to {q3:.2f}"])
    return markdown_table(["method", "m", "machines where differences help",
                           "median gain (µm)", "gain IQR (µm)"], rows)


def placement_default_table(path: Path, key: str | None = None) -> str:
    """Mean held-out RMSE per budget and placement method (a method that scored no budget,
    such as an exhaustive search too large to run, has no column)."""
    rows = _csv(path)
    labels = list(dict.fromkeys(r["label"] for r in rows
                                if r["test_mean_rmse_um"] not in ("", "nan")))
    budgets = sorted({int(r["m"]) for r in rows})
    score = {(r["label"], int(r["m"])): r["test_mean_rmse_um"] for r in rows}
    return markdown_table(["m", *labels], [[m, *[_um(score.get((lb, m))) for lb in labels]]
                                           for m in budgets])


def _um(text: str | None) -> str:
    return "—" if text in (None, "", "nan") else f"{float(text):.2f}"


def compensation_population_table(path: Path, key: str | None = None) -> str:
    groups: dict[str, list[dict[str, str]]] = {}
    for row in _csv(path):
        groups.setdefault(row["retrain"], []).append(row)
    rows = []
    for rule, at in groups.items():
        helps = sum(r["diff_helps"] == "True" for r in at)
        comp = sum(r["compensation_helps"] == "True" for r in at)
        q1, median, q3 = _quartiles([float(r["gain_um"]) for r in at])
        _, best, _ = _quartiles([float(r["best_model_rms_um"]) for r in at])
        _, none, _ = _quartiles([float(r["uncompensated_rms_um"]) for r in at])
        rows.append([rule, _share(helps, len(at)), f"{median:.2f}", f"{q1:.2f} to {q3:.2f}",
                     _share(comp, len(at)), f"{best:.2f}", f"{none:.2f}"])
    return markdown_table(["retrain", "machines where six_diff beats the raw groups",
                           "median gain (µm)", "gain IQR (µm)",
                           "machines where compensation beats none",
                           "median residual RMS, best model (µm)",
                           "median uncompensated RMS (µm)"], rows)


def compensation_default_table(path: Path, key: str | None = None) -> str:
    rows = [r for r in _csv(path) if r["part"] == "all days"]
    return markdown_table(["retrain", "model", "days", "RMS (µm)", "worst daily RMS (µm)",
                           "peak (µm)", "within tolerance"],
                          [[r["retrain"], f"`{r['model']}`", r["days"], _um(r["rms_um"]),
                            _um(r["worst_daily_rms_um"]), _um(r["peak_um"]),
                            f"{100.0 * float(r['within_tolerance']):.0f} %"] for r in rows])


def placement_methods_table(path: Path, key: str | None = None) -> str:
    """Mean held-out RMSE (worst test run in brackets) per method and budget, on the nodes
    alone (``key`` ``raw``) or with their differences (``diff``: the ``+diff`` labels)."""
    if key not in ("raw", "diff"):
        raise ValueError(f"{path}: the placement-methods table needs raw or diff, not {key!r}")
    rows = [r for r in _csv(path) if (r["differences"] == "True") == (key == "diff")
            and r["test_mean_rmse_um"] not in ("", "nan")]
    methods = list(dict.fromkeys(r["method"] for r in rows))
    budgets = sorted({int(r["m"]) for r in rows})
    score = {(r["method"], int(r["m"])): r for r in rows}

    def cell(method: str, m: int) -> str:
        row = score.get((method, m))
        if row is None:
            return "—"
        return f"{_um(row['test_mean_rmse_um'])} ({float(row['test_worst_rmse_um']):.1f})"

    return markdown_table(["method", *[f"m = {m}" for m in budgets]],
                          [[method, *[cell(method, m) for m in budgets]] for method in methods])


def _month_cells(path: Path) -> tuple[list[str], dict[tuple[str, str, str], dict[str, str]]]:
    rows = _csv(path)
    models = list(dict.fromkeys(r["model"] for r in rows))
    models = [m for m in models if m != "uncompensated"] + \
        [m for m in models if m == "uncompensated"]
    return models, {(r["retrain"], r["part"], r["model"]): r for r in rows}


def _month_cell(row: dict[str, str] | None) -> str:
    if row is None:
        return "—"
    return (f"{float(row['rms_um']):.1f} / {float(row['peak_um']):.1f} / "
            f"{100.0 * float(row['within_tolerance']):.0f} %")


#: The month table's columns: (retrain, part, header); the last one shows the RMS only.
MONTH_COLUMNS = (("never", "healthy days", "healthy days, never retrained"),
                 ("never", "fault days", "fault days, never retrained"),
                 ("after-fault", "fault days", "fault days, retrained after the fault"),
                 ("weekly", "fault days", "fault days, retrained weekly"),
                 ("weekly", "healthy days", "healthy days, retrained weekly: RMS"))


def compensation_month_table(path: Path, key: str | None = None) -> str:
    """Residual RMS / peak (µm) / time within tolerance per model, on healthy and fault days
    under each retraining rule, from a month's ``summary.csv``."""
    models, cells = _month_cells(path)
    body = []
    for model in models:
        line: list[Any] = [f"`{model}`" if model != "uncompensated" else model]
        for index, (rule, part, _) in enumerate(MONTH_COLUMNS):
            row = cells.get((rule, part, model))
            line.append(_month_cell(row) if index < len(MONTH_COLUMNS) - 1 else
                        ("—" if row is None else f"{float(row['rms_um']):.1f}"))
        body.append(line)
    return markdown_table(["model", *[header for _, _, header in MONTH_COLUMNS]], body)


def compensation_month_short_table(path: Path, key: str | None = None) -> str:
    """The month's residual RMS (µm) only: healthy days, and fault days never retrained or
    retrained after the fault (the overview on docs/studies.md)."""
    models, cells = _month_cells(path)
    columns = (("never", "healthy days"), ("never", "fault days"), ("after-fault", "fault days"))
    return markdown_table(
        ["model (k = 3)", "healthy days", "T1 stuck, never retrained",
         "T1 stuck, retrained after detection"],
        [[f"`{model}`" if model != "uncompensated" else model,
          *["—" if (row := cells.get((rule, part, model))) is None else
            f"{float(row['rms_um']):.1f}" for rule, part in columns]] for model in models])


STUDY_TABLES: dict[str, Callable[[Path, Any], str]] = {
    "placement-population": placement_population_table,
    "placement-default": placement_default_table,
    "compensation-population": compensation_population_table,
    "compensation-default": compensation_default_table,
    "placement-year": placement_default_table,
    "placement-year-af": placement_default_table,
    "placement-methods": placement_methods_table,
    "compensation-month": compensation_month_table,
    "compensation-month-short": compensation_month_short_table,
    "compensation-month-cold": compensation_month_table,
}


def study_provenance(path: Path, source: str, by: str) -> str:
    record = _read_json(path.parent / "provenance.json") or {}
    study = record.get("study")
    study = study.get("path") if isinstance(study, dict) else study
    versions = record.get("package_versions", {})
    return (f"From `{source}`, written by `{STUDY_COMMANDS[by]}` (study `{study}`, "
            f"spindlebench {versions.get('spindlebench', '?')})")


def study_section(by: str, sources: Sources, key: str | None = None) -> str:
    path = study_file(by, sources)
    if path is None:
        return placeholder(f"The {by} table", STUDY_COMMANDS[by])
    source = sources.name(path)
    text = block(by, source, key, study_provenance(path, source, by),
                 STUDY_TABLES[by](path, key))
    if by == "placement-population":
        text += "\n" + placement_verdict(path) + "\n"
    return text


def placement_verdict(path: Path) -> str:
    """The population's verdict in one generated sentence (from the same CSV)."""
    rows = [r for r in _csv(path) if r["gain_um"] not in ("", "nan")]
    machines: dict[str, bool] = {}
    for r in rows:
        machines[r["machine"]] = machines.get(r["machine"], True) and r["diff_helps"] == "True"
    helps = sum(r["diff_helps"] == "True" for r in rows)
    return (f"Over every method and budget the differences help in {_share(helps, len(rows))} "
            f"machine × method × budget cases, and at every method and budget on "
            f"{_share(sum(machines.values()), len(machines))} machines.")


# --------------------------------------------------------------------------- make run's studies

RUN_COMMAND = "make run"
#: Paper-comparison folders under results/ and what writes each: ``make run`` (``spindlebench
#: demo --out results``) the first two.
RUN_FOLDERS = {
    "paper_study": RUN_COMMAND,
    "caiviac_study": RUN_COMMAND,
    "ambient_following_study": "spindlebench simulate scenarios/paper -o "
                               "results/ambient_following --machine ambient-following; "
                               "spindlebench paper --recordings results/ambient_following "
                               "--out results/ambient_following_study",
    "caiviac_cycle_study": "spindlebench adapt caiviac --phase cycle --out results/caiviac_cycle; "
                           "spindlebench paper --recordings results/caiviac_cycle --config "
                           "results/caiviac_cycle/paper_study.toml --out "
                           "results/caiviac_cycle_study",
    "caiviac_methods": "spindlebench adapt caiviac --out results/caiviac; spindlebench paper "
                       "--recordings results/caiviac --out results/caiviac_methods --methods all",
}
GROUPS = (("all_raw", "all raw"), ("six_raw", "six raw"), ("six_diff", "six + differences"))


def run_file(name: str, sources: Sources) -> Path | None:
    """``results/<name>`` if ``make run`` wrote it in this checkout, else its committed copy
    under ``docs/snapshots/<name>`` (``name``: ``paper_study/table6.md``)."""
    if name.split("/", 1)[0] not in RUN_FOLDERS:
        raise ValueError(f"{name}: not in a paper-comparison folder ({', '.join(RUN_FOLDERS)})")
    for base in (sources.results, sources.snapshots):
        if (base / name).is_file():
            return base / name
    return None


def run_provenance(path: Path, source: str) -> str:
    record = _read_json(path.parent / "provenance.json") or {}
    versions = record.get("package_versions", {})
    command = RUN_FOLDERS[path.parent.name]
    shown = f"`{command}` (`{record.get('command', '?')}`" if command == RUN_COMMAND else \
        f"`{command}` (its last step"
    return (f"From `{source}`, written by {shown}, spindlebench "
            f"{versions.get('spindlebench', '?')})")


def file_table(path: Path, key: str | None = None) -> str:
    """The ``key``-th (1 by default) Markdown table of a file a command wrote, as written."""
    found = tables(path.read_text(encoding="utf-8"))
    index = int(key or 1)
    if not 1 <= index <= len(found):
        raise ValueError(f"{path}: has {len(found)} tables, not a table number {index}")
    return found[index - 1][2]


def paper_summary_table(path: Path, key: str | None = None) -> str:
    """Mean RMSE per k and group from a paper study's ``table6_rmse.csv`` (and the paper's
    printed means, when the study predicts its experiments)."""
    rows = _csv(path)
    mean = {(r["clusters"], r["group"]): r["mean"] for r in rows}
    paper = {(r["clusters"], r["group"]): r.get("paper_mean") for r in rows}
    header = ["k", *[label for _, label in GROUPS]]
    with_paper = any(v not in (None, "", "nan") for v in paper.values())
    if with_paper:
        header.append("paper: " + " / ".join(label for _, label in GROUPS))
    body = []
    for k in dict.fromkeys(r["clusters"] for r in rows):
        line = [k, *[_um1(mean.get((k, g))) for g, _ in GROUPS]]
        if with_paper:
            line.append(" / ".join(_um1(paper.get((k, g))) for g, _ in GROUPS))
        body.append(line)
    return markdown_table(header, body)


def _um1(text: str | None) -> str:
    return "—" if text in (None, "", "nan") else f"{float(text):.1f}"


RUN_TABLES: dict[str, Callable[[Path, Any], str]] = {
    "run-table": file_table,
    "paper-summary": paper_summary_table,
}


def run_section(by: str, key: str | None, sources: Sources) -> str:
    """``run-table FOLDER/FILE[@N]``: the N-th table of that file; ``paper-summary FOLDER``:
    the mean RMSE table of ``FOLDER/table6_rmse.csv``."""
    if key is None:
        raise ValueError(f"<!-- generate: {by} -->: needs a file (e.g. paper_study/table6.md)")
    name, _, number = key.partition("@")
    if by == "paper-summary":
        name = f"{name}/table6_rmse.csv"
    path = run_file(name, sources)
    if path is None:
        return placeholder(f"`results/{name}`", RUN_FOLDERS[name.split("/", 1)[0]])
    source = sources.name(path)
    return block(by, source, number or None, run_provenance(path, source),
                 RUN_TABLES[by](path, number or None))


SENSITIVITY = "caiviac_sensitivity"
SENSITIVITY_COMMAND = ("spindlebench paper --recordings DIR --config DIR/paper_study.toml "
                       "--train RUN --tests OTHERS --out results/caiviac_sensitivity/PHASE/"
                       "train_RUN, for each constant-speed RUN (docs/validation.md)")


def sensitivity_folder(phase: str, sources: Sources) -> Path | None:
    """``results/caiviac_sensitivity/<phase>`` with its ``train_*`` runs, else its snapshot."""
    for base in (sources.results, sources.snapshots):
        if any((base / SENSITIVITY / phase).glob("train_*/table6_rmse.csv")):
            return base / SENSITIVITY / phase
    return None


def sensitivity_table(folder: Path, key: str | None = None) -> str:
    """One row per training run (``train_<run>/``): its six sensors and the mean RMSE over the
    other runs of each k and group; last, their average over the training runs."""
    import numpy as np

    header, body, columns = ["training run", "six (auto)"], [], None
    for run in sorted(folder.glob("train_*/table6_rmse.csv")):
        rows = _csv(run)
        keys = [(r["clusters"], r["group"]) for r in rows]
        if columns is None:
            columns = keys
            header += [f"k={k} {g}" for k, g in keys]
        mean = {(r["clusters"], r["group"]): float(r["mean"]) for r in rows}
        six = (_read_json(run.parent / "provenance.json") or {}).get("six", [])
        body.append([run.parent.name.removeprefix("train_"),
                     ", ".join(s.removesuffix("_C") for s in six),
                     *[mean.get(c, float("nan")) for c in columns]])
    average = ["**mean over training runs**", "",
               *[float(np.mean([row[2 + i] for row in body])) for i in range(len(columns))]]
    return markdown_table(header, [[*row[:2], *(f"{v:.1f}" for v in row[2:])]
                                   for row in [*body, average]])


def sensitivity_section(phase: str | None, sources: Sources) -> str:
    if phase is None:
        raise ValueError("<!-- generate: sensitivity -->: needs the phase (heating, cycle)")
    folder = sensitivity_folder(phase, sources)
    if folder is None:
        return placeholder(f"`results/{SENSITIVITY}/{phase}/`", SENSITIVITY_COMMAND)
    source = sources.name(folder)
    first = sorted(folder.glob("train_*/provenance.json"))
    versions = (_read_json(first[0]) or {}).get("package_versions", {}) if first else {}
    provenance = (f"From `{source}/train_*/table6_rmse.csv` (the `mean` column) and each "
                  f"run's `provenance.json` (the six), written by `spindlebench paper` for each "
                  f"training run, spindlebench {versions.get('spindlebench', '?')}")
    return block("sensitivity", source, None, provenance, sensitivity_table(folder))


FINGERPRINTS = "fingerprint"
FINGERPRINT_COMMAND = "spindlebench fingerprint RECORDINGS --json results/fingerprint/NAME.json"


def fingerprint_folder(sources: Sources) -> Path | None:
    """``results/fingerprint/`` (``fingerprint --json`` files) if there are any, else the
    committed copies under ``docs/snapshots/fingerprint/``."""
    for base in (sources.results, sources.snapshots):
        if any((base / FINGERPRINTS).glob("*.json")):
            return base / FINGERPRINTS
    return None


def fingerprint_medians_table(folder: Path, key: str | None) -> str:
    """The default machine's median (the reference of the first file), then the median of each
    named file (``key``: ``ambient_following,caiviac``), statistic by statistic."""
    from spindlebench.studies.fingerprint.statistics import KEYS

    names = (key or "").split(",")
    documents = [json.loads((folder / f"{n}.json").read_text(encoding="utf-8")) for n in names]
    reference = documents[0]["reference"]
    header = ["statistic", f"{reference['label']} (median of {len(reference['recordings'])})",
              *[f"`{n}` (median of {len(d['recordings'])})" for n, d in zip(names, documents,
                                                                           strict=True)]]
    return markdown_table(header, [[k, f"{reference['median'][k]:.3f}",
                                    *[f"{d['median'][k]:.3f}" for d in documents]]
                                   for k in KEYS])


def fingerprint_section(key: str | None, sources: Sources) -> str:
    if not key:
        raise ValueError("<!-- generate: fingerprint-medians -->: needs the files "
                         "(e.g. ambient_following,caiviac)")
    folder = fingerprint_folder(sources)
    if folder is None or not all((folder / f"{n}.json").is_file() for n in key.split(",")):
        return placeholder("The fingerprint medians", FINGERPRINT_COMMAND)
    source = sources.name(folder)
    first = _read_json(folder / f"{key.split(',')[0]}.json") or {}
    versions = first.get("provenance", {}).get("package_versions", {})
    provenance = (f"From `{source}/{{{key}}}.json`, written by `{FINGERPRINT_COMMAND}` "
                  f"(spindlebench {versions.get('spindlebench', '?')}; each file's provenance "
                  "names its recordings and their sha256)")
    return block("fingerprint-medians", source, key, provenance,
                 fingerprint_medians_table(folder, key))


# --------------------------------------------------------------------------- season sweeps

#: Sweep folders under results/ and the command that writes each (the page names it too).
SWEEP_FOLDERS = {
    "season-sweep": "spindlebench sweep scenarios/studies/season_sweep.toml "
                    "-o results/season-sweep --workers 1",
    "season-sweep-methods": "spindlebench sweep scenarios/studies/season_sweep_methods.toml "
                            "-o results/season-sweep-methods --workers 1",
    "af-sweep": "spindlebench sweep scenarios/studies/season_sweep.toml -o results/af-sweep "
                "--machine ambient-following --workers 1",
}
SWEEP_FILE = "summary/by_method.csv"
#: The groups table's columns: (method in by_method.csv, header).
SWEEP_GROUPS = (("all_raw", "all_raw"), ("six_raw", "six_raw"), ("six_diff", "six_diff"),
                ("top-k-correlated", "top-k-correlated"), ("ridge", "ridge (no k)"),
                ("oracle", "oracle floor"))
PAPER_GROUPS = ("all_raw", "six_raw", "six_diff")


def sweep_file(folder: str, sources: Sources) -> Path | None:
    """``results/<folder>/summary/by_method.csv`` if the sweep was run in this checkout, else
    its committed copy under ``docs/snapshots/<folder>/``."""
    if folder not in SWEEP_FOLDERS:
        raise ValueError(f"{folder}: not a sweep folder ({', '.join(SWEEP_FOLDERS)})")
    for base in (sources.results, sources.snapshots):
        if (base / folder / SWEEP_FILE).is_file():
            return base / folder / SWEEP_FILE
    return None


def _measured(path: Path) -> dict[tuple[str, str], dict[str, str]]:
    """by_method.csv's measured rows by (method, k); k is '' for ridge and the oracle."""
    return {(r["method"], r["k"].removesuffix(".0")): r for r in _csv(path)
            if r["data"] == "measured"}


def _ks(rows: Mapping[tuple[str, str], Any]) -> list[str]:
    return sorted({k for _, k in rows if k}, key=int)


def sweep_groups_table(path: Path, key: str | None = None) -> str:
    """Median held-out RMSE (µm) of the measured data per k: the paper's three groups, the two
    baselines and the oracle floor (``key`` ``iqr``: with the IQR in brackets and the lowest
    of the paper's three groups in bold)."""
    rows = _measured(path)
    body = []
    for index, k in enumerate(_ks(rows)):
        best = min((float(rows[(g, k)]["median_um"]), g) for g in PAPER_GROUPS
                   if (g, k) in rows)[1] if key == "iqr" else None
        line: list[Any] = [k]
        for method, _ in SWEEP_GROUPS:
            row = rows.get((method, k)) or (rows.get((method, "")) if index == 0 else None)
            if row is None:
                line.append("")
                continue
            cell = _um(row["median_um"])
            if key == "iqr":
                cell = (f"**{cell}**" if method == best else cell) + f" ({_um(row['iqr_um'])})"
            line.append(cell)
        body.append(line)
    return markdown_table(["k", *[header for _, header in SWEEP_GROUPS]], body)


def sweep_methods_table(path: Path, key: str | None = None) -> str:
    """Median / IQR / worst held-out RMSE (µm) of every method on one group's candidates
    (``key``: ``all_raw``, ``six_raw`` or ``six_diff``; methods ``GROUP:METHOD``, and the
    paper's max-min closure, the bare ``GROUP``, as ``closure``), per k."""
    if key is None:
        raise ValueError(f"{path}: the methods table needs a group (all_raw, six_raw, six_diff)")
    rows = _measured(path)
    methods = list(dict.fromkeys(m.split(":", 1)[1] for m, _ in rows
                                 if m.startswith(f"{key}:")))
    if not methods:
        raise ValueError(f"{path}: no methods on the {key} candidates")
    ks = _ks(rows)
    if any((key, k) in rows for k in ks):
        methods.insert(0, "closure")

    def cell(method: str, k: str) -> str:
        row = rows.get((key if method == "closure" else f"{key}:{method}", k))
        if row is None:
            return "—"
        return (f"{_um(row['median_um'])} / {_um(row['iqr_um'])} / "
                f"{float(row['worst_um']):.1f}")

    return markdown_table(["method", *[f"k = {k}" for k in ks]],
                          [[m, *[cell(m, k) for k in ks]] for m in methods])


SWEEP_TABLES: dict[str, Callable[[Path, Any], str]] = {
    "sweep-groups": sweep_groups_table,
    "sweep-methods": sweep_methods_table,
}


def sweep_provenance(path: Path, source: str, folder: str) -> str:
    record = _read_json(path.parent.parent / "provenance.json") or {}
    fmu = record.get("fmu") or {}
    machine = record.get("machine") or {}
    machine = machine.get("name", "?") if isinstance(machine, dict) else machine
    versions = record.get("package_versions", {})
    return (f"From `{source}`, written by `{SWEEP_FOLDERS[folder]}` (machine `{machine}`, "
            f"FMU sha256 {str(fmu.get('sha256', '?'))[:12]}, spindlebench "
            f"{versions.get('spindlebench', '?')})")


def sweep_section(by: str, key: str | None, sources: Sources) -> str:
    """``sweep-groups FOLDER[@iqr]`` or ``sweep-methods FOLDER@GROUP``."""
    if key is None:
        raise ValueError(f"<!-- generate: {by} -->: needs a sweep folder (e.g. season-sweep)")
    folder, _, option = key.partition("@")
    path = sweep_file(folder, sources)
    if path is None:
        return placeholder(f"`results/{folder}/{SWEEP_FILE}`", SWEEP_FOLDERS[folder])
    source = sources.name(path)
    return block(by, source, option or None, sweep_provenance(path, source, folder),
                 SWEEP_TABLES[by](path, option or None))


# --------------------------------------------------------------------------- several targets

#: Multi-target compensation folders under results/ and the command that writes each.
TARGET_FOLDERS = {
    "tiny-compensate-five-probe": "spindlebench compensate "
                                  "scenarios/studies/tiny_compensate_five_probe.toml "
                                  "-o results/tiny-compensate-five-probe",
}


def targets_file(folder: str, sources: Sources) -> Path | None:
    """The folder's ``README.md`` (its side-by-side table of every target) in ``results/`` if
    the study was run here, else its committed copy under ``docs/snapshots/``."""
    if folder not in TARGET_FOLDERS:
        raise ValueError(f"{folder}: not a multi-target folder ({', '.join(TARGET_FOLDERS)})")
    for base in (sources.results, sources.snapshots):
        if (base / folder / "README.md").is_file():
            return base / folder / "README.md"
    return None


def compensation_targets_table(path: Path, key: str | None = None) -> str:
    """The residual RMS of every model and target under one retraining rule (``key``,
    ``after-fault`` by default): the rows of that rule from the README's first table, which
    ``compensate`` writes from each target's ``summary.csv``."""
    rule = key or "after-fault"
    found = tables(path.read_text(encoding="utf-8"))
    if not found:
        raise ValueError(f"{path}: has no table")
    lines = found[0][2].splitlines()
    header = [c.strip() for c in lines[0].strip("|").split("|")]
    if header[:2] != ["retrain", "model"]:
        raise ValueError(f"{path}: the first table is not the per-target residual table")
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in lines[2:]]
    kept = [row[1:] for row in rows if row[0] == rule]
    if not kept:
        raise ValueError(f"{path}: no rows retrained {rule!r}")
    return markdown_table(header[1:], kept)


def targets_section(key: str | None, sources: Sources) -> str:
    """``compensation-targets FOLDER[@RULE]``."""
    if key is None:
        raise ValueError("<!-- generate: compensation-targets -->: needs a folder")
    folder, _, rule = key.partition("@")
    path = targets_file(folder, sources)
    if path is None:
        return placeholder(f"`results/{folder}/README.md`", TARGET_FOLDERS[folder])
    source = sources.name(path)
    record = _read_json(path.parent / "drift_um" / "provenance.json") or {}
    fmu = record.get("fmu") or {}
    provenance = (f"From `{source}`, written by `{TARGET_FOLDERS[folder]}` (FMU sha256 "
                  f"{str(fmu.get('sha256', '?'))[:12]}, spindlebench "
                  f"{record.get('package_versions', {}).get('spindlebench', '?')})")
    return block("compensation-targets", source, rule or None, provenance,
                 compensation_targets_table(path, rule or None))


# --------------------------------------------------------------------------- ISO 230-3 reports

#: The two reports the comparison reads, folders under ``iso230-3/`` of results/ or the
#: snapshots, and what writes each (the commands docs/iso230-3.md names).
ISO_DEFAULT = "spindle"
ISO_RECORDING = "caiviac_spindle"
ISO_COMMANDS = {
    ISO_DEFAULT: "spindlebench iso230-3 spindle --machine default -o results/iso230-3/spindle",
    ISO_RECORDING: "spindlebench adapt caiviac --phase cycle --out results/iso230-3/"
                   "caiviac_cycles; spindlebench iso230-3 spindle --recording results/iso230-3/"
                   "caiviac_cycles/run3_3750rpm.csv --map results/iso230-3/caiviac_cycles/"
                   "iso230_3_map.toml -o results/iso230-3/caiviac_spindle",
}


def iso_file(test: str, sources: Sources) -> Path | None:
    """The default machine's ``TEST.json`` from results/ if both reports of the comparison
    were written here, else from the snapshot (both from one place, never mixed)."""
    for base in (sources.results, sources.snapshots):
        folder = base / "iso230-3"
        if all((folder / run / f"{test}.json").is_file()
               for run in (ISO_DEFAULT, ISO_RECORDING)):
            return folder / ISO_DEFAULT / f"{test}.json"
    return None


def _stability(report: Mapping[str, Any]) -> str:
    stability = report["stability"]
    if stability["met"]:
        verdict = f"met at {number(stability['met_at_h'])} h"
    else:
        verdict = f"not met in {number(stability['time_limit_h'])} h"
    alone = sorted(((h, d) for d, h in stability["per_direction_met_at_h"].items()
                    if h is not None))
    return verdict + " (alone: " + ", ".join(f"{d} {h:.1f} h" for h, d in alone) + ")"


def _hottest(report: Mapping[str, Any]) -> str:
    sensor, rise = max(report["temperature_range_K"].items(), key=lambda item: item[1])
    return f"{sensor} {rise:.1f} K"


def iso_comparison_table(path: Path, key: str | None = None) -> str:
    """The spindle-on phase of the default machine's report (``path``) beside the recording's
    (``../caiviac_spindle/`` next to it): ranges per direction and tilt (``heating_range_um``,
    ``heating_range_urad``), the largest temperature range, the stability criterion."""
    default = json.loads(path.read_text(encoding="utf-8"))
    recording = json.loads((path.parent.parent / ISO_RECORDING / path.name)
                           .read_text(encoding="utf-8"))
    end = number(default["spindle_on_end_h"])
    rows: list[list[Any]] = []
    for direction in ("X", "Y", "Z"):
        rows.append([f"{direction} range (µm)"] + [
            f"{report['heating_range_um'][direction]['range']:.1f} "
            f"({report['channels'][direction]})" for report in (default, recording)])
    for tilt in ("A", "B"):
        rows.append([f"tilt {tilt} range (µrad)"] + [
            f"{report['heating_range_urad'][tilt]['range']:.1f} "
            f"({report['channels'][tilt]})" for report in (default, recording)])
    rows.append(["largest temperature range over the test"] +
                [_hottest(report) for report in (default, recording)])
    rows.append(["stability criterion"] + [_stability(report) for report in (default,
                                                                             recording)])
    return markdown_table([f"spindle-on phase (0–{end} h)", f"default machine "
                           f"({default['provenance'].get('machine', '?')})",
                           f"recording {Path(recording['provenance']['recording']['path']).name}"],
                          rows)


def iso_section(by: str, key: str | None, sources: Sources) -> str:
    test = key or "spindle"
    path = iso_file(test, sources)
    if path is None:
        return placeholder(f"The {by} table", "; ".join(ISO_COMMANDS.values()))
    source = sources.name(path)
    recording = sources.name(path.parent.parent / ISO_RECORDING / path.name)
    fmu = json.loads(path.read_text(encoding="utf-8"))["provenance"].get("fmu", {})
    provenance = (f"From `{source}` and `{recording}`, written by `{ISO_COMMANDS[ISO_DEFAULT]}` "
                  f"(FMU sha256 {str(fmu.get('sha256', '?'))[:12]}) and "
                  f"`{ISO_COMMANDS[ISO_RECORDING]}`")
    return block(by, source, test, provenance, iso_comparison_table(path, test))


#: Multi-target evaluations (``spindlebench evaluate ... --target A B ... --json F``) the page
#: reads, files under ``iso230-3/`` of results/ or the snapshots: name -> the command.
_CAIVIAC_EVALUATE = (
    "spindlebench evaluate --train results/iso230-3/caiviac_cycles/run4_5000rpm.csv --test "
    + " ".join(f"results/iso230-3/caiviac_cycles/{run}.csv" for run in (
        "run1_1250rpm", "run2_2500rpm", "run3_3750rpm", "run5_3500rpm", "run6_stepped"))
    + " --target ch1_um ch2_um ch3_um ch4_um ch5_um --clusters 3")
_PROBES_EVALUATE = (
    "spindlebench evaluate --train results/iso230-3/probes_rec/exp1.csv --test "
    + " ".join(f"results/iso230-3/probes_rec/exp{i}.csv" for i in (2, 3, 4, 5))
    + " --target drift_um drift_x_um drift_y_um tilt_a_urad tilt_b_urad --clusters 3")
ISO_EVALUATIONS = {
    "probes_targets_raw": _PROBES_EVALUATE + " --json results/iso230-3/probes_targets_raw.json",
    "probes_targets_diff": _PROBES_EVALUATE + " --differences --json "
                           "results/iso230-3/probes_targets_diff.json",
    "caiviac_targets_raw": _CAIVIAC_EVALUATE + " --json results/iso230-3/caiviac_targets_raw.json",
    "caiviac_targets_diff": _CAIVIAC_EVALUATE + " --differences --json "
                            "results/iso230-3/caiviac_targets_diff.json",
}


def iso_targets_table(path: Path, key: str | None = None) -> str:
    """Mean RMSE per target over the test recordings: each target's own selection (its
    sensors together) and every joint selection, as ``evaluate --json`` holds them."""
    document = json.loads(path.read_text(encoding="utf-8"))
    targets = document["targets"]

    def sensors(names: list[str]) -> str:
        short = ", ".join(name.removesuffix("_C") for name in names)
        return f"{len(names)} ({short})" if len(names) <= 4 else str(len(names))

    rows: list[list[Any]] = [["per-target", sensors(document["per_target_sensors"])] +
                             [f"{document['per_target'][t]['mean_rmse_um']:.2f}"
                              for t in targets]]
    for name, joint in document["joint"].items():
        rows.append([name, sensors(joint["sensors"])] +
                    [f"{joint['mean_rmse'][t]:.2f}" for t in targets])
    return markdown_table(["selection", "sensors", *targets], rows)


def iso_targets_section(by: str, key: str | None, sources: Sources) -> str:
    if key not in ISO_EVALUATIONS:
        raise ValueError(f"<!-- generate: {by} {key} -->: no such evaluation (have: "
                         f"{', '.join(ISO_EVALUATIONS)})")
    path = next((base / "iso230-3" / f"{key}.json" for base in (sources.results,
                 sources.snapshots) if (base / "iso230-3" / f"{key}.json").is_file()), None)
    if path is None:
        return placeholder(f"The {by} {key} table", ISO_EVALUATIONS[key])
    source = sources.name(path)
    provenance = (f"From `{source}`, written by `{ISO_EVALUATIONS[key]}`; mean RMSE over "
                  "the test recordings, each target in its own unit (µm, tilts µrad)")
    return block(by, source, key, provenance, iso_targets_table(path, key))


#: The default machine's four reports the ISO page describes (``iso230-3-report TEST``, or
#: ``TEST@steps`` for the speed spectrum's steps), each ``iso230-3/TEST/TEST.json``.
ISO_REPORTS = ("spindle", "spectrum", "etve", "axis")


def iso_report_file(test: str, sources: Sources) -> Path | None:
    return _results_or_snapshot(f"iso230-3/{test}/{test}.json", sources)


def _iso_rows(report: Mapping[str, Any], unit: str) -> list[list[Any]]:
    whole = report[f"range_{unit}"]
    heating = report.get(f"heating_range_{unit}")
    etve = report.get(f"etve_{unit}")
    label = "µm" if unit == "um" else "µrad"
    rows = []
    for channel, r in whole.items():
        row = [f"{channel} ({label})", f"{r['range']:.1f}",
               f"{r['max']:.1f} at {r['at_max_h']:.1f} h", f"{r['min']:.1f}", f"{r['final']:.1f}"]
        if heating is not None:
            row.append(f"{heating[channel]['range']:.1f}")
        if etve is not None:
            row.append(f"{etve[channel]:.1f}")
        rows.append(row)
    return rows


def iso_report_table(path: Path, key: str | None = None) -> str:
    """One report of the default machine: per direction and tilt, the whole test's range, its
    maximum and when, minimum and final value (``range_um``, ``range_urad``), with the
    spindle-on phase's range (``heating_range_*``) or the ETVE (``etve_*``) where the test has
    them; ``TEST@steps``: the speed spectrum's value at the end of each speed step."""
    report = json.loads(path.read_text(encoding="utf-8"))
    if key is not None and key.endswith("@steps"):
        channels = [*report["steps"][0]["end_um"], *report["steps"][0]["end_urad"]]
        return markdown_table(
            ["speed (rpm)", "from–to (h)", *[f"{c} at the end ({'µrad' if c in 'AB' else 'µm'})"
                                              for c in channels]],
            [[f"{st['speed_rpm']:g}", f"{st['from_h']:.2f}–{st['to_h']:.2f}",
              *[f"{v:.1f}" for v in [*st["end_um"].values(), *st["end_urad"].values()]]]
             for st in report["steps"]])
    header = ["channel", "range", "max (when)", "min", "final"]
    if "heating_range_um" in report:
        header.append(f"range, spindle on (0–{report['spindle_on_end_h']:g} h)")
    if "etve_um" in report:
        header.append("ETVE")
    return markdown_table(header, _iso_rows(report, "um") + _iso_rows(report, "urad"))


def iso_report_section(key: str | None, sources: Sources) -> str:
    test = (key or "").split("@")[0]
    if test not in ISO_REPORTS:
        raise ValueError(f"<!-- generate: iso230-3-report {key} -->: no such test (have: "
                         f"{', '.join(ISO_REPORTS)})")
    command = f"spindlebench iso230-3 {test} --machine default -o results/iso230-3/{test}"
    path = iso_report_file(test, sources)
    if path is None:
        return placeholder(f"The {test} report table", command)
    source = sources.name(path)
    fmu = json.loads(path.read_text(encoding="utf-8"))["provenance"].get("fmu", {})
    provenance = (f"From `{source}`, written by `{command}` (FMU sha256 "
                  f"{str(fmu.get('sha256', '?'))[:12]}); values in µm and µrad, times in h "
                  "from the test's start")
    return block("iso230-3-report", source, key, provenance, iso_report_table(path, key))


ISO_TABLES: dict[str, Callable[[Path, Any], str]] = {
    "iso230-3-comparison": iso_comparison_table,
    "iso230-3-report": iso_report_table,
    "iso230-3-targets": iso_targets_table,
}


# --------------------------------------------------------------------------- identification

IDENTIFICATION = "caiviac_identification"
IDENTIFICATION_COMMAND = ("python -m spindlebench.identification.validation --splits SPLITS "
                          "--out results/caiviac_identification/NAME")


def identification_file(split: str, sources: Sources) -> Path | None:
    """The ``caiviac.json`` holding ``split`` (a letter): the first of
    ``results/caiviac_identification/*/caiviac.json`` (one folder per run, named by its splits),
    else of their snapshots under ``docs/snapshots/``."""
    for base in (sources.results, sources.snapshots):
        for path in sorted((base / IDENTIFICATION).glob("*/caiviac.json")):
            splits = (_read_json(path) or {}).get("splits", {})
            if any(n.split(":", 1)[0] == split for n in splits):
                return path
    return None


def identification_split_table(path: Path, key: str | None = None) -> str:
    """One CAIVIAC split of ``caiviac.json`` (``key``: its letter, ``C``), as the validation
    script prints it (``identification.validation.markdown``, without its heading)."""
    from spindlebench.identification.validation import markdown

    splits = json.loads(path.read_text(encoding="utf-8"))["splits"]
    name = next((n for n in splits if n.split(":", 1)[0] == key), None)
    if name is None:
        raise ValueError(f"{path}: has no split {key!r} (has {', '.join(splits)})")
    text = markdown(name, splits[name])
    return text[text.index("\n| model |") + 1:]


def identification_section(key: str | None, sources: Sources) -> str:
    if not key:
        raise ValueError("<!-- generate: identification-split -->: needs the split (e.g. C)")
    path = identification_file(key, sources)
    if path is None:
        return placeholder(f"The identification table of split {key}", IDENTIFICATION_COMMAND)
    source = sources.name(path)
    document = _read_json(path) or {}
    versions = document.get("provenance", {}).get("package_versions", {})
    command = IDENTIFICATION_COMMAND.replace("SPLITS", ",".join(
        n.split(":", 1)[0] for n in document.get("splits", {}))).replace("NAME",
                                                                        path.parent.name)
    provenance = (f"From `{source}`, written by `{command}` (spindlebench "
                  f"{versions.get('spindlebench', '?')}, its provenance names the recording "
                  "and its sha256)")
    return block("identification-split", source, key, provenance,
                 identification_split_table(path, key))


# --------------------------------------------------------------------------- model, benchmark

DISCRETISATION = "discretisation/discretisation.json"
DISCRETISATION_COMMAND = ("python -m spindlebench.model.discretisation --out "
                          f"results/{DISCRETISATION}")


def _results_or_snapshot(name: str, sources: Sources) -> Path | None:
    """``results/NAME`` where a command wrote it in this checkout, else its committed copy
    ``docs/snapshots/NAME``, else None."""
    return next((base / name for base in (sources.results, sources.snapshots)
                 if (base / name).is_file()), None)


def discretisation_table(path: Path, key: str | None = None) -> str:
    """The drift rise per segment count, as ``model.discretisation`` prints it."""
    from spindlebench.model.discretisation import markdown

    return markdown(json.loads(path.read_text(encoding="utf-8")))


def discretisation_section(sources: Sources) -> str:
    path = _results_or_snapshot(DISCRETISATION, sources)
    if path is None:
        return placeholder("The discretisation table", DISCRETISATION_COMMAND)
    from spindlebench.core.provenance import sha256_file

    source = sources.name(path)
    record = json.loads(path.read_text(encoding="utf-8"))["provenance"]
    model = record["model"]
    current = sources.root / model["path"]
    changed = "" if current.is_file() and sha256_file(current) == model["sha256"] else (
        f"; `{model['path']}` has changed since: rerun it")
    provenance = (f"From `{source}`, written by `{record['command']}` (`{model['path']}` "
                  f"sha256 {model['sha256'][:12]}{changed}; {record['ambient_C']:g} °C soak, "
                  f"{record['speed_rpm']:g} rpm, feed {record['feed_mm_per_min']:g} mm/min; "
                  f"{record['solver']}; spindlebench "
                  f"{record['package_versions'].get('spindlebench', '?')})")
    return block("discretisation", source, None, provenance, discretisation_table(path))


COLD_START = "cold_start/cold_start.json"
COLD_START_COMMAND = f"python -m spindlebench.model.cold_start --json results/{COLD_START}"


def cold_start_table(path: Path, key: str | None = None) -> str:
    """The cold-start runs' rises and the drift's peak, as ``model.cold_start`` prints them."""
    from spindlebench.model.cold_start import markdown

    return markdown(json.loads(path.read_text(encoding="utf-8")))


def cold_start_section(sources: Sources) -> str:
    path = _results_or_snapshot(COLD_START, sources)
    if path is None:
        return placeholder("The cold-start table", COLD_START_COMMAND)
    from spindlebench.core.provenance import sha256_file

    source = sources.name(path)
    record = json.loads(path.read_text(encoding="utf-8"))["provenance"]
    fmu = record["fmu"]["sha256"]
    changed = "" if sources.fmu.is_file() and sha256_file(sources.fmu) == fmu else (
        f"; `{sources.name(sources.fmu)}` has changed since: rerun it")
    provenance = (f"From `{source}`, written by `{record['command']}` (FMU sha256 {fmu[:12]}"
                  f"{changed}; {record['ambient_C']:g} °C soak, feed "
                  f"{record['feed_mm_per_min']:g} mm/min, {record['hours']:g} h; "
                  f"{record['solver']}; spindlebench "
                  f"{record['package_versions'].get('spindlebench', '?')})")
    return block("cold-start", source, None, provenance, cold_start_table(path))


#: Folders of ``evaluate --json`` runs that differ only in ``--clusters`` (one ``kN.json`` per
#: k), under results/ or docs/snapshots/: name -> the command (``K``: the budget).
EVALUATE_RUNS = {
    "caiviac-six-correlated": (
        "spindlebench evaluate --train results/caiviac/run4_5000rpm.csv --test "
        + " ".join(f"results/caiviac/{run}.csv" for run in (
            "run1_1250rpm", "run2_2500rpm", "run3_3750rpm", "run5_3500rpm", "run6_stepped"))
        + " --target ch3_um --sensors t1_C,t8_C,t2_C,t13_C,t7_C,t12_C --differences "
        "--clusters K --json results/caiviac-six-correlated/kK.json"),
}


def _evaluate_folder(name: str, sources: Sources) -> Path | None:
    return next((base / name for base in (sources.results, sources.snapshots)
                 if any((base / name).glob("k*.json"))), None)


def evaluate_runs_table(path: Path, key: str | None = None) -> str:
    """One row per ``kN.json`` of the folder ``path``: k, the selected terms, the RMSE on each
    test recording (its file's stem) and their mean, as ``evaluate`` prints them."""
    documents = [json.loads(p.read_text(encoding="utf-8")) for p in path.glob("k*.json")]
    documents.sort(key=lambda d: d["provenance"]["clusters"])
    tests = list(documents[0]["rmse_um"])
    rows = [[d["provenance"]["clusters"], ", ".join(f"`{t}`" for t in d["selected"]),
             *[f"{d['rmse_um'][t]:.2f}" for t in tests], f"**{d['mean_rmse_um']:.2f}**"]
            for d in documents]
    return markdown_table(["k", "selected", *[Path(t).stem for t in tests], "mean"], rows)


def evaluate_runs_section(key: str | None, sources: Sources) -> str:
    if key not in EVALUATE_RUNS:
        raise ValueError(f"<!-- generate: evaluate-runs {key} -->: no such folder (have: "
                         f"{', '.join(EVALUATE_RUNS)})")
    folder = _evaluate_folder(key, sources)
    if folder is None:
        return placeholder(f"The evaluate-runs {key} table", EVALUATE_RUNS[key])
    source = sources.name(folder)
    first = json.loads(sorted(folder.glob("k*.json"))[0].read_text(encoding="utf-8"))
    record = first["provenance"]
    provenance = (f"From `{source}/k*.json`, written by `{EVALUATE_RUNS[key]}` for each k "
                  f"(training file sha256 {record['train']['sha256'][:12]}; RMSE in µm of "
                  f"`{record['target']}` on each test run; spindlebench "
                  f"{record['package_versions'].get('spindlebench', '?')})")
    return block("evaluate-runs", source, key, provenance, evaluate_runs_table(folder))


#: The leaderboard run the benchmark page shows (folder under results/ or docs/snapshots/).
LEADERBOARD_RUN = "benchmark/mine"
LEADERBOARD_COMMAND = ("PYTHONPATH=docs/examples/user-method spindlebench benchmark --method "
                       "my_selector:DecorrelatedSelector -o results/benchmark/mine")


def leaderboard_table(path: Path, key: str | None = None) -> str:
    """One table of a ``leaderboard.json``: ``overall`` or a task's (the key is its name), as
    ``leaderboard.md`` has it (``studies.benchmark.benchmark_report``)."""
    from spindlebench.studies.benchmark import benchmark_report

    document = json.loads(path.read_text(encoding="utf-8"))
    if key == "overall":
        return benchmark_report.overall_table(document["overall"])
    return benchmark_report.task_table(document["rows"], str(key),
                                       document["suite"]["band_um"])


def leaderboard_section(key: str | None, sources: Sources) -> str:
    """``<!-- generate: leaderboard FOLDER -->``: the run's suite and command, then the overall
    table and one table per task under a heading of its own, each with its marker."""
    folder = key or LEADERBOARD_RUN
    path = _results_or_snapshot(f"{folder}/leaderboard.json", sources)
    if path is None:
        return placeholder(f"The leaderboard of `{folder}`", LEADERBOARD_COMMAND)
    from spindlebench.studies.benchmark import benchmark_report

    source = sources.name(path)
    document = json.loads(path.read_text(encoding="utf-8"))
    suite, record = document["suite"], document["provenance"]
    fmu = record.get("fmu_sha256")
    head = (f"*From `{source}`, written by `{record['command']}`: suite `{suite['name']}` "
            f"version {suite['version']}, tasks SHA-256 `{suite['tasks_sha256'][:12]}…`, "
            f"k = {suite['k']} sensors per selection method, seed {suite['seed']}, FMU sha256 "
            f"{str(fmu)[:12]}, spindlebench "
            f"{record['package_versions'].get('spindlebench', '?')}"
            + ("; a partial run (`--tasks`)" if record.get("partial") else "") + ".*\n\n"
            f"{benchmark_report.MARKS_TEXT}\n")
    parts = [head, "### Overall (mean rank over tasks)\n",
             block("leaderboard", source, "overall", "Mean rank over the tasks",
                   leaderboard_table(path, "overall"))]
    for task in benchmark_report.tasks_of(document["rows"]):
        parts += [f"### {task}\n", block("leaderboard", source, task, f"Task `{task}`",
                                         leaderboard_table(path, task))]
    return "\n".join(parts)
#: The twin page's other tables (``twin KEY``): key -> (file under ``results/twin/`` or
#: ``docs/snapshots/twin/``, the ``identification.validation`` function that renders it, and
#: the command that writes the file). ``summary`` reads every split's ``caiviac.json``.
TWIN = "twin"
TWIN_TABLES: dict[str, tuple[str, str, str]] = {
    "synthetic": ("synthetic.json", "synthetic_markdown",
                  "python -m spindlebench.identification.validation --synthetic DIR "
                  "--out results/twin"),
    "superposition": ("synthetic.json", "superposition_markdown",
                      "python -m spindlebench.identification.validation --synthetic DIR "
                      "--out results/twin"),
    "heat-path": ("synthetic.json", "superposition_markdown",
                  "python -m spindlebench.identification.validation --synthetic DIR "
                  "--out results/twin"),
    "evidence": ("evidence.json", "evidence_markdown",
                 "python -m spindlebench.identification.validation --evidence --out results/twin"),
    "room-proxy": ("room_proxy.json", "room_proxy_markdown",
                   "python -m spindlebench.identification.validation --room-proxy "
                   "--out results/twin"),
    "every-split": ("every_split.json", "every_split_markdown",
                    "python -m spindlebench.identification.validation --every-split "
                    "--out results/twin"),
    "evaluate": ("evaluate.json", "evaluate_markdown",
                 "python -m spindlebench.identification.validation --evaluate DIR "
                 "--out results/twin"),
}


def twin_file(key: str, sources: Sources) -> Path | None:
    """The file behind ``twin KEY`` (``KEY@RUN`` for ``evaluate``): from ``results/``, else
    its snapshot; ``summary``: the folder of the splits' ``caiviac.json`` files."""
    if key == "summary":
        for base in (sources.results, sources.snapshots):
            if list((base / IDENTIFICATION).glob("*/caiviac.json")):
                return base / IDENTIFICATION
        return None
    name = TWIN_TABLES[key.split("@", 1)[0]][0]
    for base in (sources.results, sources.snapshots):
        if (base / TWIN / name).is_file():
            return base / TWIN / name
    return None


def twin_table(path: Path, key: str | None = None) -> str:
    """``twin KEY``'s table from ``path``, rendered as the validation script prints it."""
    from spindlebench.identification import validation

    if key == "summary":
        splits: dict = {}
        for file in sorted(path.glob("*/caiviac.json")):
            splits.update(json.loads(file.read_text(encoding="utf-8"))["splits"])
        return validation.summary_markdown(dict(sorted(splits.items())))
    what, _, run = (key or "").partition("@")
    if what not in TWIN_TABLES:
        raise ValueError(f"twin {key!r}: no such table (have: summary, {', '.join(TWIN_TABLES)})")
    document = json.loads(path.read_text(encoding="utf-8"))
    render = getattr(validation, TWIN_TABLES[what][1])
    if what == "evaluate":
        text = render(document["runs"], run)
    elif what in ("superposition", "heat-path"):
        text = render(document["superposition"])
    elif what in ("room-proxy", "every-split"):
        text = render(document["splits"])
    else:
        text = render(document)
    # a script's printout may hold several tables (and a line of words) apart by blank
    # lines: each is its own generated table, so its marker stands right above it
    return text.split("\n\n")[1 if what == "heat-path" else 0]


def twin_section(key: str | None, sources: Sources) -> str:
    if not key:
        raise ValueError("<!-- generate: twin -->: needs the table (e.g. synthetic)")
    path = twin_file(key, sources)
    command = (IDENTIFICATION_COMMAND.replace("SPLITS NAME", "A,B AB").replace(
        "SPLITS", "A,B").replace("NAME", "AB") + "` and `--splits C,D --out .../CD") \
        if key == "summary" else TWIN_TABLES[key.split("@", 1)[0]][2]
    if path is None:
        return placeholder(f"The twin table {key}", command)
    source = sources.name(path)
    return block("twin", source, key, f"From `{source}`, written by `{command}`",
                 twin_table(path, key))


# --------------------------------------------------------------------------- calibration

CALIBRATION = "caiviac_calibration"
CALIBRATION_FILE = "caiviac_calibration.json"
#: RUNS_DIR: what ``spindlebench adapt caiviac --phase cycle --out RUNS_DIR`` writes.
CALIBRATION_COMMAND = "python -m spindlebench.calibration.validation RUNS_DIR --out docs/figures"
#: ``calibration KEY``: the tables of the CAIVIAC calibration's validation, each made by the
#: script's own function from the JSON it writes (``calibration.validation``).
CALIBRATION_KEYS = ("heldout", "variants", "runs")


def calibration_file(sources: Sources) -> Path | None:
    """``results/caiviac_calibration/caiviac_calibration.json``, else its snapshot."""
    return next((base / CALIBRATION / CALIBRATION_FILE for base in (sources.results,
                 sources.snapshots) if (base / CALIBRATION / CALIBRATION_FILE).is_file()), None)


def calibration_table(path: Path, key: str | None = None) -> str:
    """One table of the calibration validation's JSON (``key`` in ``CALIBRATION_KEYS``)."""
    from spindlebench.calibration import validation

    document = json.loads(path.read_text(encoding="utf-8"))
    makers = {"heldout": validation.heldout_table, "variants": validation.variants_table,
              "runs": validation.runs_table}
    if key not in makers:
        raise ValueError(f"<!-- generate: calibration {key} -->: no such table (have: "
                         f"{', '.join(CALIBRATION_KEYS)})")
    return makers[key](document)


def calibration_section(key: str | None, sources: Sources) -> str:
    if key not in CALIBRATION_KEYS:
        raise ValueError(f"<!-- generate: calibration {key} -->: no such table (have: "
                         f"{', '.join(CALIBRATION_KEYS)})")
    path = calibration_file(sources)
    if path is None:
        return placeholder(f"The calibration {key} table", CALIBRATION_COMMAND)
    source = sources.name(path)
    versions = (_read_json(path) or {}).get("provenance", {}).get("package_versions", {})
    provenance = (f"From `{source}`, written by `{CALIBRATION_COMMAND}` (spindlebench "
                  f"{versions.get('spindlebench', '?')}; its provenance names the recording, "
                  "each run and the model with their sha256)")
    return block("calibration", source, key, provenance, calibration_table(path, key))


# --------------------------------------------------------------------------- values in prose

#: One number of a sentence, read from a file a command wrote: ``<!-- value: FILE PATH
#: [FORMAT] -->`` (inline, anywhere in a line).
#:
#: - FILE: ``bench/...`` or ``docs/...`` (the checkout's), or a name under ``results/`` (its
#:   committed copy under ``docs/snapshots/`` where the command has not been run here); a JSON
#:   file, or a CSV file as its list of rows (numbers as floats, an empty cell None).
#: - PATH: the field, dot-separated: a key, a list's index, ``[KEY=VALUE]`` for the one item of
#:   a list whose KEY is VALUE (``rows.[hours=39.0].cpu_s``; ``[label=greedy,m=2]``: both),
#:   ``[KEY]`` for a key holding dots; the whole PATH in double quotes when a key has spaces
#:   (``"range_um.[X at 0.8 m].min"``).
#: - FORMAT: a Python format spec (``.1f``; ``-`` or none: ``number``).
#:
#: It becomes ``<!-- value from=FILE key=PATH format=FORMAT -->43.1<!-- /value -->``, which
#: ``tests/repo/test_docs_tables.py`` reads again from the file alone.
VALUE = re.compile(r'(?<!`)<!-- value: (\S+) ("[^"]+"|\S+)(?: (\S+))? -->')  # not in `code`
VALUE_OUT = re.compile(r'<!-- value from=(\S+) key=("[^"]+"|\S+) format=(\S+) -->(.*?)'
                       r"<!-- /value -->")


def value_file(name: str, sources: Sources) -> Path | None:
    """Where ``<!-- value: NAME ... -->`` reads: the checkout's file for ``bench/`` and
    ``docs/`` names, else ``results/NAME`` or its snapshot; None when there is none."""
    if name.startswith(("bench/", "docs/")):
        path = sources.bench / name.removeprefix("bench/results/") \
            if name.startswith("bench/results/") else sources.root / name
        return path if path.is_file() else None
    return _results_or_snapshot(name, sources)


def field_of(document: Any, key: str, where: str) -> Any:
    """The field ``key`` (dot-separated, see ``VALUE``) of a JSON document; a missing field
    is a one-line error naming the file and the key."""
    value = document
    key = key.strip('"')
    for part in re.findall(r"\[[^\]]*\]|[^.]+", key):
        selector = re.fullmatch(r"\[(\w+=[^\],]*(?:,\w+=[^\],]*)*)\]", part)
        literal = re.fullmatch(r"\[([^=\]]+)\]", part)
        part = literal.group(1) if literal else part
        if selector and isinstance(value, list):
            wanted = dict(c.split("=", 1) for c in selector.group(1).split(","))
            found = [item for item in value if isinstance(item, dict) and
                     all(_matches(item.get(k), v) for k, v in wanted.items())]
            if len(found) != 1:
                raise ValueError(f"{where}: {key}: {len(found)} items have {selector.group(1)}")
            value = found[0]
        elif isinstance(value, list) and re.fullmatch(r"-?\d+", part):
            try:
                value = value[int(part)]
            except IndexError:
                raise ValueError(f"{where}: {key}: no item {part}") from None
        elif isinstance(value, dict) and part in value:
            value = value[part]
        else:
            raise ValueError(f"{where}: {key}: no field {part!r}")
    if isinstance(value, dict | list) or value is None:
        raise ValueError(f"{where}: {key}: is not one value")
    return value


def _matches(value: Any, wanted: str) -> bool:
    """A selector's condition: the field's text, or the same number (``m=2`` finds 2.0)."""
    if str(value) == wanted:
        return True
    try:
        return float(value) == float(wanted)
    except (TypeError, ValueError):
        return False


def _cell(text: str) -> Any:
    try:
        return float(text)
    except ValueError:
        return text if text else None


def value_document(path: Path) -> Any:
    """A JSON file as parsed; a CSV file as its rows, numbers as floats, empty cells None."""
    text = path.read_text(encoding="utf-8")
    if path.suffix == ".csv":
        import csv
        import io

        return [{k: _cell(v) for k, v in row.items()} for row in csv.DictReader(io.StringIO(text))]
    return json.loads(text)


def formatted(value: Any, spec: str) -> str:
    return number(value) if spec == "-" else format(value, spec)


def value_text(path: Path, key: str, spec: str) -> str:
    """One value as a page shows it, read again from ``path`` (the check's entry point)."""
    return formatted(field_of(value_document(path), key, str(path)), spec)


def value_section(name: str, key: str, spec: str | None, sources: Sources) -> str:
    spec = spec or "-"
    path = value_file(name, sources)
    if path is None:
        return f"*(value: `{name}` is not in this build)*"
    source = sources.name(path)
    text = formatted(field_of(value_document(path), key, source), spec)
    return f"<!-- value from={source} key={key} format={spec} -->{text}<!-- /value -->"


def expand_values(markdown: str, sources: Sources) -> str:
    return VALUE.sub(lambda m: value_section(m.group(1), m.group(2), m.group(3), sources),
                     markdown)


# --------------------------------------------------------------------------- pages

def section(by: str, key: str | None, sources: Sources) -> str:
    """What a ``<!-- generate: BY KEY -->`` line becomes."""
    if by == "speed":
        return speed_section(sources)
    if by == "bench":
        return bench_section(key, sources)
    if by == "parameters":
        return parameters_section(sources)
    if by in MACHINE_TABLES:
        return machine_section(by, key, sources)
    if by in STUDY_TABLES:
        return study_section(by, sources, key)
    if by in RUN_TABLES:
        return run_section(by, key, sources)
    if by in SWEEP_TABLES:
        return sweep_section(by, key, sources)
    if by == "compensation-targets":
        return targets_section(key, sources)
    if by == "sensitivity":
        return sensitivity_section(key, sources)
    if by == "fingerprint-medians":
        return fingerprint_section(key, sources)
    if by == "iso230-3-targets":
        return iso_targets_section(by, key, sources)
    if by == "iso230-3-report":
        return iso_report_section(key, sources)
    if by in ISO_TABLES:
        return iso_section(by, key, sources)
    if by == "identification-split":
        return identification_section(key, sources)
    if by == TWIN:
        return twin_section(key, sources)
    if by == "discretisation":
        return discretisation_section(sources)
    if by == "cold-start":
        return cold_start_section(sources)
    if by == "evaluate-runs":
        return evaluate_runs_section(key, sources)
    if by == "leaderboard":
        return leaderboard_section(key, sources)
    if by == "calibration":
        return calibration_section(key, sources)
    raise ValueError(f"<!-- generate: {by} -->: no such table (have: speed, bench, parameters, "
                     f"{', '.join([*MACHINE_TABLES, *STUDY_TABLES, *RUN_TABLES, *SWEEP_TABLES])}, "
                     "sensitivity, fingerprint-medians, compensation-targets, "
                     f"{', '.join(ISO_TABLES)}, identification-split, discretisation, "
                     "cold-start, evaluate-runs, leaderboard, calibration, twin)")


def expand(markdown: str, sources: Sources | None = None) -> str:
    """Every ``<!-- generate: ... -->`` line of a page replaced by its table(s), and every
    inline ``<!-- value: ... -->`` by its value."""
    sources = sources or Sources()
    markdown = PLACEHOLDER.sub(lambda m: section(m.group(1), m.group(2), sources), markdown)
    return expand_values(markdown, sources)


def regenerate(by: str, source: str, key: str | None, sources: Sources | None = None) -> str:
    """The table a marker says was made by ``by`` from ``source`` (with ``key``), made again
    from that file alone (the check of ``tests/repo/test_docs_tables.py``)."""
    sources = sources or Sources()
    path = sources.path(source)
    if by == "bench":
        return bench_table(path, key)
    if by == "parameters":
        return parameters_table(path, sources.fmu)
    if by == "machine-parameters":
        return machine_parameters_table(path)
    if by in MACHINE_TABLES:
        return MACHINE_TABLES[by][0](json.loads(path.read_text(encoding="utf-8")), key)
    if by in RUN_TABLES:
        return RUN_TABLES[by](path, key)
    if by in SWEEP_TABLES:
        return SWEEP_TABLES[by](path, key)
    if by == "compensation-targets":
        return compensation_targets_table(path, key)
    if by == "sensitivity":
        return sensitivity_table(path, key)
    if by == "fingerprint-medians":
        return fingerprint_medians_table(path, key)
    if by in ISO_TABLES:
        return ISO_TABLES[by](path, key)
    if by == "identification-split":
        return identification_split_table(path, key)
    if by == "discretisation":
        return discretisation_table(path, key)
    if by == "cold-start":
        return cold_start_table(path, key)
    if by == "evaluate-runs":
        return evaluate_runs_table(path, key)
    if by == "leaderboard":
        return leaderboard_table(path, key)
    if by == "calibration":
        return calibration_table(path, key)
    if by == TWIN:
        return twin_table(path, key)
    return STUDY_TABLES[by](path, key)


def tables(markdown: str) -> list[tuple[re.Match | None, str, str]]:
    """Every Markdown table of a page: (its marker or None, its header line, its text)."""
    found = []
    lines = markdown.splitlines()
    i = 0
    while i < len(lines):
        if lines[i].startswith("|") and i + 1 < len(lines) and \
                re.match(r"^\|(\s*:?-+:?\s*\|)+\s*$", lines[i + 1]):
            start = i
            while i < len(lines) and lines[i].startswith("|"):
                i += 1
            before = [ln for ln in lines[max(0, start - 4):start] if ln.strip()]
            marker = next((MARKER.fullmatch(ln.strip()) for ln in reversed(before)
                           if MARKER.fullmatch(ln.strip())), None)
            found.append((marker, lines[start], "\n".join(lines[start:i])))
        else:
            i += 1
    return found
