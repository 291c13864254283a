"""Several thermal errors at once: per-target selection and one joint sensor set (issue 21).

A five-probe machine has X, Y, Z drift and two tilts; a compensation that corrects all of them
reads one set of sensors. ``evaluate_targets`` answers both questions on the same recordings:

- **per target**: ``evaluate`` for each target on its own (its own k candidates, its own
  model): exactly what a single-target ``evaluate`` gives, target by target;
- **joint**: one candidate set for every target, then one model per target on that set
  (the regressor of ``method``), scored per target. A joint selection is named by
  ``JOINT_UNION`` (the union of the per-target selections: more sensors, each target keeps
  its own choice) or by a multi-output method of the registry
  (``method_registry.method_names(multi_output=True)``: ``k`` candidates chosen for all
  targets together, from the training rises and every target).

The targets' RMSE are in their own units (µm for a drift, µrad for a tilt); the JSON's
``rmse_um`` key keeps the single-target shape's name.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from spindlebench.core.names import DEFAULT_SIMILARITY, JOINT_UNION
from spindlebench.selection.errors import SelectionError
from spindlebench.selection.evaluate import (
    CandidateSet,
    CheckedRecording,
    Evaluation,
    _complete_rows,
    _finite,
    evaluate_checked,
)
from spindlebench.selection.method_registry import METHOD_REGISTRY, joint_names
from spindlebench.selection.registry import MethodChoice
from spindlebench.selection.similarity import constant_columns


def check_targets(targets: Sequence[str], where: str = "--target") -> list[str]:
    """The targets, refused if empty or one is given twice."""
    targets = list(targets)
    if not targets:
        raise SelectionError(f"{where}: give at least one target column")
    twice = sorted({t for t in targets if targets.count(t) > 1})
    if twice:
        raise SelectionError(f"{where}: target {', '.join(twice)} given twice")
    return targets


@dataclass(frozen=True)
class JointEvaluation:
    """One candidate set for every target, and each target's model on it."""

    name: str
    selected: list[str]
    sensors: list[str]
    per_target: dict[str, Evaluation]

    def mean_rmse(self) -> dict[str, float]:
        """Each target's mean RMSE over the test recordings (in the target's unit)."""
        return {t: e.mean_rmse_um for t, e in self.per_target.items()}

    def to_dict(self) -> dict[str, Any]:
        return {"selected": self.selected, "sensors": self.sensors,
                "n_sensors": len(self.sensors),
                "mean_rmse": self.mean_rmse(),
                "per_target": {t: e.to_dict() for t, e in self.per_target.items()}}


@dataclass(frozen=True)
class MultiEvaluation:
    """Result of ``evaluate_targets``: each target on its own, and every joint selection."""

    targets: list[str]
    per_target: dict[str, Evaluation]
    joint: dict[str, JointEvaluation]
    #: Raw sensors the per-target models read together (each target reads its own part).
    per_target_sensors: list[str]

    def to_dict(self) -> dict[str, Any]:
        """The JSON shape of ``spindlebench evaluate --target A B ... --json``."""
        return {"targets": self.targets,
                "per_target": {t: e.to_dict() for t, e in self.per_target.items()},
                "per_target_sensors": self.per_target_sensors,
                "joint": {name: j.to_dict() for name, j in self.joint.items()}}

    def comparison_rows(self) -> list[dict[str, Any]]:
        """One row per selection (per target, then each joint one): sensors read, and each
        target's mean RMSE over the test recordings."""
        rows = [{"selection": "per-target", "n_sensors": len(self.per_target_sensors),
                 "sensors": self.per_target_sensors,
                 **{t: e.mean_rmse_um for t, e in self.per_target.items()}}]
        rows += [{"selection": name, "n_sensors": len(j.sensors), "sensors": j.sensors,
                  **j.mean_rmse()} for name, j in self.joint.items()]
        return rows

    def comparison(self) -> str:
        """The per-target vs joint table as text."""
        width = max(12, *(len(t) for t in self.targets))
        head = f"{'selection':<14}{'sensors':>8}" + "".join(f"{t:>{width + 2}}"
                                                          for t in self.targets)
        lines = ["mean RMSE over the test recordings (each target in its own unit):", head]
        for row in self.comparison_rows():
            lines.append(f"{row['selection']:<14}{row['n_sensors']:>8}"
                         + "".join(f"{row[t]:>{width + 2}.3f}" for t in self.targets)
                         + "   " + ", ".join(row["sensors"]))
        return "\n".join(lines)

    def summary(self) -> str:
        """Each target's ``evaluate`` summary, each joint selection, then the comparison."""
        parts = []
        for target, result in self.per_target.items():
            parts += [f"=== target {target} (its own selection)", result.summary(), ""]
        for name, joint in self.joint.items():
            parts.append(f"=== joint selection {name}: {', '.join(joint.selected)} "
                         f"({len(joint.sensors)} sensors: {', '.join(joint.sensors)})")
            for target, result in joint.per_target.items():
                rmse = ", ".join(f"{v:.3f}" for v in result.rmse_um.values())
                parts.append(f"  {target}: training R2 {result.fit.r2:.4f}; RMSE per test "
                             f"recording {rmse}; mean {result.mean_rmse_um:.3f}")
            parts.append("")
        parts.append(self.comparison())
        return "\n".join(parts)


