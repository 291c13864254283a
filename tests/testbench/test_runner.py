"""Co-simulation runner on the committed FMU: recordings, reproducibility, state hand-over.

Short scenarios (10-30 simulated minutes) keep this fast; the model's physics is tested in
depth by the model's own tests, here only what the recording must show.
"""

import json
from pathlib import Path

import fmpy
import numpy as np
import pandas as pd
import pytest
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.core.provenance import sha256_file
from spindlebench.testbench import simulate_scenario
from spindlebench.testbench.runner import co_simulate, inspect_fmu
from spindlebench.testbench.scenario import load_scenario

FMU = DEFAULT_FMU
SENSORS = [f"T{i}" for i in range(1, 21)]
DRIVERS = ["spindle_speed_rpm", "feed_x_mm_per_min", "feed_y_mm_per_min", "ambient_C"]


def scenario_text(minutes=20, rpm=4000, ambient='kind = "constant"\ntemperature_C = 20.0',
                  sample_s=60, seed=5, extra=""):
    return f"""\
duration_s = {minutes * 60}
step_s = 1.0
sample_interval_s = {sample_s}
seed = {seed}

[speed]
kind = "constant"
rpm = {rpm}

[feed]
kind = "constant"
x_mm_per_min = 1500
y_mm_per_min = 1500

[ambient]
{ambient}
{extra}
"""


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    """One 20-minute run at 4000 rpm, shared by the read-only checks."""
    tmp = tmp_path_factory.mktemp("quick")
    scenario = write(tmp, "quick.toml", scenario_text())
    csv = simulate_scenario(scenario, tmp / "quick.csv", fmu_path=FMU)
    return scenario, csv, pd.read_csv(csv), json.loads(csv.with_suffix(".json").read_text())


def test_recording_has_the_contract_columns(quick_run):
    _, _, frame, _ = quick_run
    columns = list(frame.columns)
    assert columns[:22] == ["time_s", *SENSORS, "drift_um"]
    assert columns[22:26] == DRIVERS
    assert [f"true_T{i}_C" for i in range(1, 21)] == columns[26:46]
    assert "true_drift_um" in columns
    nodes = [c for c in columns if c.startswith("true_node_") and c.endswith("_C")]
    flows = [c for c in columns if c.startswith("true_Q_") and c.endswith("_W")]
    assert len(nodes) >= 30
    assert flows
    assert all(c.startswith("true_") for c in columns[26:])
    np.testing.assert_array_equal(frame.time_s, np.arange(0.0, 1201.0, 60.0))
    assert not frame.isna().any().any()


def test_recording_measures_the_truth(quick_run):
    _, _, frame, _ = quick_run
    assert frame.drift_um.iloc[0] == 0.0  # probe zeroed at the first sample
    for sensor in SENSORS:
        error = frame[sensor] - frame[f"true_{sensor}_C"]
        assert error.abs().max() < 0.5  # noise 0.05 °C plus 0.1 °C quantisation
        np.testing.assert_allclose(frame[sensor] * 10, np.round(frame[sensor] * 10), atol=1e-9)
    drift_change = frame.true_drift_um - frame.true_drift_um.iloc[0]
    assert (frame.drift_um - drift_change).abs().max() < 2.0
    assert (frame.spindle_speed_rpm == 4000).all()
    assert (frame.ambient_C == 20.0).all()


def test_cold_start_puts_every_node_at_the_ambient(quick_run):
    _, _, frame, sidecar = quick_run
    first = frame.iloc[0]
    nodes = [c for c in frame.columns if c.startswith("true_node_")]
    np.testing.assert_allclose(first[nodes].to_numpy(dtype=float), 20.0, atol=1e-9)
    states = sidecar["initial_state"]["states_K"]
    assert states and all(v == pytest.approx(293.15) for v in states.values())


