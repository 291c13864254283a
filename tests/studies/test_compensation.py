"""``spindlebench compensate``: the controller (hand-computed), the fault monitor, the study
file, and the loop on the real FMU over the tiny 4-day study (short runs)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from conftest import REPO
from spindlebench.commands import main as cli
from spindlebench.core.errors import SpindlebenchError
from spindlebench.studies.compensation.compensation_file import load_compensation
from spindlebench.studies.compensation.controller import (
    ControllerSettings,
    FaultMonitor,
    applied_offset,
    detect_faults,
)
from spindlebench.studies.compensation.loop import plan_days, run_loop, simulate_days, summary

TINY = REPO / "scenarios" / "studies" / "tiny_compensate.toml"


def test_offset_holds_between_updates_and_respects_dead_band_and_rate():
    t = np.arange(8) * 10.0
    predicted = np.array([0.4, 2.0, 2.5, 2.6, 6.0, 6.0, 6.2, 6.2])
    # updates every 20 s (samples 0, 2, 4, 6); dead band 1: 0.4 and 0.1 changes ignored
    offset = applied_offset(t, predicted, ControllerSettings(20.0, None, 1.0))
    assert offset.tolist() == [0.0, 0.0, 2.5, 2.5, 6.0, 6.0, 6.0, 6.0]
    # rate limit 0.1 um/s: at most 1 um per 10 s sample towards the set-point (2.5 from
    # sample 2, 6.0 from sample 4, so the offset climbs 1 um per sample from 0 to 6)
    limited = applied_offset(t, predicted, ControllerSettings(20.0, 0.1, 1.0))
    np.testing.assert_allclose(limited, [0.0, 0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    slow = applied_offset(t, predicted, ControllerSettings(20.0, 0.02, 1.0))
    np.testing.assert_allclose(slow, [0.0, 0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.2])
    with pytest.raises(SpindlebenchError, match="update_interval_s"):
        ControllerSettings(0.0)
    with pytest.raises(SpindlebenchError, match="time must increase"):
        applied_offset(np.array([0.0, 0.0]), np.array([1.0, 2.0]), ControllerSettings())


def test_monitor_flags_a_jump_and_a_stuck_reading_not_a_healthy_one():
    t = np.arange(300) * 10.0
    rng = np.random.default_rng(0)
    healthy = np.round((20 + 0.002 * t + rng.normal(0, 0.05, t.size)) / 0.1) * 0.1
    jumped = healthy + np.where(t >= 1000, 1.0, 0.0)
    stuck = np.where(t >= 500, healthy[49] + 0.03, healthy)  # frozen from sample 50 on
    found = detect_faults(t, np.column_stack([healthy, jumped, stuck]), ["a", "b", "c"],
                          FaultMonitor(stuck_window_s=600.0, jump_C=0.5))
    assert [(d.sensor, d.kind, d.sample) for d in found] == [("b", "jump", 100),
                                                           ("c", "stuck", 110)]
    # a fast but sustained rise (0.6 K per reading for two minutes) is not a step
    ramp = healthy + np.clip((t - 1000) * 0.06, 0, 7.2)
    assert detect_faults(t, ramp[:, None], ["d"], FaultMonitor(600.0, 0.5)) == []


@pytest.mark.parametrize("replace, message", [
    ('models = ["all_raw", "six_diff", "all_raw:greedy"]', "key 'compensate.models'"),
    ("update_interval_s = 120", "not a multiple"),
    ('fault = "T8-stuck"', "no fault 'T9'"),
    ('retrain = ["after-fault", "never"]', "must be one of never, weekly, after-fault"),
])
def test_bad_compensation_study_is_one_line(tmp_path, replace, message):
    text = TINY.read_text(encoding="utf-8")
    bad = {"models": 'models = ["raw99"]', "update": "update_interval_s = 90",
           "fault": 'fault = "T9"', "retrain": 'retrain = "monthly"'}
    new = next(v for k, v in bad.items() if k in replace.split(" ")[0])
    path = tmp_path / "c.toml"
    path.write_text(text.replace(replace, new), encoding="utf-8")
    with pytest.raises(SpindlebenchError, match=message):
        load_compensation(path)


@pytest.fixture(scope="module")
def tiny():
    study = load_compensation(TINY)
    return study, simulate_days(study, study.family.fmu)


def test_days_train_first_and_fault_from_its_day(tiny):
    study, truths = tiny
    days = plan_days(study)
    assert [d.number for d in days] == [1, 2, 3, 4] and sorted(truths) == [1, 2, 3, 4]
    assert days[0].experiment.speed_rpm == 4000 and days[0].replica == 1
    assert [d.fault_active for d in days] == [False, False, True, True]


def test_residual_is_true_drift_minus_applied_offset(tiny):
    study, truths = tiny
    outcome = run_loop(study, truths)
    series = pd.concat(outcome.series)
    np.testing.assert_allclose(series["residual_um"],
                               series["true_drift_um"] - series["offset_um"])
    days = pd.DataFrame(outcome.days)
    assert len(days) == 3 * len(study.models)
    first = series[(series["model"] == "all_raw") & (series["day"] == 2)]
    rms = float(np.sqrt(np.mean(first["residual_um"] ** 2)))
    at = days[(days["model"] == "all_raw") & (days["day"] == 2)].iloc[0]
    assert at["rms_residual_um"] == pytest.approx(rms)
    assert at["rms_residual_um"] < at["rms_uncompensated_um"]
    table = summary(study, days, series)
    assert set(table["part"]) == {"all days", "healthy days", "fault days"}
    assert set(table["retrain"]) == {"after-fault"}


def test_after_fault_retrains_without_the_stuck_sensor(tiny):
    study, truths = tiny
    monitored = run_loop(study, truths)
    ignored = run_loop(study, truths, "never")
    days = pd.DataFrame(monitored.days)
    readers = [name for name in study.models if "T8" in
               ";".join(days[(days["model"] == name) & (days["day"] == 2)]["inputs"])]
    assert readers, "no model reads T8: the tiny study no longer tests the fault"
    for name in readers:
        detected = days[(days["model"] == name) & (days["day"] == 3)]["detected"].iloc[0]
        assert detected.startswith("T8 stuck")
        assert "T8" in monitored.models[name][-1].excluded
        day4 = days[(days["model"] == name) & (days["day"] == 4)].iloc[0]
        assert "T8" not in day4["inputs"] and day4["detected"] == ""
        # whether dropping the sensor beats living with it is data, not a rule: the
        # never-retrain run keeps reading the stuck T8 on both fault days
        kept = pd.DataFrame(ignored.days)
        kept = kept[(kept["model"] == name) & (kept["day"] == 4)].iloc[0]
        assert "T8" in kept["inputs"]


def test_weekly_rule_retrains_on_the_previous_day(tiny):
    study, truths = tiny
    weekly = type(study)(**{**study.__dict__, "retrain_every_days": 2})
    outcome = run_loop(weekly, truths, "weekly")
    versions = outcome.models["six_diff"]
    assert [m.trained_on_day for m in versions] == [1, 2]  # day 3 retrains on day 2


def test_cli_writes_report_figure_and_provenance(tmp_path, capsys):
    out = tmp_path / "comp"
    # --days overrides the study's continuous days (the other tests run those)
    assert cli.main(["compensate", str(TINY), "-o", str(out), "--days", "cold-starts"]) == 0
    printed = capsys.readouterr().out
    assert "uncompensated" in printed
    for name in ("README.md", "days.csv", "summary.csv", "timeseries.csv.gz",
                 "compensation.png", "provenance.json"):
        assert (out / name).is_file(), name
    assert (out / "compensation.png").read_bytes()[:4] == b"\x89PNG"
    record = json.loads((out / "provenance.json").read_text())
    assert record["retrain"] == ["after-fault", "never"] and record["fmu"]["sha256"]
    assert record["days"] == "cold-starts" and record["off_h"] is None
    table = pd.read_csv(out / "summary.csv")
    assert set(table["retrain"]) == {"after-fault", "never"}
    readme = (out / "README.md").read_text()
    assert "## Residual over the run" in readme and "its own cold start" in readme


def test_continuous_days_carry_the_machine_state_and_keep_the_days_air(tiny):
    """One machine day after day: with no night between the days, day 2 starts in the state
    day 1 ended in; with the study's 4 h nights it starts warmer than a cold start, in the
    same air as the cold-start day (the air of working hours is the day's own weather)."""
    from dataclasses import replace

    from spindlebench.studies.compensation.continuous import continuous_scenario
    from spindlebench.studies.family.experiments import ambient_for
    from spindlebench.testbench.drivers import ambient_C

    study, truths = tiny
    assert study.days == "continuous" and study.off_h == 4
    sensors = [f"true_T{i}_C" for i in range(1, 21)]
    no_night = replace(study, off_h=0.0)
    joined = simulate_days(no_night, study.family.fmu)
    np.testing.assert_allclose(joined[2][sensors].iloc[0], joined[1][sensors].iloc[-1])
    cold = simulate_days(replace(study, days="cold-starts"), study.family.fmu)
    for day in (2, 3, 4):
        start_air = cold[day]["true_T1_C"].iloc[0]
        assert cold[day][sensors].iloc[0].max() - start_air < 1e-6  # a cold start
        assert truths[day][sensors].iloc[0].max() > start_air + 0.2  # yesterday's heat
    days = plan_days(study)
    scenario = continuous_scenario(study, days)
    local = np.arange(41) * 60.0
    for day in days:
        start = (day.number - 1) * (study.family.duration_s + 4 * 3600.0)
        np.testing.assert_allclose(
            ambient_C(scenario.ambient, start + local),
            ambient_C(ambient_for(study.family, day.replica, day.experiment), local))
    air = ambient_C(scenario.ambient, np.arange(0.0, scenario.duration_s, 60.0))
    assert np.abs(np.diff(air)).max() < 0.05  # continuous through the nights


def test_a_stuck_sensor_stays_stuck_on_the_following_days(tiny):
    from spindlebench.studies.compensation.loop import measure_days

    study, truths = tiny
    frames = measure_days(study, truths)
    stuck = frames[3]["T8"].iloc[15:].to_numpy()  # 15 min into day 3, readings every minute
    assert np.all(stuck == stuck[0]) and np.all(frames[4]["T8"] == stuck[0])
    assert frames[2]["T8"].nunique() > 3  # healthy before the fault day


@pytest.mark.parametrize("line, message", [
    ('days = "weekly"', "key 'compensate.days': must be one of continuous, cold-starts"),
    ('days = "cold-starts"\noff_h = 2', "key 'compensate.off_h': only a \"continuous\" run"),
    ("off_h = -1", "key 'compensate.off_h'"),
])
def test_bad_day_mode_is_one_line(tmp_path, line, message):
    text = TINY.read_text(encoding="utf-8").replace("off_h = 4\n", "")
    path = tmp_path / "c.toml"
    path.write_text(text.replace("[compensate]\n", f"[compensate]\n{line}\n"), encoding="utf-8")
    with pytest.raises(SpindlebenchError, match=message):
        load_compensation(path)


@pytest.mark.slow
def test_identified_models_run_in_the_controller(tiny):
    """Issue 22: a dynamic regressor in a compensation model reads each day's speed
    programme (``selection.dynamic``); the speed-only one gives the same offset whatever the
    sensors say, the observer reads them."""
    study, truths = tiny
    dynamic = type(study)(**{**study.__dict__, "models": ("all_raw:closure+tf1",
                                                          "six_raw:all-candidates+observer")})
    outcome = run_loop(dynamic, truths, "never")
    days = pd.DataFrame(outcome.days)
    assert set(days["model"]) == set(dynamic.models) and len(days) == 3 * 2
    assert np.isfinite(days["rms_residual_um"]).all()
    tf1 = outcome.models["all_raw:closure+tf1"][0]
    assert tf1.regressor == "tf1" and type(tf1.fit.estimator).__name__ == \
        "TransferFunctionRegressor"
    series = pd.concat(outcome.series)
    day2 = series[(series["model"] == "all_raw:closure+tf1") & (series["day"] == 2)]
    # day 2 runs at 2000 rpm after 4000 on day 1: the speed model predicts a smaller drift
    assert 0 < np.abs(day2["predicted_um"]).max() < np.abs(
        tf1.fit.estimator.predict(np.column_stack([
            truths[1]["time_s"], truths[1]["spindle_speed_rpm"]]))).max()
