"""The placement study's README: what was run, which sensors each method chose, how well.

Every finding is a sentence generated from the placements table, so the text cannot
disagree with the numbers.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from spindlebench.studies.family.experiments import Experiment
from spindlebench.studies.placement.placement_file import PlacementStudy
from spindlebench.studies.placement.placements import Placement
from spindlebench.studies.sweep.sweep_report import duration_text, markdown_table

if TYPE_CHECKING:
    from spindlebench.studies.placement.placement_run import PlacementOutcome


def _um(value: Any) -> str:
    return "n/a" if value is None or not math.isfinite(float(value)) else f"{value:.2f} µm"


def findings(table: pd.DataFrame, honest: bool) -> list[str]:
    """Bullets: the best placement per budget, and how the methods compare."""
    ok = table[table["test_mean_rmse_um"].notna()]
    days = "test days" if honest else "design day (no test replica: in-sample for the searches)"
    lines = []
    for m, at in ok.groupby("m"):
        best = at.loc[at["test_mean_rmse_um"].idxmin()]
        fuzzy = at[at["method"] == "fuzzy"]
        versus = ""
        if len(fuzzy) and best["method"] != "fuzzy":
            ref = fuzzy.loc[fuzzy["test_mean_rmse_um"].idxmin()]
            versus = (f"; the best fuzzy placement ({ref['label']}) gives "
                      f"{_um(ref['test_mean_rmse_um'])}")
        lines.append(f"- m = {m}: lowest mean RMSE on the {days}: **{best['label']}** "
                     f"{_um(best['test_mean_rmse_um'])} with `{best['variables']}` "
                     f"({best['n_sensors']} physical sensor(s)){versus}.")
    # the paper's claim for placement: a method does better given the differences too
    pairs = [("greedy", "fuzzy"), ("greedy+diff", "fuzzy+diff"), ("exhaustive", "greedy"),
             ("fuzzy+diff", "fuzzy"), ("greedy+diff", "greedy")]
    for a, b in pairs:
        wa = ok[ok["label"] == a].set_index("m")["test_mean_rmse_um"]
        wb = ok[ok["label"] == b].set_index("m")["test_mean_rmse_um"]
        common = wa.index.intersection(wb.index)
        if len(common):
            won = [m for m in common if wa[m] < wb[m]]
            where = f"m = {', '.join(str(m) for m in won)}" if won else "none"
            lines.append(f"- {a} beats {b} at {len(won)} of {len(common)} budget(s) "
                         f"({where}) on the {days}.")
    if honest:
        gap = ok.assign(gap=ok["test_mean_rmse_um"] - ok["design_rmse_um"]) \
            .groupby("label", sort=False)["gap"].median()
        if len(gap):
            parts = ", ".join(f"{label} {value + 0.0:+.2f} µm"  # + 0.0: no "-0.00"
                              for label, value in gap.round(2).items())
            lines.append(f"- Test minus design RMSE (median over budgets; how much a method's "
                         f"choice was tuned to the design day): {parts}.")
    return lines


def overview(table: pd.DataFrame, column: str) -> str:
    """Markdown: ``column`` (an RMSE) as budget m × method label."""
    ok = table[table[column].notna()]
    if ok.empty:
        return "(no placement was scored)"
    wide = ok.pivot_table(index="m", columns="label", values=column, sort=False)
    wide = wide.loc[:, [c for c in dict.fromkeys(table["label"]) if c in wide.columns]]
    wide = wide.reset_index()
    wide["m"] = wide["m"].astype(int).astype(str)
    return markdown_table(wide)


def chaining(placements: Sequence[Placement]) -> list[str]:
    """Bullets on fuzzy cuts dominated by one cluster (single-linkage chaining)."""
    lines = []
    fuzzy = [p for p in placements if p.method == "fuzzy" and p.cluster_sizes]
    for label in dict.fromkeys(p.label for p in fuzzy):
        largest = max((p for p in fuzzy if p.label == label), key=lambda p: p.budget)
        sizes = largest.cluster_sizes
        total = sum(sizes)
        if max(sizes) < 0.9 * total or len(sizes) < 2:
            continue
        weakest = min(abs(v) for v in largest.psi)
        lines.append(
            f"- {label}: at m = {largest.budget} the cut leaves one cluster of {max(sizes)} "
            f"of {total} candidates and {len(sizes) - 1} small one(s) (sizes "
            f"{', '.join(map(str, sizes))}): the max-min closure is single linkage, which "
            "chains similar candidates into one cluster and splits off outliers; the picks "
            f"from the small clusters correlate weakly with the drift (|ψ| down to "
            f"{weakest:.2f}).")
    return lines


def fuzzy_table(placements: Sequence[Placement]) -> list[str]:
    """Markdown: per fuzzy placement, the cluster sizes of the cut and each pick's ψ."""
    fuzzy = [p for p in placements if p.method == "fuzzy" and p.cluster_sizes]
    if not fuzzy:
        return []
    lines = ["## How the fuzzy cut split the candidates", "",
             "Cluster sizes of the λ-cut on the training run, and the candidate kept in each "
             "cluster with its correlation ψ with the drift (eq. 4 of the paper):", "",
             "| label | m | cluster sizes | kept (ψ) |", "|---|---|---|---|"]
    for p in fuzzy:
        kept = ", ".join(f"{v} ({psi:+.3f})" for v, psi in zip(p.variables, p.psi,
                                                                  strict=True))
        lines.append(f"| {p.label} | {p.budget} | {', '.join(map(str, p.cluster_sizes))} | "
                     f"{kept} |")
    return [*lines, ""]