def test_sidecar_carries_provenance_and_end_state(quick_run):
    scenario, csv, frame, sidecar = quick_run
    assert sidecar["recording_sha256"] == sha256_file(csv)  # the pair is checkable
    assert sidecar["scenario"]["path"] == str(scenario)
    assert len(sidecar["scenario"]["sha256"]) == 64
    assert sidecar["fmu"]["sha256"] == fmpy_sha(FMU)
    assert sidecar["seed"] == 5
    assert sidecar["package_versions"]["fmpy"] != "not installed"
    assert sidecar["scenario_parsed"]["speed"] == {"rpm": 4000.0, "kind": "constant"}
    end = sidecar["end_state"]
    assert end["time_s"] == 1200.0
    assert set(end["states_K"]) == set(inspect_fmu(FMU).state_names)
    # the spindle warmed up: the end state is above the start for some node
    assert max(end["states_K"].values()) > 293.15 + 0.5
    assert frame.true_T1_C.iloc[-1] > frame.true_T1_C.iloc[0] + 0.5


def fmpy_sha(path):
    from spindlebench.core.provenance import sha256_file

    return sha256_file(path)


def test_same_seed_gives_the_same_bytes_other_seed_other_noise(tmp_path, quick_run):
    scenario, first_csv, first, _ = quick_run
    again = simulate_scenario(scenario, tmp_path / "again.csv", fmu_path=FMU)
    assert again.read_bytes() == first_csv.read_bytes()
    other = pd.read_csv(simulate_scenario(scenario, tmp_path / "seed9.csv", fmu_path=FMU,
                                          seed=9))
    assert not np.array_equal(other[SENSORS].to_numpy(), first[SENSORS].to_numpy())
    truth = [c for c in first.columns if c.startswith("true_")]
    np.testing.assert_array_equal(other[truth].to_numpy(), first[truth].to_numpy())
    assert json.loads((tmp_path / "seed9.json").read_text())["seed"] == 9


def test_truth_agrees_with_fmpy_simulate_fmu(quick_run):
    """The co-simulation loop against FMPy's own simulateME (CVode) with the same inputs."""
    _, _, frame, _ = quick_run
    info = inspect_fmu(FMU)
    inputs = np.array([(0.0, 4000.0, 1500.0, 1500.0, 20.0)],
                      dtype=[("time", float)] + [(n, float) for n in DRIVERS])
    result = fmpy.simulate_fmu(
        str(FMU), stop_time=1200.0, output_interval=60.0, input=inputs,
        start_values=dict.fromkeys(info.state_names, 293.15), relative_tolerance=1e-8,
        output=["T1_C", "T8_C", "T16_C", "drift_um"], fmi_type="ModelExchange",
    )
    for name in ("T1_C", "T8_C", "T16_C"):
        np.testing.assert_allclose(frame[f"true_{name}"], result[name], atol=2e-3)
    scale = max(1.0, np.abs(result["drift_um"]).max())
    np.testing.assert_allclose(frame.true_drift_um, result["drift_um"], atol=2e-3 * scale)


def test_continue_from_end_state_equals_one_long_run(tmp_path):
    long = write(tmp_path, "long.toml", scenario_text(minutes=30))
    part1 = write(tmp_path, "part1.toml", scenario_text(minutes=20))
    part2 = write(tmp_path, "part2.toml", scenario_text(
        minutes=10, extra='[initial]\nkind = "continue"\nfrom = "part1.csv"\n'))
    whole = pd.read_csv(simulate_scenario(long, tmp_path / "long.csv", fmu_path=FMU))
    simulate_scenario(part1, tmp_path / "part1.csv", fmu_path=FMU)
    second = pd.read_csv(simulate_scenario(part2, tmp_path / "part2.csv", fmu_path=FMU))
    truth = [c for c in whole.columns if c.startswith("true_")]
    tail = whole[whole.time_s >= 1200][truth].to_numpy()
    np.testing.assert_allclose(second[truth].to_numpy(), tail, atol=1e-3, rtol=1e-5)
    sidecar = json.loads((tmp_path / "part2.json").read_text())
    assert sidecar["initial_state_from"]["path"].endswith("part1.json")


def test_continue_from_a_missing_run_fails_cleanly(tmp_path):
    path = write(tmp_path, "c.toml", scenario_text(
        minutes=10, extra='[initial]\nkind = "continue"\nfrom = "never_ran.json"\n'))
    with pytest.raises(SpindlebenchError, match=r"c\.toml: key 'initial\.from': no such file"):
        simulate_scenario(path, tmp_path / "c.csv", fmu_path=FMU)
    assert not (tmp_path / "c.csv").exists()


