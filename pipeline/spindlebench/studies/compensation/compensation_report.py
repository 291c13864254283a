"""The compensation study's outputs: ``README.md``, ``days.csv``, ``summary.csv``,
``timeseries.csv.gz``, ``compensation.png`` and ``provenance.json`` (``spindlebench compensate``
is ``commands.compensate``).
"""

from __future__ import annotations

import gzip
import json
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from spindlebench.core import atomic, interrupts, provenance
from spindlebench.core.names import SIX_DIFF
from spindlebench.formats.recording import TIME_COLUMN, TRUE_DRIFT_COLUMN
from spindlebench.studies.compensation.compensation_file import (
    CompensationStudy,
)

FIGURE_DPI = 110


#: Every sample of the first retraining rule (gzip: a month at 10 s is ~10^6 rows).
TIMESERIES = "timeseries.csv.gz"
#: Every file ``compensate`` writes: its folder holds these (and its lock) or nothing.
OUTPUT_FILES = frozenset({"README.md", "days.csv", "summary.csv", TIMESERIES,
                          "compensation.png", "provenance.json"})
#: Written last: a folder without them is an unfinished output.
COMPLETE_MARKERS = ("provenance.json", "README.md")


def _csv(path: Path, frame: pd.DataFrame) -> None:
    """A CSV, gzipped for ``.gz`` with neither a time nor a file name in the gzip header
    (pandas' gzip writes both: the bytes changed from run to run)."""
    with atomic.atomic_path(path) as tmp:
        if path.suffix != ".gz":
            frame.to_csv(tmp, index=False, float_format="%.6g")
            return
        with open(tmp, "wb") as raw, gzip.GzipFile(filename="", mode="wb", fileobj=raw,
                                                   mtime=0) as packed:
            packed.write(frame.to_csv(index=False, float_format="%.6g").encode("utf-8"))


def write_outputs(study: CompensationStudy, study_path: Path, fmu: Path, out: Path,
                  days: pd.DataFrame, series: pd.DataFrame, table: pd.DataFrame,
                  outcomes: dict, target: str | None = None) -> None:
    """Every output file; a signal waits until they are all written, and the two files that
    say the folder is complete (README, provenance) go first and come back last, so even a
    ``kill -9`` leaves no old README over new tables. ``target``: the folder is one of a
    study's several targets (said under the README's title and in the provenance)."""
    with interrupts.deferred():
        out.mkdir(parents=True, exist_ok=True)
        for marker in COMPLETE_MARKERS:
            (out / marker).unlink(missing_ok=True)
        _write_outputs(study, study_path, fmu, out, days, series, table, outcomes, target)


def _write_outputs(study: CompensationStudy, study_path: Path, fmu: Path, out: Path,
                   days: pd.DataFrame, series: pd.DataFrame, table: pd.DataFrame,
                   outcomes: dict, target: str | None = None) -> None:
    _csv(out / "days.csv", days)
    _csv(out / "summary.csv", table)
    rule = study.retrain[0]
    _csv(out / TIMESERIES, series[series["retrain"] == rule])
    figure(study, series[series["retrain"] == rule], days[days["retrain"] == rule],
           table[table["retrain"] == rule], out / "compensation.png")
    models = {rule: {name: [{"trained_on_day": m.trained_on_day, "inputs": list(m.selected),
                             "excluded": list(m.excluded),
                             "coefficients": None if m.fit.coefficients is None else
                             [float(m.fit.intercept), *map(float, m.fit.coefficients)]}
                            for m in versions] for name, versions in o.models.items()}
              for rule, o in outcomes.items()}
    record = provenance.provenance(
        command="compensate", study=provenance.file_entry(study_path),
        fmu=provenance.file_entry(fmu), seed=study.family.seed, method_seed=study.seed,
        models=models,
        controller={"update_interval_s": study.controller.update_interval_s,
                    "rate_limit_um_per_s": study.controller.rate_limit_um_per_s,
                    "dead_band_um": study.controller.dead_band_um},
        tolerance_um=study.tolerance_um, retrain=list(study.retrain),
        fault=None if study.fault is None else study.fault.name,
        fault_from_day=study.fault_from_day, days=study.days,
        off_h=study.off_h if study.days == "continuous" else None,
        **({} if target is None else {"target": target}))
    text = readme(study, study_path, days, table)
    if target is not None:  # one of several targets: say which, under the title
        title, rest = text.split("\n", 1)
        text = (f"{title} — target `{target}`\n\nThis folder compensates the target "
                f"`{target}` alone (its models trained on its probe reading; 'drift', 'µm' "
                "and the tolerance below are in its unit); every target's residual is in "
                "`../README.md`.\n" + rest)
    atomic.write_text(out / "README.md", text)
    atomic.write_text(out / "provenance.json", json.dumps(record, indent=2) + "\n")


