"""Scenario files (TOML) → frozen, validated dataclasses.

A scenario says what the virtual machine does during one experiment: how long, at which
communication step, which spindle speed and feed programme, which ambient, cooling, sensor model
and initial state. Every problem in a file becomes one ``SpindlebenchError`` line that names the
file and the dotted key, so a user never has to read a traceback to fix a typo.
"""

from __future__ import annotations

import csv
import io
import math
import re
from collections.abc import Iterator, Mapping
from dataclasses import MISSING, dataclass, field, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from spindlebench.core.errors import SpindlebenchError, columns_hint
from spindlebench.core.files import check_input
from spindlebench.core.limits import (
    COLDEST_AMBIENT_C,
    FOLLOW_AMBIENT_MAX_K,
    KELVIN_SUSPECT_C,
    MAX_FEED_MM_PER_MIN,
    MAX_LAG1,
    MAX_NOISE_C,
    MAX_OFFSET_C,
    MAX_PROBE_DRIFT_UM,
    MAX_PROBE_NOISE_UM,
    MAX_RPM,
    RPM_RANGE_UNIT,
)
from spindlebench.core.names import SENSORS
from spindlebench.core.paths import file_kind
from spindlebench.formats.recording import AMBIENT_COLUMN, TIME_COLUMN
from spindlebench.formats.toml import REQUIRED, Table, load_toml, range_problem
from spindlebench.machines.variants import DEFAULT_MACHINE, Machine, load_machine

if TYPE_CHECKING:
    from spindlebench.formats.recording import EndState

# The physical limits (rpm, feed, ambient, noise) have their one home in ``core.limits``.
#: Smallest communication step (s): the thermal time constants are minutes, a millisecond step
#: already resolves them a thousand times over.
MIN_STEP_S = 1e-3
#: Most communication steps of one run: 90 days at 1 s; the driver arrays (4 inputs × 8 bytes
#: a step) and the run time stay bounded.
MAX_STEPS = 10_000_000
#: Samples a recording may have: ~140 columns of float64 at 1 M samples are 1.1 GB (9 M
#: samples, 90 days at 1 s, failed deep in numpy allocating the output matrix).
MAX_SAMPLES = 1_000_000
#: Longest soak history (days) before a run: the slowest node (the floor slab, about a day)
#: has long forgotten its cold start by then.
MAX_SOAK_DAYS = 60
#: ``continuous``: the ambient is evaluated at the solver's own time inside the right-hand
#: side and CVode stops only at output points and input jumps; ``hold``: every input is held
#: over each communication step (zero-order hold, a stop every ``step_s``).
INPUT_MODES = ("continuous", "hold")


# --------------------------------------------------------------------------- dataclasses


@dataclass(frozen=True)
class ConstantSpeed:
    """The spindle turns at one speed for the whole run."""

    rpm: float
    kind: Literal["constant"] = "constant"


@dataclass(frozen=True)
class SpeedStep:
    """From ``at_s`` on (until the next step) the spindle turns at ``rpm``."""

    at_s: float
    rpm: float


@dataclass(frozen=True)
class SteppedSpeed:
    """Piecewise-constant speed; the spindle stands still before the first step."""

    steps: tuple[SpeedStep, ...]
    kind: Literal["steps"] = "steps"


@dataclass(frozen=True)
class SpeedCycles:
    """Start/stop cycles: ``on_s`` at ``rpm``, then ``off_s`` standing, from ``start_s`` on."""

    rpm: float
    on_s: float
    off_s: float
    start_s: float = 0.0
    count: int | None = None  # None: repeat until the end of the run
    kind: Literal["cycles"] = "cycles"


SpeedProgramme = ConstantSpeed | SteppedSpeed | SpeedCycles


def at_speed(programme: SpeedProgramme, rpm: float) -> SpeedProgramme:
    """``programme`` with every speed multiplied by ``rpm``: a programme written at unit speed
    (1 = a study's axis speed, a step's speed a fraction of it) at the experiment's speed.

    Examples
    --------
    >>> at_speed(SpeedCycles(rpm=1.0, on_s=600.0, off_s=300.0), 4000.0).rpm
    4000.0
    >>> [s.rpm for s in at_speed(SteppedSpeed((SpeedStep(0.0, 1.0), SpeedStep(60.0, 0.5))),
    ...                          3000.0).steps]
    [3000.0, 1500.0]
    """
    if isinstance(programme, SteppedSpeed):
        return replace(programme, steps=tuple(replace(step, rpm=rpm * step.rpm)
                                              for step in programme.steps))
    return replace(programme, rpm=rpm * programme.rpm)


@dataclass(frozen=True)
class ConstantFeed:
    """Both feed axes move all the time at these mean absolute feed rates."""

    x_mm_per_min: float
    y_mm_per_min: float
    kind: Literal["constant"] = "constant"