def test_continue_from_a_sibling_scenario_is_looked_up_next_to_the_output(tmp_path):
    path = write(tmp_path, "c.toml", scenario_text(
        minutes=10, extra='[initial]\nkind = "continue"\nfrom = "day1"\n'))
    with pytest.raises(SpindlebenchError, match=r"c\.toml: key 'initial\.from': no recording "
                       r"of scenario 'day1' at .*out/day1\.json"):
        simulate_scenario(path, tmp_path / "out" / "c.csv", fmu_path=FMU)
    with pytest.raises(SpindlebenchError, match=r"c\.toml: key 'initial\.from': names the "
                       r"scenario 'day1'"):
        co_simulate(load_scenario(path), FMU)  # no output folder to look in
    assert not (tmp_path / "out").exists()


def test_unknown_parameter_is_one_line_and_writes_nothing(tmp_path):
    path = write(tmp_path, "p.toml", scenario_text(
        minutes=10, extra="[parameters]\nno_such_parameter_xyz = 1.0\n"))
    with pytest.raises(SpindlebenchError) as info:
        simulate_scenario(path, tmp_path / "p.csv", fmu_path=FMU)
    message = str(info.value)
    assert "'parameters.no_such_parameter_xyz'" in message and "p.toml" in message
    assert "\n" not in message
    assert list(tmp_path.iterdir()) == [path]


def test_tunable_parameter_from_the_scenario_reaches_the_fmu(tmp_path):
    info = inspect_fmu(FMU)
    T_ref = info.parameters["T_ref"]
    scenario = load_scenario(write(tmp_path, "t.toml", scenario_text(
        minutes=10, extra=f"[parameters]\nT_ref = {float(T_ref.start) + 5.0}\n")))
    base = load_scenario(write(tmp_path, "b.toml", scenario_text(minutes=10)))
    shifted = co_simulate(scenario, FMU).outputs["drift_um"]
    reference = co_simulate(base, FMU).outputs["drift_um"]
    # a hotter reference temperature means the cold machine sits "shrunk" relative to it
    assert np.abs(shifted - reference).min() > 1.0
    assert co_simulate(scenario, FMU).parameters["T_ref"] == float(T_ref.start) + 5.0


def test_a_mechanism_s_outputs_are_recorded_only_when_it_is_switched_on(tmp_path):
    """issue 20: the default machine has the bearing air and the thermal preload on, the rotor
    losses and the jacket off; a scenario's [parameters] switching the jacket on adds its
    three outputs; ambient-following (every mechanism off) records none of the six."""
    from spindlebench.formats.recording import MECHANISM_SWITCHES
    from spindlebench.testbench.scenario import with_machine

    base = load_scenario(write(tmp_path, "b.toml", scenario_text(minutes=5)))
    jacket = load_scenario(write(tmp_path, "j.toml", scenario_text(
        minutes=5, extra="[parameters]\njacket_enabled = 1.0\n")))
    recorded = {name: set(MECHANISM_SWITCHES) & set(co_simulate(scenario, FMU).outputs)
                for name, scenario in (("default", base), ("jacket", jacket),
                                       ("following", with_machine(base, "ambient-following")))}
    assert recorded["default"] == {"Q_bearing_air_W", "front_preload_thermal_N"}
    assert recorded["jacket"] == recorded["default"] | {"Q_jacket_W", "jacket_inlet_C",
                                                        "jacket_outlet_C"}
    assert recorded["following"] == set()


def test_faster_spindle_warms_more_and_drifts_more(tmp_path):
    runs = {}
    for rpm in (2000, 4000):
        scenario = load_scenario(write(tmp_path, f"r{rpm}.toml",
                                       scenario_text(minutes=30, rpm=rpm)))
        runs[rpm] = co_simulate(scenario, FMU).outputs
    rise = {rpm: out["T1_C"][-1] - out["T1_C"][0] for rpm, out in runs.items()}
    drift = {rpm: abs(out["drift_um"][-1] - out["drift_um"][0]) for rpm, out in runs.items()}
    assert rise[4000] > rise[2000] > 0.0
    assert drift[4000] > drift[2000]