def targets_readme(study: CompensationStudy, study_path: Path,
                   tables: dict[str, pd.DataFrame],
                   joint_tables: dict[str, pd.DataFrame] | None = None) -> str:
    """The folder's README of a study with several targets: every target's residual RMS over
    all days, per retraining rule and model (each target's own, then the joint models
    ``<model>@<joint>`` of ``joint_tables``), beside the uncompensated target."""
    targets = list(tables)
    first = tables[targets[0]]
    rows = first[first["part"] == "all days"][["retrain", "model"]]
    if joint_tables:
        tables = {t: pd.concat([tables[t], joint_tables[t][joint_tables[t]["model"]
                                                           != "uncompensated"]])
                  for t in targets}
        joint = joint_tables[targets[0]]
        extra = joint[(joint["part"] == "all days") & (joint["model"] != "uncompensated")]
        rows = pd.concat([rows, extra[["retrain", "model"]]])
    lines = [f"# Compensation in the loop: {study.name}, several targets", "",
             f"Made by `spindlebench compensate {study_path}`: one simulation of the days, then "
             "each target compensated on its own (its models trained on day 1 on its probe "
             "reading, its residual = its true rise − its applied offset). Each target's "
             "folder holds the same files as a study of that target alone: "
             + ", ".join(f"[`{t}/`]({t}/README.md)" for t in targets) + ".", "",
             "Residual RMS over all compensated days (each target in its unit: µm for a "
             "drift, µrad for a tilt):", "",
             "Per-target models (`all_raw`, ...) select for each target on its own; a joint "
             "model `<model>@<joint>` reads one candidate set for every target, chosen on day "
             "1 (`union`: the union of the per-target selections; `mtlasso`, `pls-vip`: k "
             "candidates for all targets at once), each target refitted on it "
             "(in `joint/<target>/`).", "",
             "| retrain | model | " + " | ".join(targets) + " |",
             "|---|---|" + "---|" * len(targets)]
    for row in rows.itertuples():
        cells = []
        for target in targets:
            t = tables[target]
            at = t[(t["part"] == "all days") & (t["retrain"] == row.retrain)
                   & (t["model"] == row.model)]
            cells.append(_fmt(float(at["rms_um"].iloc[0])) if len(at) else "–")
        lines.append(f"| {row.retrain} | {row.model} | " + " | ".join(cells) + " |")
    lines += ["", "The controller's settings (dead band, rate limit, tolerance) apply to every "
              "target in its own unit.", ""]
    return "\n".join(lines)


def best_model(table: pd.DataFrame) -> str:
    """The model with the lowest residual RMS over all run days (under the first rule)."""
    at = table[(table["part"] == "all days") & (table["model"] != "uncompensated")
               & (table["retrain"] == table["retrain"].iloc[0])]
    return str(at.loc[at["rms_um"].idxmin(), "model"])


def figure(study: CompensationStudy, series: pd.DataFrame, days: pd.DataFrame,
           table: pd.DataFrame, path: Path) -> None:
    """Uncompensated drift, applied offset (best model and the paper's six_diff) and the
    residual of every model over the whole run, days side by side."""
    duration_h = study.family.duration_s / 3600.0
    best = best_model(table)
    fig = Figure(figsize=(11, 6.5))
    top, bottom = fig.subplots(2, 1, sharex=True)
    first = series[series["model"] == study.models[0]]
    hours = (first["day"] - 2) * duration_h + first[TIME_COLUMN] / 3600.0
    top.plot(hours, first[TRUE_DRIFT_COLUMN], color="black", lw=1.0, label="uncompensated drift")
    shown = [best] + [m for m in study.models if m == SIX_DIFF and m != best]
    for name in shown:
        at = series[series["model"] == name]
        top.plot(hours.to_numpy(), at["offset_um"].to_numpy(), lw=0.9,
                 label=f"applied offset, {name}")
    for name in study.models:
        at = series[series["model"] == name]
        bottom.plot(hours.to_numpy(), at["residual_um"].to_numpy(), lw=0.8, label=name)
    tol = study.tolerance_um
    bottom.axhspan(-tol, tol, color="0.85", zorder=0, label=f"±{tol:g} µm")
    fault_days = sorted(set(days.loc[days["fault_active"], "day"]))
    for ax in (top, bottom):
        for d in fault_days:
            ax.axvspan((d - 2) * duration_h, (d - 1) * duration_h, color="tab:red",
                       alpha=0.06, lw=0)
        for d in sorted(set(days["day"])):
            ax.axvline((d - 2) * duration_h, color="0.8", lw=0.4)
    top.set_ylabel("drift / offset (µm)")
    bottom.set_ylabel("residual (µm)")
    nights = (f", the {study.off_h:g} h standing between them not shown"
              if study.days == "continuous" else ", each a cold start")
    bottom.set_xlabel(f"operating hours (days 2–{int(days['day'].max())} side by side, "
                      f"{duration_h:g} h each{nights}; red: fault active)")
    top.legend(loc="upper left", fontsize=8)
    bottom.legend(loc="upper left", fontsize=8, ncol=3)
    top.set_title(f"{study.name}: compensation in the loop (trained on day 1; retrain "
                  f"{study.retrain[0]})", fontsize=10)
    fig.tight_layout()
    with atomic.atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=FIGURE_DPI)


