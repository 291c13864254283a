"""Drivers: the scenario's programmes evaluated on the communication time grid.

The runner holds each input constant over a communication step (zero-order hold), so it needs
the programme values only at the grid points. Evaluating the whole grid at once with numpy keeps
per-step Python work out of the co-simulation loop.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from spindlebench.formats.recording import (
    DRIVER_COLUMNS,
)
from spindlebench.testbench.scenario import (
    AmbientModel,
    ConstantAmbient,
    ConstantFeed,
    ConstantSpeed,
    FeedProgramme,
    FeedWithSpindle,
    IndoorAmbient,
    MeasuredAmbient,
    Scenario,
    SeasonAmbient,
    SpeedCycles,
    SpeedProgramme,
    SteppedFeed,
    SteppedSpeed,
)

#: FMU input names, in the order of the columns of ``DriverSignals.matrix``.
INPUT_NAMES = DRIVER_COLUMNS


@dataclass(frozen=True)
class DriverSignals:
    """Input values at the grid times; row k is held over ``[time_s[k], time_s[k+1])``."""

    time_s: np.ndarray
    spindle_speed_rpm: np.ndarray
    feed_x_mm_per_min: np.ndarray
    feed_y_mm_per_min: np.ndarray
    ambient_C: np.ndarray  # noqa: N815

    @property
    def matrix(self) -> np.ndarray:
        """``(n, 4)`` array in ``INPUT_NAMES`` order, ready for one setFloat64 per step."""
        return np.column_stack([getattr(self, name) for name in INPUT_NAMES])

    def jumps(self) -> np.ndarray:
        """Boolean per grid point: a programmed (discontinuous) input changes there.

        Speed and feed are piecewise constant, so any change is a jump the ODE solver should
        be restarted at; the ambient is continuous (season curve, interpolated series).
        """
        jump = np.zeros(self.time_s.shape, dtype=bool)
        for signal in (self.spindle_speed_rpm, self.feed_x_mm_per_min, self.feed_y_mm_per_min):
            jump[1:] |= signal[1:] != signal[:-1]
        return jump


def _piecewise(at_s: np.ndarray, levels: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Level of the last step at or before each time; 0 before the first step."""
    index = np.searchsorted(at_s, t, side="right") - 1
    return np.where(index >= 0, levels[np.clip(index, 0, None)], 0.0)


def speed_rpm(programme: SpeedProgramme, t: np.ndarray) -> np.ndarray:
    """Spindle speed (rev/min) of a programme at times ``t`` (s)."""
    t = np.asarray(t, dtype=float)
    if isinstance(programme, ConstantSpeed):
        return np.full(t.shape, programme.rpm)
    if isinstance(programme, SteppedSpeed):
        at = np.array([s.at_s for s in programme.steps])
        rpm = np.array([s.rpm for s in programme.steps])
        return _piecewise(at, rpm, t)
    if isinstance(programme, SpeedCycles):
        period = programme.on_s + programme.off_s
        since = t - programme.start_s
        cycle = np.floor(since / period)
        running = (since >= 0) & (since - cycle * period < programme.on_s)
        if programme.count is not None:
            running &= cycle < programme.count
        return np.where(running, programme.rpm, 0.0)
    raise TypeError(f"unknown speed programme {programme!r}")


