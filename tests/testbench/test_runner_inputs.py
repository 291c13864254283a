"""Continuous-time inputs (the default) against the zero-order-hold runner (inputs = "hold").

Every paper experiment and example scenario, shortened to 1.5 h (the speed steps and start/stop
cycles still jump inside it), must agree with the 1 s hold within 0.01 µm and 0.01 K, while
CVode stops only at the output points and the input jumps.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.testbench.runner import co_simulate, solver_stops
from spindlebench.testbench.scenario import InitialState, load_scenario

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
CASES = sorted((SCENARIOS / "paper").glob("exp*.toml")) + sorted(
    (SCENARIOS / "examples").glob("*.toml"))
SHORT_S = 5400.0


def shortened(path: Path):
    """The scenario cut to 1.5 h; a continue/soak start becomes a cold start (the start state
    is not what the two input modes differ in, and a continue needs another run's file)."""
    scenario = load_scenario(path)
    initial = scenario.initial if scenario.initial.kind == "cold" else InitialState()
    return dataclasses.replace(scenario, duration_s=min(scenario.duration_s, SHORT_S),
                               initial=initial)


@pytest.mark.parametrize("path", CASES, ids=lambda p: f"{p.parent.name}/{p.stem}")
def test_continuous_inputs_match_the_one_second_hold(path):
    scenario = shortened(path)
    new = co_simulate(scenario, DEFAULT_FMU)
    old = co_simulate(dataclasses.replace(scenario, inputs="hold"), DEFAULT_FMU)
    assert new.solver["inputs"] == "continuous" and old.solver["inputs"] == "hold"
    np.testing.assert_array_equal(new.time_s, old.time_s)
    assert set(new.outputs) == set(old.outputs)
    for name, values in new.outputs.items():
        if name.endswith(("_um", "_C")):
            tolerance = 0.01  # µm for displacements, K for temperatures
        else:  # heat flows (W): the hold lags the ambient by up to a step; 0.1 % of range
            tolerance = 1e-3 * max(np.ptp(old.outputs[name]), 1.0)
        assert np.max(np.abs(values - old.outputs[name])) <= tolerance, name
    for name, value in new.end_state_K.items():
        assert abs(value - old.end_state_K[name]) <= 0.01, name
    assert old.solver["solver_stops"] == scenario.n_steps
    samples = scenario.n_steps // scenario.steps_per_sample
    assert samples <= new.solver["solver_stops"] <= samples + new.solver[
        "restarts_at_input_jumps"]


def test_stops_are_outputs_and_jumps_and_no_segment_crosses_a_jump():
    jumps = np.zeros(13, dtype=bool)
    jumps[[5, 9]] = True
    stops, ends = solver_stops(jumps, every=4, n_steps=12, inputs="continuous")
    assert stops.tolist() == [4, 5, 8, 9, 12]
    assert ends.tolist() == [5, 5, 9, 9, 12]
    stops, ends = solver_stops(jumps, every=4, n_steps=12, inputs="hold")
    assert stops.tolist() == list(range(1, 13)) and ends.tolist() == stops.tolist()


def test_the_input_mode_is_a_checked_scenario_key(tmp_path):
    text = (SCENARIOS / "examples" / "quick.toml").read_text(encoding="utf-8")
    held = tmp_path / "held.toml"
    held.write_text('inputs = "hold"\n' + text, encoding="utf-8")
    assert load_scenario(held).inputs == "hold"
    assert load_scenario(SCENARIOS / "examples" / "quick.toml").inputs == "continuous"
    bad = tmp_path / "bad.toml"
    bad.write_text('inputs = "smooth"\n' + text, encoding="utf-8")
    with pytest.raises(SpindlebenchError, match="inputs") as error:
        load_scenario(bad)
    assert "\n" not in str(error.value)