def _fmt(value: float, digits: int = 2) -> str:
    return "–" if not np.isfinite(value) else f"{value:.{digits}f}"


def summary_text(table: pd.DataFrame) -> str:
    lines = [f"{'retrain':<12} {'part':<13} {'model':<24} {'RMS':>7} {'peak':>7} {'within':>7}"]
    for row in table.itertuples():
        lines.append(f"{row.retrain:<12} {row.part:<13} {row.model:<24} {row.rms_um:7.2f} "
                     f"{row.peak_um:7.2f} {100 * row.within_tolerance:6.1f}%")
    return "\n".join(lines)


def readme(study: CompensationStudy, study_path: Path, days: pd.DataFrame,
           table: pd.DataFrame) -> str:
    c = study.controller
    rate = "none" if c.rate_limit_um_per_s is None else f"{c.rate_limit_um_per_s:g} µm/s"
    fault = "none" if study.fault is None else (
        f"{study.fault.name} ({study.fault.value.kind} of {study.fault.value.sensor} from "
        f"{study.fault.value.start_s / 3600:g} h into every day from day {study.fault_from_day})")
    lines = [f"# Compensation in the loop: {study.name}", "",
             f"Made by `spindlebench compensate {study_path}`. Every number is computed from "
             "the simulated samples (`timeseries.csv.gz` holds those of the first rule).", "",
             "## Set-up", "",
             f"- Days: {int(days['day'].max())} working days of "
             f"{study.family.duration_s / 3600:g} h (the study family's experiments × "
             f"{study.family.replicas} replica(s)), "
             + (f"consecutive on one machine: one simulation, {study.off_h:g} h standing "
                "between two days, each day starting in the state the night before left"
                if study.days == "continuous" else "each simulated from its own cold start")
             + "; day 1 trains every model, days 2 onward are compensated.",
             f"- Models (k = {study.k}): {', '.join(study.models)} (sweep method names; "
             "`spindlebench methods`).",
             f"- Controller: update every {c.update_interval_s:g} s, rate limit {rate}, dead "
             f"band {c.dead_band_um:g} µm; tolerance ±{study.tolerance_um:g} µm.",
             f"- Sensor fault: {fault}; retraining rules (each on the same days): "
             f"{', '.join(study.retrain)}.",
             "- Residual = true drift − applied offset (the probe's measurement is used "
             "only for training).", "",
             "## Residual over the run", "",
             "| retrain | part | model | days | RMS (µm) | mean daily RMS | worst daily RMS "
             "| peak (µm) | within ± tol |", "|---|---|---|---|---|---|---|---|---|"]
    for row in table.itertuples():
        lines.append(f"| {row.retrain} | {row.part} | {row.model} | {row.days} | "
                     f"{_fmt(row.rms_um)} | "
                     f"{_fmt(row.mean_daily_rms_um)} | {_fmt(row.worst_daily_rms_um)} | "
                     f"{_fmt(row.peak_um)} | {100 * row.within_tolerance:.1f} % |")
    best = best_model(table)
    rule = study.retrain[0]
    lines += ["", f"Lowest residual RMS over all days (retrain {rule}): **{best}**.", "",
              f"![drift, offset and residual](compensation.png) (retrain {rule})", "",
              f"## Per day (RMS / peak of the residual, µm; retrain {rule})", ""]
    days = days[days["retrain"] == rule]
    wide = days.pivot_table(index=["day", "experiment", "fault_active"], columns="model",
                            values=["rms_residual_um", "peak_residual_um"], aggfunc="first")
    unc = days.groupby("day")["rms_uncompensated_um"].first()
    header = ["day", "experiment", "fault", "uncompensated RMS", *study.models]
    lines += ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for (day, experiment, fault_active), row in wide.iterrows():
        cells = [f"{_fmt(row[('rms_residual_um', m)])} / {_fmt(row[('peak_residual_um', m)])}"
                 for m in study.models]
        lines.append(f"| {day} | {experiment} | {'yes' if fault_active else ''} | "
                     f"{_fmt(unc[day])} | " + " | ".join(cells) + " |")
    detected = days[days["detected"] != ""]
    if len(detected):
        lines += ["", "Faults detected (the model retrained without the sensor):", ""]
        lines += [f"- day {r.day}, {r.model}: {r.detected}" for r in detected.itertuples()]
    lines += ["", "## Files", "",
              "- `days.csv`: one row per model and day (inputs, retraining, RMS, peak, "
              "fraction within tolerance); `summary.csv`: the table above.",
              f"- `{TIMESERIES}`: every sample of every compensated day and model under the "
              "first rule.",
              "- `provenance.json`: study and FMU hashes, seeds, every model version "
              "(inputs, coefficients), package versions.", ""]
    return "\n".join(lines)
