"""Day after day with the model in the controller: simulate, measure, predict, offset, score.

Every day is an experiment of the study family on one replica's weather, measured by the
study's instruments. By default (``days = "continuous"``, ``studies.compensation.continuous``) the
days follow each other on one machine: one simulation, the heat of each day carried through
the night into the next; ``days = "cold-starts"`` simulates every day on its own. Day 1
trains every model (on its measured temperatures and the probe's drift, as a commissioning
day would). On each later day the controller reads the sensors, the model predicts the drift
from their rises since the day's first reading (the machine is referenced at power-on), the
controller turns the predictions into an applied offset (``controller.applied_offset``), and
the residual is the *true* drift minus that offset. A fault (``fault``, from
``fault_from_day`` on) changes what the sensors report, never the machine (continuous days:
from ``start_h`` into that day to the end of the run; cold starts: from ``start_h`` into
every day from that day on).

Retraining rules:
- ``never``: the commissioning model runs to the end.
- ``weekly``: every ``retrain_every_days`` (7) days (days 8, 15, ...) the model is retrained
  on the previous day's measured data, faults included: what a scheduled recalibration does
  when nobody has noticed a bad sensor.
- ``after-fault``: the fault monitor (``controller.detect_faults``) watches the sensors the
  model reads; from the sample where it declares one faulty, the model is retrained on the
  commissioning day without that sensor and takes over at once.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from spindlebench.core.names import SENSORS, SIX_DIFF
from spindlebench.formats.recording import (
    DRIFT_COLUMN,
    STUDY_DRIVER_COLUMNS,
    TIME_COLUMN,
    TRUE_DRIFT_COLUMN,
    TRUE_SENSOR_COLUMNS,
    true_column,
)
from spindlebench.selection import SelectionWarning, evaluate
from spindlebench.selection.dynamic import is_dynamic, model_inputs
from spindlebench.selection.evaluate import CandidateSet, CheckedRecording, evaluate_checked
from spindlebench.selection.regression import EstimatorFit, LinearFit
from spindlebench.studies.compensation import continuous
from spindlebench.studies.compensation.compensation_file import CompensationStudy
from spindlebench.studies.compensation.controller import applied_offset, detect_faults
from spindlebench.studies.family.experiments import (
    Experiment,
    experiments,
    measured_target,
    replicas,
    scenario_for,
    sensor_model,
    sensor_seed,
    training_experiments,
)
from spindlebench.studies.family.methods import GROUP_SENSORS, TARGET, TRUTH, MethodSpec
from spindlebench.testbench.sensors import measure
from spindlebench.testbench.simulate import record


@dataclass(frozen=True)
class Day:
    number: int  #: 1 is the commissioning (training) day
    replica: int
    experiment: Experiment
    fault_active: bool


def plan_days(study: CompensationStudy) -> list[Day]:
    """Day 1 = the training experiment of replica 1, then every other (replica, experiment)."""
    family = study.family
    runs = experiments(family)
    trains = training_experiments(family, runs)
    if not trains:
        raise ValueError("the study's [training] names no experiment of the family")
    first = (1, trains[0])
    order = [first] + [(r, e) for r in replicas(family) for e in runs if (r, e) != first]
    return [Day(i, r, e, study.fault is not None and i >= study.fault_from_day)
            for i, (r, e) in enumerate(order, start=1)]


def measured(study: CompensationStudy, day: Day, truth: pd.DataFrame,
             target: str = DRIFT_COLUMN,
             geometry_m: tuple[float, float] | None = None) -> pd.DataFrame:
    """What the controller reads on ``day``: T1..T20 (a dropout held at its last reading),
    the probe's drift (``drift_um``, for training) and the true drift rise (``TRUTH``).
    Another ``target`` (``[study] targets``) stands in those two columns: its probe reading
    (``experiments.measured_target``, over the probes' ``geometry_m``) and its true rise."""
    family = study.family
    temperatures = truth[list(TRUE_SENSOR_COLUMNS)].to_numpy(float)
    drift = truth[TRUE_DRIFT_COLUMN].to_numpy(float)
    time_s = truth[TIME_COLUMN].to_numpy(float)
    model = sensor_model(family.noise[0], study.fault if day.fault_active else None)
    seed = sensor_seed(family, day.replica, day.experiment)
    readings, probe = measure(model, time_s, temperatures, drift, SENSORS, seed)
    frame = pd.DataFrame({TIME_COLUMN: time_s})
    frame[list(SENSORS)] = pd.DataFrame(readings).ffill().bfill().to_numpy()
    frame[TARGET] = measured_target(target, model, time_s, truth, probe, seed, geometry_m)
    if target != DRIFT_COLUMN:
        drift = truth[true_column(target)].to_numpy(float)
    frame[TRUTH] = drift - drift[0]
    for column in STUDY_DRIVER_COLUMNS:  # the programme, for the dynamic regressors
        frame[column] = truth[column].to_numpy(float)
    return frame


@dataclass(frozen=True)
class TrainedModel:
    """A model as the controller runs it: which rises it reads and the linear fit."""

    name: str
    candidates: CandidateSet
    columns: np.ndarray
    selected: tuple[str, ...]
    fit: LinearFit | EstimatorFit
    trained_on_day: int
    excluded: tuple[str, ...] = ()
    #: The regressor's name: a dynamic one reads the day's time and speed too.
    regressor: str = "ols"

    @property
    def sensors(self) -> list[str]:
        return self.candidates.sensors_of(self.columns)

    def predict(self, frame: pd.DataFrame) -> np.ndarray:
        values = self.candidates.matrix(frame, self.columns)
        if is_dynamic(self.regressor):  # time and speed in front (``selection.dynamic``)
            values = model_inputs(self.regressor, lambda c: frame[c].to_numpy(float), values)
        return self.fit.predict(values)


#: Between a model and a joint selection in a joint model's name (``six_diff@union``).
JOINT_SEPARATOR = "@"


def train(name: str, study: CompensationStudy, frame: pd.DataFrame, day: int,
          excluded: tuple[str, ...] = (),
          supports: JointSupports | None = None) -> TrainedModel:
    """Fit model ``name`` (a sweep method name) on one measured day, without ``excluded``.

    A joint model ``<model>@<joint>`` (several targets) reads the candidates chosen for
    every target at once without ``excluded`` (``supports.get``): no selection here, the
    model's regressor is fitted on them."""
    spec = MethodSpec(name.partition(JOINT_SEPARATOR)[0], study.k, study.seed)
    sensors = [s for s in GROUP_SENSORS[spec.group] if s not in excluded]
    options = dict(sensors=sensors, k=study.k, differences=spec.group == SIX_DIFF,
                   method=spec.choice, seed=study.seed, missing="drop-rows")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SelectionWarning)
        if supports is not None and JOINT_SEPARATOR in name:
            checked = CheckedRecording("commissioning", frame)
            result = evaluate_checked(checked, {"commissioning": checked}, TARGET, **options,
                                      support=supports.get(name, excluded))
        else:
            result = evaluate(frame, {"commissioning": frame}, TARGET, **options)
    candidates = CandidateSet(tuple(result.sensors), spec.group == SIX_DIFF)
    return TrainedModel(name, candidates, np.asarray(result.selection.selected),
                        tuple(result.selected), result.fit, day, excluded,
                        spec.choice.regressor)