def test_speed_steps_and_ambient_series_drive_the_fmu(tmp_path):
    (tmp_path / "amb.csv").write_text("time_s,ambient_C\n0,15\n900,18\n1800,16\n")
    text = scenario_text(minutes=30, sample_s=30,
                         ambient='kind = "csv"\nfile = "amb.csv"').replace(
        'kind = "constant"\nrpm = 4000',
        'kind = "steps"\nsteps = [{at_s = 0, rpm = 0}, {at_s = 600, rpm = 3000}]')
    frame = pd.read_csv(simulate_scenario(write(tmp_path, "s.toml", text), tmp_path / "s.csv",
                                          fmu_path=FMU))
    np.testing.assert_allclose(frame.ambient_C, np.interp(frame.time_s, [0, 900, 1800],
                                                          [15, 18, 16]))
    assert (frame.spindle_speed_rpm == np.where(frame.time_s >= 600, 3000, 0)).all()
    bearing = [c for c in frame.columns if c.startswith("true_Q_") and "bearing" in c]
    assert bearing
    q = frame[bearing].sum(axis=1)
    assert q[frame.time_s < 600].max() < 0.5 * q[frame.time_s >= 600].min()
    # the ambient sensor T10 follows the air, with some lag
    assert abs(frame.true_T10_C.iloc[-1] - 16.0) < 1.5
    assert frame.true_T10_C.max() > 16.5


def test_sensor_faults_show_in_the_recording(tmp_path):
    extra = ('[[sensors.faults]]\nsensor = "T7"\nkind = "dropout"\nstart_s = 300\nend_s = 600\n'
             '[[sensors.faults]]\nsensor = "T1"\nkind = "stuck"\nstart_s = 600\n')
    frame = pd.read_csv(simulate_scenario(
        write(tmp_path, "f.toml", scenario_text(minutes=15, extra=extra)), tmp_path / "f.csv",
        fmu_path=FMU))
    assert frame.T7.isna().sum() == 5  # samples at 300, 360, ..., 540 s
    assert frame.T1[frame.time_s >= 600].nunique() == 1
    assert frame.T1.iloc[-1] < frame.true_T1_C.iloc[-1] - 0.3  # it stopped following


def test_bad_fmu_path_is_one_line(tmp_path):
    scenario = write(tmp_path, "q.toml", scenario_text(minutes=10))
    with pytest.raises(SpindlebenchError, match=r"nothing\.fmu: no such FMU"):
        simulate_scenario(scenario, tmp_path / "q.csv", fmu_path=tmp_path / "nothing.fmu")
    junk = tmp_path / "junk.fmu"
    junk.write_bytes(b"not a zip")
    with pytest.raises(SpindlebenchError, match=r"junk\.fmu: not a readable FMU"):
        simulate_scenario(scenario, tmp_path / "q.csv", fmu_path=junk)
    assert not (tmp_path / "q.csv").exists()


def test_cooling_that_follows_the_ambient_reaches_the_fmu_and_cools(tmp_path):
    cooled = load_scenario(write(tmp_path, "c.toml", scenario_text(
        minutes=30, extra='[cooling]\nmode = "follow_ambient"\nsetpoint_C = -1.0\n')))
    plain = load_scenario(write(tmp_path, "p.toml", scenario_text(minutes=30)))
    with_cooling = co_simulate(cooled, FMU)
    without = co_simulate(plain, FMU)
    assert with_cooling.parameters["cooling_enabled"] == 1.0
    assert with_cooling.parameters["cooling_follows_ambient"] == 1.0
    assert with_cooling.parameters["cooling_setpoint_C"] == -1.0
    assert without.parameters["cooling_enabled"] == 0.0
    rise = {name: run.outputs["T1_C"][-1] - run.outputs["T1_C"][0]
            for name, run in (("cooled", with_cooling), ("plain", without))}
    assert rise["cooled"] < rise["plain"]
    assert np.abs(with_cooling.outputs["Q_cooling_W"]).max() > 1.0
    assert np.abs(without.outputs["Q_cooling_W"]).max() < 1e-9


def test_fmu_without_a_binary_for_this_platform_is_one_line(tmp_path):
    import zipfile

    stripped = tmp_path / "nobinary.fmu"
    with zipfile.ZipFile(FMU) as source, zipfile.ZipFile(stripped, "w") as target:
        for item in source.infolist():
            if not item.filename.startswith("binaries/"):
                target.writestr(item, source.read(item.filename))
    scenario = load_scenario(write(tmp_path, "q.toml", scenario_text(minutes=10)))
    with pytest.raises(SpindlebenchError, match=r"nobinary\.fmu: has no binary for .*build"):
        co_simulate(scenario, stripped)


