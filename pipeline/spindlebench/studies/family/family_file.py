"""The season-sweep study file: schema, defaults and validation.

A study describes a family of virtual experiments and how to judge the selection methods on
it. Experiments are the cross product of the *experiment axes* (months of a climate, spindle
speeds, speed programmes, cooling modes); every experiment is simulated once per random
replica (its own day's weather and sensor noise). The *condition axes* (sensor noise levels,
sensor faults) describe the instruments, not the machine: each condition re-measures the same
simulated truth, so conditions are compared on identical thermal histories.

Faults strike the held-out experiments only: they model a sensor that goes bad after the
compensation model was trained on healthy data, the case a practitioner worries about.

Every problem becomes one line naming the study file and the dotted key.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Generic, TypeVar

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.limits import (
    MAX_FEED_MM_PER_MIN,
    MAX_OFFSET_C,
    MAX_RPM,
    RPM_RANGE_UNIT,
)
from spindlebench.core.names import (
    DEFAULT_METHOD,
    DEFAULT_METHOD_SEED,
    DEFAULT_SIMILARITY,
    GROUPS,
    SENSORS,
    SIMILARITIES,
)
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.core.provenance import sha256_file
from spindlebench.formats.recording import (
    DRIFT_COLUMN,
    ERROR_COLUMNS,
    FEED_X_COLUMN,
    FEED_Y_COLUMN,
    SPEED_COLUMN,
)
from spindlebench.formats.toml import (
    Table,
    in_range,
    load_toml,
    non_negative,
    one_of,
    positive,
    range_problem,
)
from spindlebench.machines.variants import DEFAULT_MACHINE, Machine, load_machine
from spindlebench.studies.family.population import Population, read_population
from spindlebench.studies.family.seasons import MONTHS, Climate, load_climate, resolve_climate_path
from spindlebench.testbench.scenario import (
    MAX_SOAK_DAYS,
    ConstantSpeed,
    Cooling,
    IndoorAmbient,
    InitialState,
    SensorFault,
    SensorModel,
    SpeedCycles,
    SpeedProgramme,
    SpeedStep,
    SteppedSpeed,
    read_building,
    read_cooling,
    read_sensor_model,
    step_count_problem,
    temperature_problem,
)

V = TypeVar("V")

#: Most replicas and clusters a study may ask for.
MAX_REPLICAS, MAX_CLUSTERS = 10_000, 6
#: Most simulations one study may ask for: at ~1 s each on one core, 100 000 is more than a
#: day on a workstation; 960 000 spent 5 min and 2 GB building tasks before the first run.
MAX_SIMULATIONS = 100_000
#: The sweep's baselines: the top-k-correlated selection method on the raw sensors then OLS,
#: and ridge on all sensors; their names are the method's and the regressor's.
TOP_K_BASELINE, RIDGE_BASELINE = "top-k-correlated", "ridge"
BASELINES = (TOP_K_BASELINE, RIDGE_BASELINE)
TRAINING_RULES = ("one", "each-season")
PROGRAMME_KINDS = ("constant", "cycles", "steps")
FAULT_KINDS = ("dropout", "stuck", "offset")
NO_FAULT = "none"


@dataclass(frozen=True)
class AxisValue(Generic[V]):
    """One named value of a study axis: the testbench's own type (``Cooling``,
    ``SensorModel``), read from the ``[AXIS.NAME]`` table by the scenario's reader of that key
    path (``SCENARIO_AXES``), so the study mirrors no scenario type."""

    name: str
    value: V


#: The axes whose values are scenario tables: axis -> (the scenario key path its
#: ``[AXIS.NAME]`` tables are, the scenario's reader of that table). A scenario key a study
#: can vary is added here (one entry) once its reader exists in ``testbench.scenario``.
SCENARIO_AXES: dict[str, tuple[str, Callable[..., Any]]] = {
    "cooling": ("cooling", lambda t, study: read_cooling(t)),
    "noise": ("sensors", lambda t, study: read_sensor_model(t, study["duration_s"],
                                                              STUDY_SENSORS)),
}
#: A study's instruments unless its ``[noise.NAME]`` says otherwise (the scenario's
#: ``SensorModel`` defaults, with a probe of 0.3 µm noise), and its ``default`` noise level.
STUDY_SENSORS = SensorModel(probe_noise_um=0.3)
#: The axis values a study may name without defining them.
BUILT_IN_VALUES: dict[str, tuple[str, Any]] = {"cooling": ("off", Cooling()),
                                               "noise": ("default", STUDY_SENSORS)}


#: A study's fault: the testbench's ``SensorFault`` (to the end of the run, ``end_s`` None)
#: applied to every held-out experiment from ``start_s`` on, under its ``[faults.NAME]`` name.
#: Its table is the family's own (``start_h``, hours into the run; a compensation study
#: shifts it into each day), not a scenario's ``[[sensors.faults]]``.
Fault = AxisValue
#: A study's speed programme: the testbench's own speed type written at unit speed (1 = the
#: experiment's speed, an axis; ``testbench.scenario.at_speed`` scales it), under its
#: ``[programmes.NAME]`` name. Its table is the family's own (``on_min``/``off_min``,
#: ``at_h``/``fraction`` of the axis speed), not a scenario's ``[speed]``.
Programme = AxisValue


@dataclass(frozen=True)
class Training:
    rule: str
    month: str
    speed_rpm: float
    programme: str
    cooling: str


@dataclass(frozen=True)
class Methods:
    clusters: tuple[int, ...]
    groups: tuple[str, ...]
    baselines: tuple[str, ...]
    similarity: str
    ground_truth: bool
    #: Selection method labels (``selection.registry``) run on every group; ``closure`` is
    #: the paper's and keeps the group's plain name in the results.
    methods: tuple[str, ...] = (DEFAULT_METHOD,)
    #: Seed of the seeded methods (fcm, kmeans, stability).
    seed: int = DEFAULT_METHOD_SEED


@dataclass(frozen=True)
class SweepStudy:
    """A validated season-sweep study."""

    path: Path
    name: str
    description: str
    seed: int
    replicas: int
    climate: Climate
    fmu: Path
    duration_s: float
    step_s: float
    sample_interval_s: float
    start_hour: float
    weather_sd_C: float  # noqa: N815
    feed: str
    feed_x_mm_per_min: float
    feed_y_mm_per_min: float
    months: tuple[str, ...]
    speeds_rpm: tuple[float, ...]
    programmes: tuple[AxisValue[SpeedProgramme], ...]
    cooling: tuple[AxisValue[Cooling], ...]
    noise: tuple[AxisValue[SensorModel], ...]
    faults: tuple[AxisValue[SensorFault] | None, ...]
    training: Training
    methods: Methods
    parameters: dict[str, float] = field(default_factory=dict)
    #: ``initial = "soak"``: every run starts from ``soak_days`` idle days of its month's
    #: normal daily cycle (one soak per month, shared by all its runs); None: a cold start.
    soak_days: int | None = None
    #: ``[experiment.indoor]``: the indoor ambient's building and weather (outdoor cycle and
    #: seed are filled in per run); None: the season curve of the replica's day.
    indoor: IndoorAmbient | None = None
    #: The machine variant every run simulates (``[study] machine``, or ``--machine``).
    machine: Machine = field(default_factory=load_machine)
    #: ``[axes] machines``: the study is run once per machine (``machine_runs``), each into
    #: its own results folder; empty: one run on ``machine``.
    machines: tuple[str, ...] = ()
    #: ``[axes] machines = { population = N, ... }``: the study is run once per machine drawn
    #: around a base machine (``studies.population``), each into its own results folder.
    population: Population | None = None
    #: ``[study] targets``: the thermal-error columns the study selects for (default: the
    #: axial drift alone); any other makes every run record the five probes.
    targets: tuple[str, ...] = (DRIFT_COLUMN,)

    @property
    def probes(self) -> bool:
        """Whether the runs must record the five-probe outputs (a target other than Z)."""
        return any(target != DRIFT_COLUMN for target in self.targets)

    @property
    def sha256(self) -> str:
        return sha256_file(self.path)


def load_study(path: str | Path, extra_tables: tuple[str, ...] = (),
               machine: str | None = None) -> SweepStudy:
    """Read and validate a sweep study file.

    ``machine`` (``--machine``) replaces the study's ``[study] machine`` (default machine when
    neither names one).

    ``extra_tables``: top-level tables another study kind reads itself (the placement study's
    ``[placement]``); they are let through instead of rejected as unknown keys.
    """
    path = Path(path)
    root = Table(load_toml(path, "study"), path)
    here = path.resolve().parent

    head = root.table("study")
    name = head.get("name", str, default=path.stem)
    description = head.get("description", str, default="")
    seed = head.get("seed", int, check=non_negative)
    replicas = head.get("replicas", int, check=in_range(1, MAX_REPLICAS))
    climate_name = head.get("climate", str)
    climate_path = resolve_climate_path(climate_name, here)
    if not climate_path.exists():
        raise head.error("climate", f"no climate table {climate_path}")
    climate = load_climate(climate_path)
    fmu_text = head.get("fmu", str, default="")
    fmu = (here / fmu_text).resolve() if fmu_text else DEFAULT_FMU
    if fmu_text and not fmu.is_file():
        raise head.error("fmu", f"no such FMU: {fmu}")
    fmu_parameters = _fmu_parameters(head, fmu) if fmu.is_file() else None
    machine_name = head.get("machine", str, default=DEFAULT_MACHINE)
    targets = tuple(head.get_list("targets", str, default=[DRIFT_COLUMN],
                                  check=lambda v: one_of(v, ERROR_COLUMNS)))
    try:
        machine_variant = load_machine(machine or machine_name, source=None if machine else path)
    except SpindlebenchError as exc:
        raise (head.error("machine", str(exc)) if machine is None else exc) from None
    head.finish()
    if fmu_parameters is not None:
        _check_machine(machine_variant, fmu_parameters, fmu)

    exp = root.table("experiment")
    duration_s, duration_key = _duration_s(exp)
    step_s = exp.get("step_s", float, check=lambda v: step_count_problem(duration_s, v))
    sample_interval_s = exp.get("sample_interval_s", float, default=max(step_s, 60.0),
                                check=positive)
    if step_s > duration_s:
        raise exp.error("step_s", f"{step_s:g} s is longer than the duration ({duration_s:g} s)")
    if sample_interval_s > duration_s / 2:
        raise exp.error("sample_interval_s", f"{sample_interval_s:g} s leaves fewer than 3 "
                                             f"samples in {duration_s:g} s")
    for key, value, unit_name, unit in (("sample_interval_s", sample_interval_s, "step_s", step_s),
                                        (duration_key, duration_s, "sample_interval_s",
                                         sample_interval_s)):
        ratio = value / unit
        if abs(ratio - round(ratio)) > 1e-9 * max(1.0, ratio):
            raise exp.error(key, f"{value:g} s is not a multiple of {unit_name} ({unit:g} s)")
    start_hour = exp.get("start_hour", float, default=8.0,
                         check=lambda v: None if 0 <= v < 24 else "must be in [0, 24)")
    weather_sd = exp.get("weather_sd_C", float, default=1.0,
                         check=in_range(0, 10, "K"))
    feed = exp.get("feed", str, default="constant",
                   check=lambda v: one_of(v, ("constant", "with_spindle")))
    feed_x = exp.get(FEED_X_COLUMN, float, default=1500.0, check=_feed)
    feed_y = exp.get(FEED_Y_COLUMN, float, default=1500.0, check=_feed)
    soak_days = _soak_days(exp)
    indoor = _indoor(exp)
    exp.finish()

    definitions = {
        "programmes": root.table("programmes", required=False),
        "cooling": root.table("cooling", required=False),
        "noise": root.table("noise", required=False),
        "faults": root.table("faults", required=False),
    }

    axes = root.table("axes")
    months = tuple(axes.get_list("months", str, check=lambda m: None if m in MONTHS
                                 else f"not a month (use {', '.join(MONTHS)})"))
    speeds = tuple(axes.get_list("speeds_rpm", float,
                                 check=in_range(maximum=MAX_RPM, unit=RPM_RANGE_UNIT,
                                                positive=True)))
    programme_names = axes.get_list("programmes", str, default=["constant"])
    cooling_names = axes.get_list("cooling", str, default=["off"])
    noise_names = axes.get_list("noise", str, default=["default"])
    fault_names = axes.get_list("faults", str, default=[NO_FAULT])
    population = None
    if isinstance(axes.raw("machines", default=None), Mapping):
        population = read_population(axes.table("machines"), path)
        machine_axis: tuple[str, ...] = ()
    else:
        machine_axis = tuple(axes.get_list("machines", str, default=[]))
    if fmu_parameters is not None:
        _check_input_axis(axes, "speeds_rpm", speeds, SPEED_COLUMN, fmu)
    axes.finish()
    machines = population.size if population is not None else max(1, len(machine_axis))
    simulations = (replicas * machines * len(months) * len(speeds) * len(programme_names)
                   * len(cooling_names))
    if simulations > MAX_SIMULATIONS:  # refused now, not after minutes of building tasks
        raise axes.error("speeds_rpm", f"the axes give {simulations:,} simulations (replicas × "
                         "machines × months × speeds × programmes × cooling), more than the "
                         f"{MAX_SIMULATIONS:,} a study may run; split it into several studies")
    if (machine_axis or population) and machine_name != DEFAULT_MACHINE:
        raise axes.error("machines", "give either [study] machine or [axes] machines, not both")
    if population is not None and len(targets) > 1:  # its report counts one result per machine
        raise head.error("targets", "a population study ([axes] machines = { population = "
                         "... }) takes one target; run each target as its own study")
    for name in machine_axis:
        try:
            variant = load_machine(name, source=path)
            if fmu_parameters is not None:
                _check_machine(variant, fmu_parameters, fmu)
        except SpindlebenchError as exc:
            raise axes.error("machines", str(exc)) from None

    programmes = tuple(_programme(definitions["programmes"], axes, n, duration_s)
                       for n in programme_names)
    known = {"duration_s": duration_s}
    cooling = tuple(_scenario_axis("cooling", definitions["cooling"], axes, n, known)
                    for n in cooling_names)
    noise = tuple(_scenario_axis("noise", definitions["noise"], axes, n, known)
                  for n in noise_names)
    faults = tuple(_fault(definitions["faults"], axes, n, duration_s) for n in fault_names)
    for table in definitions.values():
        for defined in table.unused():
            raise table.error(defined, "defined but not listed in [axes]")

    training = _training(root.table("training"), months, speeds, programme_names,
                         cooling_names, climate)
    methods = _methods(root.table("methods", required=False))

    params = root.table("parameters", required=False)
    parameters = {name: params.get(name, float) for name in list(params.names())}
    params.finish()
    if fmu_parameters is not None:
        _check_parameters(params, parameters, fmu_parameters, fmu)
    for table_name in extra_tables:  # not 'name': that is the study's name
        root.raw(table_name, default=None)
    root.finish()

    n_experiments = len(months) * len(speeds) * len(programmes) * len(cooling)
    if n_experiments < 2:
        raise root.error("axes", "the axes give only one experiment; a sweep needs a training "
                                 "experiment and at least one held-out experiment")
    return SweepStudy(
        path=path, name=name, description=description, seed=seed, replicas=replicas,
        climate=climate, fmu=fmu, duration_s=duration_s, step_s=step_s,
        sample_interval_s=sample_interval_s, start_hour=start_hour, weather_sd_C=weather_sd,
        feed=feed, feed_x_mm_per_min=feed_x, feed_y_mm_per_min=feed_y, months=months,
        speeds_rpm=speeds, programmes=programmes, cooling=cooling, noise=noise, faults=faults,
        training=training, methods=methods, parameters=parameters, soak_days=soak_days,
        indoor=indoor, machine=machine_variant, machines=machine_axis, population=population,
        targets=targets,
    )


def machine_runs(study: SweepStudy, machine: str | None,
                 out: Path) -> list[tuple[str | None, Path]]:
    """The (machine, results folder) of each run of a study command: one run on ``machine``
    (``--machine``) or the study's own, or one per ``[axes] machines`` entry, each into
    ``out/<machine name>``."""
    if machine is not None or not study.machines:
        return [(machine, out)]
    return [(name, out / Path(name).stem) for name in study.machines]


def _check_machine(machine: Machine, known: Mapping[str, Any], fmu: Path) -> None:
    """The machine's parameters must be the FMU's, within its declared bounds (at load time,
    not once per simulation in the workers)."""
    from spindlebench.testbench.runner import check_machine

    check_machine(machine, known, fmu.name)


def _check_input_axis(axes: Table, key: str, values: tuple[float, ...], input_name: str,
                      fmu: Path) -> None:
    """An axis of input values within the FMU's declared bounds of that input (the model
    description is the one home of the limits; the worker's check would fail every run)."""
    from spindlebench.testbench.runner import bound_problem, declared_bounds, inspect_fmu

    variable = inspect_fmu(fmu).inputs.get(input_name)
    for value in values if variable is not None else ():
        if bound_problem(variable, value):
            low, high = declared_bounds(variable)
            raise axes.error(key, f"{value:g} {variable.unit or ''} is outside {low:g}..{high:g},"
                             f" the range {fmu.name} declares for {input_name}")