@dataclass
class Outcome:
    """Per model: one row per day, and the time series of every day."""

    days: list[dict] = field(default_factory=list)
    series: list[pd.DataFrame] = field(default_factory=list)
    models: dict[str, list[TrainedModel]] = field(default_factory=dict)


class JointSupports:
    """The candidates of the joint models ``<model>@<joint>`` of several targets: each of the
    study's models × ``method_registry.joint_names()``, chosen on the commissioning day for
    every target at once by ``multi_target.evaluate_targets`` (the home of joint selection)
    from ``frames``, each target's measured day 1 (``measure_days``). A model retrained
    without a faulty sensor gets the joint choice made again without it (the monitor sees
    the same sensor readings whatever the target, so every target drops the same sensor)."""

    def __init__(self, study: CompensationStudy, frames: dict[str, pd.DataFrame]) -> None:
        from spindlebench.selection.method_registry import joint_names

        self.study = study
        self.targets = list(frames)
        self.joints = joint_names()
        day1 = frames[self.targets[0]].loc[:, [TIME_COLUMN, *SENSORS]].copy()
        for target, frame in frames.items():
            day1[target] = frame[TARGET].to_numpy()
        self.day1 = CheckedRecording("commissioning", day1)
        self._chosen: dict[tuple[str, tuple[str, ...]], dict[str, tuple[str, ...]]] = {}

    @property
    def models(self) -> tuple[str, ...]:
        """The joint models' names, model by model."""
        return tuple(f"{name}{JOINT_SEPARATOR}{joint}" for name in self.study.models
                     for joint in self.joints)

    def get(self, name: str, excluded: tuple[str, ...] = ()) -> tuple[str, ...]:
        """The candidates of joint model ``name`` chosen without the ``excluded`` sensors."""
        from spindlebench.selection.multi_target import evaluate_targets

        model, _, joint = name.partition(JOINT_SEPARATOR)
        key = (model, tuple(sorted(excluded)))
        if key not in self._chosen:
            spec = MethodSpec(model, self.study.k, self.study.seed)
            sensors = [s for s in GROUP_SENSORS[spec.group] if s not in excluded]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", SelectionWarning)
                result = evaluate_targets(
                    self.day1, {"commissioning": self.day1}, self.targets, sensors=sensors,
                    k=self.study.k, differences=spec.group == SIX_DIFF, missing="drop-rows",
                    method=spec.choice, seed=self.study.seed, joint=self.joints)
            self._chosen[key] = {j: tuple(r.selected) for j, r in result.joint.items()}
        return self._chosen[key][joint]


