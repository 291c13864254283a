"""Joint placements of a study with several targets (``[study] targets``, issue 21): where to
put m sensors to compensate X, Y, Z and the tilts together.

Each target has its own placement study in ``<out>/<target>/`` (``placement_run``). Here one
sensor set serves every target, each target refitted on it (the same OLS as every placement)
and scored on the same held-out runs:

- ``union:<label>``: the union of the per-target placements of method ``label`` at budget m
  (more sensors than m; each target keeps its own choice);
- a multi-output method of the registry (``method_registry.method_names(multi_output=True)``:
  ``mtlasso``, ``pls-vip``): m candidates chosen on the design replica's training runs for
  all targets at once (candidates that vary there, as every method sees them).

Written: ``joint.csv`` (one row per joint placement: its sensors and each target's mean test
RMSE), the per-target best placements beside it in ``README.md``, and ``joint.json`` with
provenance.
"""

from __future__ import annotations

import math
import time
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from spindlebench.core.atomic import write_text
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.selection.method_registry import METHOD_REGISTRY, method_names
from spindlebench.studies.placement.placements import (
    Design,
    Placement,
    _placement,
    score_placement,
)

if TYPE_CHECKING:
    from spindlebench.studies.placement.placement_run import (
        PlacementOutcome,
        PlacementStudyRun,
    )


def _test_replicas(work: PlacementStudyRun, outcome: PlacementOutcome) -> list[int]:
    """The replicas whose held-out runs count as test runs (as ``placements_table``)."""
    study = work.study
    honest = len(study.test_replicas) and study.test_replicas != (study.design_replica,)
    wanted = study.test_replicas if honest else (study.design_replica,)
    return [r for r in wanted if r in outcome.runs]


def joint_placements(work: PlacementStudyRun,
                     outcomes: dict[str, PlacementOutcome]) -> list[Placement]:
    """Every union and multi-output placement of the study's budgets and candidate sets."""
    study = work.study
    targets = list(outcomes)
    first = outcomes[targets[0]]
    train_runs, valid_runs = first.runs[study.design_replica]
    out: list[Placement] = []
    for differences in study.with_differences:
        design = Design(study, differences, train_runs, valid_runs)
        labels = list(dict.fromkeys(p.label for p in first.placements
                                    if p.differences == differences))
        for m in study.budgets:
            for label in labels:
                chosen = [next((p for p in outcomes[t].placements if p.label == label
                                and p.budget == m and p.found), None) for t in targets]
                if any(p is None for p in chosen):
                    continue
                columns = sorted({c for p in chosen for c in p.columns})
                out.append(_placement(f"union:{chosen[0].method}", differences, m,
                                      design.candidates, columns, math.nan, 0.0,
                                      "union of the per-target placements"))
            for name in method_names(multi_output=True):
                start = time.perf_counter()
                pool = design.pool
                X = design.train.X[:, pool]
                Y = np.column_stack([np.concatenate([run.drift_um for run in
                                                     outcomes[t].runs[study.design_replica][0]])
                                     for t in targets])
                selector = METHOD_REGISTRY[name].make(m).fit(X, Y)
                out.append(_placement(name, differences, m, design.candidates,
                                      pool[np.asarray(selector.selected_, dtype=np.intp)],
                                      math.nan, time.perf_counter() - start,
                                      "one selection for every target"))
    return out


def joint_table(work: PlacementStudyRun, outcomes: dict[str, PlacementOutcome],
                placements: list[Placement]) -> pd.DataFrame:
    """One row per joint placement: its sensors and each target's mean test RMSE."""
    rows = []
    for placement in placements:
        row: dict[str, Any] = {"label": placement.label, "m": placement.budget,
                               "variables": ";".join(placement.variables),
                               "sensors": ";".join(placement.nodes),
                               "n_sensors": len(placement.nodes)}
        for target, outcome in outcomes.items():
            scores = [r["rmse_um"] for replica in _test_replicas(work, outcome)
                      for r in score_placement(work.study, placement,
                                               *outcome.runs[replica])]
            row[f"test_mean_rmse_{target}"] = float(np.mean(scores))
        rows.append(row)
    return pd.DataFrame(rows)


def best_per_target(outcomes: dict[str, PlacementOutcome]) -> pd.DataFrame:
    """Per target and budget, its own best placement (lowest mean test RMSE)."""
    rows = []
    for target, outcome in outcomes.items():
        table = outcome.table[outcome.table["test_mean_rmse_um"].notna()]
        for m, at in table.groupby("m"):
            best = at.loc[at["test_mean_rmse_um"].idxmin()]
            rows.append({"target": target, "m": int(m), "label": best["label"],
                         "sensors": best["sensors"], "n_sensors": int(best["n_sensors"]),
                         "test_mean_rmse": float(best["test_mean_rmse_um"])})
    return pd.DataFrame(rows)


def _markdown(frame: pd.DataFrame) -> str:
    from spindlebench.studies.sweep.sweep_report import markdown_table

    return markdown_table(frame)


def write_joint(work: PlacementStudyRun, outcomes: dict[str, PlacementOutcome]) -> None:
    """``joint.csv``, ``joint.json`` and the study folder's ``README.md``."""
    study, store = work.study, work.store
    placements = joint_placements(work, outcomes)
    table = joint_table(work, outcomes, placements)
    best = best_per_target(outcomes)
    store.write_frame("joint.csv", table)
    store.write_frame("best_per_target.csv", best)
    record = provenance(kind="spindlebench joint sensor placement", study=file_entry(study.path),
                        fmu=file_entry(work.fmu), targets=list(outcomes),
                        machine=study.family.machine.provenance())
    store.write_json("joint.json", {"rows": table.to_dict(orient="records"),
                                    "best_per_target": best.to_dict(orient="records"),
                                    "provenance": record})
    targets = ", ".join(f"`{t}`" for t in outcomes)
    shown = table.copy()
    for column in [c for c in shown if c.startswith("test_mean_rmse_")]:
        shown[column] = shown[column].map(lambda v: f"{v:.2f}")
    best_shown = best.assign(test_mean_rmse=best["test_mean_rmse"].map(lambda v: f"{v:.2f}"))
    text = "\n".join([
        f"# Sensor placement: {study.name}, several targets", "",
        f"Made by `spindlebench place {study.path}` (targets {targets}; study file SHA-256 "
        f"`{record['study']['sha256'][:12]}…`, FMU `{record['fmu']['sha256'][:12]}…`). Each "
        "target's own placement study is in its folder (`<target>/README.md`); the tables "
        "below are `best_per_target.csv` and `joint.csv`. RMSE are the mean over the test "
        "replicas' held-out runs, each target in its own unit (µm, a tilt µrad).", "",
        "## Each target's own best placement", "", _markdown(best_shown), "",
        "## One sensor set for every target", "",
        "`union:<method>`: the union of that method's per-target placements at budget m; "
        f"{', '.join(method_names(multi_output=True))}: m candidates chosen for all targets at "
        "once on the design replica's training runs. Every target is refitted (OLS) on the "
        "set.", "", _markdown(shown), ""])
    write_text(store.path("README.md"), text)
