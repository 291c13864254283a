"""Every entrant on every fold of every task, and the metrics of the leaderboard.

A method is scored by ``selection.evaluate`` itself (``load_recordings`` once per fold, then
``evaluate_checked`` per method: the same numbers, messages and warnings as ``evaluate`` on
the same recordings; a test checks it). The three baselines are always entered:

- ``baseline:constant``: the training run's mean error, predicted everywhere;
- ``baseline:replay``: the training run's error against time since its start, replayed on
  the held-out run (linear interpolation; held at its last value after its end): what a
  compensation table of one run would do;
- ``baseline:ols-all``: OLS on the rises of all sensors (the method label
  ``all-candidates``, through ``evaluate`` like any method).

Per task and entrant (over all its folds): ``rmse_um`` is the mean over folds of
``Evaluation.mean_rmse_um`` (the mean over held-out runs of their RMSE, the paper's score),
``rmse_sd_um`` its standard deviation over folds, ``max_abs_error_um`` the largest |error|
of any held-out sample, ``within_band`` the share of held-out samples with
|error| <= ``band_um``, ``n_sensors`` the mean number of distinct sensors the fitted model
reads, and ``stability`` the mean Jaccard index of those sensor sets between pairs of folds
(1: the same sensors in every fold), and ``rollout_rmse_um`` the same mean of the RMSE of
the rollout over each whole held-out run from its start, no resets (``rollout``: a dynamic
model's ``predict_rollout``; a static model's ordinary prediction, which is already that). A
method that fails on a fold is recorded with its one-line error and gets no score on that
task.
"""

from __future__ import annotations

import itertools
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from spindlebench.core.names import ALL_CANDIDATES
from spindlebench.selection.evaluate import (
    CandidateSet,
    Evaluation,
    evaluate_checked,
    load_recordings,
)
from spindlebench.selection.registry import MethodChoice, parse_method
from spindlebench.selection.regression import rmse
from spindlebench.studies.benchmark.rollout import DynamicChoice, RunModel, rollout_of
from spindlebench.studies.benchmark.tasks import TIME, Fold, Task

CONSTANT, REPLAY, OLS_ALL = "baseline:constant", "baseline:replay", "baseline:ols-all"
BASELINES: tuple[str, ...] = (CONSTANT, REPLAY, OLS_ALL)
#: The method label the OLS-on-all-sensors baseline runs.
OLS_ALL_LABEL = ALL_CANDIDATES


@dataclass
class FoldScore:
    """One entrant on one fold: per held-out run RMSE, all errors, the sensors read."""

    fold: str
    rmse_um: dict[str, float]
    errors: np.ndarray
    sensors: tuple[str, ...]
    selected: tuple[str, ...] = ()
    #: Per held-out run, the RMSE of the rollout from the run's start (``rollout``); the
    #: ordinary ``rmse_um`` for a static model.
    rollout_rmse_um: dict[str, float] = field(default_factory=dict)

    @property
    def mean_rmse_um(self) -> float:
        return float(np.mean(list(self.rmse_um.values())))

    @property
    def mean_rollout_rmse_um(self) -> float:
        return float(np.mean(list((self.rollout_rmse_um or self.rmse_um).values())))


@dataclass
class Entry:
    """One entrant on one task: its fold scores (or its error) and the warnings it gave."""

    task: str
    method: str
    folds: list[FoldScore] = field(default_factory=list)
    error: str = ""
    warnings: list[str] = field(default_factory=list)
    seconds: float = 0.0

    def metrics(self, band_um: float) -> dict[str, Any]:
        """The leaderboard's numbers (None where the entrant failed)."""
        if self.error or not self.folds:
            return {"rmse_um": None, "rmse_sd_um": None, "max_abs_error_um": None,
                    "within_band": None, "n_sensors": None, "stability": None,
                    "rollout_rmse_um": None}
        per_fold = np.array([f.mean_rmse_um for f in self.folds])
        errors = np.concatenate([f.errors for f in self.folds])
        return {
            "rmse_um": float(per_fold.mean()),
            "rmse_sd_um": float(per_fold.std(ddof=1)) if len(per_fold) > 1 else 0.0,
            "max_abs_error_um": float(np.max(np.abs(errors))),
            "within_band": float(np.mean(np.abs(errors) <= band_um)),
            "n_sensors": float(np.mean([len(f.sensors) for f in self.folds])),
            "stability": stability([f.sensors for f in self.folds]),
            "rollout_rmse_um": float(np.mean([f.mean_rollout_rmse_um for f in self.folds])),
        }


def stability(sets: Sequence[Sequence[str]]) -> float | None:
    """Mean Jaccard index of the sensor sets over pairs of folds (None with one fold; 1.0
    for two empty sets: a baseline reading no sensor is perfectly stable)."""
    if len(sets) < 2:
        return None
    scores = []
    for a, b in itertools.combinations([set(s) for s in sets], 2):
        union = a | b
        scores.append(1.0 if not union else len(a & b) / len(union))
    return float(np.mean(scores))