def _soak_days(exp: Table) -> int | None:
    """``initial = "cold"`` (default) or ``"soak"`` with ``soak_days`` (1-60, default 7)."""
    initial = exp.get("initial", str, default="cold",
                      check=lambda v: one_of(v, ("cold", "soak")))
    if initial == "cold":
        return None  # soak_days is then an unknown key
    return exp.get("soak_days", int, default=InitialState().days,
                   check=in_range(1, MAX_SOAK_DAYS))


def _indoor(exp: Table) -> IndoorAmbient | None:
    """The optional ``[experiment.indoor]`` table: the building and weather of an indoor
    ambient (scenario keys and defaults); the outdoor cycle is each month's normals."""
    if not exp.has("indoor"):
        return None
    if exp.has("weather_sd_C"):
        raise exp.error("weather_sd_C", "with [experiment.indoor] the weather is the indoor "
                        "model's (weather_sd_K there); remove weather_sd_C")
    t = exp.table("indoor")
    template = IndoorAmbient(outdoor_low_C=0.0, outdoor_high_C=0.0, **read_building(t))
    t.finish()
    return template


def _feed(value: float) -> str | None:
    """A scenario's feed limit (like its step-count and speed limits, imported from
    ``testbench.scenario``): a study's experiments are scenarios."""
    return range_problem(value, 0.0, MAX_FEED_MM_PER_MIN, "mm/min")


