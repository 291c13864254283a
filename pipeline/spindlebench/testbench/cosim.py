"""A scenario through the FMU's co-simulation interface (``fmi3DoStep``), the runner's check.

The runner (``testbench.runner``) integrates the model-exchange interface with CVode; this
module steps the same FMU as any co-simulation importer would: inputs held over each
communication step (set at its start), one ``fmi3DoStep`` per step, outputs read at the
sample points. Its result is what FMPy's ``simulate_fmu(..., fmi_type="CoSimulation")`` or
an SSP tool computes, and what docs/fmu.md compares with the runner's (the runner's
``inputs = "hold"`` mode is the like-for-like reference: the same zero-order hold).

"""

from __future__ import annotations

import ctypes
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from fmpy.fmi3 import FMU3Slave, fmi3Float64, fmi3ValueReference

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.testbench.drivers import drive
from spindlebench.testbench.runner import (
    RELATIVE_TOLERANCE,
    check_scenario,
    extracted_fmu,
    initial_state,
    inspect_fmu,
    parameter_values,
    restore_state,
    save_state,
)
from spindlebench.testbench.scenario import Scenario


@dataclass(frozen=True)
class CoSimulation:
    """Sampled outputs of a co-simulated scenario, and the saved state at its end."""

    time_s: np.ndarray
    outputs: Mapping[str, np.ndarray]
    end_state: bytes  # fmi3SerializeFMUState at the end of the run


def _slave(fmu_path: Path) -> tuple[FMU3Slave, object]:
    info = inspect_fmu(fmu_path)
    md = info.model_description
    if md.coSimulation is None:
        raise SpindlebenchError(f"{fmu_path}: has no <CoSimulation> interface (rebuild it with "
                                "`spindlebench build`)")
    slave = FMU3Slave(guid=md.guid, unzipDirectory=str(extracted_fmu(info)),
                      modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="spindlebench-cs")
    return slave, info


def co_simulate_cs(scenario: Scenario, fmu_path: str | Path | None = None, *,
                   start_state: bytes | None = None, tolerance: float | None = None,
                   ) -> CoSimulation:
    """Step ``scenario`` through ``fmi3DoStep`` at its communication step.

    ``start_state`` (a serialised FMU state of this FMU build) replaces the scenario's
    initial state: states, parameters and the integrator's memory are restored, then the
    scenario's parameters are set on top and the clock restarts at 0 s.
    """
    fmu_path = Path(DEFAULT_FMU if fmu_path is None else fmu_path)
    slave, info = _slave(fmu_path)
    check_scenario(scenario, info)
    signals = drive(scenario)
    inputs = np.ascontiguousarray(signals.matrix)
    params = parameter_values(scenario, info)
    n_steps, every = scenario.n_steps, scenario.steps_per_sample
    n_out = len(info.output_vrs)
    samples = np.empty((n_steps // every + 1, n_out))
    tol = RELATIVE_TOLERANCE["hold"] if tolerance is None else tolerance
    slave.instantiate()
    try:
        if start_state is not None:
            restore_state(slave, start_state)
        else:
            x0 = initial_state(scenario, info, float(signals.ambient_C[0]))
            slave.setFloat64(list(info.state_vrs), [x0[n] for n in info.state_names])
        if params:
            slave.setFloat64([info.parameters[n].valueReference for n in params],
                             list(params.values()))
        slave.enterInitializationMode(tolerance=tol, startTime=0.0,
                                      stopTime=scenario.duration_s)
        n_in = len(info.input_vrs)
        in_vrs = (fmi3ValueReference * n_in)(*info.input_vrs)
        out_vrs = (fmi3ValueReference * n_out)(*info.output_vrs)
        u = (fmi3Float64 * n_in)()
        y = (fmi3Float64 * n_out)()
        y_view = np.ctypeslib.as_array(y)
        row = inputs.strides[0]
        ctypes.memmove(u, inputs.ctypes.data, row)
        slave.fmi3SetFloat64(slave.component, in_vrs, n_in, u, n_in)
        slave.exitInitializationMode()
        slave.fmi3GetFloat64(slave.component, out_vrs, n_out, y, n_out)
        samples[0] = y_view
        step = scenario.step_s
        for k in range(1, n_steps + 1):
            slave.doStep(currentCommunicationPoint=(k - 1) * step, communicationStepSize=step)
            # the inputs of the new communication point first, so an output read here sees
            # them (as the runner's: outputs that depend on an input directly, e.g. the air)
            ctypes.memmove(u, inputs.ctypes.data + k * row, row)
            slave.fmi3SetFloat64(slave.component, in_vrs, n_in, u, n_in)
            if k % every == 0:
                slave.fmi3GetFloat64(slave.component, out_vrs, n_out, y, n_out)
                samples[k // every] = y_view
        end = save_state(slave)
        slave.terminate()
    finally:
        slave.freeInstance()
    return CoSimulation(time_s=np.arange(samples.shape[0]) * every * scenario.step_s,
                        outputs={n: samples[:, i] for i, n in enumerate(info.output_names)},
                        end_state=end)