def feed_mm_per_min(
    programme: FeedProgramme, t: np.ndarray, speed: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Mean absolute feed rates (mm/min) of X and Y at times ``t``, given the spindle speed."""
    t = np.asarray(t, dtype=float)
    if isinstance(programme, ConstantFeed):
        return (np.full(t.shape, programme.x_mm_per_min),
                np.full(t.shape, programme.y_mm_per_min))
    if isinstance(programme, FeedWithSpindle):
        running = speed > 0
        return (np.where(running, programme.x_mm_per_min, 0.0),
                np.where(running, programme.y_mm_per_min, 0.0))
    if isinstance(programme, SteppedFeed):
        at = np.array([s.at_s for s in programme.steps])
        x = np.array([s.x_mm_per_min for s in programme.steps])
        y = np.array([s.y_mm_per_min for s in programme.steps])
        return _piecewise(at, x, t), _piecewise(at, y, t)
    raise TypeError(f"unknown feed programme {programme!r}")


def season_fraction(hour: np.ndarray, trough_hour: float, peak_hour: float) -> np.ndarray:
    """Position in the daily swing (0 at the trough, 1 at the peak), smooth and 24 h periodic.

    A half cosine rises from trough to peak and another falls from peak to the next trough,
    so the curve has zero slope at both extremes like a real daily temperature record.
    """
    rise_h = (peak_hour - trough_hour) % 24.0
    since_trough = (np.asarray(hour, dtype=float) - trough_hour) % 24.0
    rising = since_trough < rise_h
    up = 0.5 * (1.0 - np.cos(np.pi * since_trough / rise_h))
    down = 0.5 * (1.0 + np.cos(np.pi * (since_trough - rise_h) / (24.0 - rise_h)))
    return np.where(rising, up, down)


#: Spacing (s) of the weather anomaly's knots; between knots it is interpolated linearly, so
#: the weather of a run does not depend on its communication step.
WEATHER_KNOT_S = 3600.0


def weather_anomaly_K(model: IndoorAmbient, t: np.ndarray) -> np.ndarray:  # noqa: N802
    """The outdoor weather anomaly (K) at times ``t`` (s, may be negative), from the seed.

    An Ornstein-Uhlenbeck process sampled exactly on hourly knots from ``t = -1 day`` on
    (stationary start, ``w[k+1] = a w[k] + sqrt(1 - a²) sd ε``, ``a = exp(-1 h / tau)``),
    drawn in time order from ``numpy.random.default_rng(weather_seed)``: the same seed gives
    the same weather whatever the run's length or step, a longer run only adds knots.
    """
    t = np.asarray(t, dtype=float)
    if model.weather_sd_K == 0.0 or t.size == 0:
        return np.zeros(t.shape)
    if float(t.min()) < WEATHER_ORIGIN_S:
        raise ValueError(f"weather is defined from {WEATHER_ORIGIN_S:g} s on, asked at "
                         f"{t.min():g} s")
    needed = int(np.ceil((float(t.max()) - WEATHER_ORIGIN_S) / WEATHER_KNOT_S)) + 2
    count = 1 << max(6, (needed - 1).bit_length())  # cached in doublings: one draw per run
    knots = _weather_knots(model.weather_seed, model.weather_tau_h, count)
    times = WEATHER_ORIGIN_S + WEATHER_KNOT_S * np.arange(count)
    return model.weather_sd_K * np.interp(t, times, knots)


#: Time (s) of the first weather knot: a day before the run, so a lagged indoor air has weather.
WEATHER_ORIGIN_S = -86400.0


@functools.lru_cache(maxsize=32)
def _weather_knots(seed: int, tau_h: float, count: int) -> np.ndarray:
    """The first ``count`` knots of the unit-variance OU process of ``seed`` (read-only); a
    longer ``count`` repeats the shorter one's knots, as the draws are taken in order."""
    shocks = np.random.default_rng(seed).standard_normal(count)
    a = float(np.exp(-WEATHER_KNOT_S / (tau_h * 3600.0)))
    drive = shocks * np.sqrt(1.0 - a * a)
    drive[0] = shocks[0]  # stationary start
    knots = lfilter([1.0], [1.0, -a], drive)
    knots.flags.writeable = False
    return knots


def _daily_cycle_C(low_C: float, high_C: float, start_hour: float, trough_hour: float,  # noqa: N802
                   peak_hour: float, t: np.ndarray) -> np.ndarray:
    hour = start_hour + t / 3600.0
    return low_C + (high_C - low_C) * season_fraction(hour, trough_hour, peak_hour)


def ambient_C(model: AmbientModel, t: np.ndarray) -> np.ndarray:  # noqa: N802
    """Ambient air temperature (°C) at times ``t`` (s from the start of the run)."""
    t = np.asarray(t, dtype=float)
    if isinstance(model, ConstantAmbient):
        return np.full(t.shape, model.temperature_C)
    if isinstance(model, SeasonAmbient):
        return _daily_cycle_C(model.low_C, model.high_C, model.start_hour, model.trough_hour,
                              model.peak_hour, t)
    if isinstance(model, IndoorAmbient):
        late = t - model.lag_h * 3600.0
        outdoor = _daily_cycle_C(model.outdoor_low_C, model.outdoor_high_C, model.start_hour,
                                 model.trough_hour, model.peak_hour, late)
        outdoor = outdoor + weather_anomaly_K(model, late)
        mean = 0.5 * (model.outdoor_low_C + model.outdoor_high_C)
        return mean + model.building_offset_K + model.attenuation * (outdoor - mean)
    if isinstance(model, MeasuredAmbient):
        return np.interp(t, np.asarray(model.times_s), np.asarray(model.values_C))
    raise TypeError(f"unknown ambient model {model!r}")


def communication_grid(scenario: Scenario) -> np.ndarray:
    """Communication points 0, h, 2h, … duration (s), computed as k·h to avoid drift."""
    return np.arange(scenario.n_steps + 1, dtype=float) * scenario.step_s


def drive(scenario: Scenario, t: np.ndarray | None = None) -> DriverSignals:
    """Evaluate all of a scenario's drivers on the grid ``t`` (default: communication grid)."""
    t = communication_grid(scenario) if t is None else np.asarray(t, dtype=float)
    speed = speed_rpm(scenario.speed, t)
    feed_x, feed_y = feed_mm_per_min(scenario.feed, t, speed)
    return DriverSignals(
        time_s=t,
        spindle_speed_rpm=speed,
        feed_x_mm_per_min=feed_x,
        feed_y_mm_per_min=feed_y,
        ambient_C=ambient_C(scenario.ambient, t),
    )
