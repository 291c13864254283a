"""The analogues of the paper's Tables 4, 5 and 6, as DataFrames (CSV) and Markdown.

Ours come from a ``StudyResult``; the paper's numbers (``reference``) sit beside them so a
reader sees both. The paper's experiments are not ours, so its numbers are a yardstick for
the size of the effect, not a target to match.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from spindlebench.core.names import GROUP_LABELS, GROUPS
from spindlebench.studies.paper import reference
from spindlebench.studies.paper.analysis import StudyResult


def _fmt(value: float, digits: int) -> str:
    return "–" if value is None or not math.isfinite(value) else f"{value:.{digits}f}"


def _markdown(frame: pd.DataFrame) -> str:
    """A GitHub-flavoured Markdown table (no extra dependency)."""
    header = "| " + " | ".join(str(c) for c in frame.columns) + " |"
    rule = "|" + "|".join("---" for _ in frame.columns) + "|"
    rows = ["| " + " | ".join(str(v) for v in row) + " |" for row in frame.itertuples(False)]
    return "\n".join([header, rule, *rows])


def trains_like_paper(result: StudyResult) -> bool:
    """Whether this study trains on the paper's training experiment (its exp1): only then do
    the paper's selections (Table 4) and R² (Table 5) answer the same question as ours."""
    return result.config.train == reference.TRAIN_EXPERIMENT


def paper_training_note(result: StudyResult, table: int) -> str:
    """One sentence under Table 4 or 5 when the paper's columns are left out, else ''."""
    if trains_like_paper(result):
        return ""
    return (f"The paper's Table {table} (trained on its {reference.TRAIN_EXPERIMENT}) is not "
            f"shown: this study trains on {result.config.train}, so its numbers would answer "
            "another question.")


def table4_frame(result: StudyResult) -> pd.DataFrame:
    """Selected candidates, one row each: k, group, rank, name, ψ, cluster size, η (and the
    paper's choice at the same rank when the study trains like the paper)."""
    rows = []
    for cell in result.cells:
        for rank, (name, psi) in enumerate(zip(cell.selected, cell.psi, strict=True), start=1):
            row: dict[str, object] = {
                "clusters": cell.k, "group": cell.group, "rank": rank, "selected": name,
                "psi": psi, "cluster_size": len(cell.clusters[rank - 1]), "eta": cell.eta,
            }
            if trains_like_paper(result):
                paper = reference.SELECTED.get(cell.k, {}).get(cell.group, [])
                row["paper_selected"] = paper[rank - 1][0] if rank <= len(paper) else ""
                row["paper_psi"] = paper[rank - 1][1] if rank <= len(paper) else float("nan")
            rows.append(row)
    return pd.DataFrame(rows)


def table5_frame(result: StudyResult) -> pd.DataFrame:
    """Training R², one row per k, one column per group, then the paper's (when the study
    trains like the paper)."""
    rows = []
    for k in result.config.clusters:
        row: dict[str, object] = {"clusters": k}
        for group in result.groups:
            row[group] = result.cell(group, k).r2
        if trains_like_paper(result):
            for group in GROUPS:
                row[f"paper_{group}"] = reference.R2.get(k, {}).get(group, float("nan"))
        rows.append(row)
    return pd.DataFrame(rows)


def paper_tests(result: StudyResult) -> tuple[str, ...]:
    """The predicted experiments whose RMSE the paper's Table 6 also gives: ours that are
    among its exp2 … exp5, and none unless we train on its exp1 too (otherwise its numbers
    answer another question)."""
    if result.config.train != reference.TRAIN_EXPERIMENT:
        return ()
    return tuple(t for t in result.config.tests if t in reference.TEST_EXPERIMENTS)


def paper_mean_label(result: StudyResult) -> str:
    """``paper mean`` for the paper's four predictions, ``paper mean over exp3, exp4`` for a
    subset (the mean of those columns, not the paper's printed 4-run mean)."""
    shown = paper_tests(result)
    if set(shown) == set(reference.TEST_EXPERIMENTS):
        return "paper mean"
    return f"paper mean over {', '.join(shown)}"


def _paper_mean(numbers: tuple[float, ...], shown: tuple[str, ...]) -> float:
    """The printed mean when all four are shown, else the mean of the shown ones."""
    if set(shown) == set(reference.TEST_EXPERIMENTS):
        return numbers[-1]
    return float(np.mean([numbers[reference.TEST_EXPERIMENTS.index(t)] for t in shown]))


