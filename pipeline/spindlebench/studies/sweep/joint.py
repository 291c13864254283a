"""Joint selections of a sweep with several targets (``[study] targets``, issue 21): one sensor
set for X, Y, Z and the tilts together, trained and scored as the sweep scores each target.

Each target has its own sweep in ``<out>/<target>/`` (``sweep_run``). Here, per replica,
condition, training experiment, paper group, selection method and k, the runs as that
condition's instruments measure them (``jobs.measured_frame`` of each target's job: the same
sensor readings, each target's probe reading) go through ``multi_target.evaluate_targets``,
the one home of per-target and joint selection that ``evaluate --target A B ...`` uses:

- ``per-target``: each target's own selection (the per-target sweep's rows, to the bit);
- ``union``: the union of the per-target selections, each target refitted on it;
- each multi-output method of the registry (``mtlasso``, ``pls-vip``): k candidates chosen
  on the training run for all targets at once, each target refitted on them.

Written: ``joint.csv`` (tidy: one row per case × selection × target × held-out experiment,
the RMSE in the target's unit and the raw sensors the selection reads), a table of the means
in ``README.md``, and ``joint.json`` with provenance. The baselines (``ridge``,
``top-k-correlated``, ``oracle``) have no joint form and stay per target.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from spindlebench.core.atomic import write_text
from spindlebench.core.console import one_line_error
from spindlebench.core.names import SIX_DIFF
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.selection.evaluate import CheckedRecording
from spindlebench.selection.method_registry import joint_names
from spindlebench.selection.multi_target import evaluate_targets
from spindlebench.selection.registry import parse_method
from spindlebench.studies.family.experiments import Experiment, replicas
from spindlebench.studies.family.methods import GROUP_SENSORS, group_method_name
from spindlebench.studies.running.jobs import EvaluationJob, measured_targets

if TYPE_CHECKING:
    from spindlebench.studies.running.executor import TaskRunner
    from spindlebench.studies.sweep.sweep_run import Sweep

PER_TARGET = "per-target"
JOINT_COLUMNS = (
    "replica", "data", "noise", "fault", "train_experiment", "test_experiment", "method", "k",
    "selection", "n_sensors", "sensors", "target", "rmse", "error",
)


def _frame(jobs: dict[str, EvaluationJob], experiment: Experiment,
           held_out: bool) -> pd.DataFrame:
    """The run's sensor readings and every target's probe reading (column named by it),
    the sensors measured once for all targets (``jobs.measured_targets``)."""
    return measured_targets(jobs, experiment, held_out)


def joint_rows(sweeps: list[Sweep]) -> pd.DataFrame:
    """Every per-target and joint selection of the sweep's paper groups, scored per target
    on every held-out experiment (a case that raises is one row with its error)."""
    first = sweeps[0]
    study, methods = first.study, first.study.methods
    targets = [sweep.target for sweep in sweeps]
    rows: list[dict[str, Any]] = []
    for replica in replicas(study):
        for condition in [c for c in first.conditions if c is not None]:
            jobs = {s.target: s.evaluation_task(replica, condition, s.trains).args[0]
                    for s in sweeps}
            job = jobs[targets[0]]
            held_out = {e.id: _frame(jobs, e, True) for e in first.family
                        if e.id not in job.failures}
            case = {"replica": replica, "data": "measured", "noise": condition.noise.name,
                    "fault": condition.fault_name}
            for train in first.trains:
                if train.id not in held_out:
                    continue
                frame = held_out[train.id] if condition.fault is None else \
                    _frame(jobs, train, False)
                checked = CheckedRecording(train.id, frame)
                tests = {i: CheckedRecording(i, f) for i, f in held_out.items() if i != train.id}
                for group in methods.groups:
                    for label in methods.methods:
                        for k in methods.clusters:
                            where = {**case, "train_experiment": train.id,
                                     "method": group_method_name(group, label), "k": k}
                            rows += _case_rows(where, checked, tests, targets, group, label, k,
                                               methods.seed, methods.similarity)
    frame = pd.DataFrame(rows, columns=list(JOINT_COLUMNS))
    frame["k"] = frame["k"].astype("Int64")
    return frame


def _case_rows(where: dict[str, Any], train: CheckedRecording,
               tests: dict[str, CheckedRecording], targets: list[str], group: str, label: str,
               k: int, seed: int, similarity: str) -> list[dict[str, Any]]:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # constant candidates are dropped, as documented
            result = evaluate_targets(train, tests, targets, sensors=list(GROUP_SENSORS[group]),
                                      k=k, differences=group == SIX_DIFF, similarity=similarity,
                                      missing="drop-rows", method=parse_method(label),
                                      seed=seed, joint=joint_names())
    except Exception as exc:  # failure isolation per case, as the per-target sweep does
        return [{**where, "selection": name, "n_sensors": 0, "sensors": "", "target": t,
                 "test_experiment": test, "rmse": np.nan, "error": one_line_error(exc)}
                for name in (PER_TARGET, *joint_names()) for t in targets for test in tests]
    selections = {PER_TARGET: (result.per_target_sensors, result.per_target)}
    selections.update({name: (j.sensors, j.per_target) for name, j in result.joint.items()})
    rows = []
    for name, (sensors, per_target) in selections.items():
        for target in targets:
            for test, value in per_target[target].rmse_um.items():
                rows.append({**where, "selection": name, "n_sensors": len(sensors),
                             "sensors": ";".join(sensors), "target": target,
                             "test_experiment": test, "rmse": value, "error": ""})
    return rows


def joint_summary(rows: pd.DataFrame) -> pd.DataFrame:
    """Mean RMSE per target (its unit) and mean sensors read, per method, k and selection."""
    ok = rows[rows["error"] == ""]
    keys = ["method", "k", "selection"]
    order = {name: i for i, name in enumerate((PER_TARGET, *joint_names()))}
    wide = ok.pivot_table(index=keys, columns="target", values="rmse", aggfunc="mean")
    sensors = ok.groupby(keys)["n_sensors"].mean().rename("mean_sensors")
    table = pd.concat([sensors, wide], axis=1).reset_index()
    table = table.sort_values(["method", "k", "selection"],
                              key=lambda c: c.map(order) if c.name == "selection" else c)
    return table.reset_index(drop=True)


def write_joint(sweeps: list[Sweep], runner: TaskRunner) -> None:
    """``joint.csv``, ``joint.json`` and the study folder's ``README.md``."""
    first = sweeps[0]
    store, study = first.store, first.study
    rows = joint_rows(sweeps)
    store.write_frame("joint.csv", rows)
    table = joint_summary(rows)
    targets = [s.target for s in sweeps]
    store.write_json("joint.json", {
        "summary": table.to_dict(orient="records"),
        "provenance": provenance(kind="spindlebench season sweep, joint selections",
                                 study=file_entry(study.path), fmu=file_entry(first.fmu),
                                 targets=targets, joints=list(joint_names()),
                                 executor=runner.describe()),
    })
    lines = ["| method | k | selection | sensors read |"
             + "".join(f" {t} |" for t in targets),
             "|---|---|---|---|" + "---|" * len(targets)]
    for _, row in table.iterrows():
        lines.append(f"| {row['method']} | {row['k']} | {row['selection']} | "
                     f"{row['mean_sensors']:.1f} |"
                     + "".join(f" {row.get(t, np.nan):.3f} |" for t in targets))
    failed = int((rows["error"] != "").sum())
    text = "\n".join([
        f"# {study.name}: several targets", "",
        f"Targets: {', '.join(f'`{t}`' for t in targets)}. Each target's sweep (the same "
        "files as a sweep of that target alone) is in its folder: "
        + ", ".join(f"[`{t}/`]({t}/README.md)" for t in targets) + ".", "",
        "## Joint selections: one sensor set for every target", "",
        "Mean test RMSE per target (each in its unit: µm for a drift, µrad for a tilt) over "
        "every replica, measured condition, training experiment and held-out experiment, and "
        "the mean number of raw sensors read. `per-target`: each target its own selection "
        "(the sensors read together); `union`: the union of the per-target selections, "
        "each target refitted on it; "
        f"{', '.join(f'`{n}`' for n in joint_names()[1:])}: k candidates chosen on the "
        "training run for all targets at once, each target refitted on them. "
        "The baselines and the noise-free rows stay per target.", "",
        *lines, "",
        f"`joint.csv`: {len(rows)} rows ({failed} with errors), one per case × selection × "
        "target × held-out experiment.", ""])
    write_text(store.path("README.md"), text)
