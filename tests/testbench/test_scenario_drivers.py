"""Drivers: speed, feed and ambient programmes evaluated on the communication grid."""

import numpy as np
import pytest
from spindlebench.testbench import drivers
from spindlebench.testbench.scenario import (
    ConstantAmbient,
    ConstantFeed,
    FeedStep,
    FeedWithSpindle,
    SeasonAmbient,
    SpeedCycles,
    SpeedStep,
    SteppedFeed,
    SteppedSpeed,
)


def test_speed_steps_are_piecewise_constant_and_zero_before_the_first():
    programme = SteppedSpeed((SpeedStep(100.0, 2000.0), SpeedStep(200.0, 4000.0)))
    t = np.array([0.0, 99.0, 100.0, 150.0, 199.0, 200.0, 1000.0])
    np.testing.assert_array_equal(drivers.speed_rpm(programme, t),
                                  [0, 0, 2000, 2000, 2000, 4000, 4000])


def test_start_stop_cycles_with_delay_and_count():
    programme = SpeedCycles(rpm=3000.0, on_s=10.0, off_s=5.0, start_s=5.0, count=2)
    t = np.arange(0.0, 50.0, 1.0)
    speed = drivers.speed_rpm(programme, t)
    on = t[speed > 0]
    np.testing.assert_array_equal(on, [*range(5, 15), *range(20, 30)])
    assert set(np.unique(speed)) == {0.0, 3000.0}


def test_endless_cycles_repeat_until_the_end():
    programme = SpeedCycles(rpm=1000.0, on_s=60.0, off_s=30.0)
    speed = drivers.speed_rpm(programme, np.arange(0.0, 900.0, 1.0))
    assert speed.mean() == pytest.approx(1000.0 * 60 / 90)


def test_feed_follows_spindle_or_steps():
    speed = np.array([0.0, 2000.0, 2000.0, 0.0])
    x, y = drivers.feed_mm_per_min(FeedWithSpindle(1500.0, 900.0), np.arange(4.0), speed)
    np.testing.assert_array_equal(x, [0, 1500, 1500, 0])
    np.testing.assert_array_equal(y, [0, 900, 900, 0])
    stepped = SteppedFeed((FeedStep(1.0, 100.0, 200.0), FeedStep(3.0, 0.0, 50.0)))
    x, y = drivers.feed_mm_per_min(stepped, np.arange(4.0), speed)
    np.testing.assert_array_equal(x, [0, 100, 100, 0])
    np.testing.assert_array_equal(y, [0, 200, 200, 50])
    x, _ = drivers.feed_mm_per_min(ConstantFeed(1500.0, 1500.0), np.arange(4.0), speed)
    assert (x == 1500).all()


def test_season_swings_between_daily_low_and_high_at_the_given_hours():
    model = SeasonAmbient(low_C=5.0, high_C=11.0, start_hour=0.0, trough_hour=6.0,
                          peak_hour=15.0)
    t = np.arange(0.0, 2 * 86400.0, 60.0)
    ambient = drivers.ambient_C(model, t)
    assert ambient.min() == pytest.approx(5.0)
    assert ambient.max() == pytest.approx(11.0)
    hour = t / 3600.0
    assert hour[np.argmin(ambient[:1440])] == pytest.approx(6.0)
    assert hour[np.argmax(ambient[:1440])] == pytest.approx(15.0)
    np.testing.assert_allclose(ambient[:1440], ambient[1440:])  # 24 h periodic
    assert np.abs(np.diff(ambient)).max() < 0.05  # smooth: no jump anywhere, also at midnight


def test_season_start_hour_shifts_the_clock():
    early = SeasonAmbient(5.0, 11.0, start_hour=6.0, trough_hour=6.0, peak_hour=15.0)
    assert drivers.ambient_C(early, np.array([0.0]))[0] == pytest.approx(5.0)
    assert drivers.ambient_C(early, np.array([9 * 3600.0]))[0] == pytest.approx(11.0)


def test_jumps_flag_programmed_steps_but_not_the_ambient_drift():
    t = np.arange(0.0, 10.0)
    signals = drivers.DriverSignals(
        time_s=t,
        spindle_speed_rpm=np.where(t >= 4, 2000.0, 0.0),
        feed_x_mm_per_min=np.where(t >= 7, 10.0, 0.0),
        feed_y_mm_per_min=np.zeros(10),
        ambient_C=20.0 + 0.1 * t,
    )
    np.testing.assert_array_equal(np.flatnonzero(signals.jumps()), [4, 7])
    assert signals.matrix.shape == (10, 4)
    np.testing.assert_array_equal(signals.matrix[:, 3], signals.ambient_C)


def test_constant_ambient():
    values = drivers.ambient_C(ConstantAmbient(20.0), np.arange(3.0))
    np.testing.assert_array_equal(values, [20.0, 20.0, 20.0])