def table6_frame(result: StudyResult) -> pd.DataFrame:
    """RMSE (µm) per predicted experiment and mean, one row per (k, group), then the paper's
    for the experiments it predicts too (``paper_tests``) and their mean; the mean column is
    ``paper_mean`` only when it is the paper's 4-run mean, else ``paper_mean_over_exp3_exp4``."""
    rows = []
    shown = paper_tests(result)
    mean_column = paper_mean_label(result).replace(", ", "_").replace(" ", "_")
    for k in result.config.clusters:
        for group in result.groups:
            cell = result.cell(group, k)
            row: dict[str, object] = {"clusters": k, "group": group}
            for test in result.config.tests:
                row[test] = cell.rmse_um[test]
            row["mean"] = cell.mean_rmse_um
            if shown:
                paper = reference.RMSE_UM.get(k, {}).get(group)
                for test in shown:
                    row[f"paper_{test}"] = (paper[reference.TEST_EXPERIMENTS.index(test)]
                                            if paper else float("nan"))
                row[mean_column] = _paper_mean(paper, shown) if paper else float("nan")
            rows.append(row)
    return pd.DataFrame(rows)


def table6_paper_note(result: StudyResult) -> str:
    """One sentence on which of the paper's Table 6 numbers are shown, and why."""
    config = result.config
    shown = paper_tests(result)
    theirs = f"trained on {reference.TRAIN_EXPERIMENT}, predicting " \
        f"{', '.join(reference.TEST_EXPERIMENTS)}"
    if not any(t in reference.TEST_EXPERIMENTS for t in config.tests):
        return (f"The paper's Table 6 ({theirs}) is not shown: none of the experiments "
                f"predicted here ({', '.join(config.tests)}) is one of its.")
    if not shown:
        return (f"The paper's Table 6 ({theirs}) is not shown: this study trains on "
                f"{config.train}, so none of its numbers answers the same question.")
    if set(shown) == set(reference.TEST_EXPERIMENTS):
        return f"The paper's columns are its Table 6 ({theirs}), its printed mean last."
    return (f"The paper's columns are its Table 6 ({theirs}) for the experiments predicted "
            f"here too ({', '.join(shown)}), and their mean; its printed 4-run mean is not "
            f"comparable with ours and not shown.")


def table4_markdown(result: StudyResult) -> str:
    """Like the paper's Table 4: per k, the selected points of each group with ψ."""
    lines = []
    header = ["k", *(f"{GROUP_LABELS[g]} (ours)" for g in result.groups)]
    with_paper = trains_like_paper(result)
    paper_groups = GROUPS if with_paper else ()
    header += [f"{GROUP_LABELS[g]} (paper)" for g in paper_groups]
    body = []
    for k in result.config.clusters:
        cells = [result.cell(g, k) for g in result.groups]
        paper = reference.SELECTED.get(k, {}) if with_paper else {}
        depth = max([len(c.selected) for c in cells] + [len(v) for v in paper.values()])
        for rank in range(depth):
            row = [str(k) if rank == 0 else ""]
            for cell in cells:
                row.append(
                    f"{cell.selected[rank]} (ψ={cell.psi[rank]:+.4f})"
                    if rank < len(cell.selected) else ""
                )
            for group in paper_groups:
                chosen = paper.get(group, [])
                row.append(
                    f"{chosen[rank][0]} (ψ={chosen[rank][1]:.4f})" if rank < len(chosen) else ""
                )
            body.append(row)
    lines.append(_markdown(pd.DataFrame(body, columns=header)))
    if note := paper_training_note(result, 4):
        lines += ["", note]
    eta_rows = [
        [str(k), *(_fmt(result.cell(g, k).eta, 4) for g in result.groups)]
        for k in result.config.clusters
    ]
    lines.append("")
    lines.append("Cut thresholds η of t(R) (the λ-cut giving k clusters):")
    lines.append("")
    lines.append(_markdown(pd.DataFrame(
        eta_rows, columns=["k", *(GROUP_LABELS[g] for g in result.groups)]
    )))
    return "\n".join(lines)


def table5_markdown(result: StudyResult) -> str:
    """Training R² of each model, ours beside the paper's."""
    frame = table5_frame(result)
    paper_groups = GROUPS if trains_like_paper(result) else ()
    header = ["k", *(f"{GROUP_LABELS[g]} (ours)" for g in result.groups)]
    header += [f"{GROUP_LABELS[g]} (paper)" for g in paper_groups]
    body = [
        [str(int(row["clusters"])),
         *(_fmt(row[g], 4) for g in result.groups),
         *(_fmt(row[f"paper_{g}"], 4) for g in paper_groups)]
        for _, row in frame.iterrows()
    ]
    table = _markdown(pd.DataFrame(body, columns=header))
    note = paper_training_note(result, 5)
    return f"{table}\n\n{note}" if note else table


