"""Machine variants: every shipped machine meets its file's fingerprint targets on the paper's
five experiments (noise-free, the committed FMU), and the machine key reaches the FMU."""

import json

import pytest
from conftest import FMU, SCENARIOS
from spindlebench import cli
from spindlebench.errors import SpindlebenchError
from spindlebench.machine_check import paper_fingerprints
from spindlebench.machines import (
    DEFAULT_MACHINE,
    Target,
    load_machine,
    machine_names,
    target_problems,
)
from spindlebench.testbench.runner import inspect_fmu, parameter_values
from spindlebench.testbench.scenario import load_scenario, with_machine


def test_default_and_ambient_following_are_shipped():
    assert {DEFAULT_MACHINE, "ambient-following"} <= set(machine_names())
    assert load_machine().parameters == {}  # the FMU's defaults are the default machine


@pytest.mark.parametrize("name", machine_names())
def test_shipped_machine_meets_its_fingerprint_targets(name):
    machine = load_machine(name)
    assert machine.targets, f"{name} states no fingerprint targets"
    fingerprints = paper_fingerprints(machine, FMU)
    assert target_problems(machine, fingerprints) == []


def test_targets_are_checked_median_or_each():
    machine = load_machine()
    good = {run: {"best_raw_psi": 0.9, "best_diff_psi": 0.99, "early_fraction": 0.6,
                  "overshoot": 1.1} for run in ("exp1", "exp2", "exp3", "exp4", "exp5")}
    assert target_problems(machine, good) == []
    one_flat = {**good, "exp3": {**good["exp3"], "overshoot": 1.0}}  # a 4000 rpm run, each
    assert len(target_problems(machine, one_flat)) == 1
    raw_close = {run: {**stats, "best_diff_psi": 0.91} for run, stats in good.items()}
    (problem,) = target_problems(machine, raw_close)
    assert "best_diff_psi - best_raw_psi >= 0.02" in problem and "got 0.010" in problem
    assert Target("overshoot", minimum=1.0).describe().startswith("overshoot >= 1")


def write(tmp_path, text, name="m.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize(("text", "message"), [
    ('name = "x"\n', "key 'description': missing"),
    ('description = "d"\n[parameters]\nA_column = "big"\n',
     "key 'parameters.A_column': must be"),
    ('description = "d"\n[[targets]]\nstatistic = "psi"\nmax = 1\n',
     r"key 'targets\[0\]\.statistic'"),
    ('description = "d"\n[[targets]]\nstatistic = "overshoot"\n', "needs min and/or max"),
    ('description = "d"\ncolour = 1\n', "unknown key"),
])
def test_bad_machine_file_is_one_line(tmp_path, text, message):
    path = write(tmp_path, text)
    with pytest.raises(SpindlebenchError, match=message) as info:
        load_machine(str(path))
    assert "\n" not in str(info.value) and str(path) in str(info.value)


def test_unknown_machine_lists_the_shipped_ones(tmp_path):
    scenario = SCENARIOS / "examples" / "quick.toml"
    bad = write(tmp_path, 'machine = "lathe"\n' + scenario.read_text(), "bad.toml")
    with pytest.raises(SpindlebenchError, match=r"key 'machine'.*'lathe' not found.*default"):
        load_scenario(bad)


def test_machine_parameters_reach_the_fmu_under_the_scenario_ones(tmp_path):
    fmu = inspect_fmu(FMU)
    scenario = load_scenario(SCENARIOS / "examples" / "quick.toml")
    assert scenario.machine.name == DEFAULT_MACHINE
    following = with_machine(scenario, "ambient-following")
    values = parameter_values(following, fmu)
    assert values["headstock_column_G"] == 5.0 and values["A_column"] == 5.0
    machine = write(tmp_path, 'description = "d"\n[parameters]\nno_such_G = 1.0\n')
    with pytest.raises(SpindlebenchError, match=r"m\.toml: key 'parameters\.no_such_G'"):
        parameter_values(with_machine(scenario, str(machine)), fmu)