def _day_row(study: CompensationStudy, day: Day, model: TrainedModel, residual: np.ndarray,
             true_rise: np.ndarray, detection: str) -> dict:
    return {
        "model": model.name, "day": day.number, "replica": day.replica,
        "experiment": day.experiment.id, "month": day.experiment.month,
        "speed_rpm": day.experiment.speed_rpm, "programme": day.experiment.programme,
        "fault_active": day.fault_active, "trained_on_day": model.trained_on_day,
        "inputs": ";".join(model.selected), "detected": detection,
        "rms_uncompensated_um": float(np.sqrt(np.mean(true_rise**2))),
        "peak_uncompensated_um": float(np.max(np.abs(true_rise))),
        "rms_residual_um": float(np.sqrt(np.mean(residual**2))),
        "peak_residual_um": float(np.max(np.abs(residual))),
        "within_tolerance": float(np.mean(np.abs(residual) <= study.tolerance_um)),
    }


def simulate_days(study: CompensationStudy, fmu: Path,
                  progress: Callable[[str], None] | None = None) -> dict[int, pd.DataFrame]:
    """Every day's noise-free recording (the FMU's truth, time from the day's power-on), by
    day number. The control loop runs on these, so one simulation serves every controller
    setting and retraining rule."""
    days = plan_days(study)
    if study.days == "continuous":
        if progress:
            progress(f"simulating {len(days)} consecutive days as one run "
                     f"({study.off_h:g} h standing between working days)")
        truth, _ = record(continuous.continuous_scenario(study, days), fmu)
        return continuous.split_days(study, days, truth)
    truths = {}
    for day in days:
        if progress:
            progress(f"simulating day {day.number}/{len(days)}: {day.experiment.id}, "
                     f"replica {day.replica}")
        truths[day.number], _ = record(scenario_for(study.family, day.replica,
                                                    day.experiment), fmu)
    return truths


def measure_days(study: CompensationStudy, truths: dict[int, pd.DataFrame],
                 target: str = DRIFT_COLUMN, geometry_m: tuple[float, float] | None = None,
                 ) -> dict[int, pd.DataFrame]:
    """What the controller reads on every day (``measured``) for ``target``, by day number."""
    days = plan_days(study)
    if study.days == "continuous":
        return continuous.measure_continuous(study, days, truths, target, geometry_m)
    return {day.number: measured(study, day, truths[day.number], target, geometry_m)
            for day in days}