def readme(study: PlacementStudy, outcome: PlacementOutcome, figures: dict[str, Path],
           record: dict[str, Any], trains: list[Experiment], scored: list[int]) -> str:
    """The README.md of a placement study's results folder."""
    family = study.family
    level = family.noise[0]
    noise = level.value
    n = len(study.nodes)
    table = outcome.table
    honest = study.test_replicas != (study.design_replica,)
    instruments = (f"measured through the study's noise level `{level.name}` (white noise "
                   f"σ = {noise.noise_C:g} K, quantum {noise.quantum_C:g} K; probe σ = "
                   f"{noise.probe_noise_um:g} µm)" if study.measured else
                   "noise-free (true node temperatures)")
    sets = " and ".join(
        f"{n} nodes + {n * (n - 1) // 2} differences = {n + n * (n - 1) // 2} candidates"
        if d else f"{n} nodes" for d in study.with_differences)
    tests = ", ".join(str(r) for r in study.test_replicas)
    out = [
        f"# Sensor placement: {study.name}", "",
        family.description or "", "",
        f"Made by `spindlebench place {study.path}` (study file SHA-256 "
        f"`{record['study']['sha256'][:12]}…`, FMU `{record['fmu']['sha256'][:12]}…`, "
        f"simulated on {record['executor']}). Every number below is computed from "
        "`placements.csv` and `scores.csv`.", "",
        "## The question", "",
        "Where on the machine should m temperature sensors go so that a linear model of their "
        "rises predicts the thermal drift best, in every season? Each node of the model's "
        "temperature field is a candidate location (a virtual sensor).", "",
        "## What was run", "",
        f"- Candidates: {sets}; node temperatures {instruments}"
        + (f"; excluded nodes: {', '.join(study.excluded)}" if study.excluded else "") + ".",
        f"- Candidate nodes ({n}): {', '.join(study.nodes)}.",
        (f"- Rotating parts left out (no probe can be glued there; `rotating_nodes = true` "
         f"keeps them for a telemetry study): {', '.join(study.rotating_excluded)}."
         if study.rotating_excluded else
         "- Nodes of rotating parts are candidates (`rotating_nodes = true`: a telemetry "
         "study)." if study.rotating_nodes else "- No node of a rotating part in the model."),
        f"- Days: climate {family.climate.name}, months {', '.join(family.months)}, speeds "
        f"{', '.join(f'{s:g}' for s in family.speeds_rpm)} rpm, programmes "
        f"{', '.join(p.name for p in family.programmes)}, cooling "
        f"{', '.join(c.name for c in family.cooling)}; runs of "
        f"{duration_text(family.duration_s)} from a cold start at {family.start_hour:g}:00, "
        f"sampled every {family.sample_interval_s:g} s.",
        f"- Model: OLS of the drift on the rises of the m chosen variables, trained on "
        f"{', '.join(e.id for e in trains)} and predicting every other run of the same "
        "replica (the paper's protocol).",
        f"- Replica {study.design_replica} is the *design* day set: the methods choose their "
        "sensors on it. "
        + (f"Replica(s) {tests} are *test* day sets (the day's weather re-drawn with "
           f"σ = {family.weather_sd_C:g} K, fresh sensor noise): every placement is refit on "
           "their training run and scored on their other runs, which no method has seen."
           if honest else "There is no test replica (replicas = 1): the scores below are "
           "in-sample for greedy and exhaustive, which chose their sensors on these runs."),
        "",
        "Methods (m = number of model variables; with differences a variable may need two "
        "physical sensors, counted in `n_sensors`):", "",
        f"- `fuzzy`: the paper's selection (fuzzy similarity `{study.similarity}`, max-min "
        "closure, cut into k = m clusters, in each the candidate most correlated with the "
        "drift) on the training run only.",
        "- `greedy`: forward selection; each step adds the candidate that minimises the mean "
        "held-out RMSE of the design replica (one nested path, m = 1 … max).",
        f"- `exhaustive`: every m-subset scored the same way where C(n, m) ≤ "
        f"{study.exhaustive_limit:,}; the true optimum on the design day.",
        "- `+diff`: the same method with node differences among the candidates.", "",
        "## Findings", "",
        f"For scale: predicting no drift at all gives {_um(outcome.no_model_rmse_um)} on the "
        f"test runs; the probe's own noise is σ = {noise.probe_noise_um:g} µm.", "",
        *findings(table, honest), *chaining(outcome.placements), "",
        f"Mean held-out RMSE (µm) on the {'test days' if honest else 'design day'}, by budget "
        "and method (blank: not run):", "",
        overview(table, "test_mean_rmse_um"), "",
        "The same on the design day, the objective greedy and exhaustive minimise:", "",
        overview(table, "design_rmse_um"), "",
        "## Placements", "",
        "RMSE in µm; `design` = held-out runs of the design replica, `test` = held-out runs "
        "of the test replica(s), mean over runs and per season.", "",
    ]
    seasons = [c for c in table.columns if c.startswith("test_") and c.endswith("_rmse_um")
               and c not in ("test_mean_rmse_um", "test_worst_rmse_um")]
    shown = table[table["variables"] != ""].rename(columns={
        "design_rmse_um": "design", "test_mean_rmse_um": "test mean",
        "test_worst_rmse_um": "test worst",
        **{s: s.removeprefix("test_").removesuffix("_rmse_um") for s in seasons}})
    columns = ["label", "m", "variables", "n_sensors", "design", "test mean", "test worst",
               *[s.removeprefix("test_").removesuffix("_rmse_um") for s in seasons]]
    out += [markdown_table(shown, columns), ""]
    skipped = table[table["variables"] == ""]
    if len(skipped):
        out += ["Not run:", ""]
        out += [f"- {row['label']} m = {row['m']}: {row['note']}" for _, row in
                skipped.iterrows()]
        out.append("")
    out += fuzzy_table(outcome.placements)
    if figures:
        out += ["## Figures", ""]
        for name, path in figures.items():
            relative = path.relative_to(outcome.out_dir).as_posix()
            out += [f"![{name}]({relative})", ""]
    out += ["## Failures", ""]
    if outcome.failures:
        out += [f"- {key}: {error}" for key, error in outcome.failures.items()]
    else:
        out.append("None: every simulation finished.")
    out += ["", "## Files", "",
            "- `placements.csv`: one row per method × budget: chosen variables, the physical "
            "sensors they need, design and test RMSE (mean, worst, per season), search time.",
            "- `scores.csv`: one row per placement × replica × held-out run (`rmse_um` "
            "against the probe, `rmse_true_um` against the true drift).",
            "- `comparison.png`, `schematic/`: the figures above; `runs/`: the simulated "
            "recordings (resume state); `provenance.json`: study, climate and FMU hashes, "
            "seeds, package versions.", ""]
    return "\n".join(out)
