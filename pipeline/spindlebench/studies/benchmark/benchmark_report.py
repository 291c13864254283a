"""The leaderboard: ranks per task and overall, baseline marks, and its four files.

Per task the entrants are ranked by ``rmse_um`` (1 = lowest; ties share the mean rank; a
failed entrant is unranked). Overall, an entrant's score is its mean rank over the tasks
(every entrant runs on every task, so the means are comparable; one that failed a task gets
the worst rank there plus one), then its mean RMSE breaks ties. ``worse_than`` lists the
baselines with a lower RMSE on that task: a method worse than the constant predictor has
learnt nothing usable there.

Files (in the output folder): ``leaderboard.md`` (the tables), ``leaderboard.csv`` (one row
per task and entrant, plus per-fold rows in ``folds.csv``), ``leaderboard.json`` (everything,
with the suite's version and task hash and the provenance of every entrant's code) and
``leaderboard.png`` (RMSE per task and entrant).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from spindlebench.core import atomic
from spindlebench.formats.table_csv import write_table
from spindlebench.studies.benchmark.benchmark_file import Suite
from spindlebench.studies.benchmark.scoring import BASELINES, Entry

COLUMNS = ("task", "method", "rank", "rmse_um", "rmse_sd_um", "max_abs_error_um",
           "within_band", "n_sensors", "stability", "rollout_rmse_um", "worse_than", "folds",
           "error")
#: Short marks of the baselines in the Markdown tables.
MARKS = {"baseline:constant": "C", "baseline:replay": "R", "baseline:ols-all": "O"}
#: What the marks and the rollout column mean (above the tables, in leaderboard.md and docs).
MARKS_TEXT = ("Marks: C, R, O = worse (higher RMSE) than the constant training-mean predictor, "
              "the replay of the training run's error, OLS on all sensors. Rollout: the RMSE of "
              "the prediction over each whole held-out run from its start, no resets (a static "
              "model's is its RMSE; a dynamic model's differs when its ordinary prediction "
              "corrects itself with the run's measurements).")


def rows(entries: Sequence[Entry], band_um: float) -> pd.DataFrame:
    """One row per (task, entrant) with metrics, rank and baseline marks."""
    records = []
    for entry in entries:
        records.append({"task": entry.task, "method": entry.method,
                        **entry.metrics(band_um), "folds": len(entry.folds),
                        "error": entry.error})
    frame = pd.DataFrame.from_records(records)
    frame["rank"] = np.nan
    frame["worse_than"] = ""
    for _, part in frame.groupby("task", sort=False):
        scored = part["rmse_um"].astype(float)
        frame.loc[part.index, "rank"] = scored.rank(method="average")
        baselines = {row.method: row.rmse_um for row in part.itertuples()
                     if row.method in BASELINES and row.rmse_um is not None
                     and not math.isnan(row.rmse_um)}
        for index, row in part.iterrows():
            if row["method"] in BASELINES or row["rmse_um"] is None or \
                    math.isnan(float(row["rmse_um"])):
                continue
            worse = [name for name, value in baselines.items() if row["rmse_um"] > value]
            frame.loc[index, "worse_than"] = ";".join(worse)
    return frame.loc[:, list(COLUMNS)]


def overall(frame: pd.DataFrame) -> pd.DataFrame:
    """Mean rank over tasks (a failed task counts as the task's worst rank + 1), mean RMSE,
    and how many tasks each entrant was worse than each baseline on."""
    worst = frame.groupby("task")["rank"].transform("max").fillna(0) + 1
    ranks = frame["rank"].fillna(worst)
    table = frame.assign(rank_filled=ranks).groupby("method", sort=False).agg(
        mean_rank=("rank_filled", "mean"),
        mean_rmse_um=("rmse_um", lambda v: float(np.nanmean(v.astype(float)))
                      if np.isfinite(v.astype(float)).any() else np.nan),
        tasks=("task", "count"),
        failed=("error", lambda v: int((v != "").sum())),
    )
    for baseline in BASELINES:
        column = f"worse_than_{baseline.split(':')[1].replace('-', '_')}"
        table[column] = frame.groupby("method", sort=False)["worse_than"].agg(
            lambda v, b=baseline: int(sum(b in s.split(";") for s in v)))
    table = table.sort_values(["mean_rank", "mean_rmse_um"], kind="stable")
    table.insert(0, "overall_rank", np.arange(1, len(table) + 1))
    return table.reset_index()


def fold_rows(entries: Sequence[Entry]) -> pd.DataFrame:
    """One row per (task, entrant, fold, held-out run): the RMSE and the sensors read."""
    records = []
    for entry in entries:
        for fold in entry.folds:
            for test, value in fold.rmse_um.items():
                records.append({"task": entry.task, "method": entry.method,
                                "fold": fold.fold, "test": test, "rmse_um": value,
                                "rollout_rmse_um": (fold.rollout_rmse_um or
                                                    fold.rmse_um)[test],
                                "sensors": ";".join(fold.sensors),
                                "selected": ";".join(fold.selected)})
    return pd.DataFrame.from_records(
        records, columns=["task", "method", "fold", "test", "rmse_um", "rollout_rmse_um",
                          "sensors", "selected"])


def _cell(value: Any, digits: int = 2) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "–"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


def overall_table(records: Sequence[Mapping[str, Any]]) -> str:
    """The overall table (one row per entrant, in rank order) from the ``overall`` records of
    ``leaderboard.json``: the one rendering of it (``leaderboard.md`` and the docs' table)."""
    lines = ["| # | method | mean rank | mean RMSE µm | worse than C / R / O (tasks) | failed |",
             "|---|---|---|---|---|---|"]
    for row in records:
        lines.append(f"| {row['overall_rank']} | `{row['method']}` | {row['mean_rank']:.2f} | "
                     f"{_cell(row['mean_rmse_um'])} | {row['worse_than_constant']} / "
                     f"{row['worse_than_replay']} / {row['worse_than_ols_all']} | "
                     f"{row['failed']} |")
    return "\n".join(lines)


def tasks_of(records: Sequence[Mapping[str, Any]]) -> list[str]:
    """The tasks of the ``rows`` records of ``leaderboard.json``, in the suite's order."""
    return list(dict.fromkeys(row["task"] for row in records))


def task_table(records: Sequence[Mapping[str, Any]], task: str, band_um: float) -> str:
    """One task's table (entrants by rank, a failed one last) from the ``rows`` records of
    ``leaderboard.json``: the one rendering of it (``leaderboard.md`` and the docs' table)."""
    part = [row for row in records if row["task"] == task]
    if not part:
        raise ValueError(f"the leaderboard has no task {task!r} (has "
                         f"{', '.join(tasks_of(records))})")
    lines = [f"| rank | method | RMSE µm | sd over folds | max abs µm | within ±{band_um:g} µm "
             "| sensors | stability | rollout µm | worse than |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for row in sorted(part, key=lambda r: (_missing(r["rank"]), r["rank"] or 0.0, r["method"])):
        marks = "".join(MARKS[b] for b in row["worse_than"].split(";") if b)
        shown = f"failed: {row['error']}" if row["error"] else _cell(row["rmse_um"])
        lines.append(
            f"| {_cell(row['rank'], 1)} | `{row['method']}` | {shown} | "
            f"{_cell(row['rmse_sd_um'])} | {_cell(row['max_abs_error_um'])} | "
            f"{_cell(row['within_band'])} | {_cell(row['n_sensors'], 1)} | "
            f"{_cell(row['stability'])} | {_cell(row['rollout_rmse_um'])} | {marks} |")
    return "\n".join(lines)


def _missing(value: Any) -> bool:
    return value is None or (isinstance(value, float) and math.isnan(value))


def markdown(suite: Suite, frame: pd.DataFrame, table: pd.DataFrame,
             command: str) -> str:
    """The leaderboard as Markdown: the overall table, then one table per task."""
    lines = [
        f"# Leaderboard: suite `{suite.name}` version {suite.version}",
        "",
        f"Tasks SHA-256 `{suite.tasks_sha256}`; k = {suite.k} sensors per selection method; "
        f"seed {suite.seed}. Made by `{command}`.",
        "",
        MARKS_TEXT,
        "",
        "## Overall (mean rank over tasks)",
        "",
        overall_table(_records(table)),
    ]
    records = _records(frame)
    for task in tasks_of(records):
        lines += ["", f"## {task}", "", task_table(records, task, suite.band_um)]
    return "\n".join(lines) + "\n"


def figure(frame: pd.DataFrame, path: Path) -> Path:
    """RMSE per task (panels) and entrant (bars from zero, baselines grey)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tasks = list(dict.fromkeys(frame["task"]))
    methods = list(dict.fromkeys(frame["method"]))
    fig, axes = plt.subplots(len(tasks), 1, figsize=(10, 1.2 + 2.2 * len(tasks)),
                             squeeze=False, sharex=True)
    for ax, task in zip(axes[:, 0], tasks, strict=True):
        part = frame[frame["task"] == task].set_index("method")
        values = [float(part.loc[m, "rmse_um"]) if m in part.index and
                  part.loc[m, "rmse_um"] is not None else np.nan for m in methods]
        colours = ["#9a9a9a" if m in BASELINES else "#d9622b" for m in methods]
        ax.bar(range(len(methods)), values, color=colours)
        constant = part.loc["baseline:constant", "rmse_um"] if \
            "baseline:constant" in part.index else None
        if constant is not None and np.isfinite(constant):
            ax.axhline(constant, color="black", linewidth=0.8, linestyle="--")
        ax.set_ylim(bottom=0)
        ax.set_ylabel("RMSE (µm)")
        ax.set_title(task, fontsize=9, loc="left")
    axes[-1, 0].set_xticks(range(len(methods)))
    axes[-1, 0].set_xticklabels(methods, rotation=60, ha="right", fontsize=8)
    fig.suptitle("Held-out RMSE per task (grey: baselines; dashed: the constant predictor)",
                 fontsize=10)
    fig.tight_layout()
    with atomic.atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100, format="png", metadata={"Software": None})
    plt.close(fig)
    return path


def write(out: Path, suite: Suite, entries: Sequence[Entry], record: dict[str, Any],
          command: str) -> list[Path]:
    """Write the leaderboard's files into ``out``; return their paths (docs/benchmark.md's
    tables are generated from ``leaderboard.json``, committed under docs/snapshots/)."""
    out.mkdir(parents=True, exist_ok=True)
    frame = rows(entries, suite.band_um)
    table = overall(frame)
    written = [out / "leaderboard.md", out / "leaderboard.csv", out / "folds.csv",
               out / "leaderboard.json", out / "leaderboard.png"]
    board = markdown(suite, frame, table, command)
    atomic.write_text(written[0], board)
    write_table(written[1], frame)
    write_table(written[2], fold_rows(entries))
    document = {**record, "suite": suite.describe(),
                "overall": _records(table), "rows": _records(frame),
                "warnings": {f"{e.task} | {e.method}": e.warnings for e in entries
                             if e.warnings}}
    atomic.write_text(written[3], json.dumps(document, indent=2, allow_nan=False,
                                             default=str) + "\n")
    figure(frame, written[4])
    return written


def _records(frame: pd.DataFrame) -> list[dict[str, Any]]:
    out = []
    for record in frame.to_dict(orient="records"):
        out.append({key: (None if isinstance(value, float) and math.isnan(value) else
                          value.item() if hasattr(value, "item") else value)
                    for key, value in record.items()})
    return out