def _fmu_parameters(head: Table, fmu: Path) -> Mapping[str, Any]:
    """The FMU's settable parameters by name; an unreadable FMU fails here, at load time.

    Checked now, not in the workers, so a wrong FMU or a misspelt parameter is one line
    before any results folder exists, not the same error once per simulation afterwards.
    """
    from spindlebench.testbench.runner import inspect_fmu

    try:
        return inspect_fmu(fmu).parameters
    except SpindlebenchError as exc:
        raise head.error("fmu", str(exc)) from None


def _check_parameters(params: Table, parameters: dict[str, float], known: Mapping[str, Any],
                      fmu: Path) -> None:
    """Every ``[parameters]`` name must be one the FMU lets the runner set, within the min/max
    its model description declares (as for a scenario)."""
    import difflib

    from spindlebench.testbench.runner import COOLING_PARAMETERS, bound_problem

    for name in parameters:
        if name in COOLING_PARAMETERS:
            raise params.error(name, "set cooling with [cooling] and axes.cooling "
                                     "(mode, setpoint_C)")
        if name not in known:
            near = difflib.get_close_matches(name, sorted(known), n=1)
            hint = f" (did you mean {near[0]!r}?)" if near else ""
            raise params.error(name, f"the FMU {fmu.name} has no parameter {name!r}{hint}")
        problem = bound_problem(known[name], parameters[name])
        if problem:
            raise params.error(name, problem)


