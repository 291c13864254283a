"""A recording as the calibration sees it: inputs, measured channels and their noise on one grid.

The map (``mapping.RecordingMap``) turns the recording's own columns into the model's inputs and
outputs; this module reads the CSV once, thins it to the calibration step, estimates each
channel's noise where the map does not give it, and guesses an initial state.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spindlebench.calibration.mapping import (
    DRIFT_OUTPUT,
    INPUT_RANGES,
    INPUTS,
    UNKNOWN,
    RecordingMap,
    apply_units,
    seconds_per_unit,
)
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.provenance import sha256_file
from spindlebench.formats.recording import AMBIENT_COLUMN, TIME_COLUMN, read_header, read_recording
from spindlebench.formats.roles import (
    ColumnRoles,
    as_time_s,
    detect_dialect,
    refuse_implausible_temperatures,
    refuse_target_copies,
)

#: Smallest noise a channel is given: a logger that quantises to 0.1 K on a slow signal shows
#: almost no sample-to-sample scatter, and a weight of 1/0.001 K would let one channel rule.
MIN_NOISE = {"temperature": 0.02, "error": 0.1}


@dataclass(frozen=True)
class Channel:
    """One measured column and the model output it is compared with."""

    column: str
    output: str  # model output, e.g. ``T1_C``, ``node_housing_3_C``, ``drift_um``
    kind: str  # "temperature" (degC) or "error" (um; model drift plus a free offset)
    values: np.ndarray  # measured, NaN where missing; error already multiplied by the sign
    noise: float  # 1 sigma, in the channel's unit


@dataclass(frozen=True)
class Series:
    """One recording on the calibration grid (``time_s`` has N + 1 samples)."""

    name: str
    path: Path
    sha256: str
    time_s: np.ndarray
    inputs: np.ndarray  # (4, N + 1) in INPUTS order; the ambient row is NaN when unknown
    channels: tuple[Channel, ...]
    ambient_unknown: bool
    ambient_knot_h: float
    ignored: tuple[str, ...] = ()  # columns of the recording the map does not use

    @property
    def intervals(self) -> int:
        return len(self.time_s) - 1

    def ambient_basis(self) -> np.ndarray:
        """(N + 1, knots): the estimated ambient at each sample is ``basis @ knots``.

        Knots are ``knot_h`` apart (> 0, the map checks), piecewise linear between them; a recording
        shorter than one knot interval gives one constant.
        """
        t = self.time_s - self.time_s[0]
        span = t[-1]
        step = self.ambient_knot_h * 3600.0
        if step <= 0 or span <= step:
            return np.ones((len(t), 1))
        knots = np.arange(0.0, span + step, step)
        basis = np.zeros((len(t), len(knots)))
        for j in range(len(knots)):
            unit = np.zeros(len(knots))
            unit[j] = 1.0
            basis[:, j] = np.interp(t, knots, unit)
        return basis

    def first_temperatures(self) -> dict[str, float]:
        """Model output -> first finite measured value of each temperature channel."""
        first = {}
        for channel in self.channels:
            if channel.kind == "temperature":
                finite = channel.values[np.isfinite(channel.values)]
                if finite.size:
                    first[channel.output] = float(finite[0])
        return first

    def ambient_guess(self) -> float:
        """A start value for an unknown ambient: the coolest measured temperature at the start
        (a machine at rest is at or above its room); 20 °C without any temperature channel."""
        first = self.first_temperatures()
        return float(np.percentile(list(first.values()), 10)) if first else 20.0


def noise_estimate(values: np.ndarray, kind: str) -> float:
    """1-sigma white noise from the scatter of successive differences (a slow thermal signal
    hardly changes between samples), floored by ``MIN_NOISE``."""
    finite = values[np.isfinite(values)]
    differences = np.diff(finite)
    if differences.size < 2:
        return MIN_NOISE[kind]
    # median absolute deviation: a few jumps (a step in the programme) do not inflate it
    mad = np.median(np.abs(differences - np.median(differences))) * 1.4826 / np.sqrt(2.0)
    return float(max(mad, MIN_NOISE[kind]))


def check_roles(path: Path, roles: ColumnRoles) -> tuple[str, str, str]:
    """The delimiter, decimal mark and time column of a recording, from its header alone:
    ``calibrate`` checks them before the slow model translation."""
    delimiter, decimal = detect_dialect(path, roles.delimiter, roles.decimal, roles.encoding)
    time_column = roles.time_column or TIME_COLUMN
    if time_column not in read_header(path, delimiter, roles.encoding):
        raise SpindlebenchError(f"recording {path}: no time column {time_column!r}; the "
                                "calibration integrates the model over time and needs one: "
                                "name it with --time-column")
    return delimiter, decimal, time_column


#: The recording map's ambient input: checked to be °C like the scenario's ambient.
AMBIENT_INPUT = AMBIENT_COLUMN


def _refuse_implausible_ambient(values: np.ndarray, source: object, path: Path) -> None:
    """A kelvin ambient (291 °C) made the fit fail as "did not converge"; say what it is."""
    from spindlebench.testbench.scenario import COLDEST_AMBIENT_C, KELVIN_SUSPECT_C

    bad = np.flatnonzero((values > KELVIN_SUSPECT_C) | (values < COLDEST_AMBIENT_C))
    if bad.size:
        where = f"column {source!r}" if isinstance(source, str) else "the map's value"
        raise SpindlebenchError(f"recording {path}: ambient_C from {where} is "
                                f"{values[bad[0]]:g} °C, outside [{COLDEST_AMBIENT_C:g}, "
                                f"{KELVIN_SUSPECT_C:g}] °C (kelvin?); give °C")


def _refuse_out_of_range(values: np.ndarray, name: str, column: str, time_s: np.ndarray,
                         path: Path, map_path: Path) -> None:
    """An input column outside the model's declared range (a negative speed: a spindle
    turning backwards is not a slower one) is one line naming the column and the map key."""
    if name not in INPUT_RANGES:
        return
    low, high, unit = INPUT_RANGES[name]
    bad = np.flatnonzero((values < low) | (values > high))
    if bad.size:
        row = int(bad[0])
        raise SpindlebenchError(f"recording {path}: column {column!r} ({map_path.name} key "
                                f"'inputs.{name}') is {values[row]:g} at time_s = "
                                f"{time_s[row]:g}; the model's {name} is {low:g} … {high:g} "
                                f"{unit} (for a reversed spindle give the magnitude)")


def load_series(path: str | Path, recording_map: RecordingMap, step_s: float | None,
                roles: ColumnRoles | None = None) -> Series:
    """Read ``path`` with ``recording_map``; thin it to every ``step_s`` seconds if given.

    The map names every column used; ``roles`` (``formats.roles``) gives the time column
    (required: the model is integrated over it), the CSV dialect and whether a temperature
    column that copies the error column (|r| > 0.999) is allowed.
    """
    path = Path(path)
    roles = roles or ColumnRoles()
    delimiter, decimal, time_column = check_roles(path, roles)
    frame = read_recording(path, allow_missing=True,
                           columns=[*recording_map.columns(), time_column],
                           delimiter=delimiter, decimal=decimal, encoding=roles.encoding)
    header = frame.attrs.get("header", list(frame.columns))
    ignored = recording_map.check_columns(header, path, time_column)
    frame = as_time_s(frame, time_column, path, roles.time_unit)
    refuse_implausible_temperatures(frame, list(recording_map.temperatures), str(path))
    if recording_map.error_column:
        refuse_target_copies(frame, recording_map.error_column, list(recording_map.temperatures),
                             str(path), roles.allow_target_copy)
    time_s = frame[TIME_COLUMN].to_numpy(dtype=float)
    steps = np.diff(time_s)
    if step_s is not None:
        native = float(np.median(steps)) * seconds_per_unit(recording_map)
        factor = step_s / native
        if factor < 1 - 1e-9 or abs(factor - round(factor)) > 1e-6:
            raise SpindlebenchError(f"--step-s {step_s:g}: not a whole multiple of {path}'s "
                                    f"sample step ({native:g} s)")
        frame = frame.iloc[:: round(factor)].reset_index(drop=True)
        time_s = frame[TIME_COLUMN].to_numpy(dtype=float)
    if len(time_s) < 3:
        raise SpindlebenchError(f"recording {path}: fewer than 3 samples to calibrate on")
    time_s, measured = apply_units(
        recording_map, time_s,
        {c: frame[c].to_numpy(dtype=float) for c in recording_map.temperatures}, str(path))
    inputs = np.empty((len(INPUTS), len(time_s)))
    for i, name in enumerate(INPUTS):
        source = recording_map.inputs[name]
        if source == UNKNOWN:
            inputs[i] = np.nan
        elif isinstance(source, str):
            column = frame[source].to_numpy(dtype=float)
            if not np.all(np.isfinite(column)):
                row = int(np.flatnonzero(~np.isfinite(column))[0])
                raise SpindlebenchError(f"recording {path}: input column {source!r} has a gap "
                                        f"at time_s = {time_s[row]:g}; inputs must be complete")
            _refuse_out_of_range(column, name, source, time_s, path, recording_map.path)
            inputs[i] = column
        else:
            inputs[i] = source
        if name == AMBIENT_INPUT and source != UNKNOWN:
            _refuse_implausible_ambient(inputs[i], source, path)
    channels = []
    for column, output in recording_map.temperatures.items():
        values = measured[column]
        noise = recording_map.noise.get(column) or noise_estimate(values, "temperature")
        channels.append(Channel(column, output, "temperature", values, noise))
    if recording_map.error_column:
        values = recording_map.error_sign * frame[recording_map.error_column].to_numpy(float)
        finite = values[np.isfinite(values)]
        if finite.size and np.ptp(finite) == 0.0:  # the fit would "not converge" on it
            raise SpindlebenchError(f"recording {path}: error column "
                                    f"{recording_map.error_column!r} is constant "
                                    f"({finite[0]:g}) over the recording; nothing to fit the "
                                    "error to (a disconnected probe? another column?)")
        noise = recording_map.noise.get(recording_map.error_column) or noise_estimate(
            values, "error")
        channels.append(Channel(recording_map.error_column, DRIFT_OUTPUT, "error", values, noise))
    return Series(
        name=path.stem, path=path, sha256=sha256_file(path), time_s=time_s, inputs=inputs,
        channels=tuple(channels), ambient_unknown=recording_map.ambient_unknown,
        ambient_knot_h=recording_map.ambient_knot_h, ignored=tuple(ignored),
    )
