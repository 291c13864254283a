"""Season-sweep study files: validation errors, experiment generation, derived seeds."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO
from spindlebench.core.errors import SpindlebenchError
from spindlebench.studies.family import experiments as ex
from spindlebench.studies.family.family_file import load_study
from spindlebench.studies.family.seasons import MONTHS, load_climate, resolve_climate_path
from spindlebench.studies.family.seeds import derive_seed

TINY = REPO / "scenarios" / "studies" / "tiny_sweep.toml"
EXAMPLE = REPO / "scenarios" / "studies" / "season_sweep.toml"


def write_study(tmp_path: Path, text: str, name: str = "study.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def tiny_text(**replace: str) -> str:
    text = TINY.read_text(encoding="utf-8")
    for old, new in replace.items():
        assert old in text, old
        text = text.replace(old, new)
    return text


def test_shipped_studies_load():
    for path in (TINY, EXAMPLE):
        study = load_study(path)
        assert len(ex.experiments(study)) >= 4
        assert ex.training_experiments(study, ex.experiments(study))


def test_chongqing_climate_is_complete_and_plausible():
    climate = load_climate(resolve_climate_path("chongqing"))
    assert list(climate.months) == list(MONTHS)
    january, july = climate.months["Jan"], climate.months["Jul"]
    assert january.low_C < january.high_C < july.low_C < july.high_C
    assert climate.season_of("Jan") == "winter" and climate.season_of("Jul") == "summer"
    assert "CMA" in climate.source


@pytest.mark.parametrize(
    ("replace", "expected"),
    [
        ({"seed = 7": "sed = 7"}, "key 'study.seed': missing"),
        ({"replicas = 2": "replicas = 2\nreplica = 3"}, "key 'study.replica': unknown key "
                                                        "(did you mean 'replicas'?)"),
        ({"replicas = 2": "replicas = 0"}, "key 'study.replicas': must be in [1, 10000], got 0"),
        ({"replicas = 2": 'replicas = "two"'}, "key 'study.replicas': must be an integer"),
        ({'months = ["Jan", "Jul"]': 'months = ["Jan", "July"]'},
         "key 'axes.months': item 2 ('July'): not a month"),
        ({'months = ["Jan", "Jul"]': 'months = ["Jan", "Jan"]'},
         "key 'axes.months': item 'Jan' appears twice"),
        ({"speeds_rpm = [2000, 4000]": "speeds_rpm = [2000, -4000]"},
         "key 'axes.speeds_rpm': item 2 (-4000): must be in (0, 30000] rev/min (the FMU's "
         "declared range)"),
        ({'noise = ["lab"]': 'noise = ["lab", "shop"]'},
         "key 'axes.noise': 'shop' is not defined (add a [noise.shop] table)"),
        ({'sensor = "T1"': 'sensor = "T21"'}, "key 'faults.T1-stuck.sensor': must be one of"),
        ({"start_h = 0.25": "start_h = 5.0"}, "key 'faults.T1-stuck.start_h': must be within"),
        ({'month = "Jan"': 'month = "Apr"'}, "key 'training.month': must be one of the study's"),
        ({"duration_min = 40": "duration_min = 41"},
         "key 'experiment.duration_min': 2460 s is not a multiple of sample_interval_s"),
        ({"duration_min = 40": "duration_min = 40\nduration_h = 1"},
         "key 'experiment.duration_h': give exactly one of duration_h and duration_min"),
        ({'climate = "chongqing"': 'climate = "atlantis"'}, "key 'study.climate': no climate"),
        ({"clusters = [2, 3]": "clusters = [2, 9]"},
         "key 'methods.clusters': item 2 (9): must be in [1, 6]"),
        ({"[noise.lab]": "[noise.lab]\nnoise_K = 0.1"}, "key 'noise.lab.noise_K': unknown key"),
        # non-finite numbers slip past range checks unless refused as such
        ({"[noise.lab]": "[parameters]\nfb_housing_G = nan\n\n[noise.lab]"},
         "key 'parameters.fb_housing_G': must be a finite number, got nan"),
        ({"speeds_rpm = [2000, 4000]": "speeds_rpm = [2000, inf]"},
         "key 'axes.speeds_rpm': item 2 must be a finite number, got inf"),
        # parameter names are checked against the FMU at load time, not in every simulation
        ({"[noise.lab]": "[parameters]\nfoo = 1.0\n\n[noise.lab]"},
         "key 'parameters.foo': the FMU SpindleBench.fmu has no parameter 'foo'"),
        ({"[noise.lab]": "[parameters]\ncooling_enabled = 1.0\n\n[noise.lab]"},
         "key 'parameters.cooling_enabled': set cooling with [cooling]"),
        ({"step_s = 120.0": "step_s = 1e-300"},
         "key 'experiment.step_s': must be >= 0.001 s, got 1e-300"),
        ({"duration_min = 40\nstep_s = 120.0": "duration_min = 600\nstep_s = 0.001"},
         "key 'experiment.step_s': 0.001 s gives 3.6e+07 communication steps over 36000 s; "
         "at most 10,000,000"),
        ({"weather_sd_C = 1.0": "weather_sd_C = 1.0\nfeed_x_mm_per_min = 1e15"},
         "key 'experiment.feed_x_mm_per_min': must be in [0, 60000] mm/min"),
    ],
)
def test_bad_study_gets_one_line_naming_file_and_key(tmp_path, replace, expected):
    path = write_study(tmp_path, tiny_text(**replace))
    with pytest.raises(SpindlebenchError) as info:
        load_study(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: ")
    assert expected in message


def test_bad_toml_and_missing_file(tmp_path):
    with pytest.raises(SpindlebenchError, match=r"nope\.toml: study file not found"):
        load_study(tmp_path / "nope.toml")
    path = write_study(tmp_path, "[study\nseed = 1")
    with pytest.raises(SpindlebenchError, match=r"study\.toml: not valid TOML"):
        load_study(path)


@pytest.mark.parametrize(("value", "message"), [
    ("278.9", r"278.9 looks like Kelvin"),
    ("nan", r"must be a finite number, got nan"),
])
def test_a_bad_climate_value_names_the_file_and_month(tmp_path, value, message):
    text = resolve_climate_path("chongqing").read_text(encoding="utf-8")
    write_study(tmp_path, text.replace("low_C = 5.8", f"low_C = {value}"), "bad.toml")
    study = write_study(tmp_path, tiny_text(**{'climate = "chongqing"': 'climate = "bad.toml"'}))
    with pytest.raises(SpindlebenchError, match=r"bad.toml: key 'months.Jan.low_C': " + message):
        load_study(study)


def test_an_unreadable_fmu_is_refused_at_load_time(tmp_path):
    (tmp_path / "bad.fmu").write_text("not a zip", encoding="utf-8")
    study = write_study(tmp_path, tiny_text(**{'climate = "chongqing"':
                                               'climate = "chongqing"\nfmu = "bad.fmu"'}))
    with pytest.raises(SpindlebenchError, match=r"key 'study.fmu': .*bad.fmu: not a readable "
                                                r"FMU"):
        load_study(study)


def test_experiment_family_and_training_rules(tmp_path):
    study = load_study(EXAMPLE)
    family = ex.experiments(study)
    assert len(family) == 6 * 2 * 2 * 1
    assert len({e.id for e in family}) == len(family)
    assert len(ex.conditions(study)) == 2 * 3
    trains = ex.training_experiments(study, family)
    assert [e.id for e in trains] == [f"{m}-4000rpm-constant-off"
                                      for m in ("Jan", "Mar", "Jun", "Oct")]
    assert [e.season for e in trains] == ["winter", "spring", "summer", "autumn"]
    one = load_study(write_study(tmp_path, EXAMPLE.read_text(encoding="utf-8").replace(
        'rule = "each-season"', 'rule = "one"\nmonth = "Apr"')))
    assert [e.id for e in ex.training_experiments(one, ex.experiments(one))] == [
        "Apr-4000rpm-constant-off"]
    with pytest.raises(SpindlebenchError, match=r"key 'training\.month': with rule 'each-season'"):
        load_study(write_study(tmp_path, EXAMPLE.read_text(encoding="utf-8").replace(
            'rule = "each-season"', 'rule = "each-season"\nmonth = "Apr"'), "bad.toml"))


def test_seeds_depend_on_names_not_on_loop_order(tmp_path):
    small = load_study(TINY)
    bigger = load_study(write_study(tmp_path, tiny_text(
        **{'months = ["Jan", "Jul"]': 'months = ["Oct", "Jan", "Apr", "Jul"]'})))
    jan = next(e for e in ex.experiments(small) if e.month == "Jan")
    assert jan in ex.experiments(bigger)
    # Adding months before it changes neither its noise seed nor its weather.
    assert ex.sensor_seed(small, 1, jan) == ex.sensor_seed(bigger, 1, jan)
    assert ex.day_weather(small, 1, jan) == ex.day_weather(bigger, 1, jan)
    # Replicas and experiments get distinct seeds; the study seed changes all of them.
    seeds = {ex.sensor_seed(small, r, e) for r in (1, 2) for e in ex.experiments(small)}
    assert len(seeds) == 2 * len(ex.experiments(small))
    other = load_study(write_study(tmp_path, tiny_text(**{"seed = 7": "seed = 8"}), "o.toml"))
    assert ex.sensor_seed(other, 1, jan) != ex.sensor_seed(small, 1, jan)
    assert derive_seed(7, "a", 1) == derive_seed(7, "a", 1) < 2**31


def test_weather_scatter_around_the_monthly_normals():
    study = load_study(TINY)
    jan = next(e for e in ex.experiments(study) if e.month == "Jan")
    normal = study.climate.months["Jan"]
    days = [ex.day_weather(study, r, jan) for r in range(1, 200)]
    shifts = [low - normal.low_C for low, _ in days]
    assert all(abs((high - low) - (normal.high_C - normal.low_C)) < 1e-9 for low, high in days)
    assert 0.8 < (sum(s * s for s in shifts) / len(shifts)) ** 0.5 < 1.2  # weather_sd_C = 1


def test_scenario_objects_carry_the_experiment(tmp_path):
    study = load_study(EXAMPLE)
    family = ex.experiments(study)
    cycles = next(e for e in family if e.programme == "start-stop" and e.month == "Jul")
    scenario = ex.scenario_for(study, 2, cycles)
    assert scenario.speed.kind == "cycles" and scenario.speed.rpm == cycles.speed_rpm
    assert scenario.speed.on_s == 50 * 60 and scenario.speed.off_s == 10 * 60
    assert scenario.feed.kind == "with_spindle"
    low, high = ex.day_weather(study, 2, cycles)
    assert (scenario.ambient.low_C, scenario.ambient.high_C) == (low, high)
    assert scenario.seed == ex.sensor_seed(study, 2, cycles)
    assert scenario.duration_s == study.duration_s == 6 * 3600
    assert scenario.sensors.faults == ()
    assert scenario.n_steps * scenario.step_s == scenario.duration_s