def _duration_s(exp: Table) -> tuple[float, str]:
    """``duration_h`` or ``duration_min`` (exactly one of them), in seconds, and its key."""
    given = [key for key in ("duration_h", "duration_min") if exp.has(key)]
    if len(given) != 1:
        raise exp.error("duration_h", "give exactly one of duration_h and duration_min")
    key = given[0]
    scale = 3600.0 if key == "duration_h" else 60.0
    value = exp.get(key, float, check=lambda v: None if 0 < v * scale <= 30 * 86400.0
                    else "must be > 0 and at most 30 days")
    return value * scale, key


def _definition(table: Table, axes: Table, axis: str, name: str) -> Table:
    if not table.has(name):
        raise axes.error(axis, f"'{name}' is not defined (add a [{table.prefix}.{name}] table)")
    return table.table(name)


def _programme(table: Table, axes: Table, name: str,
               duration_s: float) -> AxisValue[SpeedProgramme]:
    if name == "constant" and not table.has(name):
        return AxisValue(name, ConstantSpeed(rpm=1.0))
    t = _definition(table, axes, "programmes", name)
    kind = t.get("kind", str, check=lambda v: one_of(v, PROGRAMME_KINDS))
    programme: SpeedProgramme
    if kind == "constant":
        programme = ConstantSpeed(rpm=1.0)
    elif kind == "cycles":
        on_s = t.get("on_min", float, check=positive) * 60.0
        off_s = t.get("off_min", float, check=positive) * 60.0
        if on_s + off_s > duration_s:
            raise t.error("on_min", f"one cycle ({(on_s + off_s) / 60:g} min) is longer than "
                                    f"the experiment ({duration_s / 60:g} min)")
        programme = SpeedCycles(rpm=1.0, on_s=on_s, off_s=off_s)
    else:
        at_h = t.get_list("at_h", float, check=non_negative)
        fractions = t.get_list("fraction", float,
                               check=in_range(0, 1.5, "(a fraction of the axis speed)"))
        if len(at_h) != len(fractions):
            raise t.error("fraction", f"has {len(fractions)} values but at_h has {len(at_h)}")
        if at_h != sorted(at_h) or at_h[-1] * 3600.0 >= duration_s:
            raise t.error("at_h", "must increase and stay within the experiment's duration")
        programme = SteppedSpeed(steps=tuple(SpeedStep(at_s=h * 3600.0, rpm=fraction)
                                             for h, fraction in zip(at_h, fractions,
                                                                    strict=True)))
    t.finish()
    return AxisValue(name, programme)


