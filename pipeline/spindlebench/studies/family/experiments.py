"""From a study to concrete work: experiments, conditions, replicas, scenarios and seeds.

An *experiment* is one operating point of the machine on one day of a month (month × speed ×
programme × cooling). A *replica* re-draws the day: the weather (the day's low and high
scatter around the month's normals by ``weather_sd_C``) and the sensor noise. A *condition*
(noise level × fault) is how that day is measured. The expensive part, the FMU simulation,
depends only on (replica, experiment); each condition re-measures its noise-free truth.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from spindlebench.formats.toml import Table, with_key_paths
from spindlebench.studies.family.family_file import (
    NO_FAULT,
    AxisValue,
    SweepStudy,
)
from spindlebench.studies.family.seeds import derive_seed
from spindlebench.testbench.scenario import (
    AmbientModel,
    InitialState,
    Scenario,
    SeasonAmbient,
    SensorFault,
    SensorModel,
    at_speed,
    read_scenario,
)
from spindlebench.testbench.scenario import scenario_table as scenario_table_of


@dataclass(frozen=True)
class Experiment:
    """One operating point in one month; ``id`` names its files and result rows."""

    month: str
    season: str
    speed_rpm: float
    programme: str
    cooling: str

    @property
    def id(self) -> str:
        return f"{self.month}-{speed_label(self.speed_rpm)}rpm-{self.programme}-{self.cooling}"


def speed_label(rpm: float) -> str:
    """A speed as it names an experiment: ``2000``, ``1500.5``; as many digits as it takes
    to be the speed (``2000.0001``, where ``:g`` gave ``2000`` for it and for 2000)."""
    short = f"{rpm:g}"
    return short if float(short) == rpm else repr(float(rpm))


@dataclass(frozen=True)
class Condition:
    """How the experiments are measured: a noise level and an optional fault."""

    noise: AxisValue[SensorModel]
    fault: AxisValue[SensorFault] | None

    @property
    def id(self) -> str:
        return f"{self.noise.name}+{self.fault.name if self.fault else NO_FAULT}"

    @property
    def fault_name(self) -> str:
        return self.fault.name if self.fault else NO_FAULT


def experiments(study: SweepStudy) -> list[Experiment]:
    """Every experiment of the study, in the order of its axes."""
    return [
        Experiment(month, study.climate.season_of(month), speed, programme.name, cooling.name)
        for month, speed, programme, cooling in itertools.product(
            study.months, study.speeds_rpm, study.programmes, study.cooling)
    ]


def conditions(study: SweepStudy) -> list[Condition]:
    return [Condition(noise, fault) for noise, fault in itertools.product(study.noise,
                                                                          study.faults)]


def replicas(study: SweepStudy) -> list[int]:
    return list(range(1, study.replicas + 1))


def training_experiments(study: SweepStudy, family: list[Experiment]) -> list[Experiment]:
    """The experiments models are trained on, per the study's training rule.

    ``one``: the experiment the ``[training]`` table names. ``each-season``: for every season
    in the study, its first listed month at the ``[training]`` speed, programme and cooling.
    """
    rule = study.training

    def matches(exp: Experiment, month: str) -> bool:
        return (exp.month == month and exp.speed_rpm == rule.speed_rpm
                and exp.programme == rule.programme and exp.cooling == rule.cooling)

    if rule.rule == "one":
        months = [rule.month]
    else:
        first_of_season: dict[str, str] = {}
        for month in study.months:
            first_of_season.setdefault(study.climate.season_of(month), month)
        months = list(first_of_season.values())
    return [exp for month in months for exp in family if matches(exp, month)]


def sensor_seed(study: SweepStudy, replica: int, experiment: Experiment) -> int:
    """Seed of the sensor noise; shared by all conditions (common random numbers)."""
    return derive_seed(study.seed, "sensors", replica, experiment.id)


def day_weather(study: SweepStudy, replica: int, experiment: Experiment) -> tuple[float, float]:
    """The (low, high) of this replica's day: the month's normals plus a common shift.

    The shift is Gaussian with ``weather_sd_C``; low and high move together because day-to-day
    weather mostly shifts the whole daily curve.
    """
    normal = study.climate.months[experiment.month]
    if study.weather_sd_C == 0:
        return normal.low_C, normal.high_C
    rng = np.random.default_rng(derive_seed(study.seed, "weather", replica, experiment.id))
    shift = float(rng.normal(0.0, study.weather_sd_C))
    return round(normal.low_C + shift, 3), round(normal.high_C + shift, 3)


def sensor_model(noise: AxisValue[SensorModel],
                 fault: AxisValue[SensorFault] | None) -> SensorModel:
    """The testbench's sensor model of a noise level with an optional fault (to the end)."""
    if fault is None:
        return noise.value
    return replace(noise.value, faults=(fault.value,))