@dataclass(frozen=True)
class FeedWithSpindle:
    """The feed axes move while the spindle turns and stand while it stands (machining)."""

    x_mm_per_min: float
    y_mm_per_min: float
    kind: Literal["with_spindle"] = "with_spindle"


@dataclass(frozen=True)
class FeedStep:
    """From ``at_s`` on the axes move at these feed rates."""

    at_s: float
    x_mm_per_min: float
    y_mm_per_min: float


@dataclass(frozen=True)
class SteppedFeed:
    """Piecewise-constant feed; the axes stand before the first step."""

    steps: tuple[FeedStep, ...]
    kind: Literal["steps"] = "steps"


FeedProgramme = ConstantFeed | FeedWithSpindle | SteppedFeed


@dataclass(frozen=True)
class ConstantAmbient:
    """A climate-controlled room."""

    temperature_C: float  # noqa: N815
    kind: Literal["constant"] = "constant"


@dataclass(frozen=True)
class SeasonAmbient:
    """A day of a season: the air swings between the day's low and high.

    The daily cycle is a smooth asymmetric cosine: it rises from ``low_C`` at ``trough_hour``
    to ``high_C`` at ``peak_hour`` and falls back until the next day's trough. ``start_hour``
    is the clock time at which the run starts.
    """

    low_C: float  # noqa: N815
    high_C: float  # noqa: N815
    start_hour: float = 8.0
    trough_hour: float = 6.0
    peak_hour: float = 15.0
    kind: Literal["season"] = "season"


@dataclass(frozen=True)
class MeasuredAmbient:
    """A measured ambient series from a CSV file, linearly interpolated in time."""

    file: Path
    time_column: str
    value_column: str
    times_s: tuple[float, ...] = field(repr=False)
    values_C: tuple[float, ...] = field(repr=False)  # noqa: N815
    kind: Literal["csv"] = "csv"


@dataclass(frozen=True)
class IndoorAmbient:
    """Workshop air inside a building: an attenuated, lagged copy of the outdoor day.

    The outdoor air follows the season's daily cycle (``outdoor_low_C`` … ``outdoor_high_C``,
    the same curve as :class:`SeasonAmbient`) plus a random weather anomaly (an
    Ornstein-Uhlenbeck process, ``weather_sd_K`` around 0 with correlation time
    ``weather_tau_h``, drawn from ``weather_seed``). The building passes the deviation from the
    outdoor daily mean through with the factor ``attenuation`` and ``lag_h`` hours late, and
    adds ``building_offset_K`` (heat of machines, lights and people; heating in winter)::

        indoor(t) = mean + offset + attenuation · (outdoor(t - lag) - mean)

    Defaults are in scenarios/README.md (chosen typical values, not measured on one building).
    """

    outdoor_low_C: float  # noqa: N815
    outdoor_high_C: float  # noqa: N815
    start_hour: float = 8.0
    trough_hour: float = 6.0
    peak_hour: float = 15.0
    attenuation: float = 0.5
    lag_h: float = 2.0
    building_offset_K: float = 2.0  # noqa: N815
    weather_sd_K: float = 3.0  # noqa: N815
    weather_tau_h: float = 36.0
    weather_seed: int = 0
    kind: Literal["indoor"] = "indoor"


AmbientModel = ConstantAmbient | SeasonAmbient | MeasuredAmbient | IndoorAmbient


@dataclass(frozen=True)
class Cooling:
    """Spindle cooling unit: off, an absolute setpoint, or a setpoint that follows the ambient.

    With ``follow_ambient`` the setpoint is an offset (K) from the ambient air temperature.
    """

    mode: Literal["off", "absolute", "follow_ambient"] = "off"
    setpoint_C: float = 0.0  # noqa: N815


@dataclass(frozen=True)
class SensorFault:
    """One misbehaving sensor over ``[start_s, end_s)``, or from ``start_s`` to the end.

    ``dropout`` records missing values (NaN, an empty CSV field); ``stuck`` repeats one value
    (``value_C``, or the last good reading before the fault); ``offset`` adds ``offset_C``.
    """

    sensor: str
    kind: Literal["dropout", "stuck", "offset"]
    start_s: float
    end_s: float | None
    value_C: float | None = None  # noqa: N815
    offset_C: float | None = None  # noqa: N815


#: Temperature noise processes: independent per sample, AR(1), or a random walk.
NOISE_KINDS = ("white", "ar1", "random_walk")


