"""The analogues of the paper's Tables 4, 5 and 6, as DataFrames (CSV) and Markdown.

Ours come from a ``StudyResult``; the paper's numbers (``reference``) sit beside them so a
reader sees both. The paper's experiments are not ours, so its numbers are a yardstick for
the size of the effect, not a target to match.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from spindlebench.paper_study import reference
from spindlebench.paper_study.study import GROUP_LABELS, StudyResult


def _fmt(value: float, digits: int) -> str:
    return "–" if value is None or not math.isfinite(value) else f"{value:.{digits}f}"


def _markdown(frame: pd.DataFrame) -> str:
    """A GitHub-flavoured Markdown table (no extra dependency)."""
    header = "| " + " | ".join(str(c) for c in frame.columns) + " |"
    rule = "|" + "|".join("---" for _ in frame.columns) + "|"
    rows = ["| " + " | ".join(str(v) for v in row) + " |" for row in frame.itertuples(False)]
    return "\n".join([header, rule, *rows])


def table4_frame(result: StudyResult) -> pd.DataFrame:
    """Selected candidates, one row each: k, group, rank, name, ψ, cluster size, η."""
    rows = []
    for cell in result.cells:
        for rank, (name, psi) in enumerate(zip(cell.selected, cell.psi, strict=True), start=1):
            paper = reference.SELECTED.get(cell.k, {}).get(cell.group, [])
            rows.append({
                "clusters": cell.k, "group": cell.group, "rank": rank, "selected": name,
                "psi": psi, "cluster_size": len(cell.clusters[rank - 1]), "eta": cell.eta,
                "paper_selected": paper[rank - 1][0] if rank <= len(paper) else "",
                "paper_psi": paper[rank - 1][1] if rank <= len(paper) else float("nan"),
            })
    return pd.DataFrame(rows)


def table5_frame(result: StudyResult) -> pd.DataFrame:
    """Training R², one row per k, one column per group, then the paper's."""
    rows = []
    for k in result.config.clusters:
        row: dict[str, object] = {"clusters": k}
        for group in result.groups:
            row[group] = result.cell(group, k).r2
        for group in reference.GROUPS:
            row[f"paper_{group}"] = reference.R2.get(k, {}).get(group, float("nan"))
        rows.append(row)
    return pd.DataFrame(rows)


def table6_frame(result: StudyResult) -> pd.DataFrame:
    """RMSE (µm) per predicted experiment and mean, one row per (k, group), then the paper's."""
    rows = []
    paper_tests = reference.TEST_EXPERIMENTS
    for k in result.config.clusters:
        for group in result.groups:
            cell = result.cell(group, k)
            row: dict[str, object] = {"clusters": k, "group": group}
            for test in result.config.tests:
                row[test] = cell.rmse_um[test]
            row["mean"] = cell.mean_rmse_um
            paper = reference.RMSE_UM.get(k, {}).get(group)
            for i, test in enumerate(paper_tests):
                row[f"paper_{test}"] = paper[i] if paper else float("nan")
            row["paper_mean"] = paper[-1] if paper else float("nan")
            rows.append(row)
    return pd.DataFrame(rows)


def table4_markdown(result: StudyResult) -> str:
    """Like the paper's Table 4: per k, the selected points of each group with ψ."""
    lines = []
    header = ["k", *(f"{GROUP_LABELS[g]} (ours)" for g in result.groups)]
    header += [f"{GROUP_LABELS[g]} (paper)" for g in reference.GROUPS]
    body = []
    for k in result.config.clusters:
        cells = [result.cell(g, k) for g in result.groups]
        paper = reference.SELECTED.get(k, {})
        depth = max([len(c.selected) for c in cells] + [len(v) for v in paper.values()])
        for rank in range(depth):
            row = [str(k) if rank == 0 else ""]
            for cell in cells:
                row.append(
                    f"{cell.selected[rank]} (ψ={cell.psi[rank]:+.4f})"
                    if rank < len(cell.selected) else ""
                )
            for group in reference.GROUPS:
                chosen = paper.get(group, [])
                row.append(
                    f"{chosen[rank][0]} (ψ={chosen[rank][1]:.4f})" if rank < len(chosen) else ""
                )
            body.append(row)
    lines.append(_markdown(pd.DataFrame(body, columns=header)))
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
    header = ["k", *(f"{GROUP_LABELS[g]} (ours)" for g in result.groups)]
    header += [f"{GROUP_LABELS[g]} (paper)" for g in reference.GROUPS]
    body = [
        [str(int(row["clusters"])),
         *(_fmt(row[g], 4) for g in result.groups),
         *(_fmt(row[f"paper_{g}"], 4) for g in reference.GROUPS)]
        for _, row in frame.iterrows()
    ]
    return _markdown(pd.DataFrame(body, columns=header))


def table6_markdown(result: StudyResult) -> str:
    """RMSE per predicted experiment and mean, ours, then the paper's in the same row."""
    frame = table6_frame(result)
    tests = list(result.config.tests)
    header = ["k", "group", *tests, "**mean**"]
    header += [f"paper {t}" for t in reference.TEST_EXPERIMENTS] + ["**paper mean**"]
    body = []
    for _, row in frame.iterrows():
        body.append([
            str(int(row["clusters"])), GROUP_LABELS[row["group"]],
            *(_fmt(row[t], 1) for t in tests), f"**{_fmt(row['mean'], 1)}**",
            *(_fmt(row[f"paper_{t}"], 1) for t in reference.TEST_EXPERIMENTS),
            f"**{_fmt(row['paper_mean'], 1)}**",
        ])
    scale = measured_rms(result)
    body.append([
        "", "*scale: RMS of the measured error (= RMSE of predicting 0)*",
        *(_fmt(scale[t], 1) for t in tests), f"*{_fmt(float(np.mean(list(scale.values()))), 1)}*",
        *([""] * (len(reference.TEST_EXPERIMENTS) + 1)),
    ])
    return _markdown(pd.DataFrame(body, columns=header))


def measured_rms(result: StudyResult) -> dict[str, float]:
    """RMS of the measured error of each predicted experiment: the RMSE a model that always
    predicts zero drift would get, for scale (missing samples left out)."""
    return {
        test: float(np.sqrt(np.nanmean(result.frames[test][result.config.target].to_numpy() ** 2)))
        for test in result.config.tests
    }