def run_loop(study: CompensationStudy, truths: dict[int, pd.DataFrame],
             retrain: str | None = None, target: str = DRIFT_COLUMN,
             geometry_m: tuple[float, float] | None = None,
             supports: JointSupports | None = None) -> Outcome:
    """Run every model of the study through the controller on the simulated days, retrained
    by rule ``retrain`` (default: the study's first), compensating ``target`` (the axial
    drift by default; another of ``[study] targets`` over the probes' ``geometry_m``, its
    offsets and residuals in its own unit). ``supports``: the candidates of the joint models
    among ``study.models`` (``JointSupports``)."""
    retrain = study.retrain[0] if retrain is None else retrain
    days = plan_days(study)
    outcome = Outcome()
    frames = measure_days(study, truths, target, geometry_m)
    current: dict[str, TrainedModel] = {}
    for day in days:
        frame = frames[day.number]
        if day.number == 1:
            for name in study.models:
                current[name] = train(name, study, frame, 1, supports=supports)
                outcome.models[name] = [current[name]]
            continue
        time_s = frame[TIME_COLUMN].to_numpy(float)
        true_rise = frame[TRUTH].to_numpy(float)
        for name in study.models:
            model = current[name]
            if retrain == "weekly" and (day.number - 1) % study.retrain_every_days == 0:
                model = train(name, study, frames[day.number - 1], day.number - 1,
                              model.excluded, supports)
                outcome.models[name].append(model)
            predicted = model.predict(frame)
            detection = ""
            if retrain == "after-fault":
                sensors = model.sensors
                found = detect_faults(time_s, frame[sensors].to_numpy(float), sensors,
                                      study.monitor)
                if found:
                    first = min(found, key=lambda d: d.sample)
                    model = train(name, study, frames[1], day.number,
                                  (*model.excluded, first.sensor), supports)
                    outcome.models[name].append(model)
                    predicted[first.sample:] = model.predict(frame)[first.sample:]
                    detection = (f"{first.sensor} {first.kind} at "
                                 f"{time_s[first.sample] / 3600:.2f} h")
            current[name] = model
            offset = applied_offset(time_s, predicted, study.controller)
            residual = true_rise - offset
            outcome.days.append({"retrain": retrain, **_day_row(study, day, model, residual,
                                                                 true_rise, detection)})
            outcome.series.append(pd.DataFrame({
                "retrain": retrain, "model": name, "day": day.number, TIME_COLUMN: time_s,
                TRUE_DRIFT_COLUMN: true_rise, "predicted_um": predicted,
                "offset_um": offset, "residual_um": residual}))
    return outcome


def summary(study: CompensationStudy, days: pd.DataFrame, series: pd.DataFrame) -> pd.DataFrame:
    """Per retraining rule and model (and the uncompensated machine): residual RMS and peak
    over all run days, the mean and worst daily RMS, the fraction of time within the
    tolerance; split into days with and without the fault when there is one."""
    tables = [_summary(study, days[days["retrain"] == rule], series[series["retrain"] == rule])
              .assign(retrain=rule) for rule in dict.fromkeys(days["retrain"])]
    table = pd.concat(tables, ignore_index=True)
    return table[["retrain", *[c for c in table.columns if c != "retrain"]]]


def _summary(study: CompensationStudy, days: pd.DataFrame, series: pd.DataFrame) -> pd.DataFrame:
    rows = []
    parts = [("all days", days["fault_active"] | ~days["fault_active"])]
    if days["fault_active"].any():
        parts += [("healthy days", ~days["fault_active"]), ("fault days", days["fault_active"])]
    fault_days = set(days.loc[days["fault_active"], "day"])
    for part, mask in parts:
        chosen_days = set(days.loc[mask, "day"])
        for name in [*study.models, "uncompensated"]:
            model = study.models[0] if name == "uncompensated" else name
            at = series[(series["model"] == model) & series["day"].isin(chosen_days)]
            values = at[TRUE_DRIFT_COLUMN] if name == "uncompensated" else at["residual_um"]
            per_day = np.sqrt((values**2).groupby(at["day"]).mean())
            rows.append({"part": part, "model": name, "days": len(per_day),
                         "rms_um": float(np.sqrt(np.mean(values**2))),
                         "mean_daily_rms_um": float(per_day.mean()),
                         "worst_daily_rms_um": float(per_day.max()),
                         "peak_um": float(values.abs().max()),
                         "within_tolerance": float(np.mean(values.abs() <= study.tolerance_um)),
                         "fault_days": len(chosen_days & fault_days)})
    return pd.DataFrame(rows)