@dataclass(frozen=True)
class SensorModel:
    """How the virtual data logger turns true temperatures and drift into measurements.

    ``noise_kind`` is the temperature noise process (see ``testbench.sensors``): ``white``
    (``noise_C`` per sample), ``ar1`` (stationary ``noise_C``, lag-1 autocorrelation
    ``noise_lag1`` between samples) or ``random_walk`` (``noise_C`` after one hour). The
    probe's zero wanders as a random walk (``probe_drift_um_per_sqrt_h``, 1 sigma after one
    hour) and creeps at ``probe_drift_rate_um_per_h``.
    """

    noise_C: float = 0.05  # noqa: N815
    quantum_C: float = 0.1  # noqa: N815
    probe_noise_um: float = 0.2
    probe_quantum_um: float = 0.1
    faults: tuple[SensorFault, ...] = ()
    noise_kind: Literal["white", "ar1", "random_walk"] = "white"
    noise_lag1: float = 0.86
    probe_drift_um_per_sqrt_h: float = 0.0
    probe_drift_rate_um_per_h: float = 0.0


@dataclass(frozen=True)
class InitialState:
    """Cold start (every node at one temperature), continue from a saved end state, or soak.

    ``cold`` uses ``temperature_C`` or, if absent, the ambient at the start of the run;
    ``continue`` reads the end state from a previous run's JSON sidecar (``from_file``).
    ``from_scenario`` names a sibling scenario instead of a file: its recording is the one in
    this run's output folder, so ``from_file`` stays ``None`` until ``resolve_initial`` knows
    that folder (a scenario file cannot know where its sibling's output will be written).
    """

    kind: Literal["cold", "continue", "soak"] = "cold"
    temperature_C: float | None = None  # noqa: N815
    from_file: Path | None = None
    from_scenario: str | None = None
    #: ``soak``: days of the climate's daily cycle with the machine standing idle before the
    #: run (``testbench.soak``); ``soak_ambient`` is that cycle, None for the run's own
    #: ambient without its random weather.
    days: int = 7
    soak_ambient: AmbientModel | None = None


@dataclass(frozen=True)
class Scenario:
    """One virtual experiment, validated."""

    path: Path
    name: str
    description: str
    duration_s: float
    step_s: float
    sample_interval_s: float
    seed: int
    speed: SpeedProgramme
    feed: FeedProgramme
    ambient: AmbientModel
    cooling: Cooling
    sensors: SensorModel
    initial: InitialState
    parameters: Mapping[str, float]
    #: How the runner feeds the drivers to the FMU (``INPUT_MODES``; scenarios/README.md).
    inputs: str = "continuous"
    #: The machine variant (``scenarios/machines``); its parameters apply under ``parameters``.
    machine: Machine = field(default_factory=load_machine)
    #: ``[outputs] probes = true``: record the five-probe outputs (X, Y, tilts) and their
    #: cross-section nodes (``formats.recording.PROBE_OUTPUTS``); off, a recording keeps the
    #: columns it had before the five-probe model.
    probes: bool = False

    @property
    def n_steps(self) -> int:
        """Number of communication steps."""
        return round(self.duration_s / self.step_s)

    @property
    def steps_per_sample(self) -> int:
        """Communication steps between two recorded samples."""
        return round(self.sample_interval_s / self.step_s)

    def to_dict(self) -> dict[str, Any]:
        """The scenario as parsed, JSON-ready (for the recording's provenance)."""
        return _jsonable(self)