def _scenario_axis(axis: str, table: Table, axes: Table, name: str,
                   study: Mapping[str, Any]) -> AxisValue:
    """The value ``name`` of ``axis``: its ``[AXIS.NAME]`` table read by the scenario's reader
    of the axis's key path (``SCENARIO_AXES``), or the built-in value of that name."""
    built_in, value = BUILT_IN_VALUES.get(axis, (None, None))
    if name == built_in and not table.has(name):
        return AxisValue(name, value)
    t = _definition(table, axes, axis, name)
    if axis == "noise" and t.has("faults"):
        raise t.error("faults", "a study's sensor faults are its [faults] axis")
    _, read = SCENARIO_AXES[axis]
    return AxisValue(name, read(t, study))


def _fault(table: Table, axes: Table, name: str,
           duration_s: float) -> AxisValue[SensorFault] | None:
    if name == NO_FAULT:
        if table.has(name):
            raise table.error(name, f"'{NO_FAULT}' is reserved for 'no fault'")
        return None
    t = _definition(table, axes, "faults", name)
    sensor = t.get("sensor", str, check=lambda v: one_of(v, SENSORS))
    kind = t.get("kind", str, check=lambda v: one_of(v, FAULT_KINDS))
    start_s = t.get("start_h", float, default=0.0, check=non_negative) * 3600.0
    if start_s >= duration_s:
        raise t.error("start_h", "must be within the experiment's duration")
    value = offset = None
    if kind == "stuck" and t.has("value_C"):
        value = t.get("value_C", float, check=temperature_problem)
    if kind == "offset":
        offset = t.get("offset_C", float, check=lambda v: "must be non-zero" if v == 0 else
                       range_problem(v, -MAX_OFFSET_C, MAX_OFFSET_C, "K"))
    t.finish()
    return AxisValue(name, SensorFault(sensor, kind, start_s, None, value, offset))