def _joint_support(name: str, train: CheckedRecording, targets: list[str],
                   per_target: dict[str, Evaluation], k: int, differences: bool,
                   seed: int) -> list[str]:
    """The candidate names of joint selection ``name`` on the training recording."""
    first = per_target[targets[0]]
    names = first.candidates
    if name == JOINT_UNION:
        chosen = {c for result in per_target.values() for c in result.selected}
        return [c for c in names if c in chosen]
    entry = METHOD_REGISTRY.get(name)
    if entry is None or not entry.multi_output:
        raise SelectionError(f"--joint: {name!r} is not a joint selection (choose from "
                             f"{', '.join(joint_names())})")
    rows = np.asarray(sorted(set.intersection(*(set(r.train_rows.tolist())
                                                for r in per_target.values()))), dtype=np.intp)
    if len(rows) < len(train):
        rows = _complete_rows(train, [*first.sensors, *targets])
    frame = train if len(rows) == len(train) else train.take(rows)
    candidates = CandidateSet(tuple(first.sensors), differences)
    matrix = _finite(candidates.matrix(frame), names)
    Y = np.column_stack([frame.values(t) for t in targets])
    kept = np.flatnonzero(~constant_columns(matrix))
    if len(kept) < k:
        raise SelectionError(f"recording {train.name}: only {len(kept)} candidate(s) vary; "
                             f"--joint {name} cannot select {k}")
    selector = entry.make(k, random_state=seed).fit(matrix[:, kept], Y)
    return [names[i] for i in kept[np.asarray(selector.selected_, dtype=np.intp)]]


def evaluate_targets(
    train: CheckedRecording,
    tests: dict[str, CheckedRecording],
    targets: Sequence[str],
    sensors: Sequence[str] | None = None,
    k: int = 2,
    differences: bool = False,
    similarity: str = DEFAULT_SIMILARITY,
    closure: str = "fast",
    missing: str = "error",
    method: MethodChoice | None = None,
    seed: int = 0,
    joint: Sequence[str] = (JOINT_UNION,),
) -> MultiEvaluation:
    """Each target evaluated on its own (``evaluate_checked``, so each equals a single-target
    ``evaluate``), then every joint selection of ``joint`` scored per target.

    Recordings as ``evaluate.load_recordings`` gives them. ``method`` selects per target and
    its regressor fits every model (per target and joint)."""
    targets = check_targets(targets)
    choice = MethodChoice() if method is None else method
    options = dict(sensors=sensors, k=k, differences=differences, similarity=similarity,
                   closure=closure, missing=missing, method=choice, seed=seed)
    per_target = {t: evaluate_checked(train, tests, t, **options) for t in targets}
    first = per_target[targets[0]]
    candidates = CandidateSet(tuple(first.sensors), differences)
    position = {name: i for i, name in enumerate(first.candidates)}

    def raw(selected: Sequence[str]) -> list[str]:
        return candidates.sensors_of([position[c] for c in selected])

    used = sorted({c for r in per_target.values() for c in r.selected}, key=position.get)
    joints: dict[str, JointEvaluation] = {}
    for name in dict.fromkeys(joint):
        support = _joint_support(name, train, targets, per_target, k, differences, seed)
        fitted = {t: evaluate_checked(train, tests, t, **options, support=support)
                  for t in targets}
        joints[name] = JointEvaluation(name, support, raw(support), fitted)
    return MultiEvaluation(targets, per_target, joints, raw(used))
