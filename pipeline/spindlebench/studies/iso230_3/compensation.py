"""``iso230-3 --compensate``: what a trained compensation leaves of the Z drift in a test.

The standard frames its tests as the way to evaluate a compensation. ``spindlebench
compensate`` trains its models (linear fits on temperature rises, sensors and ``A-B``
differences, the drift as target) and writes them into its ``provenance.json`` (``models``:
per retraining rule, per model, each trained version's ``inputs`` and ``coefficients``,
intercept first). Here the last trained version of one model predicts the drift from the
test's measured temperatures (rises since the first sample, as the controller sees them
after power-on), and the residual ``Z − prediction`` joins the report as one more direction.
The models predict the axial drift only: X, Y and the tilts stay uncompensated.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spindlebench.core.errors import SpindlebenchError


@dataclass(frozen=True)
class LinearModel:
    """One trained model: its inputs (sensor ``T1`` or difference ``T1-T10`` of rises) and
    ``intercept + sum(coefficient * input)``."""

    name: str
    inputs: tuple[str, ...]
    intercept: float
    coefficients: tuple[float, ...]
    source: Path

    @property
    def sensors(self) -> list[str]:
        names: list[str] = []
        for item in self.inputs:
            for sensor in item.split("-"):
                if sensor not in names:
                    names.append(sensor)
        return names

    def predict(self, columns: dict[str, np.ndarray]) -> np.ndarray:
        """The predicted drift (µm) from the measured temperatures by sensor name."""
        rises = {s: np.asarray(columns[s], float) - float(columns[s][0]) for s in self.sensors}
        out = np.full(next(iter(rises.values())).shape, self.intercept)
        for item, c in zip(self.inputs, self.coefficients, strict=True):
            parts = item.split("-")
            value = rises[parts[0]] if len(parts) == 1 else rises[parts[0]] - rises[parts[1]]
            out = out + c * value
        return out


def load_model(path: str | Path, name: str | None = None) -> LinearModel:
    """A trained model from ``compensate``'s provenance.json: ``name`` (default: the first
    model of the first retraining rule), its last trained version."""
    path = Path(path)
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
        by_rule = record["models"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise SpindlebenchError(f"{path}: not a provenance.json of `spindlebench compensate` "
                                f"(no 'models': {exc})") from None
    if not isinstance(by_rule, dict) or not by_rule:
        raise SpindlebenchError(f"{path}: key 'models': no trained model")
    models = next(iter(by_rule.values()))
    chosen = name if name is not None else next(iter(models))
    if chosen not in models:
        raise SpindlebenchError(f"{path}: key 'models': no model {chosen!r} (has "
                                f"{', '.join(models)})")
    last = models[chosen][-1]
    coefficients = [float(c) for c in last["coefficients"]]
    inputs = tuple(str(i) for i in last["inputs"])
    if len(coefficients) != len(inputs) + 1:
        raise SpindlebenchError(f"{path}: key 'models.{chosen}': {len(coefficients)} "
                                f"coefficients for {len(inputs)} inputs (intercept first)")
    return LinearModel(chosen, inputs, coefficients[0], tuple(coefficients[1:]), path)
