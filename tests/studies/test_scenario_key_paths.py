"""``scenario_for`` is a merge of key paths into a scenario table, read by the one scenario
reader: for every experiment of every shipped study it gives the ``Scenario`` the hand-built
assembly gave (a frozen copy of it below, the reference), so studies and their outputs are
unchanged; and each testbench value round-trips through its scenario table."""

from __future__ import annotations

from dataclasses import MISSING, fields, replace
from pathlib import Path

import pytest
from spindlebench.formats.toml import Table, with_key_paths
from spindlebench.studies.family import experiments as ex
from spindlebench.studies.family.family_file import SweepStudy, load_study
from spindlebench.testbench.scenario import (
    ConstantFeed,
    Cooling,
    FeedWithSpindle,
    IndoorAmbient,
    Scenario,
    SeasonAmbient,
    SensorFault,
    SensorModel,
    SpeedCycles,
    SpeedStep,
    SteppedSpeed,
    at_speed,
    read_scenario,
    scenario_table,
)

ROOT = Path(__file__).resolve().parents[2]
STUDIES = sorted([*ROOT.glob("scenarios/studies/*.toml"), *ROOT.glob("benchmarks/studies/*.toml")])


def hand_built_scenario(study: SweepStudy, replica: int, experiment: ex.Experiment) -> Scenario:
    """The frozen reference: ``scenario_for`` as it was before the key-path merge."""
    programme = next(p for p in study.programmes if p.name == experiment.programme)
    cooling = next(c for c in study.cooling if c.name == experiment.cooling)
    feed_cls = ConstantFeed if study.feed == "constant" else FeedWithSpindle
    return Scenario(
        path=study.path,
        name=experiment.id,
        description=f"{study.name}: {experiment.id}, replica {replica}",
        duration_s=study.duration_s,
        step_s=study.step_s,
        sample_interval_s=study.sample_interval_s,
        seed=ex.sensor_seed(study, replica, experiment),
        speed=at_speed(programme.value, experiment.speed_rpm),
        feed=feed_cls(study.feed_x_mm_per_min, study.feed_y_mm_per_min),
        ambient=ex.ambient_for(study, replica, experiment),
        cooling=cooling.value,
        sensors=ex.sensor_model(study.noise[0], None),
        initial=ex.initial_for(study, experiment),
        parameters=dict(study.parameters),
        machine=study.machine,
        probes=study.probes,
    )


def _family(path: Path) -> SweepStudy:
    return load_study(path, extra_tables=("placement", "compensate"))


def _check_study(study: SweepStudy) -> int:
    count = 0
    for replica in ex.replicas(study):
        for experiment in ex.experiments(study):
            assert ex.scenario_for(study, replica, experiment) == hand_built_scenario(
                study, replica, experiment), (study.path, replica, experiment.id)
            count += 1
    return count


@pytest.mark.parametrize("path", STUDIES, ids=[p.name for p in STUDIES])
def test_every_shipped_experiment_gets_the_hand_built_scenario(path):
    assert _check_study(_family(path)) > 0


VARIANTS = """
[axes]
months = ["Jan", "Jul"]
speeds_rpm = [2000, 4000]
programmes = ["constant", "start-stop", "ramp"]
cooling = ["off", "chiller", "follow"]
noise = ["lab"]
faults = ["none", "x"]

[programmes.start-stop]
kind = "cycles"
on_min = 20
off_min = 5

[programmes.ramp]
kind = "steps"
at_h = [0.0, 0.25]
fraction = [0.5, 1.0]

[cooling.chiller]
mode = "absolute"
setpoint_C = 21.5

[cooling.follow]
mode = "follow_ambient"
setpoint_C = -0.5

[noise.lab]
noise_C = 0.04
noise_kind = "ar1"
noise_lag1 = 0.7
probe_drift_rate_um_per_h = 0.2
"""


