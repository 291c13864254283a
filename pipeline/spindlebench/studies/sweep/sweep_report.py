"""The sweep's README: what was run, what it shows, and where the paper's claim fails.

Every sentence about the findings is generated from the summary tables, so the text cannot
disagree with the numbers it describes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from spindlebench.core.names import SIX_RAW
from spindlebench.studies.family.experiments import Experiment
from spindlebench.studies.family.family_file import NO_FAULT, SweepStudy
from spindlebench.studies.sweep.summary import DIFF, RAW

CRITERIA = {
    "iqr": "interquartile range over held-out runs",
    "worst": "worst case",
    "season_spread": "spread of the per-season medians",
    "k_spread": "spread over k of the same case",
}


def markdown_table(frame: pd.DataFrame, columns: Sequence[str] | None = None,
                   digits: int = 2) -> str:
    """A GitHub Markdown table; floats rounded, missing values blank."""
    columns = list(columns or frame.columns)

    def cell(value: Any) -> str:
        if value is None or (isinstance(value, float) and math.isnan(value)) or \
                value is pd.NA:
            return ""
        if isinstance(value, float):
            return f"{value:.{digits}f}"
        return str(value).replace("|", "\\|")

    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(cell(row[c]) for c in columns) + " |"
              for _, row in frame.iterrows()]
    return "\n".join(lines)


def _fmt(value: float) -> str:
    return "n/a" if value is None or not math.isfinite(value) else f"{value:.2f} µm"


def _pct(value: Any) -> str:
    return "n/a" if value is None or not math.isfinite(value) else f"{100 * value:.0f} %"


def verdict_sentences(verdict: pd.DataFrame, kind: str) -> list[str]:
    """One bullet per k on the *lower* half, one on the *stable* half."""
    lines = []
    for _, row in verdict[verdict["data"] == kind].iterrows():
        k = row["k"]
        lower = "**holds**" if row["lower"] else "**fails**"
        raws = [r for r in RAW if f"win_rate_vs_{r}" in row]
        medians = ", ".join(f"{r} {_fmt(row[f'median_{r}_um'])}" for r in raws)
        wins = ", ".join(f"{_pct(row[f'win_rate_vs_{r}'])} of paired cases vs {r}"
                         for r in raws)
        lines.append(
            f"- k = {k}, *lower*: {lower}: median {_fmt(row['median_diff_um'])} with "
            f"differences vs {medians} (six_diff wins {wins}).")
        held = [name for name in CRITERIA if row.get(f"{name}_holds") is True]
        failed = [name for name in CRITERIA if row.get(f"{name}_holds") is False]
        parts = [f"{CRITERIA[n]} {_fmt(row[f'{n}_diff_um'])} vs {_fmt(row[f'{n}_best_raw_um'])}"
                 for n in CRITERIA if row.get(f"{n}_holds") is not None]
        stable = "**holds**" if row["more_stable"] and held else (
            "**partly holds**" if held else "**fails**")
        detail = "; ".join(parts)
        lines.append(f"- k = {k}, *more stable*: {stable} ({detail}"
                     + (f"; not better on: {', '.join(CRITERIA[n] for n in failed)}"
                        if failed else "") + ").")
    return lines


def _claim_state(rows: pd.DataFrame) -> tuple[str, str]:
    """("holds" | "fails" | "partly", what the differences do per k) for one data kind."""
    lower = rows["lower"].astype(bool).tolist()
    stable = rows["more_stable"].astype(bool).tolist()
    ks = [str(k) for k in rows["k"]]
    if all(lower) and all(stable):
        return "holds", (f"at every k tested ({', '.join(ks)}) the six sensors plus their "
                         "differences give a lower median held-out error and a smaller spread "
                         "than either raw group")
    if not any(lower):
        return "fails", (f"at no k tested ({', '.join(ks)}) do the differences give a lower "
                         "median held-out error than the better raw group")
    good = [k for k, lo, st in zip(ks, lower, stable, strict=True) if lo and st]
    low_only = [k for k, lo, st in zip(ks, lower, stable, strict=True) if lo and not st]
    bad = [k for k, lo in zip(ks, lower, strict=True) if not lo]
    parts = []
    if good:
        parts.append(f"lower and more stable at k = {', '.join(good)}")
    if low_only:
        parts.append(f"lower but not more stable on all criteria at k = {', '.join(low_only)}")
    if bad:
        parts.append(f"not lower at k = {', '.join(bad)}")
    return "partly", "differences are " + "; ".join(parts)


def overall(verdict: pd.DataFrame) -> str:
    """The headline: the verdict on measured data, then, if run, on the noise-free truth.

    Both come from the same ``verdict`` rows as the per-k bullets, so they cannot disagree.
    """
    measured = verdict[verdict["data"] == "measured"]
    if measured.empty:
        return "No paired results of the three groups: the claim could not be tested."
    state, detail = _claim_state(measured)
    head = {"holds": "**On measured data the paper's claim holds in this synthetic world**",
            "fails": "**On measured data the paper's claim does not hold in this synthetic "
                     "world**",
            "partly": "**On measured data the paper's claim holds only in part**"}[state]
    text = f"{head}: {detail}."
    truth = verdict[verdict["data"] == "noise-free"]
    if not truth.empty:
        state, detail = _claim_state(truth)
        verb = {"holds": "it holds", "fails": "it does not hold",
                "partly": "it holds only in part"}[state]
        text += f" On the noise-free truth (perfect instruments) {verb}: {detail}."
    return text


def duration_text(seconds: float) -> str:
    """A run length people read at a glance: 40 min, 1.5 h, 6 h (not 0.666667 h)."""
    if seconds < 3600.0:
        return f"{seconds / 60:.3g} min"
    return f"{seconds / 3600:.3g} h"


def failure_slices(slices: pd.DataFrame, versus: str) -> list[str]:
    """A table: per axis value and k, median(six_diff) / median(reference), ✓ if below 1."""
    if slices.empty or slices[slices["versus"] == versus].empty:
        return ["(The study varies no axis with more than one value: nothing to slice.)"]
    slices = slices[slices["versus"] == versus]
    ks = sorted(slices["k"].unique())
    failing = slices[~slices["holds"].astype(bool)]
    lines = [f"Differences lose in {len(failing)} of {len(slices)} slices (axis value × k).",
             "", "| axis | value | " + " | ".join(f"k = {k}" for k in ks) + " |",
             "|---|---|" + "---|" * len(ks)]
    for (axis, value), by_k in _by_slice_and_k(slices).items():
        cells = []
        for k in ks:
            if k not in by_k:
                cells.append("")
                continue
            row = by_k[k][0]
            mark = "✓" if row.holds else "✗"
            reference = f" ({row.reference})" if versus == "best-raw" else ""
            cells.append(f"{row.ratio:.2f} {mark}{reference}")
        lines.append(f"| {axis} | {value} | " + " | ".join(cells) + " |")
    return lines


def _by_slice_and_k(table: pd.DataFrame) -> dict[tuple, dict[Any, list]]:
    """The rows of a per-slice table (``axis``, ``value``, ``k`` columns) as named tuples,
    per slice and k, in the table's order: one pass over it, not a mask per slice and k
    (those were most of the README's time)."""
    cells: dict[tuple, dict[Any, list]] = {}
    for row in table.itertuples(index=False):
        cells.setdefault((row.axis, row.value), {}).setdefault(row.k, []).append(row)
    return cells


def rank_lines(ranks: pd.DataFrame | None, shown: int = 3) -> list[str]:
    """"Methods ranked per slice": per slice and k the best ``shown`` methods with their
    median, and where the paper's ``six_diff`` ranks among all of them."""
    if ranks is None or ranks.empty:
        return []
    ks = [k for k in ranks["k"].dropna().unique()]
    lines = ["### Methods ranked per slice", "",
             "Every method (not the oracle) by median held-out RMSE within each slice of the "
             f"measured data (`summary/rank_by_slice.csv` has the full order): the best {shown}, "
             "and the rank of the paper's six_diff (closure + differences).", "",
             "| slice | " + " | ".join(f"k = {int(k)}" for k in ks) + " |",
             "|---|" + "---|" * len(ks)]
    for (axis, value), by_k in _by_slice_and_k(ranks).items():
        cells = []
        for k in ks:
            if k not in by_k:
                cells.append("")
                continue
            here = sorted(by_k[k], key=lambda row: row.rank)
            top = ", ".join(f"{row.method} ({row.median_um:.2f})" for row in here[:shown])
            diff = [row for row in here if row.method == DIFF]
            if diff:
                top += f"; six_diff {int(diff[0].rank)}/{int(here[0].of)}"
            cells.append(top.replace("|", "\\|"))
        name = "whole study" if axis == "all" else f"{axis} = {value}"
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return [*lines, ""]


def readme(study: SweepStudy, results: pd.DataFrame, tables: dict[str, pd.DataFrame],
           figures: dict[str, Path], record: dict[str, Any],
           trains: list[Experiment]) -> str:
    """The README.md of a sweep's results folder."""
    summary, verdict = tables["by_method"], tables["verdict"]
    n_failed = int(results["rmse_um"].isna().sum()) if len(results) else 0
    simulations = len(study.months) * len(study.speeds_rpm) * len(study.programmes) * \
        len(study.cooling) * study.replicas
    faults = [f.name if f else NO_FAULT for f in study.faults]
    out: list[str] = [
        f"# Season sweep: {study.name}",
        "",
        study.description or "",
        "",
        f"Made by `spindlebench sweep {study.path}` (study file SHA-256 "
        f"`{record['study']['sha256'][:12]}…`, FMU `{record['fmu']['sha256'][:12]}…`, "
        f"{record['executor']}). Every number below is computed from `results.csv`.",
        "",
        "## What was run",
        "",
        f"- Climate: {study.climate.name} (monthly normals, {study.climate.source}); "
        f"months {', '.join(study.months)}; each run starts cold at "
        f"{study.start_hour:g}:00, the day's low/high scattered by ±{study.weather_sd_C:g} K "
        "(1 σ) around the monthly normals per replica.",
        f"- Spindle speeds {', '.join(f'{s:g}' for s in study.speeds_rpm)} rpm; programmes "
        f"{', '.join(p.name for p in study.programmes)}; cooling "
        f"{', '.join(c.name for c in study.cooling)}; runs of {duration_text(study.duration_s)} "
        f"sampled every {study.sample_interval_s:g} s.",
        f"- Measurement conditions: noise levels {', '.join(n.name for n in study.noise)} × "
        f"faults {', '.join(faults)} (faults strike the held-out runs only)"
        + (", plus the noise-free truth (true temperatures and drift, no faults)."
           if study.methods.ground_truth else "."),
        f"- {study.replicas} replica(s) → {simulations} simulations; training "
        f"({study.training.rule}): {', '.join(e.id for e in trains)}; every other run is "
        "held out.",
        f"- {len(results)} result rows (replica × condition × method × k × held-out run), "
        f"{n_failed} without a score (see *Failures*).",
        "",
        "Methods: `all_raw`, `six_raw`, `six_diff` are the paper's candidate groups (all 20 "
        "sensors; T1, T6, T8, T10, T13, T16; those six plus their 15 differences), selected "
        "by fuzzy clustering into k clusters and fitted by OLS on rises. `top-k-correlated` "
        "keeps the k raw sensors most correlated with the error (no clustering). `ridge` "
        "fits all 20 sensors and 190 differences with a cross-validated ridge penalty (no "
        "selection, no k). `group:label` is another selection method (`spindlebench "
        "methods`) on that group's candidates, e.g. `six_diff:kmeans+grey`. *noise-free* "
        "rows run the same methods on the true temperatures "
        "and true drift: what perfect instruments would give. That is a reference, not a "
        "bound: selection can choose worse on perfectly smooth data. `oracle` fits all 20 "
        "sensors on the held-out run itself: no method that predicts from these sensors' "
        "rises can score lower on the same run, so it is the floor (a lower bound on "
        "`rmse_um`).",
        "",
        "## Does the paper's claim hold?",
        "",
        "Claim (Xu et al. 2023): adding actively constructed temperature differences gives a "
        "lower and more stable thermal-error model than raw temperatures.",
        "",
        overall(verdict),
        "",
        "Measured data:",
        "",
        *verdict_sentences(verdict, "measured"),
        "",
    ]
    if (verdict["data"] == "noise-free").any():
        out += ["Noise-free truth (perfect instruments):", "",
                *verdict_sentences(verdict, "noise-free"), ""]
    slices = tables["claim_by_slice"]
    out += ["### Where the claim fails", "",
            "The *lower* test repeated within each value of each study axis (measured data). "
            "Each cell is the median RMSE of six_diff divided by that of the reference in "
            "the slice: below 1 (✓) the differences win, above 1 (✗) they lose.", "",
            "Against the better of the two raw groups (named in brackets):", "",
            *failure_slices(slices, "best-raw"), "",
            "Against the same six sensors without differences (six_raw), the paper's "
            "like-for-like comparison:", "",
            *failure_slices(slices, SIX_RAW), ""]
    out += rank_lines(tables.get("rank_by_slice"))
    best = tables["best"]
    out += ["### Against the baselines", ""]
    for _, row in best.iterrows():
        k = "" if pd.isna(row["best_k"]) else f" at k = {int(row['best_k'])}"
        floor = "" if pd.isna(row["oracle_median_um"]) else (
            f"; the oracle floor (any linear model of the 20 sensors, fitted on the held-out "
            f"run itself) is {_fmt(row['oracle_median_um'])}")
        out.append(f"- {row['data']}: lowest median is **{row['best_method']}**{k} "
                   f"({_fmt(row['best_median_um'])}){floor}.")
    out += ["", "## Numbers", "", "Held-out RMSE per method (µm; `vs true` scores the same "
            "predictions against the true drift instead of the probe):", "",
            markdown_table(summary.rename(columns={"median_vs_true_drift_um": "vs true"}),
                           ["data", "method", "k", "n", "median_um", "q1_um", "q3_um",
                            "iqr_um", "worst_um", "vs true", "failed"]),
            "", "Stability (µm): spread across k, across seasons, and the typical standard "
            "deviation over the held-out runs of one trained model:", "",
            markdown_table(tables["stability"], ["data", "method", "k", "k_spread_um",
                                                 "k_median_range_um", "season_spread_um",
                                                 "worst_season", "experiment_sd_um"]),
            ""]
    if figures:
        out += ["## Figures", ""]
        for name, path in figures.items():
            out.append(f"![{name}](plots/{path.name})")
            out.append("")
    out += ["## Failures", ""]
    errors = results[results["error"].astype(str) != ""]
    if errors.empty:
        out.append("None: every simulation and every method produced a score.")
    else:
        counts = errors.groupby("error").size().sort_values(ascending=False)
        out += [f"- {count} row(s): {message}" for message, count in counts.items()]
    out += ["", "## Files", "",
            "- `results.csv`: the tidy table, one row per replica × condition × method × k × "
            "held-out run (`rmse_um` against the measured drift as in the paper, "
            "`rmse_true_um` against the true drift, `selected` candidates, `error`).",
            "- `summary/*.csv`: the tables above, per condition (`by_condition.csv`), per "
            "season (`by_season.csv`) and per slice (`claim_by_slice.csv`).",
            "- `runs/`: every simulated recording (canonical CSV + JSON sidecar); `evals/`: "
            "per-evaluation results (the resume state); `provenance.json`: study, climate "
            "and FMU hashes, seeds, package versions.", ""]
    return "\n".join(out)
