"""Consecutive days as one machine: one simulation, the state carried from day to day.

A compensated month of cold starts tests a model on days it could never see on a real
machine: every morning would begin with the machine at the air's temperature. On a real
machine the heat of day *d* is still in the bed and the column the next morning. With
``[compensate] days = "continuous"`` the study's days run as **one** co-simulation: day *d*
works from ``(d - 1) · period`` for the family's ``duration_h`` (its speed programme, the
axes moving with the spindle or at the family's feed), then the machine stands for
``off_h`` hours (spindle and axes still) until the next working day starts. The FMU's state
at the end of one day's night is the state the next day starts from, so nothing is reset.

The air during working hours is exactly the cold-start day's air (the day's weather of the
family, ``studies.family.experiments.ambient_for``); during the night it continues that day's curve
and bends linearly onto the next day's starting value, so the air is continuous too.

What the controller sees is measured once over the whole run (one instrument set, one seed):
a sensor that sticks on the fault day stays stuck at the same reading on every later day.
Every day's samples are then cut out with their time measured from that day's power-on (the
machine is referenced at power-on, as in the cold-start runs).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import SENSORS
from spindlebench.formats.recording import (
    DRIFT_COLUMN,
    STUDY_DRIVER_COLUMNS,
    TIME_COLUMN,
    TRUE_DRIFT_COLUMN,
    TRUE_SENSOR_COLUMNS,
    true_column,
)
from spindlebench.studies.family.experiments import (
    ambient_for,
    initial_for,
    measured_target,
    scenario_for,
    sensor_model,
    target_truth_columns,
)
from spindlebench.studies.family.seeds import derive_seed
from spindlebench.testbench.drivers import speed_rpm
from spindlebench.testbench.scenario import (
    FeedStep,
    FeedWithSpindle,
    MeasuredAmbient,
    Scenario,
    SpeedStep,
    SteppedFeed,
    SteppedSpeed,
)
from spindlebench.testbench.sensors import measure

SECONDS_PER_HOUR = 3600.0


def period_s(study) -> float:
    """Time from one working day's power-on to the next (s)."""
    return study.family.duration_s + study.off_h * SECONDS_PER_HOUR


def day_start_s(study, number: int) -> float:
    """Power-on of day ``number`` (1 = the training day) in the run's time (s)."""
    return (number - 1) * period_s(study)


def _day_scenarios(study, days) -> list[Scenario]:
    return [scenario_for(study.family, d.replica, d.experiment) for d in days]


def _speed_steps(study, days, scenarios: list[Scenario]) -> SteppedSpeed:
    """Every day's programme (sampled on its communication grid, piecewise constant), the
    spindle standing from the end of the day to the next power-on."""
    family = study.family
    grid = np.arange(round(family.duration_s / family.step_s)) * family.step_s
    steps: list[SpeedStep] = []
    for day, scenario in zip(days, scenarios, strict=True):
        start = day_start_s(study, day.number)
        rpm = speed_rpm(scenario.speed, grid)
        change = np.flatnonzero(np.r_[True, rpm[1:] != rpm[:-1]])
        steps += [SpeedStep(at_s=start + grid[i], rpm=float(rpm[i])) for i in change]
        steps.append(SpeedStep(at_s=start + family.duration_s, rpm=0.0))
    return SteppedSpeed(steps=tuple(steps))


def _feed(study, days):
    family = study.family
    if family.feed == "with_spindle":
        return FeedWithSpindle(family.feed_x_mm_per_min, family.feed_y_mm_per_min)
    steps: list[FeedStep] = []
    for day in days:
        start = day_start_s(study, day.number)
        steps += [FeedStep(start, family.feed_x_mm_per_min, family.feed_y_mm_per_min),
                  FeedStep(start + family.duration_s, 0.0, 0.0)]
    return SteppedFeed(steps=tuple(steps))


def _ambient(study, days, duration_s: float) -> MeasuredAmbient:
    """The air of every day at the communication points: the day's own curve while it
    works, then through the night a linear bend onto the next day's value at its power-on."""
    from spindlebench.testbench.drivers import ambient_C

    family = study.family
    period = period_s(study)
    local = np.arange(round(period / family.step_s) + 1) * family.step_s
    curves = [ambient_C(ambient_for(family, d.replica, d.experiment), local) for d in days]
    times, values = [], []
    for i, (day, curve) in enumerate(zip(days, curves, strict=True)):
        last = i == len(days) - 1
        if not last:
            jump = curves[i + 1][0] - curve[-1]
            night = np.clip((local - family.duration_s) / max(period - family.duration_s,
                                                                 family.step_s), 0.0, 1.0)
            curve = curve + night * jump
        keep = local < period if not last else local <= family.duration_s + 1e-9
        times.append(day_start_s(study, day.number) + local[keep])
        values.append(curve[keep])
    t = np.concatenate(times)
    if t[-1] < duration_s:
        raise AssertionError("the ambient series ends before the run")  # pragma: no cover
    return MeasuredAmbient(file=family.path, time_column="time_s (continuous days)",
                           value_column="ambient_C (each day's weather, bent at night)",
                           times_s=tuple(map(float, t)),
                           values_C=tuple(map(float, np.concatenate(values))))