def _variants(tmp_path: Path, indoor: bool) -> Path:
    """tiny_sweep with the axes the shipped studies leave out."""
    text = (ROOT / "scenarios/studies/tiny_sweep.toml").read_text(encoding="utf-8")
    head, rest = text.split("[axes]\n", 1)
    rest = rest[rest.index("[faults.T1-stuck]"):].replace("[faults.T1-stuck]", "[faults.x]")
    head = head.replace("[study]\n", '[study]\ntargets = ["drift_um", "drift_x_um"]\n')
    if indoor:
        head = head.replace("weather_sd_C = 1.0\n", 'initial = "soak"\n'
                            'soak_days = 2\nfeed = "with_spindle"\n')
        rest += "\n[experiment.indoor]\nattenuation = 0.4\n"
    path = tmp_path / f"variants_{indoor}.toml"
    path.write_text(head + VARIANTS + rest, encoding="utf-8")
    return path


@pytest.mark.parametrize("indoor", [False, True])
def test_the_variants_the_shipped_studies_miss_merge_the_same(tmp_path, indoor):
    """Cycles and steps programmes, absolute and follow-ambient cooling, AR(1) noise with probe
    drift, five-probe targets; indoor air with its weather seed, soak and machining feed."""
    study = load_study(_variants(tmp_path, indoor))
    assert (study.indoor is not None) == indoor == (study.soak_days == 2)
    assert _check_study(study) == 2 * 2 * 2 * 3 * 3
    # no weather scatter, parameters, another (e.g. a population's drawn) machine, no soak
    other = replace(study, weather_sd_C=0.0, parameters={"probe_l": 0.1}, soak_days=None,
                    machine=replace(study.machine, name="drawn-007"))
    assert _check_study(other) == 2 * 2 * 2 * 3 * 3


def _off_default(value):
    """``value``, after checking that each of its fields (but ``kind``) is off its default:
    a new field must be given a value here, so the round trip below covers its key."""
    for f in fields(value):
        if f.name != "kind" and f.default is not MISSING:
            assert getattr(value, f.name) != f.default, (type(value).__name__, f.name)
    return value


def test_every_field_of_a_scenario_section_is_its_key(tmp_path):
    """The rule ``scenario_table`` rests on (a field is named as its key), for every
    section a study merges: each value read back from its table is the value."""
    faults = (SensorFault("T1", "stuck", 60.0, 120.0, value_C=21.0),
              SensorFault("T2", "offset", 0.0, None, offset_C=0.5))
    sensors = _off_default(SensorModel(
        noise_C=0.07, quantum_C=0.05, probe_noise_um=0.4, probe_quantum_um=0.05, faults=faults,
        noise_kind="ar1", noise_lag1=0.5, probe_drift_um_per_sqrt_h=0.1,
        probe_drift_rate_um_per_h=-0.1))
    indoor = _off_default(IndoorAmbient(
        15.0, 25.0, start_hour=7.0, trough_hour=5.0, peak_hour=14.0, attenuation=0.3, lag_h=1.0,
        building_offset_K=1.0, weather_sd_K=2.0, weather_tau_h=24.0, weather_seed=9))
    season = _off_default(SeasonAmbient(12.0, 22.0, start_hour=7.0, trough_hour=5.0,
                                        peak_hour=14.0))
    cycles = _off_default(SpeedCycles(3000.0, 120.0, 60.0, start_s=60.0, count=2))
    steps = SteppedSpeed((SpeedStep(0.0, 1000.0), SpeedStep(300.0, 2000.0)))
    cooling = _off_default(Cooling("follow_ambient", -1.0))
    for speed, ambient, feed in [(cycles, indoor, FeedWithSpindle(100.0, 50.0)),
                                 (steps, season, ConstantFeed(80.0, 40.0))]:
        table = with_key_paths({"duration_s": 600.0, "step_s": 60.0, "sample_interval_s": 60.0},
                               {"speed": scenario_table(speed), "feed": scenario_table(feed),
                                "ambient": scenario_table(ambient),
                                "cooling": scenario_table(cooling),
                                "sensors": scenario_table(sensors)})
        read = read_scenario(Table(table, "roundtrip"), tmp_path / "roundtrip.toml")
        assert (read.speed, read.feed, read.ambient, read.cooling, read.sensors) == (
            speed, feed, ambient, cooling, sensors)