def sensors_read(result: Evaluation) -> tuple[str, ...]:
    """The distinct sensors a fitted model reads (a difference A-B reads A and B)."""
    candidates = CandidateSet(tuple(result.sensors), len(result.candidates) > len(result.sensors))
    return tuple(candidates.sensors_of(result.selection.selected))


def score_method(task: Task, choice: MethodChoice, k: int, seed: int,
                 differences: bool = False) -> Entry:
    """``choice`` on every fold of ``task`` through ``evaluate``."""
    def score(fold: Fold) -> FoldScore:
        result = evaluate_fold(task, fold, choice, k, seed, differences)
        errors = np.concatenate([result.measured[name] - result.predictions[name]
                                 for name in fold.tests])
        estimator = getattr(result.fit, "estimator", None)
        rollouts = {name: rmse(result.measured[name], rollout_of(
            estimator, fold.tests[name], result.predictions[name])) for name in fold.tests}
        return FoldScore(fold.name, dict(result.rmse_um), errors, sensors_read(result),
                         tuple(result.selected), rollouts)

    return _scored(Entry(task.name, choice.label), task, score)


def _scored(entry: Entry, task: Task, score) -> Entry:
    """``score(fold)`` of every fold into ``entry``, with the warnings it gave and its time;
    an exception becomes the entry's one-line error (one failing method must not cost the
    others)."""
    started = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            for fold in task.folds:
                entry.folds.append(score(fold))
        except Exception as exc:
            entry.error = " ".join(f"{type(exc).__name__}: {exc}".split())
            entry.folds = []
    entry.warnings = sorted({" ".join(str(w.message).split()) for w in caught})
    entry.seconds = time.perf_counter() - started
    return entry


def evaluate_fold(task: Task, fold: Fold, choice: MethodChoice, k: int, seed: int,
                  differences: bool = False) -> Evaluation:
    """``evaluate`` of one fold: what the leaderboard's numbers of a method are made of."""
    train, tests = fold_recordings(fold)
    budget = min(k, len(task.sensors)) if not differences else k
    return evaluate_checked(train, tests, task.target, list(task.sensors), k=budget,
                            differences=differences, method=choice, seed=seed)


def fold_recordings(fold: Fold):
    """The fold's recordings as ``evaluate`` loads them (cached on the fold: every method
    shares their conversions)."""
    cached = getattr(fold, "_recordings", None)
    if cached is None:
        cached = load_recordings(fold.train, fold.tests)
        fold._recordings = cached  # type: ignore[attr-defined]
    return cached


def score_baseline(task: Task, name: str, k: int, seed: int) -> Entry:
    """One of ``BASELINES`` on every fold of ``task``."""
    if name == OLS_ALL:
        entry = score_method(task, parse_method(OLS_ALL_LABEL), 1, seed)  # k does not apply
        entry.method = OLS_ALL
        return entry
    entry = Entry(task.name, name)
    started = time.perf_counter()
    for fold in task.folds:
        y_train = fold.train[task.target].to_numpy(float)
        t_train = fold.train[TIME].to_numpy(float)
        scores, errors = {}, []
        for test_name, frame in fold.tests.items():
            y = frame[task.target].to_numpy(float)
            if name == CONSTANT:
                predicted = np.full(y.shape, float(y_train.mean()))
            else:
                predicted = np.interp(frame[TIME].to_numpy(float), t_train, y_train)
            scores[test_name] = rmse(y, predicted)
            errors.append(y - predicted)
        entry.folds.append(FoldScore(fold.name, scores, np.concatenate(errors), ()))
    entry.seconds = time.perf_counter() - started
    return entry


def score_dynamic(task: Task, choice: DynamicChoice, k: int, seed: int) -> Entry:
    """A dynamic entrant (``rollout.RunModel``) on every fold: fitted on the training run,
    its ordinary prediction and its rollout on every held-out run."""
    def score(fold: Fold) -> FoldScore:
        model = RunModel(choice, min(k, len(task.sensors)), seed)
        model.fit_run(fold.train, task.target, task.sensors)
        scores, rollouts, errors = {}, {}, []
        for name, frame in fold.tests.items():
            y = frame[task.target].to_numpy(float)
            predicted = model.predict(frame)
            scores[name] = rmse(y, predicted)
            rollouts[name] = rmse(y, rollout_of(model, frame, predicted))
            errors.append(y - predicted)
        return FoldScore(fold.name, scores, np.concatenate(errors), model.sensors,
                         model.sensors, rollouts)

    return _scored(Entry(task.name, choice.label), task, score)