def _training(t: Table, months: tuple[str, ...], speeds: tuple[float, ...],
              programmes: list[str], cooling: list[str], climate: Climate) -> Training:
    rule = t.get("rule", str, default="one", check=lambda v: one_of(v, TRAINING_RULES))
    def of_the_study(values: Sequence[Any], what: str) -> Callable[[Any], str | None]:
        from spindlebench.studies.family.experiments import speed_label

        shown = ", ".join(speed_label(v) if isinstance(v, float) else str(v) for v in values)
        return lambda v: None if v in values else f"must be one of the study's {what} ({shown})"

    month = t.get("month", str, default=months[0], check=of_the_study(months, "months"))
    speed = t.get("speed_rpm", float, default=speeds[0], check=of_the_study(speeds, "speeds"))
    programme = t.get("programme", str, default=programmes[0],
                      check=of_the_study(programmes, "programmes"))
    cooling_mode = t.get("cooling", str, default=cooling[0],
                         check=of_the_study(cooling, "cooling modes"))
    if rule == "each-season" and t.has("month"):
        raise t.error("month", "with rule 'each-season' the first listed month of every "
                               "season trains; remove 'month'")
    t.finish()
    if rule == "each-season" and len({climate.season_of(m) for m in months}) < 2:
        raise t.error("rule", "'each-season' needs months from at least two seasons")
    return Training(rule, month, speed, programme, cooling_mode)


