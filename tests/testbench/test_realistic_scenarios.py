"""Realistic scenarios: indoor ambient with weather, soak history, AR(1) / random-walk sensor
noise and probe drift (scenarios/README.md, "Realistic scenarios")."""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from spindlebench.commands import main as cli
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import KELVIN_OFFSET
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.testbench import soak
from spindlebench.testbench.drivers import ambient_C, weather_anomaly_K
from spindlebench.testbench.scenario import (
    ConstantAmbient,
    IndoorAmbient,
    InitialState,
    SeasonAmbient,
    SensorModel,
    load_scenario,
)
from spindlebench.testbench.sensors import measure

HOUR = 3600.0
DAY = 86400.0


# --------------------------------------------------------------------------- indoor ambient


def test_indoor_air_is_the_outdoor_cycle_attenuated_lagged_and_offset():
    indoor = IndoorAmbient(outdoor_low_C=0.0, outdoor_high_C=10.0, start_hour=0.0,
                           trough_hour=6.0, peak_hour=15.0, attenuation=0.4, lag_h=3.0,
                           building_offset_K=5.0, weather_sd_K=0.0)
    t = np.arange(0.0, DAY, 60.0)
    air = ambient_C(indoor, t)
    # outdoor mean 5 °C, swing ±5 K: indoor 5 + 5 ± 0.4·5 = 8 … 12 °C
    assert air.max() == pytest.approx(12.0) and air.min() == pytest.approx(8.0)
    # the outdoor peak at 15:00 and trough at 06:00 arrive 3 h late
    assert t[np.argmax(air)] == 18 * HOUR and t[np.argmin(air)] == 9 * HOUR
    assert air.mean() == pytest.approx(10.0, abs=1e-9)


def test_weather_is_reproducible_from_the_seed_and_independent_of_step_and_length():
    model = IndoorAmbient(outdoor_low_C=0.0, outdoor_high_C=8.0, weather_seed=5)
    fine = ambient_C(model, np.arange(0.0, 6 * HOUR + 1, 1.0))
    coarse = ambient_C(model, np.arange(0.0, 6 * HOUR + 1, 60.0))
    longer = ambient_C(model, np.arange(0.0, 12 * HOUR + 1, 60.0))
    np.testing.assert_array_equal(fine[::60], coarse)
    np.testing.assert_array_equal(longer[: coarse.size], coarse)
    # one time at a time (a continuous-input solver asks so) gives the same values
    points = [0.0, 1234.5, 6 * HOUR]
    assert [float(ambient_C(model, np.array(p))) for p in points] == list(
        ambient_C(model, np.array(points)))
    other = ambient_C(replace(model, weather_seed=6), np.arange(0.0, 6 * HOUR + 1, 60.0))
    assert np.abs(other - coarse).max() > 0.05


def test_weather_anomaly_has_its_sd_and_correlation_time():
    model = IndoorAmbient(outdoor_low_C=0.0, outdoor_high_C=0.0, weather_sd_K=3.0,
                          weather_tau_h=36.0, weather_seed=1)
    w = weather_anomaly_K(model, np.arange(0.0, 3000 * DAY, HOUR))
    assert w.std() == pytest.approx(3.0, rel=0.05)
    lag1 = np.corrcoef(w[:-1], w[1:])[0, 1]
    assert lag1 == pytest.approx(np.exp(-1 / 36), abs=0.005)


# --------------------------------------------------------------------------- sensor model


def _measure(model: SensorModel, n: int = 20000, m: int = 3, step_s: float = 60.0, seed=4):
    time_s = np.arange(n) * step_s
    true_c = np.full((n, m), 20.0)
    return measure(model, time_s, true_c, np.zeros(n), ("T1", "T2", "T3")[:m], seed)


def test_white_noise_draws_are_what_they_always_were():
    model = SensorModel(noise_C=0.05, quantum_C=0.0, probe_noise_um=0.2, probe_quantum_um=0.0)
    temps, drift = _measure(model, n=50)
    rng = np.random.default_rng(4)  # the old recipe: temperatures, then the probe
    np.testing.assert_array_equal(temps, 20.0 + rng.standard_normal((50, 3)) * 0.05)
    probe = rng.standard_normal(50) * 0.2
    np.testing.assert_array_equal(drift, probe - probe[0])


def test_ar1_noise_has_the_lag1_coefficient_and_the_same_sd():
    model = SensorModel(noise_C=0.05, quantum_C=0.0, probe_noise_um=0.0,
                        noise_kind="ar1", noise_lag1=0.86)
    temps, _ = _measure(model)
    noise = temps - 20.0
    assert noise.std(axis=0) == pytest.approx([0.05] * 3, rel=0.06)
    lags = [np.corrcoef(noise[:-1, j], noise[1:, j])[0, 1] for j in range(3)]
    assert lags == pytest.approx([0.86] * 3, abs=0.015)
    white, _ = _measure(replace(model, noise_kind="white"))
    assert abs(np.corrcoef(white[:-1, 0], white[1:, 0])[0, 1]) < 0.03