def ambient_for(study: SweepStudy, replica: int, experiment: Experiment) -> AmbientModel:
    """The run's air: the replica's day of the season curve, or indoor air of the month's
    normals with its own weather (seeded per replica and experiment, like ``day_weather``)."""
    if study.indoor is None:
        low, high = day_weather(study, replica, experiment)
        return SeasonAmbient(low_C=low, high_C=high, start_hour=study.start_hour)
    normal = study.climate.months[experiment.month]
    return replace(study.indoor, outdoor_low_C=normal.low_C, outdoor_high_C=normal.high_C,
                   start_hour=study.start_hour,
                   weather_seed=derive_seed(study.seed, "weather", replica, experiment.id))


def initial_for(study: SweepStudy, experiment: Experiment) -> InitialState:
    """A cold start, or the soak of the month's *normal* daily cycle (no replica's weather):
    every run of one month shares it, so the soak is simulated once per month."""
    if study.soak_days is None:
        return InitialState()
    normal = study.climate.months[experiment.month]
    if study.indoor is None:
        cycle: AmbientModel = SeasonAmbient(low_C=normal.low_C, high_C=normal.high_C,
                                            start_hour=study.start_hour)
    else:
        cycle = replace(study.indoor, outdoor_low_C=normal.low_C,
                        outdoor_high_C=normal.high_C, start_hour=study.start_hour,
                        weather_sd_K=0.0)
    return InitialState(kind="soak", days=study.soak_days, soak_ambient=cycle)


def scenario_table(study: SweepStudy, replica: int, experiment: Experiment) -> dict[str, Any]:
    """The scenario table of one experiment on one replica's day: the study's values merged
    by key path into the table a scenario file would hold, each axis value the scenario table
    of its testbench value (``testbench.scenario.scenario_table``).

    Its sensor model is the study's first noise level without faults, so the stored recording
    is an ordinary healthy recording; conditions re-measure its truth with the same seed.
    """
    programme = next(p for p in study.programmes if p.name == experiment.programme)
    cooling = next(c for c in study.cooling if c.name == experiment.cooling)
    initial = initial_for(study, experiment)
    return with_key_paths({}, {
        "name": experiment.id,
        "description": f"{study.name}: {experiment.id}, replica {replica}",
        "duration_s": study.duration_s,
        "step_s": study.step_s,
        "sample_interval_s": study.sample_interval_s,
        "seed": sensor_seed(study, replica, experiment),
        "speed": scenario_table_of(at_speed(programme.value, experiment.speed_rpm)),
        "feed.kind": study.feed,
        "feed.x_mm_per_min": study.feed_x_mm_per_min,
        "feed.y_mm_per_min": study.feed_y_mm_per_min,
        "ambient": scenario_table_of(ambient_for(study, replica, experiment)),
        "cooling": scenario_table_of(cooling.value),
        "sensors": scenario_table_of(sensor_model(study.noise[0], None)),
        "initial": {"kind": initial.kind, "days": initial.days} if initial.kind == "soak" else {},
        "parameters": dict(study.parameters),
        "outputs.probes": study.probes,
    })