def _methods(t: Table) -> Methods:
    clusters = t.get_list("clusters", int, default=[2, 3, 4],
                          check=in_range(1, MAX_CLUSTERS))
    groups = t.get_list("groups", str, default=list(GROUPS), allow_empty=True,
                        check=lambda v: one_of(v, GROUPS))
    baselines = t.get_list("baselines", str, default=list(BASELINES), allow_empty=True,
                           check=lambda v: one_of(v, BASELINES))
    similarity = t.get("similarity", str, default=DEFAULT_SIMILARITY,
                       check=lambda v: one_of(v, SIMILARITIES))
    ground_truth = t.get("ground_truth", bool, default=True)
    labels = t.get_list("methods", str, default=[DEFAULT_METHOD])
    from spindlebench.selection.registry import check_labels, method_seed_problem

    seed = t.get("seed", int, default=DEFAULT_METHOD_SEED, check=method_seed_problem)
    t.finish()
    from spindlebench.selection.method_registry import method_names

    labels = list(method_names(budget=True, multi_output=False)) if labels == ["all"] else labels
    try:
        methods = check_labels(labels, "methods")
    except SpindlebenchError as exc:
        raise t.error("methods", str(exc).removeprefix("methods: ")) from None
    if not groups and not baselines:
        raise t.error("groups", "no method left to evaluate (groups and baselines are empty)")
    return Methods(tuple(clusters), tuple(groups), tuple(baselines), similarity, ground_truth,
                   methods, seed)


def describe(study: SweepStudy) -> dict[str, Any]:
    """A JSON-ready summary of the study's axes (for provenance and the README)."""
    return {
        "name": study.name,
        "climate": study.climate.name,
        "months": list(study.months),
        "speeds_rpm": list(study.speeds_rpm),
        "programmes": [p.name for p in study.programmes],
        "cooling": [c.name for c in study.cooling],
        "noise": [n.name for n in study.noise],
        "faults": [f.name if f else NO_FAULT for f in study.faults],
        "replicas": study.replicas,
        "duration_h": study.duration_s / 3600.0,
        "training_rule": study.training.rule,
    }


#: Study keys that change no result: prose, and the FMU's path (its content is pinned apart).
UNPINNED_KEYS = (("study", "description"), ("study", "fmu"))


def pinned_content(study: SweepStudy) -> dict[str, Any]:
    """What a results folder of ``study`` is pinned to: the parsed study and climate files.

    Parsed, not raw, so that editing a comment or reordering keys does not lock the user out
    of resuming; the climate table is part of it because it sets every run's ambient.
    """
    data = load_toml(study.path)
    for table, key in UNPINNED_KEYS:
        if isinstance(data.get(table), dict):
            data[table].pop(key, None)
    return {"study file": data, "climate file": load_toml(study.climate.path),
            "machine": {**study.machine.provenance(), "parameters": dict(study.machine.parameters)}}


def check_fmu(study: SweepStudy) -> Path:
    """The FMU the study runs; a missing default FMU gets a message that says how to build."""
    if not study.fmu.is_file():
        raise SpindlebenchError(f"{study.path}: FMU {study.fmu} not found; build it with "
                                "'spindlebench build' or set study.fmu")
    return study.fmu