def test_random_walk_noise_spreads_like_the_square_root_of_time():
    model = SensorModel(noise_C=0.1, quantum_C=0.0, probe_noise_um=0.0,
                        noise_kind="random_walk")
    # 4000 channels, 4 h at 60 s: the spread after one hour is noise_C, after four 2·noise_C
    temps, _ = measure(model, np.arange(241) * 60.0, np.zeros((241, 4000)), np.zeros(241),
                       tuple(f"T{i}" for i in range(4000)), 9)
    assert temps[60].std() == pytest.approx(0.1, rel=0.05)
    assert temps[240].std() == pytest.approx(0.2, rel=0.05)


def test_probe_drift_creeps_and_wanders_from_zero():
    creep = SensorModel(probe_noise_um=0.0, probe_quantum_um=0.0,
                        probe_drift_rate_um_per_h=0.5)
    _, drift = _measure(creep, n=241)
    np.testing.assert_allclose(drift, 0.5 * np.arange(241) / 60.0, atol=1e-12)
    walk = replace(creep, probe_drift_rate_um_per_h=0.0, probe_drift_um_per_sqrt_h=0.3)
    ends = np.array([_measure(walk, n=61, seed=s)[1][-1] for s in range(2000)])
    assert ends.std() == pytest.approx(0.3, rel=0.06)  # 1 sigma after one hour
    first, _ = _measure(walk, n=61)  # the temperatures' draws are untouched by the drift
    np.testing.assert_array_equal(first, _measure(creep, n=61)[0])


# --------------------------------------------------------------------------- scenario files

BASE = """\
duration_s = 1800
step_s = 1.0
sample_interval_s = 60
seed = 3

[speed]
kind = "constant"
rpm = 4000

[feed]
kind = "with_spindle"
x_mm_per_min = 1500
y_mm_per_min = 1500
"""
INDOOR = """
[ambient]
kind = "indoor"
outdoor_low_C = 2.0
outdoor_high_C = 9.0
"""
SEASON = """
[ambient]
kind = "season"
low_C = 5.0
high_C = 10.0
"""


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


def test_indoor_soak_and_noise_keys_are_read_with_documented_defaults(tmp_path):
    text = BASE + INDOOR + """
[sensors]
noise_kind = "ar1"
probe_drift_um_per_sqrt_h = 0.2

[initial]
kind = "soak"
"""
    scenario = load_scenario(write(tmp_path, "s.toml", text))
    assert scenario.ambient == IndoorAmbient(2.0, 9.0, weather_seed=3)  # the scenario's seed
    assert (scenario.ambient.attenuation, scenario.ambient.lag_h,
            scenario.ambient.building_offset_K, scenario.ambient.weather_sd_K,
            scenario.ambient.weather_tau_h) == (0.5, 2.0, 2.0, 3.0, 36.0)
    assert scenario.sensors.noise_kind == "ar1" and scenario.sensors.noise_lag1 == 0.86
    assert scenario.initial == InitialState(kind="soak", days=7)
    readme = (Path(__file__).parents[2] / "scenarios" / "README.md").read_text()
    for documented in ("attenuation = 0.5", "lag_h = 2", "building_offset_K = 2",
                       "weather_sd_K = 3", "weather_tau_h = 36", "noise_lag1 = 0.86",
                       "days = 7"):
        assert documented in readme


