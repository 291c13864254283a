"""The committed FMU: valid FMI 3.0, the contract's interface, both FMPy solvers, real sensors."""

import zipfile

import numpy as np
import pytest
from conftest import FMU
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu
from spindlebench.model.cold_start import cold_start, state_names


@pytest.fixture(scope="module")
def description():
    return read_model_description(str(FMU))


@pytest.fixture(scope="module")
def one_hour():
    return cold_start(FMU, speed_rpm=4000.0, hours=1.0, ambient_C=12.0, output_interval_s=10.0)


def test_fmpy_validate_finds_no_problem():
    assert validate_fmu(str(FMU)) == []


def test_fmu_carries_sources_and_a_binary():
    with zipfile.ZipFile(FMU) as archive:
        names = set(archive.namelist())
    assert {
        "modelDescription.xml",
        "sources/SpindleBench.c",
        "sources/SpindleBench_wrap.c",
        "sources/buildDescription.xml",
    } <= names
    assert any(name.startswith("binaries/") for name in names)


def test_inputs_and_outputs_follow_the_contract(description):
    variables = {v.name: v for v in description.modelVariables}
    inputs = {v.name: v.unit for v in description.modelVariables if v.causality == "input"}
    assert inputs == {
        "spindle_speed_rpm": "rev/min",
        "feed_x_mm_per_min": "mm/min",
        "feed_y_mm_per_min": "mm/min",
        "ambient_C": "degC",
    }
    outputs = [v.name for v in description.modelVariables if v.causality == "output"]
    assert [f"T{i}_C" for i in range(1, 21)] == outputs[:20]
    assert variables["drift_um"].unit == "um"
    nodes = [name for name in outputs if name.startswith("node_")]
    assert 50 <= len(nodes) <= 100
    assert all(variables[name].unit == "degC" for name in nodes)
    flows = [name for name in outputs if name.startswith("Q_")]
    assert {"Q_front_bearing_W", "Q_spindle_motor_W", "Q_cooling_W"} <= set(flows)
    assert all(name.endswith("_W") and variables[name].unit == "W" for name in flows)


def test_states_are_settable_node_temperatures(description):
    states = [d.variable.derivative for d in description.derivatives]
    assert len(states) == len(description.derivatives) > 50
    outputs = {v.name for v in description.modelVariables if v.causality == "output"}
    for state in states:
        assert state.name.endswith("_T") and state.unit == "K"
        assert state.initial == "exact" and float(state.start) == pytest.approx(293.15)
        if not state.name.startswith("sensor_"):
            assert f"node_{state.name.removesuffix('_T')}_C" in outputs


def test_study_parameters_are_tunable(description):
    tunable = {
        v.name
        for v in description.modelVariables
        if v.causality == "parameter" and v.variability == "tunable"
    }
    for name in (
        "cooling_enabled",
        "cooling_follows_ambient",
        "cooling_setpoint_C",
        "T_ref",
        "housing_C",
        "fb_housing_G",
        "front_bearing_friction_f0",
        "column_L",
        "alpha_iron",
    ):
        assert name in tunable


def test_initial_state_is_taken_by_name():
    states = state_names(FMU)
    start = dict.fromkeys(states, 300.0)
    start["front_bearing_T"] = 320.0
    result = simulate_fmu(
        str(FMU),
        start_values={**start, "ambient_C": 26.85},
        stop_time=10.0,
        output_interval=10.0,
        output=["node_front_bearing_C", "node_column_5_C"],
    )
    assert result["node_front_bearing_C"][0] == pytest.approx(320.0 - 273.15)
    assert result["node_column_5_C"][0] == pytest.approx(300.0 - 273.15)


def test_cvode_and_euler_agree(one_hour):
    euler = cold_start(
        FMU, speed_rpm=4000.0, hours=1.0, ambient_C=12.0, output_interval_s=1.0, solver="Euler"
    )
    euler = euler.iloc[::10].reset_index(drop=True)
    for column in ("T1_C", "T8_C", "T13_C", "node_housing_2_C"):
        np.testing.assert_allclose(euler[column], one_hour[column], atol=0.02)
    np.testing.assert_allclose(euler["drift_um"], one_hour["drift_um"], atol=0.05)
    assert one_hour["T1_C"].iloc[-1] > one_hour["T1_C"].iloc[0] + 3.0


def test_sensors_on_the_same_part_read_differently(one_hour):
    last = one_hour.iloc[-1]
    front = [last[f"T{i}_C"] for i in range(1, 6)]
    assert min(abs(a - b) for i, a in enumerate(front) for b in front[i + 1 :]) > 0.05
    for a, b in ((12, 14), (13, 15), (16, 17), (18, 19)):
        assert abs(last[f"T{a}_C"] - last[f"T{b}_C"]) > 0.01, (a, b)


def test_every_parameter_declares_physical_bounds(description):
    parameters = [v for v in description.modelVariables if v.causality == "parameter"]
    assert len(parameters) > 200
    for variable in parameters:
        assert variable.min is not None and variable.max is not None, variable.name
        low, high, start = float(variable.min), float(variable.max), float(variable.start)
        assert low <= start <= high, variable.name
        if variable.unit == "J/K":
            assert low > 0.0, variable.name  # a capacity is never zero
        if variable.unit == "W/K":
            assert low >= 0.0, variable.name
    by_name = {v.name: v for v in parameters}
    assert float(by_name["alpha_steel"].max) < 1e-3  # the hostile 1e6 is outside
    assert float(by_name["fb_housing_G"].min) == 0.0
    assert float(by_name["cooling_enabled"].max) == 1.0


def test_t_start_alone_gives_an_fmpy_cold_start():
    """Issue 12: with FMPy alone, T_start sets every state the caller does not set by name."""
    result = simulate_fmu(
        str(FMU),
        start_values={"T_start": 281.15, "ambient_C": 8.0, "housing_2_T": 300.0},
        stop_time=60.0,
        output_interval=60.0,
        output=["T1_C", "T10_C", "node_column_5_C", "node_floor_slab_C", "node_housing_2_C"],
    )
    for name in ("T1_C", "T10_C", "node_column_5_C", "node_floor_slab_C"):
        assert result[name][0] == pytest.approx(8.0), name
    assert result["node_housing_2_C"][0] == pytest.approx(300.0 - 273.15)
