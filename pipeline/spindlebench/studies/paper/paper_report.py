"""Write a study's outputs: tables (CSV + Markdown), figures, results JSON, README, provenance.

Every file is written atomically; the README is the page a reader opens first.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from spindlebench.core import atomic
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import DEFAULT_METHOD, GROUP_LABELS
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.formats.recording import sidecar_mismatch
from spindlebench.selection.registry import methods_record
from spindlebench.studies.paper import figures, reference
from spindlebench.studies.paper import paper_tables as tables
from spindlebench.studies.paper.analysis import StudyResult


def _json(value: Any) -> Any:
    """Plain JSON values (numpy scalars and arrays become numbers and lists; NaN -> null)."""
    if isinstance(value, dict):
        return {str(k): _json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json(v) for v in value]
    if isinstance(value, np.ndarray):
        return _json(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def _write_json(path: Path, data: Any) -> Path:
    atomic.write_text(path, json.dumps(_json(data), indent=2, ensure_ascii=False) + "\n")
    return path


def _write_csv(path: Path, frame) -> Path:
    with atomic.atomic_path(path) as tmp:
        frame.to_csv(tmp, index=False, float_format="%.6g")
    return path


def _inputs(result: StudyResult) -> dict[str, Any]:
    """Each recording's hash, plus its own sidecar provenance when it has one."""
    entries: dict[str, Any] = {}
    for name, path in result.paths.items():
        entry: dict[str, Any] = file_entry(path)
        sidecar = path.with_suffix(".json")
        if sidecar.is_file():
            try:
                record = json.loads(sidecar.read_text(encoding="utf-8"))
            except json.JSONDecodeError:
                record = f"{sidecar.name}: not valid JSON, not embedded"
            problem = sidecar_mismatch(entry["sha256"], record) if isinstance(record, dict) \
                else None
            if problem:
                warnings.warn(f"{sidecar}: {problem}; not embedded", stacklevel=2)
                record = f"{sidecar.name}: {problem}; not embedded"
            entry["sidecar"] = record
        entries[name] = entry
    return entries


def _groups_markdown(result: StudyResult) -> str:
    lines = []
    for group in result.groups:
        sensors, differences = result.group_sensors(group)
        n_diff = len(sensors) * (len(sensors) - 1) // 2 if differences else 0
        extra = f" plus their {n_diff} pairwise differences" if differences else ""
        lines.append(
            f"- **{GROUP_LABELS[group]}** (`{group}`): {len(sensors)} raw sensors "
            f"({', '.join(sensors)}){extra}."
        )
    return "\n".join(lines)


_MISSING_TEXT = {
    "error": "`error` (a recording with an empty or NaN value is rejected).",
    "drop-rows": "`drop-rows`: samples where the target or a sensor a model uses is missing "
    "are dropped before rises are computed (rises start at the first complete sample; "
    "nothing is filled in); the warnings say how many, where.",
}


def _methods_section(result: StudyResult) -> str:
    """The "methods compared" section, when the study lists methods beyond the paper's."""
    if tuple(result.config.methods) == (DEFAULT_METHOD,):
        return ""
    seeded = f" Seed of fcm, kmeans and stability: {result.config.seed}."
    return f"""
## Methods compared (not in the paper)

The same protocol (train on {result.config.train}, predict the others, rises, the same
candidate groups) with every method of `methods` (`spindlebench methods` says what each
label means; `closure` is the paper's method, the tables above).{seeded}

{tables.methods_markdown(result)}

All of it is in `methods_rmse.csv`.
"""