def continuous_scenario(study, days) -> Scenario:
    """The whole run as one scenario: day 1's set-up, every day's programme and air."""
    scenarios = _day_scenarios(study, days)
    first = scenarios[0]
    coolings = {s.cooling for s in scenarios}
    if len(coolings) > 1:
        raise SpindlebenchError(f"{study.family.path}: key 'compensate.days': \"continuous\" "
                                "runs one machine; the days differ in cooling (axes.cooling "
                                "has more than one mode)")
    duration = day_start_s(study, days[-1].number) + study.family.duration_s
    return replace(
        first,
        name=f"{study.name} continuous",
        description=f"{study.name}: {len(days)} consecutive days of "
                    f"{study.family.duration_s / SECONDS_PER_HOUR:g} h, {study.off_h:g} h "
                    "standing between them, one simulation",
        duration_s=duration,
        speed=_speed_steps(study, days, scenarios),
        feed=_feed(study, days),
        ambient=_ambient(study, days, duration),
        initial=initial_for(study.family, days[0].experiment),
    )


def split_days(study, days, truth: pd.DataFrame) -> dict[int, pd.DataFrame]:
    """Each day's working hours of the continuous truth, time from its power-on."""
    time_s = truth[TIME_COLUMN].to_numpy(float)
    out = {}
    for day in days:
        start = day_start_s(study, day.number)
        at = (time_s >= start - 1e-6) & (time_s <= start + study.family.duration_s + 1e-6)
        part = truth.loc[at].reset_index(drop=True)
        part[TIME_COLUMN] = part[TIME_COLUMN] - start
        out[day.number] = part
    return out


def measure_continuous(study, days, truths: dict[int, pd.DataFrame], target: str = DRIFT_COLUMN,
                       geometry_m: tuple[float, float] | None = None,
                       ) -> dict[int, pd.DataFrame]:
    """What the controller reads on every day, measured once over the run: the readings of
    T1..T20 (a dropout held at its last reading), the probe's drift since the day's power-on
    (``drift_um``, for training) and the true drift rise since power-on. Another ``target``
    stands in those two columns (as in ``loop.measured``)."""
    from spindlebench.studies.family.methods import TARGET, TRUTH

    family = study.family
    starts = [day_start_s(study, d.number) for d in days]
    time_s = np.concatenate([truths[d.number][TIME_COLUMN].to_numpy(float) + s
                             for d, s in zip(days, starts, strict=True)])
    temperatures = np.vstack([truths[d.number][list(TRUE_SENSOR_COLUMNS)]
                              .to_numpy(float) for d in days])
    drift = np.concatenate([truths[d.number][TRUE_DRIFT_COLUMN].to_numpy(float) for d in days])
    fault = None
    if study.fault is not None:
        fault_day = next((d for d in days if d.fault_active), None)
        if fault_day is not None:
            start_s = day_start_s(study, fault_day.number) + study.fault.value.start_s
            fault = replace(study.fault, value=replace(study.fault.value, start_s=start_s))
    model = sensor_model(family.noise[0], fault)
    seed = derive_seed(family.seed, "compensate", "continuous")
    readings, probe = measure(model, time_s, temperatures, drift, SENSORS, seed)
    if target != DRIFT_COLUMN:
        columns = target_truth_columns(target)
        truth = pd.concat([truths[d.number][list(columns)] for d in days], ignore_index=True)
        probe = measured_target(target, model, time_s, truth, probe, seed, geometry_m)
        drift = truth[true_column(target)].to_numpy(float)
    readings = pd.DataFrame(readings, columns=list(SENSORS)).ffill().bfill()
    frames = {}
    offset = 0
    for day in days:
        n = len(truths[day.number])
        rows = slice(offset, offset + n)
        frame = pd.DataFrame({TIME_COLUMN: time_s[rows] - day_start_s(study, day.number)})
        frame[list(SENSORS)] = readings.iloc[rows].to_numpy()
        frame[TARGET] = probe[rows] - probe[offset]
        frame[TRUTH] = drift[rows] - drift[offset]
        for column in STUDY_DRIVER_COLUMNS:  # the programme, for the dynamic regressors
            frame[column] = truths[day.number][column].to_numpy(float)
        frames[day.number] = frame
        offset += n
    return frames
