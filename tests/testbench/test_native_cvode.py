"""Issue 26: CVode on the FMU's own C right-hand side and its loop between output points in C.

The C path (``testbench.native_cvode``) must give the same bytes as FMPy's ``CVodeSolver``
with Python callbacks (kept as the fallback for an FMU without the C callbacks), for both
input modes and across input jumps; its Jacobian callbacks must agree within the solver's
tolerance; a Ctrl-C arriving while the C loop runs must end the run at the next chunk.
"""

from __future__ import annotations

import dataclasses
import os
import signal
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from spindlebench.core import interrupts
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.model.fmu_export import jacobian_structure
from spindlebench.testbench import native_cvode, runner
from spindlebench.testbench.runner import co_simulate
from spindlebench.testbench.scenario import load_scenario

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


def short(name: str, duration_s: float, **changes):
    scenario = load_scenario(SCENARIOS / name)
    return dataclasses.replace(scenario, duration_s=duration_s, **changes)


#: exp1 (continuous ambient, no jumps) and start/stop cycles (speed and feed jump at 1200 s
#: and 1800 s, CVode restarted there), each in both input modes.
CASES = {
    "exp1-continuous": short("paper/exp1.toml", 3600.0),
    "exp1-hold": short("paper/exp1.toml", 900.0, inputs="hold"),
    "start_stop-continuous": short("examples/start_stop_cycles.toml", 2400.0),
    "start_stop-hold": short("examples/start_stop_cycles.toml", 1500.0, inputs="hold"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_the_c_right_hand_side_gives_the_python_callbacks_bytes(case):
    scenario = CASES[case]
    c_path = co_simulate(scenario, DEFAULT_FMU)
    python = co_simulate(scenario, DEFAULT_FMU, native_rhs=False)
    assert "C right-hand side" in c_path.solver["integrator"]
    assert python.solver["integrator"].startswith("FMPy CVodeSolver")
    assert set(c_path.outputs) == set(python.outputs)
    for name, values in python.outputs.items():
        assert c_path.outputs[name].tobytes() == values.tobytes(), name
    assert c_path.end_state_K == python.end_state_K
    assert c_path.solver["solver_stops"] == python.solver["solver_stops"]
    if case.startswith("start_stop"):
        assert c_path.solver["restarts_at_input_jumps"] >= 1


def test_the_saved_end_state_is_the_same_bytes_on_both_paths():
    scenario = CASES["start_stop-continuous"]
    c_path = co_simulate(scenario, DEFAULT_FMU, save_end_state=True)
    python = co_simulate(scenario, DEFAULT_FMU, native_rhs=False, save_end_state=True)
    assert c_path.end_fmu_state == python.end_fmu_state


@pytest.mark.parametrize("jacobian", ["forward", "differences"])
def test_the_jacobian_callbacks_agree_with_cvodes_difference_quotients(monkeypatch, jacobian):
    """``sb_cvode_jac`` (coloured forward derivatives, a difference where one is not finite)
    and ``sb_cvode_jac_dq`` (coloured difference quotients) steer CVode to the same solution
    within its tolerance, across the jumps where the spindle stops (where the FMU's
    directional derivatives hold NaN)."""
    scenario = CASES["start_stop-continuous"]
    own = co_simulate(scenario, DEFAULT_FMU)
    monkeypatch.setattr(runner, "NATIVE_JACOBIAN", jacobian)
    other = co_simulate(scenario, DEFAULT_FMU)
    assert any(own.outputs[n].tobytes() != other.outputs[n].tobytes() for n in own.outputs)
    for name, values in own.outputs.items():
        tolerance = 1e-4 if name.endswith(("_C", "_um")) else 1e-4 * max(np.ptp(values), 1.0)
        assert np.max(np.abs(other.outputs[name] - values)) <= tolerance, name


def test_the_colouring_never_puts_two_columns_sharing_a_row_in_one_colour():
    with zipfile.ZipFile(DEFAULT_FMU) as archive:
        xml_text = archive.read("modelDescription.xml").decode()
    source = jacobian_structure(xml_text)

    def table(name: str) -> list[int]:
        line = next(x for x in source.splitlines() if f" {name}[" in x)
        return [int(v) for v in line.split("{")[1].rstrip("};").split(",")]

    colours, starts, rows = table("sb_jac_color"), table("sb_jac_colstart"), table("sb_jac_row")
    states = ET.fromstring(xml_text).find("ModelStructure").findall("ContinuousStateDerivative")
    assert len(colours) == len(states) == len(starts) - 1 and starts[-1] == len(rows)
    assert f"#define SB_JAC_COLORS {max(colours) + 1}" in source
    reached: dict[int, set[int]] = {}
    for j, colour in enumerate(colours):
        column = set(rows[starts[j]:starts[j + 1]])
        assert column, f"state {j} reaches no derivative (its own at least)"
        assert reached.setdefault(colour, set()).isdisjoint(column), j
        reached[colour] |= column


def test_an_fmu_without_the_c_callbacks_or_with_events_takes_fmpys_solver():
    assert not native_cvode.available(SimpleNamespace(dll=object()), 0)
    loaded = runner._loaded_model(runner.inspect_fmu(DEFAULT_FMU).model_description,
                                  runner.extracted_fmu(runner.inspect_fmu(DEFAULT_FMU)))
    assert native_cvode.available(loaded, 0)
    assert not native_cvode.available(loaded, 1)  # this solver does no root finding


def test_a_plan_that_would_read_past_its_matrices_is_refused():
    stops = np.array([4, 8])
    inputs, samples = np.zeros((9, 4)), np.zeros((3, 2))
    native_cvode.Plan(stops, stops, np.zeros(9, bool), 1.0, 4, inputs, samples,
                      input_vr_list=(1, 2, 3, 4), output_vr_list=(5, 6))
    with pytest.raises(ValueError, match="beyond"):
        native_cvode.Plan(np.array([4, 12]), np.array([4, 12]), np.zeros(9, bool), 1.0, 4,
                          inputs, samples, input_vr_list=(1, 2, 3, 4), output_vr_list=(5, 6))
    with pytest.raises(ValueError, match="columns"):
        native_cvode.Plan(stops, stops, np.zeros(9, bool), 1.0, 4, inputs, samples,
                          input_vr_list=(1, 2), output_vr_list=(5, 6))


def test_ctrl_c_during_the_c_loop_ends_the_run_at_the_next_chunk(monkeypatch):
    """A SIGINT that arrives while the FMU's C loop runs is recorded by the runner's deferred
    handler and raised when the chunk returns: no further chunk runs."""
    chunks = []
    original = native_cvode.NativeCVode.run

    def run_then_signal(self, plan, first, count):
        chunks.append(first)
        done = original(self, plan, first, count)
        os.kill(os.getpid(), signal.SIGINT)  # as if Ctrl-C came during this chunk
        return done

    monkeypatch.setattr(native_cvode.NativeCVode, "run", run_then_signal)
    with pytest.raises(interrupts.Interrupted):
        co_simulate(CASES["exp1-continuous"], DEFAULT_FMU)
    assert chunks == [0]