def scenario_for(study: SweepStudy, replica: int, experiment: Experiment) -> Scenario:
    """The runner's scenario of one experiment on one replica's day: ``scenario_table`` read
    by the one scenario reader, so it is checked as a scenario file is.

    Two parts of a study's run have no scenario key and are set after the reader, here only:
    ``machine`` (a study's machine may be drawn in memory, a population's, with no file for
    ``machine = "..."`` to name) and ``initial.soak_ambient`` (the soak repeats the month's
    *normal* day, not the replica's: a scenario's soak repeats its own ambient, so a scenario
    file cannot say this). ``path`` is the study's file (errors name it)."""
    table = scenario_table(study, replica, experiment)
    scenario = read_scenario(Table(table, f"{study.path}: experiment {experiment.id}'s scenario"),
                             study.path)
    return replace(scenario, machine=study.machine,
                   initial=replace(scenario.initial,
                                   soak_ambient=initial_for(study, experiment).soak_ambient))


# ----------------------------------------------------------------- targets other than drift_um

def target_truth_columns(target: str) -> tuple[str, ...]:
    """The truth columns a study re-measuring ``target`` needs beyond the sensors' and the
    axial drift's: none for the axial drift; the radial probes (the target is computed from
    them, as the recording computes it) and the target's own truth otherwise."""
    from spindlebench.formats.recording import DRIFT_COLUMN, true_column
    from spindlebench.testbench.sensors import RADIAL_PROBES

    if target == DRIFT_COLUMN:
        return ()
    return tuple(dict.fromkeys([*(true_column(p) for p in RADIAL_PROBES), true_column(target)]))


def one_target_readme(text: str, target: str, study_kind: str, joint: str) -> str:
    """A study README for one of several targets: a line under its title saying which target
    this folder is for and where the ``joint`` results of all targets are (``../README.md``);
    ``study_kind`` names the study ("sweep", "study")."""
    title, rest = text.split("\n", 1)
    return (f"{title} — target `{target}`\n\nThis folder is the {study_kind} for the target "
            f"`{target}` alone (RMSE in its unit; 'drift' below means it); the {joint} of all "
            "targets are in `../README.md`.\n" + rest)


def probe_geometry_m(study: SweepStudy, fmu) -> tuple[float, float]:
    """(l, end-face offset) in m of the five-probe set-up of the study's runs: the machine's
    and the study's parameters on top of the FMU's defaults, as ``scenario_for`` gives them
    to the runner."""
    from spindlebench.testbench.simulate import run_parameter

    parameters = {**study.machine.parameters, **study.parameters}
    return (run_parameter(parameters, fmu, "probe_l", study.path),
            run_parameter(parameters, fmu, "probe_end_offset", study.path))


def measured_target(target: str, model, time_s: np.ndarray, truth, measured_drift: np.ndarray,
                    seed: int, geometry_m: tuple[float, float] | None) -> np.ndarray:
    """``target``'s reading as the sensor ``model`` measures it from the run's ``truth``
    (a frame with ``target_truth_columns(target)``): the axial probe's ``measured_drift``
    for the axial drift, else the five probes of ``sensors.measure_probes`` (each radial
    probe with the axial probe's noise, drift and resolution; tilts and end-face drifts
    computed from them over ``geometry_m``), seeded as a recording's are."""
    from spindlebench.formats.recording import DRIFT_COLUMN, true_column
    from spindlebench.testbench.sensors import RADIAL_PROBES, measure_probes

    if target == DRIFT_COLUMN:
        return measured_drift
    if geometry_m is None:
        raise ValueError(f"target {target}: no probe geometry given")
    radial = {p: np.asarray(truth[true_column(p)], dtype=float) for p in RADIAL_PROBES}
    return measure_probes(model, time_s, radial, *geometry_m, measured_drift, seed)[target]