def _without_bounds(tmp_path):
    """A copy of the FMU whose model description declares no min/max (like many third-party
    FMUs), so an unphysical value reaches the solver."""
    import re
    import zipfile

    copy = tmp_path / "nobounds.fmu"
    with zipfile.ZipFile(FMU) as source, zipfile.ZipFile(copy, "w") as target:
        for item in source.infolist():
            data = source.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = re.sub(rb' (min|max)="[^"]*"', b"", data)
            target.writestr(item, data)
    return copy


def test_a_failing_integration_is_one_line_and_writes_nothing(tmp_path):
    capacity = next(name for name in inspect_fmu(FMU).parameters if name.endswith("bearing_C"))
    path = write(tmp_path, "neg.toml", scenario_text(
        minutes=10, extra=f"[parameters]\n{capacity} = -1e-3\n"))  # negative heat capacity
    # the committed FMU declares capacities > 0: refused before simulating
    with pytest.raises(SpindlebenchError, match=rf"neg\.toml: key 'parameters\.{capacity}': "
                                                r"must be ≥"):
        simulate_scenario(path, tmp_path / "neg.csv", fmu_path=FMU)
    with pytest.raises(SpindlebenchError, match=r"simulation failed in scenario .*neg\.toml"):
        simulate_scenario(path, tmp_path / "neg.csv", fmu_path=_without_bounds(tmp_path))
    assert not (tmp_path / "neg.csv").exists()


def _sidecar_with_states(states: object) -> str:
    return json.dumps({"end_state": {"time_s": 600.0, "states_K": states}})


def _good_states() -> dict[str, float]:
    return dict.fromkeys(inspect_fmu(FMU).state_names, 293.15)


@pytest.mark.parametrize(
    ("content", "words"),
    [
        (lambda s: {**s, next(iter(s)): "abc"}, 'is not a number (got "abc")'),
        (lambda s: {**s, next(iter(s)): None}, "is not a number (got null)"),
        (lambda s: {**s, next(iter(s)): True}, "is not a number (got true)"),
        (lambda s: list(s.values()), "states_K must map state names to kelvin, got a list"),
        (lambda s: {**s, next(iter(s)): 1e30}, "= 1e+30 K is outside 200-600 K"),
        (lambda s: {**s, next(iter(s)): 20.0}, "= 20 K is outside 200-600 K"),
    ],
)
def test_continue_from_a_sidecar_with_bad_states_is_one_line(tmp_path, content, words):
    (tmp_path / "prev.json").write_text(_sidecar_with_states(content(_good_states())),
                                        encoding="utf-8")
    path = write(tmp_path, "c.toml", scenario_text(
        minutes=10, extra='[initial]\nkind = "continue"\nfrom = "prev.json"\n'))
    with pytest.raises(SpindlebenchError) as info:
        simulate_scenario(path, tmp_path / "c.csv", fmu_path=FMU)
    message = str(info.value)
    assert "\n" not in message
    assert "c.toml: key 'initial.from'" in message and "prev.json" in message
    assert words in message
    assert not (tmp_path / "c.csv").exists()


def test_continue_from_a_non_utf8_sidecar_is_one_line(tmp_path):
    (tmp_path / "prev.json").write_bytes(b'{"end_state": "\xe9"}')
    path = write(tmp_path, "c.toml", scenario_text(
        minutes=10, extra='[initial]\nkind = "continue"\nfrom = "prev.json"\n'))
    with pytest.raises(SpindlebenchError, match=r"prev\.json is not UTF-8 text \(byte 15\)"):
        simulate_scenario(path, tmp_path / "c.csv", fmu_path=FMU)


def test_too_many_steps_of_a_scenario_built_in_code_is_one_line(tmp_path):
    """Studies build Scenario objects without load_scenario; the runner checks them too."""
    from dataclasses import replace

    scenario = replace(load_scenario(write(tmp_path, "q.toml", scenario_text(minutes=10))),
                       step_s=1e-300)
    with pytest.raises(SpindlebenchError, match=r"q\.toml: key 'step_s': must be >= 0.001 s"):
        co_simulate(scenario, FMU)