@pytest.mark.parametrize(("edit", "key"), [
    (lambda s: s + INDOOR.replace("9.0", "1.0"), "ambient.outdoor_high_C"),
    (lambda s: s + INDOOR + "attenuation = 1.5\n", "ambient.attenuation"),
    (lambda s: s + INDOOR + "lag_h = -1\n", "ambient.lag_h"),
    (lambda s: s + INDOOR + "weather_tau_h = 0\n", "ambient.weather_tau_h"),
    (lambda s: s + SEASON + "[sensors]\nnoise_lag1 = 0.9\n", "sensors.noise_lag1"),
    (lambda s: s + SEASON + "[sensors]\nnoise_kind = \"pink\"\n", "sensors.noise_kind"),
    (lambda s: s + SEASON + "[sensors]\nnoise_kind = \"ar1\"\nnoise_lag1 = 1\n",
     "sensors.noise_lag1"),
    (lambda s: s + SEASON + "[initial]\nkind = \"soak\"\ndays = 0\n", "initial.days"),
    (lambda s: s + SEASON + "[initial]\nkind = \"soak\"\ndays = 61\n", "initial.days"),
    (lambda s: s + SEASON + "[initial]\nkind = \"cold\"\ndays = 3\n", "initial.days"),
])
def test_bad_realism_keys_are_one_line_naming_the_key(tmp_path, capsys, edit, key):
    path = write(tmp_path, "bad.toml", edit(BASE))
    assert cli.main(["simulate", str(path), "-o", str(tmp_path / "o.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err and f"'{key}'" in err
    assert not (tmp_path / "o.csv").exists()


def test_soak_of_a_measured_ambient_is_refused(tmp_path):
    write(tmp_path, "air.csv", "time_s,ambient_C\n0,10\n1800,11\n")
    text = BASE + '\n[ambient]\nkind = "csv"\nfile = "air.csv"\n\n[initial]\nkind = "soak"\n'
    with pytest.raises(SpindlebenchError, match=r"'initial'.*measured series"):
        load_scenario(write(tmp_path, "m.toml", text))


# --------------------------------------------------------------------------- soak (FMU)


@pytest.fixture
def soak_cache(tmp_path, monkeypatch):
    folder = tmp_path / "soak-cache"
    monkeypatch.setenv(soak.CACHE_ENV, str(folder))
    monkeypatch.setattr(soak, "_memory", {})
    return folder


def test_soak_under_a_constant_ambient_is_the_idle_machine_s_steady_state(tmp_path,
                                                                         soak_cache):
    """Idle is standstill, not power off: only the feed servos' holding losses heat it."""
    scenario = load_scenario(write(tmp_path, "c.toml", BASE + SEASON))
    scenario = replace(scenario, ambient=ConstantAmbient(14.0),
                       initial=InitialState(kind="soak", days=2))
    states = soak.soak_state(scenario, DEFAULT_FMU)
    longer = soak.soak_state(replace(scenario, initial=InitialState(kind="soak", days=4)),
                             DEFAULT_FMU)
    ambient_K = 14.0 + KELVIN_OFFSET
    assert min(states.values()) >= ambient_K - 1e-6  # heat sources only, no sink
    assert "motor" in max(states, key=states.get)  # a feed servo holding its axis
    # the standing spindle is far from them: its bearing is within 0.1 K of the air
    assert states["front_bearing_T"] == pytest.approx(ambient_K, abs=0.1)
    assert max(abs(states[n] - longer[n]) for n in states) < 0.01  # steady after 2 days


def test_soak_lags_the_daily_cycle_and_is_cached_once_per_cycle(tmp_path, soak_cache,
                                                                 monkeypatch):
    scenario = load_scenario(write(tmp_path, "s.toml", BASE + SEASON))
    scenario = replace(scenario, initial=InitialState(kind="soak", days=3))
    states = soak.soak_state(scenario, DEFAULT_FMU)
    celsius = np.array(list(states.values())) - KELVIN_OFFSET
    # 08:00 is two hours after the 06:00 trough (5 °C): the air is just above 5 °C, the slow
    # nodes still remember the warmer afternoon, none is outside the day's range
    assert celsius.min() >= 5.0 - 1e-6 and celsius.max() <= 10.0
    assert celsius.max() - celsius.min() > 1.0
    files = list(soak_cache.glob("*.json"))
    assert len(files) == 1 and json.loads(files[0].read_text())["days"] == 3

    def no_simulation(*args, **kwargs):
        raise AssertionError("the soak was simulated again")

    monkeypatch.setattr(soak, "co_simulate", no_simulation)
    other_run = replace(scenario, speed=replace(scenario.speed, rpm=1000.0), seed=99)
    assert soak.soak_state(other_run, DEFAULT_FMU) == states  # memory
    monkeypatch.setattr(soak, "_memory", {})
    assert soak.soak_state(other_run, DEFAULT_FMU) == states  # file
    held = replace(other_run, inputs="hold")  # the run's input mode is not the soak's
    assert soak.soak_state(held, DEFAULT_FMU) == states
    warmer = replace(scenario, ambient=replace(scenario.ambient, high_C=12.0))
    with pytest.raises(AssertionError, match="simulated again"):
        soak.soak_state(warmer, DEFAULT_FMU)  # another cycle is another soak


def test_a_soaked_run_starts_from_the_history_reproducibly(tmp_path, soak_cache):
    text = BASE + INDOOR + '\n[sensors]\nnoise_kind = "ar1"\n\n[initial]\nkind = "soak"\ndays = 2\n'
    path = write(tmp_path, "s.toml", text)
    for name in ("a", "b"):
        assert cli.main(["simulate", str(path), "-o", str(tmp_path / f"{name}.csv"), "-q"]) == 0
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    sidecar = json.loads((tmp_path / "a.json").read_text())
    start = np.array(list(sidecar["initial_state"]["states_K"].values()))
    assert start.max() - start.min() > 0.5  # not one uniform cold-start temperature
    assert sidecar["scenario_parsed"]["initial"]["kind"] == "soak"
    history = sidecar["initial_state_soak"]
    assert history["days"] == 2 and history["ambient"]["weather_sd_K"] == 0.0
    assert (soak_cache / f"{history['soak_key']}.json").is_file()
    assert sidecar["scenario_parsed"]["ambient"]["weather_seed"] == 3


def test_shipped_realistic_example_and_study_load():
    from spindlebench.studies.family.family_file import load_study

    root = Path(__file__).parents[2]
    study = load_study(root / "scenarios" / "studies" / "season_sweep_realistic.toml")
    assert study.soak_days == 7 and study.indoor is not None
    assert {level.value.noise_kind for level in study.noise} == {"ar1"}
    scenario = load_scenario(root / "scenarios" / "examples" / "realistic_day.toml")
    assert isinstance(scenario.ambient, IndoorAmbient) and scenario.initial.kind == "soak"
    assert scenario.sensors.noise_kind == "ar1"
    assert not isinstance(scenario.ambient, SeasonAmbient)


# --------------------------------------------------------------------------- sweep studies


def _tiny(tmp_path: Path, old: str, new: str) -> Path:
    text = (Path(__file__).parents[2] / "scenarios" / "studies" / "tiny_sweep.toml").read_text()
    assert old in text
    path = tmp_path / "study.toml"
    path.write_text(text.replace(old, new), encoding="utf-8")
    return path


def test_a_sweep_soaks_once_per_month_and_draws_indoor_weather_per_run(tmp_path):
    from spindlebench.studies.family import experiments as ex
    from spindlebench.studies.family.family_file import load_study

    study = load_study(_tiny(
        tmp_path, "weather_sd_C = 1.0\n",
        'initial = "soak"\nsoak_days = 3\n\n[experiment.indoor]\nattenuation = 0.4\n'))
    runs = [(replica, experiment) for replica in ex.replicas(study)
            for experiment in ex.experiments(study)]
    keys: dict[str, set[str]] = {}
    seeds = set()
    for replica, experiment in runs:
        scenario = ex.scenario_for(study, replica, experiment)
        assert isinstance(scenario.ambient, IndoorAmbient)
        assert scenario.ambient.attenuation == 0.4 and scenario.initial.days == 3
        seeds.add(scenario.ambient.weather_seed)
        key = soak.soak_key(soak.soak_scenario(scenario), DEFAULT_FMU)
        keys.setdefault(experiment.month, set()).add(key)
    assert {month: len(k) for month, k in keys.items()} == {"Jan": 1, "Jul": 1}
    assert keys["Jan"] != keys["Jul"]
    assert len(seeds) == len(runs)  # every run its own weather


def test_a_sweep_noise_level_carries_the_noise_process(tmp_path):
    from spindlebench.studies.family import experiments as ex
    from spindlebench.studies.family.family_file import load_study

    study = load_study(_tiny(tmp_path, "[noise.lab]\nnoise_C = 0.05\n",
                             '[noise.lab]\nnoise_C = 0.05\nnoise_kind = "ar1"\n'
                             "noise_lag1 = 0.7\nprobe_drift_rate_um_per_h = 0.2\n"))
    model = ex.sensor_model(study.noise[0], None)
    assert (model.noise_kind, model.noise_lag1, model.probe_drift_rate_um_per_h) == (
        "ar1", 0.7, 0.2)
    scenario = ex.scenario_for(study, 1, ex.experiments(study)[0])
    assert scenario.initial.kind == "cold" and isinstance(scenario.ambient, SeasonAmbient)


@pytest.mark.parametrize(("old", "new", "key"), [
    ("weather_sd_C = 1.0\n", "weather_sd_C = 1.0\nsoak_days = 3\n", "experiment.soak_days"),
    ("weather_sd_C = 1.0\n", 'weather_sd_C = 1.0\ninitial = "warm"\n', "experiment.initial"),
    ("weather_sd_C = 1.0\n", 'initial = "soak"\nsoak_days = 90\n', "experiment.soak_days"),
    ("weather_sd_C = 1.0\n", "weather_sd_C = 1.0\n[experiment.indoor]\n",
     "experiment.weather_sd_C"),
    ("weather_sd_C = 1.0\n", "[experiment.indoor]\nlag_h = 30\n", "experiment.indoor.lag_h"),
    ("[noise.lab]\nnoise_C = 0.05\n", "[noise.lab]\nnoise_C = 0.05\nnoise_lag1 = 0.5\n",
     "noise.lab.noise_lag1"),
])
def test_bad_realism_study_keys_are_one_line(tmp_path, old, new, key):
    from spindlebench.studies.family.family_file import load_study

    with pytest.raises(SpindlebenchError, match=f"key '{key}'"):
        load_study(_tiny(tmp_path, old, new))