def readme_text(result: StudyResult, figure_paths: dict[str, Path], command: str) -> str:
    """The results page: set-up, the three tables (the paper's beside ours where they answer
    the same question), the figures."""
    config = result.config
    fig = {key: path.name for key, path in figure_paths.items()}
    best = min(result.cells, key=lambda c: c.mean_rmse_um)
    paper_note = (
        "The paper's experiments are not ours (a different machine): its numbers show the size "
        "of the effect it reported, not numbers these data should reproduce."
    )
    tests = ", ".join(config.tests)
    dendrograms = "\n".join(
        f"  - {GROUP_LABELS[g]}: ![dendrogram]({fig[f'dendrogram_{g}']})" for g in result.groups
    )
    return f"""# Paper comparison: {config.title}

The comparison of Xu et al. (2023), section 3, rerun by `spindlebench paper`: temperature-
sensitive points chosen by fuzzy clustering (similarity `{config.similarity}`, max-min
transitive closure, λ-cut into k clusters, largest |ψ| per cluster), multiple linear regression
of `{config.target}` on the temperature rises of the chosen points, trained on
**{config.train}** and used to predict {", ".join(f"**{t}**" for t in config.tests)}.

Command:

```
{command}
```

## Set-up
- Target: `{config.target}`; training experiment `{config.train}`; predicted: {tests}.
- Numbers of clusters: {", ".join(str(k) for k in config.clusters)}.
- Missing values: {_MISSING_TEXT[config.missing]}
{_groups_markdown(result)}
- Six-sensor subset: {result.six_rule}

Lowest mean RMSE here: **{best.mean_rmse_um:.2f} µm** ({GROUP_LABELS[best.group]}, k = {best.k}).
The paper's headline (k = 2): mean RMSE 11.1 and 10.3 µm for the raw groups vs 3.6 µm with
differences.

## Table 4 analogue: selected points and ψ (on {config.train})

ψ is the Pearson correlation of a candidate with `{config.target}` (sign kept; the paper prints
magnitudes).

{tables.table4_markdown(result)}

## Table 5 analogue: training R²

{tables.table5_markdown(result)}

## Table 6 analogue: RMSE of the predictions (µm)

Ours first, then the paper's Table 6 in the same row where it predicted the same experiment
(see the line below the table). {paper_note}

{tables.table6_markdown(result)}
{_methods_section(result)}
## Figures

- Thermal error of every experiment (paper Fig. 3): ![error curves]({fig["error_curves"]})
- The six sensors in the training experiment (paper Fig. 4):
  ![six temperatures]({fig["six_temperatures"]})
- Measured vs predicted, every predicted experiment and k (paper Fig. 5):
  ![measured vs predicted]({fig["measured_vs_predicted"]})
- RMSE of every prediction (paper Fig. 6, as grouped bars): ![rmse]({fig["rmse_bars"]})
- Fuzzy equivalence hierarchies with the λ-cuts (not in the paper): single-linkage dendrograms
  of 1 − t(R) on {config.train}; the line "cut for k" cuts the tree into exactly the clusters
  of t(R) ≥ η (drawn midway between the two merges it separates, not at 1 − η itself).
{dendrograms}

## Files
- `table4_selected.csv`, `table5_r2.csv`, `table6_rmse.csv`: the tables (paper's numbers in
  the `paper_*` columns when this study trains on the paper's exp1; in Table 6 only for the
  experiments it predicted too).
- `results.json`: every model's full evaluation (selected, ψ, η, clusters, coefficients, R²,
  RMSE per experiment).
- `provenance.json`: inputs with their SHA-256 (and their own provenance), configuration,
  package versions.

Paper: {reference.CITATION}.
"""


def _previous_outputs(out_dir: Path) -> list[str]:
    """The file names an earlier run listed in ``out_dir/provenance.json`` (none if unreadable)."""
    record = _paper_provenance(out_dir)
    outputs = record.get("outputs") if record else None
    if not isinstance(outputs, list):
        return []
    # Only plain names of this study's own kinds of file: never a path out of the folder.
    return [name for name in outputs if isinstance(name, str) and name == Path(name).name
            and Path(name).suffix in {".csv", ".md", ".png", ".json"}]