def table6_markdown(result: StudyResult) -> str:
    """RMSE per predicted experiment and mean, ours, then the paper's in the same row (only
    the experiments it predicts too; ``table6_paper_note`` below the table says which)."""
    frame = table6_frame(result)
    tests = list(result.config.tests)
    shown = paper_tests(result)
    mean_column = frame.columns[-1]
    header = ["k", "group", *tests, "**mean**"]
    if shown:
        header += [f"paper {t}" for t in shown] + [f"**{paper_mean_label(result)}**"]
    body = []
    for _, row in frame.iterrows():
        paper_cells = [*(_fmt(row[f"paper_{t}"], 1) for t in shown),
                       f"**{_fmt(row[mean_column], 1)}**"] if shown else []
        body.append([
            str(int(row["clusters"])), GROUP_LABELS[row["group"]],
            *(_fmt(row[t], 1) for t in tests), f"**{_fmt(row['mean'], 1)}**", *paper_cells,
        ])
    scale = measured_rms(result)
    body.append([
        "", "*scale: RMS of the measured error (= RMSE of predicting 0)*",
        *(_fmt(scale[t], 1) for t in tests), f"*{_fmt(float(np.mean(list(scale.values()))), 1)}*",
        *([""] * (len(shown) + 1 if shown else 0)),
    ])
    return _markdown(pd.DataFrame(body, columns=header)) + "\n\n" + table6_paper_note(result)


def measured_rms(result: StudyResult) -> dict[str, float]:
    """RMS of the measured error of each predicted experiment: the RMSE a model that always
    predicts zero drift would get, for scale (missing samples left out)."""
    return {
        test: float(np.sqrt(np.nanmean(result.frames[test][result.config.target].to_numpy() ** 2)))
        for test in result.config.tests
    }


def methods_frame(result: StudyResult) -> pd.DataFrame:
    """Every method x group x k: mean, spread (SD across held-out runs) and worst RMSE."""
    rows = []
    for cell in result.method_cells:
        rows.append({"method": cell.method, "group": cell.group, "k": cell.k,
                     "mean_rmse_um": cell.mean_rmse_um, "spread_um": cell.spread_um,
                     "worst_um": cell.worst_um, "selected": ";".join(cell.selected),
                     **{f"rmse_{name}_um": cell.rmse_um.get(name, np.nan)
                        for name in result.config.tests},
                     "error": cell.error})
    return pd.DataFrame(rows)


def methods_markdown(result: StudyResult) -> str:
    """Per group: rows k, one column per method (mean held-out RMSE); then every method x k
    with mean / spread / worst per group. A method that could not run shows its reason below."""
    frame = methods_frame(result)
    methods = list(dict.fromkeys(frame["method"]))
    parts = []
    for group in GROUPS:
        at = frame[frame["group"] == group]
        body = [[str(k), *(_fmt(at[(at["k"] == k) & (at["method"] == m)]["mean_rmse_um"]
                                .iloc[0], 2) for m in methods)]
                for k in result.config.clusters]
        parts.append(f"Mean held-out RMSE (µm), {GROUP_LABELS[group]}:\n\n"
                     + _markdown(pd.DataFrame(body, columns=["k", *methods])))
    header = ["method", "k", *(f"{GROUP_LABELS[g]}: mean / spread / worst" for g in GROUPS)]
    body = []
    for method in methods:
        for k in result.config.clusters:
            row = [method, str(k)]
            for group in GROUPS:
                at = frame[(frame["method"] == method) & (frame["group"] == group)
                           & (frame["k"] == k)].iloc[0]
                row.append(" / ".join(_fmt(at[c], 2)
                                      for c in ("mean_rmse_um", "spread_um", "worst_um")))
            body.append(row)
    parts.append("Every method × k (µm; spread = standard deviation of the per-run RMSE across "
                 "the held-out runs, worst = the largest per-run RMSE):\n\n"
                 + _markdown(pd.DataFrame(body, columns=header)))
    failed = frame[frame["error"] != ""]
    if len(failed):
        parts.append("Could not run (shown as –):\n\n" + "\n".join(
            f"- {row.method}, {GROUP_LABELS[row.group]}, k = {row.k}: {row.error}"
            for row in failed.itertuples()))
    return "\n\n".join(parts)