def test_simulate_machine_flag_names_the_machine_in_the_provenance(tmp_path):
    out = tmp_path / "quick.csv"
    scenario = SCENARIOS / "examples" / "quick.toml"
    assert cli.main(["simulate", str(scenario), "-o", str(out), "--machine",
                     "ambient-following", "-q"]) == 0
    sidecar = json.loads(out.with_suffix(".json").read_text())
    machine = load_machine("ambient-following")
    assert sidecar["machine"] == {"name": "ambient-following", "file": "ambient-following.toml",
                                  "sha256": machine.sha256}
    assert sidecar["parameters"]["headstock_column_G"] == 5.0


def test_machine_value_outside_the_fmu_bounds_is_refused(tmp_path):
    scenario = load_scenario(SCENARIOS / "examples" / "quick.toml")
    machine = write(tmp_path, 'description = "d"\n[parameters]\nfb_housing_G = -50.0\n')
    with pytest.raises(SpindlebenchError, match=r"key 'parameters\.fb_housing_G': must be ≥ 0"):
        parameter_values(with_machine(scenario, str(machine)), inspect_fmu(FMU))


def test_a_study_names_its_machine_and_every_run_uses_it(tmp_path):
    from spindlebench.studies.experiments import experiments, scenario_for
    from spindlebench.studies.study import load_study, pinned_content

    tiny = SCENARIOS / "studies" / "tiny_sweep.toml"
    assert load_study(tiny).machine.name == DEFAULT_MACHINE
    named = write(tmp_path, tiny.read_text().replace("[study]\n", '[study]\nmachine = '
                                                     '"ambient-following"\n', 1), "s.toml")
    text = named.read_text().replace('climate = "chongqing"', 'climate = "'
                                     + str(SCENARIOS / "seasons" / "chongqing.toml") + '"')
    named.write_text(text)
    study = load_study(named)
    assert study.machine.name == "ambient-following"
    run = scenario_for(study, 0, experiments(study)[0])
    assert run.machine.parameters["headstock_column_G"] == 5.0
    assert pinned_content(study)["machine"]["sha256"] == study.machine.sha256
    assert load_study(tiny, machine="ambient-following").machine.name == "ambient-following"
    bad = write(tmp_path, text.replace('"ambient-following"', '"lathe"'), "bad.toml")
    with pytest.raises(SpindlebenchError, match=r"bad\.toml: key 'study\.machine': .*'lathe'"):
        load_study(bad)


def test_a_study_can_run_over_machines(tmp_path):
    """[axes] machines: the study runs once per machine, each into its own folder."""
    from spindlebench.studies.study import load_study, machine_runs

    tiny = SCENARIOS / "studies" / "tiny_sweep.toml"
    text = tiny.read_text().replace("[axes]\n", '[axes]\nmachines = ["default", '
                                    '"ambient-following"]\n', 1)
    text = text.replace('climate = "chongqing"',
                        'climate = "' + str(SCENARIOS / "seasons" / "chongqing.toml") + '"')
    study = load_study(write(tmp_path, text, "m.toml"))
    assert study.machines == ("default", "ambient-following")
    out = tmp_path / "out"
    assert machine_runs(study, None, out) == [("default", out / "default"),
                                              ("ambient-following", out / "ambient-following")]
    assert machine_runs(study, "default", out) == [("default", out)]  # --machine: one run
    both = write(tmp_path, text.replace("[study]\n", '[study]\nmachine = "default2"\n', 1)
                 .replace('machine = "default2"', 'machine = "ambient-following"'), "b.toml")
    with pytest.raises(SpindlebenchError, match=r"key 'axes\.machines': give either"):
        load_study(both)
    unknown = write(tmp_path, text.replace('"ambient-following"]', '"lathe"]'), "u.toml")
    with pytest.raises(SpindlebenchError, match=r"key 'axes\.machines': .*'lathe' not found"):
        load_study(unknown)