def _jsonable(value: Any) -> Any:
    if isinstance(value, MeasuredAmbient):
        return {
            "kind": value.kind,
            "file": str(value.file),
            "time_column": value.time_column,
            "value_column": value.value_column,
            "n_points": len(value.times_s),
        }
    if hasattr(value, "__dataclass_fields__"):
        return {name: _jsonable(getattr(value, name)) for name in value.__dataclass_fields__}
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, tuple | list):
        return [_jsonable(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    return value


# --------------------------------------------------------------------------- reading helpers


def _temperature(t: Table, name: str, default: Any = REQUIRED) -> float:
    """A temperature in °C, rejecting values that look like kelvin or are absurd."""
    value = t.number(name, default)
    if value is None:
        return value
    problem = temperature_problem(value)
    if problem:
        raise t.error(name, problem)
    return value


def temperature_problem(value_C: float) -> str | None:
    """Why ``value_C`` is no workshop temperature in °C (None when it is one): the one rule for
    ambient and absolute cooling setpoints, in scenarios and studies."""
    if value_C > KELVIN_SUSPECT_C:
        return (f"{value_C:g} °C is implausible for a workshop (looks like kelvin?); "
                "give degrees Celsius")
    if value_C < COLDEST_AMBIENT_C:
        return f"{value_C:g} °C is colder than {COLDEST_AMBIENT_C:g} °C"
    return None


def _kind(table: Table, choices: tuple[str, ...], default: str | None = None) -> str:
    return table.string("kind", REQUIRED if default is None else default, choices=choices)


# --------------------------------------------------------------------------- sections


def _rpm(t: Table) -> float:
    return t.number("rpm", minimum=0.0, maximum=MAX_RPM, unit=RPM_RANGE_UNIT)


def _feed(t: Table, name: str) -> float:
    return t.number(name, minimum=0.0, maximum=MAX_FEED_MM_PER_MIN, unit="mm/min")


def _steps(t: Table, duration_s: float) -> Iterator[tuple[float, Table]]:
    """The ``[[steps]]`` of a speed or feed programme: (start time, step table) in increasing
    time order within the run; the caller reads the values, each step is then finished."""
    previous = None
    steps = t.tables("steps")
    if not steps:
        raise t.error("steps", "needs at least one step")
    for step in steps:
        at_s = step.number("at_s", minimum=0.0)
        if at_s >= duration_s:
            raise step.error("at_s", f"step at {at_s:g} s is not within the duration "
                             f"({duration_s:g} s)")
        if previous is not None and at_s <= previous:
            raise step.error("at_s", "steps must be in increasing time order")
        previous = at_s
        yield at_s, step
        step.finish()


def _read_speed(top: Table, duration_s: float) -> SpeedProgramme:
    t = top.table("speed")
    kind = _kind(t, ("constant", "steps", "cycles"))
    if kind == "constant":
        programme: SpeedProgramme = ConstantSpeed(rpm=_rpm(t))
    elif kind == "steps":
        programme = SteppedSpeed(steps=tuple(
            SpeedStep(at_s=at_s, rpm=_rpm(step)) for at_s, step in _steps(t, duration_s)))
    else:
        start_s = t.number("start_s", 0.0, minimum=0.0)
        if start_s >= duration_s:
            raise t.error("start_s", f"{start_s:g} s is not within the duration ({duration_s:g} s)")
        on_s = t.number("on_s", positive=True)
        off_s = t.number("off_s", positive=True)
        if on_s + off_s > duration_s:
            raise t.error("on_s", f"one cycle ({on_s + off_s:g} s) is longer than the duration "
                         f"({duration_s:g} s)")
        programme = SpeedCycles(
            rpm=_rpm(t), on_s=on_s, off_s=off_s, start_s=start_s,
            count=t.integer("count", None, minimum=1),
        )
    t.finish()
    return programme


def _read_feed(top: Table, duration_s: float) -> FeedProgramme:
    t = top.table("feed")
    kind = _kind(t, ("constant", "with_spindle", "steps"))
    if kind in ("constant", "with_spindle"):
        x = _feed(t, "x_mm_per_min")
        y = _feed(t, "y_mm_per_min")
        programme: FeedProgramme = (
            ConstantFeed(x, y) if kind == "constant" else FeedWithSpindle(x, y)
        )
    else:
        programme = SteppedFeed(steps=tuple(
            FeedStep(at_s=at_s, x_mm_per_min=_feed(step, "x_mm_per_min"),
                     y_mm_per_min=_feed(step, "y_mm_per_min"))
            for at_s, step in _steps(t, duration_s)))
    t.finish()
    return programme


def _hour(t: Table, name: str, default: float) -> float:
    return t.number(name, default, minimum=0.0, maximum=24.0)


def _read_indoor(t: Table, seed: int) -> IndoorAmbient:
    """``[ambient] kind = "indoor"``: the outdoor cycle, the building and the weather."""
    low = _temperature(t, "outdoor_low_C")
    high = _temperature(t, "outdoor_high_C")
    if high < low:
        raise t.error("outdoor_high_C", f"daily high {high:g} °C is below the daily low "
                     f"{low:g} °C")
    trough = _hour(t, "trough_hour", 6.0)
    peak = _hour(t, "peak_hour", 15.0)
    if math.isclose(trough % 24, peak % 24):
        raise t.error("peak_hour", "must differ from trough_hour")
    return IndoorAmbient(
        outdoor_low_C=low, outdoor_high_C=high, start_hour=_hour(t, "start_hour", 8.0),
        trough_hour=trough, peak_hour=peak, weather_seed=t.integer("weather_seed", seed,
                                                                   minimum=0),
        **read_building(t),
    )


#: Ranges of the building and weather keys of an indoor ambient, in scenario and study files.
BUILDING_LIMITS: dict[str, tuple[float, float]] = {
    "attenuation": (0.0, 1.0),
    "lag_h": (0.0, 12.0),
    "building_offset_K": (-30.0, 30.0),
    "weather_sd_K": (0.0, 15.0),
    "weather_tau_h": (1.0, 720.0),
}


def read_building(t: Table) -> dict[str, float]:
    """The building and weather keys of an indoor ambient (defaults: ``IndoorAmbient``'s)."""
    fields = IndoorAmbient.__dataclass_fields__
    return {name: t.number(name, fields[name].default, minimum=low, maximum=high)
            for name, (low, high) in BUILDING_LIMITS.items()}


def _read_ambient(top: Table, scenario_dir: Path, duration_s: float,
                  seed: int = 0) -> AmbientModel:
    t = top.table("ambient")
    kind = _kind(t, ("constant", "season", "csv", "indoor"))
    if kind == "indoor":
        model: AmbientModel = _read_indoor(t, seed)
    elif kind == "constant":
        model = ConstantAmbient(temperature_C=_temperature(t, "temperature_C"))
    elif kind == "season":
        low = _temperature(t, "low_C")
        high = _temperature(t, "high_C")
        if high < low:
            raise t.error("high_C", f"daily high {high:g} °C is below the daily low {low:g} °C")
        trough = _hour(t, "trough_hour", 6.0)
        peak = _hour(t, "peak_hour", 15.0)
        if math.isclose(trough % 24, peak % 24):
            raise t.error("peak_hour", "must differ from trough_hour")
        model = SeasonAmbient(
            low_C=low, high_C=high, start_hour=_hour(t, "start_hour", 8.0),
            trough_hour=trough, peak_hour=peak,
        )
    else:
        file_name = t.string("file")
        time_column = t.string("time_column", TIME_COLUMN)
        value_column = t.string("value_column", AMBIENT_COLUMN)
        file = (scenario_dir / file_name).resolve()
        times, values = _read_ambient_csv(t, file, time_column, value_column)
        if times[0] > 0.0 or times[-1] < duration_s:
            raise t.error("file", f"{file} covers {times[0]:g}–{times[-1]:g} s but the run needs "
                         f"0–{duration_s:g} s")
        model = MeasuredAmbient(
            file=file, time_column=time_column, value_column=value_column,
            times_s=tuple(times), values_C=tuple(values),
        )
    t.finish()
    return model


#: A number as a CSV cell writes it: Python's float() also takes ``1_8`` (as 18), which no
#: data logger writes; a cell like that is a typo, not eighteen degrees.
_CSV_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|[+-]?(?:nan|inf)",
                         re.IGNORECASE)


def csv_number(cell: str) -> float:
    """The number in a CSV cell, or ValueError (``1_8``, ``0x12``, ``١٢`` are not numbers)."""
    text = cell.strip()
    if not _CSV_NUMBER.fullmatch(text):
        raise ValueError(cell)
    return float(text)


def _read_ambient_csv(
    t: Table, file: Path, time_column: str, value_column: str
) -> tuple[list[float], list[float]]:
    """Read and check a measured ambient series; errors name the CSV file and line.

    Lines starting with ``#`` are comments (a place for the series' origin and units).
    """
    try:
        check_input(file, "measured-ambient CSV")
    except SpindlebenchError as exc:
        raise t.error("file", str(exc)) from None
    if not file.is_file():
        raise t.error("file", f"{file} is {file_kind(file)}, not a file" if file.exists()
                      else f"no such file: {file}")
    times: list[float] = []
    values: list[float] = []
    header: list[str] | None = None
    try:
        text = file.read_text(encoding="utf-8-sig")  # a BOM, as recordings accept it
    except UnicodeDecodeError as exc:
        raise t.error("file", f"{file} is not UTF-8 text (byte {exc.start})") from None
    with io.StringIO(text, newline="") as handle:
        for line_no, line in enumerate(handle, start=1):
            if not line.strip() or line.startswith("#"):
                continue
            cells = next(csv.reader([line]))
            if header is None:
                header = [c.strip() for c in cells]
                twice = sorted({c for c in header if header.count(c) > 1})
                if twice:  # which of the two would be "the" column is a guess
                    raise SpindlebenchError(f"{file}: line {line_no}: column {twice[0]!r} "
                                            "appears more than once in the header")
                for column, key in ((time_column, "time_column"), (value_column, "value_column")):
                    if column not in header:
                        raise t.error(key, f"column {column!r} not in {file} "
                                     f"({columns_hint(header, column)})")
                i_time, i_value = header.index(time_column), header.index(value_column)
                continue
            where = f"{file}: line {line_no}"
            if len(cells) != len(header):  # an extra field shifts what the columns mean
                raise SpindlebenchError(f"{where}: {len(cells)} field(s), the header has "
                                        f"{len(header)}")
            try:
                if not (cells[i_time].isascii() and cells[i_value].isascii()):
                    # float() reads full-width or Arabic-Indic digits: not what a logger writes
                    raise SpindlebenchError(f"{where}: {cells[i_time]!r}, {cells[i_value]!r}: "
                                            "numbers must be plain ASCII digits")
                time_s = csv_number(cells[i_time])
                value = csv_number(cells[i_value])
            except (IndexError, ValueError):
                raise SpindlebenchError(
                    f"{where}: expected numbers in columns {time_column} and {value_column}"
                ) from None
            if not (math.isfinite(time_s) and math.isfinite(value)):
                raise SpindlebenchError(f"{where}: non-finite value")
            if value > KELVIN_SUSPECT_C or value < COLDEST_AMBIENT_C:
                raise SpindlebenchError(
                    f"{where}: ambient {value:g} °C is implausible (kelvin?); give °C"
                )
            if times and time_s <= times[-1]:
                raise SpindlebenchError(f"{where}: time {time_s:g} s does not increase")
            times.append(time_s)
            values.append(value)
    if len(times) < 2:
        raise t.error("file", f"{file} needs at least two samples")
    return times, values


def _read_cooling(top: Table) -> Cooling:
    return read_cooling(top.table("cooling", required=False))


def read_cooling(t: Table) -> Cooling:
    """A ``[cooling]`` table: a scenario's, or a study's ``[cooling.NAME]`` axis value (the
    one reader of the cooling keys). ``follow_ambient`` without ``setpoint_C`` follows the
    ambient exactly (offset 0 K)."""
    mode = t.string("mode", "off", choices=("off", "absolute", "follow_ambient"))
    if mode == "off":
        cooling = Cooling()
    elif mode == "absolute":
        cooling = Cooling(mode="absolute", setpoint_C=_temperature(t, "setpoint_C"))
    else:
        cooling = Cooling(
            mode="follow_ambient",
            setpoint_C=t.number("setpoint_C", 0.0, minimum=-FOLLOW_AMBIENT_MAX_K,
                                maximum=FOLLOW_AMBIENT_MAX_K, unit="K from ambient"),
        )
    t.finish()
    return cooling


def _read_sensors(top: Table, duration_s: float) -> SensorModel:
    return read_sensor_model(top.table("sensors", required=False), duration_s)


def read_sensor_model(t: Table, duration_s: float,
                      defaults: SensorModel = SensorModel()) -> SensorModel:
    """A ``[sensors]`` table: a scenario's, or a study's ``[noise.NAME]`` axis value (the one
    reader of the instrument keys); keys not given take ``defaults``."""
    noise = t.number("noise_C", defaults.noise_C, minimum=0.0, maximum=MAX_NOISE_C)
    quantum = t.number("quantum_C", defaults.quantum_C, minimum=0.0, maximum=MAX_NOISE_C)
    probe_noise = t.number("probe_noise_um", defaults.probe_noise_um, minimum=0.0,
                           maximum=MAX_PROBE_NOISE_UM)
    probe_quantum = t.number(
        "probe_quantum_um", defaults.probe_quantum_um, minimum=0.0, maximum=MAX_PROBE_NOISE_UM
    )
    noise_kind = t.string("noise_kind", defaults.noise_kind, choices=NOISE_KINDS)
    # the lag-1 coefficient belongs to the AR(1) process only: elsewhere it is an unknown key
    lag1 = (t.number("noise_lag1", defaults.noise_lag1, minimum=0.0, maximum=MAX_LAG1)
            if noise_kind == "ar1" else defaults.noise_lag1)
    drift_walk = t.number("probe_drift_um_per_sqrt_h", defaults.probe_drift_um_per_sqrt_h,
                          minimum=0.0, maximum=MAX_PROBE_DRIFT_UM)
    drift_rate = t.number("probe_drift_rate_um_per_h", defaults.probe_drift_rate_um_per_h,
                          minimum=-MAX_PROBE_DRIFT_UM, maximum=MAX_PROBE_DRIFT_UM)
    faults = []
    for ft in t.tables("faults", []):
        sensor = ft.string("sensor", choices=SENSORS)
        kind = ft.string("kind", choices=("dropout", "stuck", "offset"))
        start_s = ft.number("start_s", 0.0, minimum=0.0)
        if start_s >= duration_s:
            raise ft.error("start_s", f"{start_s:g} s is not within the duration "
                          f"({duration_s:g} s)")
        end_s = ft.number("end_s", None, minimum=0.0)  # None: until the end of the run
        if end_s is not None and end_s <= start_s:
            raise ft.error("end_s", f"must be after start_s ({start_s:g} s), got {end_s:g}")
        value = _temperature(ft, "value_C", None) if kind == "stuck" else None
        offset = (ft.number("offset_C", minimum=-MAX_OFFSET_C, maximum=MAX_OFFSET_C)
                  if kind == "offset" else None)
        ft.finish()
        faults.append(SensorFault(sensor, kind, start_s, end_s, value, offset))  # type: ignore[arg-type]
    t.finish()
    return SensorModel(noise, quantum, probe_noise, probe_quantum, tuple(faults),
                       noise_kind=noise_kind, noise_lag1=lag1,  # type: ignore[arg-type]
                       probe_drift_um_per_sqrt_h=drift_walk,
                       probe_drift_rate_um_per_h=drift_rate)


def _read_initial(top: Table, scenario_dir: Path) -> InitialState:
    t = top.table("initial", required=False)
    kind = t.string("kind", "cold", choices=("cold", "continue", "soak"))
    if kind == "cold":
        initial = InitialState(temperature_C=_temperature(t, "temperature_C", None))
    elif kind == "soak":
        days = t.integer("days", InitialState().days, minimum=1, maximum=MAX_SOAK_DAYS)
        initial = InitialState(kind="soak", days=days)
    else:
        name = t.string("from")
        if not name.strip():
            raise t.error("from", "is empty; give a scenario name (\"day1_warmup\") or a "
                         "recording's .json")
        if Path(name).suffix.lower() == ".toml":
            raise t.error("from", f"{name!r} is a scenario file; name the scenario without "
                         f".toml ({Path(name).stem!r}) or give its recording's .json")
        if is_scenario_reference(name):
            initial = InitialState(kind="continue", from_scenario=name)
        else:
            source = (scenario_dir / name).resolve()
            if source.suffix.lower() == ".csv":
                source = source.with_suffix(".json")
            initial = InitialState(kind="continue", from_file=source)
    t.finish()
    return initial


def is_scenario_reference(value: str) -> bool:
    """Whether ``initial.from`` names a sibling scenario rather than a recording file.

    The rule a user can see at a glance: no folder separator and no ``.json``/``.csv`` ending
    means a scenario name (``"day1_warmup"``); anything else is a path to a recording.
    """
    return ("/" not in value and "\\" not in value
            and Path(value).suffix.lower() not in (".json", ".csv"))


def _read_machine(top: Table, path: Path) -> Machine:
    name = top.string("machine", DEFAULT_MACHINE)
    try:
        return load_machine(name, source=path)
    except SpindlebenchError as exc:
        raise top.error("machine", str(exc)) from None


def with_machine(scenario: Scenario, name: str | None) -> Scenario:
    """``scenario`` on machine ``name`` (a shipped name or a .toml path); None keeps its own."""
    return scenario if name is None else replace(scenario, machine=load_machine(name))


def resolve_initial(scenario: Scenario, output_dir: str | Path) -> Scenario:
    """The scenario with a sibling reference in ``initial.from`` turned into a file.

    ``from = "day1_warmup"`` means the recording ``day1_warmup.json`` in the folder this run
    writes into, so a folder of scenarios continues from the runs of the same batch.
    """
    initial = scenario.initial
    if initial.kind != "continue" or initial.from_scenario is None:
        return scenario
    source = Path(output_dir) / f"{initial.from_scenario}.json"
    return replace(scenario, initial=replace(initial, from_file=source))


def start_state(scenario: Scenario) -> EndState | None:
    """The parsed end state a ``continue`` scenario starts from (None for other kinds): the
    sidecar named by ``initial.from``, read once by the caller and handed to the runner."""
    initial = scenario.initial
    if initial.kind != "continue":
        return None
    where = f"{scenario.path}: key 'initial.from'"
    if initial.from_file is None:  # a sibling name, not yet placed in an output folder
        raise SpindlebenchError(f"{where}: names the scenario {initial.from_scenario!r}, whose "
                                "recording is looked up in the output folder; simulate with "
                                "simulate_scenario() or resolve_initial() first")
    missing = None
    if initial.from_scenario is not None:
        missing = (f"no recording of scenario {initial.from_scenario!r} at "
                   f"{initial.from_file} (simulate it into the same output folder first)")
    from spindlebench.formats.recording import read_end_state  # pandas: only when continuing

    return read_end_state(initial.from_file, where, missing)


def scenario_table(value: Any) -> dict[str, Any]:
    """The scenario table of one of the testbench's values (a speed or feed programme, an
    ambient, a cooling, a sensor model, a fault): the table its reader above turns back into
    ``value``, so a study can merge it into an experiment's scenario table by key path.

    The one rule that makes this generic: **a field of a scenario dataclass is named as its
    key** (``SensorModel.noise_C`` is ``[sensors] noise_C``). Fields at their default and
    ``None`` are left out (the reader's default; ``None`` is "not given"), ``kind`` is always
    written, a tuple of values is an array of tables (``[[steps]]``, ``[[faults]]``). A new
    key a study can vary is then a field and its reader, nothing else.

    >>> scenario_table(SpeedCycles(rpm=4000.0, on_s=600.0, off_s=300.0))
    {'rpm': 4000.0, 'on_s': 600.0, 'off_s': 300.0, 'kind': 'cycles'}
    >>> scenario_table(Cooling())
    {}
    """
    table: dict[str, Any] = {}
    for f in fields(value):
        item = getattr(value, f.name)
        if item is None or (f.name != "kind" and f.default is not MISSING
                            and item == f.default):
            continue
        if isinstance(item, tuple):
            item = [scenario_table(element) for element in item]
            if not item:
                continue
        table[f.name] = item
    return table


def _read_outputs(top: Table) -> bool:
    """``[outputs] probes``: whether the recording carries the five-probe outputs."""
    t = top.table("outputs", required=False)
    probes = t.get("probes", bool, False)
    t.finish()
    return probes


def _read_parameters(top: Table) -> dict[str, float]:
    t = top.table("parameters", required=False)
    values = {name: t.number(name) for name in sorted(t.data)}
    t.finish()
    return values


def step_count_problem(duration_s: float, step_s: float) -> str | None:
    """Why ``duration_s`` at ``step_s`` is too many steps to simulate (None when it is not).

    Checked before any array is made: a tiny step would otherwise fail deep in numpy
    ("Maximum allowed size exceeded") or run for hours.
    """
    too_small = range_problem(step_s, minimum=MIN_STEP_S, unit="s")
    if too_small:
        return too_small
    steps = duration_s / step_s
    if steps > MAX_STEPS:
        return (f"{step_s:g} s gives {steps:.3g} communication steps over {duration_s:g} s; at "
                f"most {MAX_STEPS:,} (use a larger step_s)")
    return None


def _check_grid(top: Table, name: str, value: float, unit_name: str, unit_s: float) -> None:
    ratio = value / unit_s
    if abs(ratio - round(ratio)) > 1e-9 * max(1.0, ratio):
        raise top.error(name, f"{value:g} s is not a multiple of {unit_name} ({unit_s:g} s)")


# --------------------------------------------------------------------------- entry point


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario TOML file; raise ``SpindlebenchError`` on any problem."""
    path = Path(path)
    return read_scenario(Table(load_toml(path, "scenario"), path), path)


def read_scenario(top: Table, path: Path) -> Scenario:
    """The one reader of a scenario table: a scenario file's, or the table a study merges
    its experiment's key paths into (``studies.family.experiments.scenario_table``).
    ``path`` is the scenario's file; relative files in the table are found beside it."""
    scenario_dir = path.resolve().parent
    name = top.string("name", path.stem)
    description = top.string("description", "")
    duration_s = top.number("duration_s", positive=True, maximum=90 * 86400.0)
    step_s = top.number("step_s", positive=True, minimum=MIN_STEP_S)
    if step_s > duration_s:
        raise top.error("step_s", f"communication step {step_s:g} s is larger than the duration "
                       f"({duration_s:g} s)")
    _check_grid(top, "duration_s", duration_s, "step_s", step_s)
    too_many = step_count_problem(duration_s, step_s)
    if too_many:
        raise top.error("step_s", too_many)
    sample_interval_s = top.number("sample_interval_s", positive=True)
    if sample_interval_s > duration_s:
        raise top.error("sample_interval_s", f"{sample_interval_s:g} s is larger than the "
                       f"duration ({duration_s:g} s)")
    _check_grid(top, "sample_interval_s", sample_interval_s, "step_s", step_s)
    _check_grid(top, "duration_s", duration_s, "sample_interval_s", sample_interval_s)
    samples = duration_s / sample_interval_s + 1
    if samples > MAX_SAMPLES:
        raise top.error("sample_interval_s", f"{sample_interval_s:g} s gives {samples:,.0f} "
                        f"samples over {duration_s:g} s; at most {MAX_SAMPLES:,} (a recording "
                        "of every output would need gigabytes of memory): use a larger "
                        "sample_interval_s")
    seed = top.integer("seed", 0, minimum=0)
    scenario = Scenario(
        path=path,
        name=name,
        description=description,
        duration_s=duration_s,
        step_s=step_s,
        sample_interval_s=sample_interval_s,
        seed=seed,
        speed=_read_speed(top, duration_s),
        feed=_read_feed(top, duration_s),
        ambient=_read_ambient(top, scenario_dir, duration_s, seed),
        cooling=_read_cooling(top),
        sensors=_read_sensors(top, duration_s),
        initial=_read_initial(top, scenario_dir),
        parameters=_read_parameters(top),
        inputs=top.string("inputs", "continuous", choices=INPUT_MODES),
        machine=_read_machine(top, path),
        probes=_read_outputs(top),
    )
    top.finish()
    if scenario.initial.kind == "soak" and isinstance(scenario.ambient, MeasuredAmbient):
        raise top.error("initial", "kind = \"soak\" repeats the ambient's daily cycle; a "
                       "measured series has none (use a season or indoor ambient, or "
                       "kind = \"cold\")")
    return scenario
