"""What a CNC controller does with a thermal-error prediction, and how it spots a bad sensor.

The model's prediction is not applied as it is: the controller reads the sensors and updates
its axis offset only every ``update_interval_s`` (holding it in between), ignores changes
smaller than a dead band (an offset that twitches by a micrometre per update only adds
noise to the part), and may limit how fast the offset moves (so an axis never jumps in the
middle of a cut). The residual error of the machine is then the true drift minus the applied
offset: that, not the model's RMSE against a probe, is what a user finally gets.

Fault monitor: a sensor whose reading stays exactly constant for ``stuck_window_s`` (real
readings of a noisy, quantised sensor flicker) or *steps*: changes by more than ``jump_C``
between two consecutive readings and by more than ``JUMP_RATIO`` times the median change of
the readings around it (a knocked or re-seated probe). The second condition keeps the fast
but sustained rise of a spindle-near sensor after a start (several tenths of a kelvin per
reading at 10 s, for minutes) from counting as a fault.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from spindlebench.core.errors import SpindlebenchError


@dataclass(frozen=True)
class ControllerSettings:
    """How predictions become an applied offset (times in s, lengths in um)."""

    update_interval_s: float = 10.0
    rate_limit_um_per_s: float | None = None
    dead_band_um: float = 0.0

    def __post_init__(self) -> None:
        if not self.update_interval_s > 0:
            raise SpindlebenchError(f"update_interval_s must be > 0, got {self.update_interval_s}")
        if self.rate_limit_um_per_s is not None and not self.rate_limit_um_per_s > 0:
            raise SpindlebenchError(
                f"rate_limit_um_per_s must be > 0 (or absent), got {self.rate_limit_um_per_s}")
        if not self.dead_band_um >= 0:
            raise SpindlebenchError(f"dead_band_um must be >= 0, got {self.dead_band_um}")


def applied_offset(time_s: np.ndarray, predicted_um: np.ndarray,
                   settings: ControllerSettings) -> np.ndarray:
    """The offset the axis carries at every sample of ``time_s``.

    At each update (the first sample at or after 0, u, 2u, ... of the day) the controller
    takes the prediction of that sample as its set-point, unless it differs from the current
    set-point by no more than the dead band. The offset follows the set-point immediately, or
    at most ``rate_limit_um_per_s`` times the elapsed time per sample. It starts at 0.

    Examples
    --------
    >>> t = np.arange(6) * 5.0
    >>> applied_offset(t, np.array([1.0, 2, 3, 4, 5, 6]), ControllerSettings(10.0)).tolist()
    [1.0, 1.0, 3.0, 3.0, 5.0, 5.0]
    """
    time_s = np.asarray(time_s, dtype=float)
    predicted_um = np.asarray(predicted_um, dtype=float)
    if time_s.shape != predicted_um.shape or time_s.ndim != 1 or time_s.size == 0:
        raise SpindlebenchError("applied_offset needs equally long, non-empty 1-D time and "
                                "prediction arrays")
    if np.any(np.diff(time_s) <= 0):
        raise SpindlebenchError("applied_offset: time must increase")
    slot = np.floor((time_s - time_s[0]) / settings.update_interval_s + 1e-9).astype(np.int64)
    is_update = np.r_[True, np.diff(slot) > 0]
    out = np.empty_like(predicted_um)
    setpoint = offset = 0.0
    previous_t = time_s[0]
    for i, (t, prediction) in enumerate(zip(time_s, predicted_um, strict=True)):
        if is_update[i] and np.isfinite(prediction) and \
                abs(prediction - setpoint) > settings.dead_band_um:
            setpoint = float(prediction)
        if settings.rate_limit_um_per_s is None:
            offset = setpoint
        else:
            step = settings.rate_limit_um_per_s * (t - previous_t)
            offset += float(np.clip(setpoint - offset, -step, step))
        out[i] = offset
        previous_t = t
    return out


#: A step is this many times larger than the median change of the readings around it ...
JUMP_RATIO = 5.0
#: ... taken over this many readings on each side.
JUMP_NEIGHBOURS = 6


@dataclass(frozen=True)
class FaultMonitor:
    """Thresholds of the fault monitor (see the module docstring)."""

    stuck_window_s: float = 1800.0
    jump_C: float = 0.5  # noqa: N815


@dataclass(frozen=True)
class Detection:
    sensor: str
    kind: str  #: "stuck" or "jump"
    sample: int  #: index of the sample where the monitor declares it


def detect_faults(time_s: np.ndarray, readings_C: np.ndarray, sensors: list[str],
                  monitor: FaultMonitor) -> list[Detection]:
    """The first fault the monitor sees in each sensor of one day's readings (n x sensors).

    Examples
    --------
    >>> t = np.arange(400) * 10.0
    >>> healthy = 20 + 0.001 * t + 0.05 * np.sin(t)
    >>> stuck = np.where(t < 1000, healthy, healthy[100])
    >>> [(d.sensor, d.kind, d.sample) for d in detect_faults(
    ...     t, np.column_stack([healthy, stuck]), ["A", "B"], FaultMonitor())]
    [('B', 'stuck', 280)]
    """
    time_s = np.asarray(time_s, dtype=float)
    readings_C = np.asarray(readings_C, dtype=float)
    found = []
    for j, name in enumerate(sensors):
        column = readings_C[:, j]
        jumps = np.flatnonzero(_steps(column, monitor.jump_C)) + 1
        changed = np.r_[True, np.diff(column) != 0]
        last_change = np.maximum.accumulate(np.where(changed, np.arange(column.size), 0))
        stuck = np.flatnonzero(time_s - time_s[last_change] >= monitor.stuck_window_s)
        candidates = []
        if jumps.size:
            candidates.append(Detection(name, "jump", int(jumps[0])))
        if stuck.size:
            candidates.append(Detection(name, "stuck", int(stuck[0])))
        if candidates:
            found.append(min(candidates, key=lambda d: d.sample))
    return found


def _steps(column: np.ndarray, jump_C: float) -> np.ndarray:
    """Which consecutive changes of ``column`` are steps (see the module docstring)."""
    change = np.abs(np.diff(column))
    if change.size == 0:
        return change.astype(bool)
    padded = np.pad(change, JUMP_NEIGHBOURS, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * JUMP_NEIGHBOURS + 1)
    around = np.delete(windows, JUMP_NEIGHBOURS, axis=1)  # the neighbours, not the change
    return (change > jump_C) & (change > JUMP_RATIO * np.median(around, axis=1))
