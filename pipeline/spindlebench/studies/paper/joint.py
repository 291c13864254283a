"""The paper's comparison for several targets (``targets = [...]``, ``paper --target A B``):
each target's own study in ``<out>/<target>/``, and beside them the joint selections (one
sensor set for every target: ``selection.multi_target``) for every group and k, scored per
target on the same experiments: ``<out>/README.md`` and ``<out>/joint.json``.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from spindlebench.core.atomic import write_text
from spindlebench.core.names import GROUP_LABELS
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.selection.evaluate import load_recordings
from spindlebench.selection.multi_target import MultiEvaluation, evaluate_targets
from spindlebench.studies.paper.analysis import StudyResult


def merged_frames(results: dict[str, StudyResult]) -> dict[str, pd.DataFrame]:
    """Every experiment's frame with all targets' columns (each study read its own)."""
    targets = list(results)
    first = results[targets[0]]
    frames = {}
    for name, frame in first.frames.items():
        merged = frame.copy()
        for target in targets[1:]:
            merged[target] = results[target].frames[name][target].to_numpy()
        frames[name] = merged
    return frames


def joint_rows(results: dict[str, StudyResult],
               joint: Sequence[str]) -> list[tuple[str, int, MultiEvaluation]]:
    """(group, k, result) of ``evaluate_targets`` for every group and k of the studies."""
    first = next(iter(results.values()))
    config = first.config
    frames = merged_frames(results)
    train, tests = load_recordings(frames[config.train],
                                   {name: frames[name] for name in config.tests},
                                   config.missing)
    out = []
    for group in first.groups:
        sensors, differences = first.group_sensors(group)
        for k in config.clusters:
            out.append((group, k, evaluate_targets(
                train, tests, list(results), sensors=sensors, k=k, differences=differences,
                similarity=config.similarity, missing=config.missing, joint=joint)))
    return out


def write_joint(results: dict[str, StudyResult], out_dir: Path, command: str,
                joint: Sequence[str]) -> Path:
    """``README.md`` and ``joint.json`` of a several-target comparison in ``out_dir``."""
    rows = joint_rows(results, joint)
    targets = list(results)
    first = next(iter(results.values()))
    table: list[dict[str, Any]] = []
    for group, k, result in rows:
        for row in result.comparison_rows():
            table.append({"group": group, "k": k, **row})
    record = {"targets": targets, "rows": table,
              "provenance": provenance(command=command,
                                       recordings={n: file_entry(p)
                                                   for n, p in first.paths.items()},
                                       config=first.config.to_dict(), joint=list(joint))}
    write_text(out_dir / "joint.json", json.dumps(record, indent=2, allow_nan=False) + "\n")
    # what ``paper_report.check_out_dir`` recognises as a paper folder, so a rerun may replace it
    own = {"paper": "several targets: each in its folder, the joint selections in joint.json",
           "study": first.config.to_dict(), "outputs": ["README.md", "joint.json",
                                                       *(f"{t}/" for t in targets)],
           **record["provenance"]}
    write_text(out_dir / "provenance.json", json.dumps(own, indent=2, allow_nan=False) + "\n")
    head = "| group | k | selection | sensors | " + " | ".join(targets) + " |"
    lines = [f"# The paper's comparison for several targets: {first.config.title}", "",
             f"Made by `{command}`. Each target's own comparison (the paper's tables and "
             "figures) is in its folder: " + ", ".join(f"[`{t}`]({t}/README.md)"
                                                       for t in targets) + ".", "",
             f"Trained on `{first.config.train}`, predicted: "
             f"{', '.join(first.config.tests)}. Mean RMSE over the predicted experiments, "
             "each target in its own unit. *per-target*: each target its own k points (sensors: "
             "how many the models read together); *union*: the union of those, every target "
             "refitted on it; a multi-output method: k points for all targets at once. "
             "Numbers from `joint.json`.", "", head,
             "|" + "---|" * (4 + len(targets))]
    for row in table:
        lines.append(f"| {GROUP_LABELS[row['group']]} | {row['k']} | {row['selection']} | "
                     f"{row['n_sensors']} | "
                     + " | ".join(f"{row[t]:.2f}" for t in targets) + " |")
    path = out_dir / "README.md"
    write_text(path, "\n".join(lines) + "\n")
    return path