def _paper_provenance(out_dir: Path) -> dict[str, Any] | None:
    """``out_dir/provenance.json`` when ``spindlebench paper`` wrote it (it names the paper
    and the study; older versions listed no outputs), else None."""
    try:
        record = json.loads((out_dir / "provenance.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if isinstance(record, dict) and "paper" in record and "study" in record:
        return record
    return None


_STAGING_PREFIX = ".paper-study."


def _is_staging(path: Path) -> bool:
    """Whether ``path`` is a staging folder of ``write_outputs``."""
    return path.name.startswith(_STAGING_PREFIX) and path.name.endswith(".part")


def check_out_dir(out_dir: str | Path) -> None:
    """Refuse an output folder that exists, is not empty and was not written by ``paper``:
    a rerun replaces its own files and removes its own stale ones, but a README.md or a table
    of something else must never be overwritten."""
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise SpindlebenchError(f"{out_dir}: exists and is not a folder")
    # A staging folder left by a killed run does not count as content.
    content = [path for path in out_dir.iterdir() if not _is_staging(path)] \
        if out_dir.is_dir() else []
    if content and _paper_provenance(out_dir) is None:
        raise SpindlebenchError(f"{out_dir}: exists and is not a paper-study folder; "
                                "choose an empty or new folder")


def _remove_stale(out_dir: Path, previous: list[str], current: dict[str, Path]) -> None:
    """Delete what an earlier run wrote and this one did not (a figure of another test run,
    a dendrogram of a dropped group), so the folder never mixes two studies."""
    kept = {path.name for path in current.values()}
    for name in previous:
        if name not in kept:
            (out_dir / name).unlink(missing_ok=True)


def write_outputs(result: StudyResult, out_dir: str | Path, command: str) -> dict[str, Path]:
    """Write everything for ``result`` into ``out_dir``; return the paths by role.

    Everything is first written into a hidden folder inside ``out_dir``; only when every file
    exists and no target name is taken by a folder are they moved into place (so an error
    never leaves half the tables replaced). Files an earlier run listed in its provenance and
    this run does not write are removed after the new ones are in place; other files in
    ``out_dir`` are never touched.
    """
    out_dir = Path(out_dir)
    check_out_dir(out_dir)
    created = not out_dir.exists()
    out_dir.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=_STAGING_PREFIX, suffix=".part", dir=out_dir))
    try:
        staged = _write_all(result, staging, command)
        blocked = sorted(path.name for path in staged.values()
                         if (out_dir / path.name).is_dir())
        if blocked:
            raise SpindlebenchError(f"{out_dir / blocked[0]}: is a folder, where the study "
                                    "writes a file; nothing was written")
        previous = _previous_outputs(out_dir)
        # provenance.json last: until it is in place the folder still describes the old run.
        order = sorted(staged, key=lambda role: role == "provenance")
        for role in order:
            os.replace(staged[role], out_dir / staged[role].name)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        if created:
            with contextlib.suppress(OSError):
                out_dir.rmdir()
        raise
    shutil.rmtree(staging, ignore_errors=True)
    paths = {role: out_dir / path.name for role, path in staged.items()}
    _remove_stale(out_dir, previous, paths)
    return paths


def _write_all(result: StudyResult, out_dir: Path, command: str) -> dict[str, Path]:
    """Every output file of ``result`` in ``out_dir`` (the staging folder); paths by role."""
    paths: dict[str, Path] = {
        "table4_csv": _write_csv(out_dir / "table4_selected.csv", tables.table4_frame(result)),
        "table5_csv": _write_csv(out_dir / "table5_r2.csv", tables.table5_frame(result)),
        "table6_csv": _write_csv(out_dir / "table6_rmse.csv", tables.table6_frame(result)),
    }
    if tuple(result.config.methods) != (DEFAULT_METHOD,):
        paths["methods_csv"] = _write_csv(out_dir / "methods_rmse.csv",
                                          tables.methods_frame(result))
    for number, render in ((4, tables.table4_markdown), (5, tables.table5_markdown),
                           (6, tables.table6_markdown)):
        target = out_dir / f"table{number}.md"
        atomic.write_text(target, render(result) + "\n")
        paths[f"table{number}_md"] = target
    figure_paths = figures.write_all(result, out_dir)
    paths.update(figure_paths)
    paths["results"] = _write_json(out_dir / "results.json", {
        "config": result.config.to_dict(),
        "six": list(result.six),
        "cells": [
            {"group": c.group, "k": c.k, "sensors": c.sensors, "differences": c.differences,
             **c.evaluation}
            for c in result.cells
        ],
    })
    readme = out_dir / "README.md"
    atomic.write_text(readme, readme_text(result, figure_paths, command))
    paths["readme"] = readme
    paths["provenance"] = _write_json(out_dir / "provenance.json", provenance(
        command=command,
        study=result.config.to_dict(),
        six=list(result.six),
        six_rule=result.six_rule,
        inputs=_inputs(result),
        outputs=sorted(p.name for p in paths.values()),
        paper=reference.CITATION,
        methods=methods_record(result.config.methods),
    ))
    return paths
