"""Issue 10's measurement: does CVode run faster with the Jacobian from the FMU's directional
derivatives (FMI 3 ``fmi3GetDirectionalDerivative``; the FMU declares
``providesDirectionalDerivatives``) than with its own difference quotients?

FMPy's ``CVodeSolver`` gives CVode no Jacobian (SUNDIALS then forms it from nx extra
right-hand-side calls, each a Python callback into the FMU). This bench-only variant of it
sets ``CVodeSetJacFn`` to a callback that fills each column of CVode's dense matrix with one
directional-derivative call, and is patched into ``fmpy.sundials`` for the runs it times, so
the runner itself is unchanged. Both variants run on FMPy's Python callbacks
(``native_rhs=False``): the runner's default, CVode on the FMU's C right-hand side, and its
C Jacobian are compared in ``bench/bench_runner.py``. Used by ``bench/bench_simulation.py``.
"""

from __future__ import annotations

import ctypes
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import fmpy.sundials
import numpy as np
from fmpy.fmi3 import fmi3Float64, fmi3ValueReference
from fmpy.sundials.libraries import sundials_cvode, sundials_sunmatrixdense
from fmpy.sundials.nvector_serial import NV_DATA_S
from fmpy.sundials.sundials_nvector import N_Vector
from fmpy.sundials.sundials_types import sunrealtype
from spindlebench.core.errors import SpindlebenchError
from spindlebench.testbench.runner import FmuInterface, Simulation, co_simulate, inspect_fmu
from spindlebench.testbench.scenario import Scenario

JacobianFn = ctypes.CFUNCTYPE(ctypes.c_int, sunrealtype, N_Vector, N_Vector, ctypes.c_void_p,
                              ctypes.c_void_p, N_Vector, N_Vector, N_Vector)
_set_jacobian = sundials_cvode.CVodeSetJacFn
_set_jacobian.argtypes = [ctypes.c_void_p, JacobianFn]
_set_jacobian.restype = ctypes.c_int
_dense_data = sundials_sunmatrixdense.SUNDenseMatrix_Data
_dense_data.argtypes = [ctypes.c_void_p]
_dense_data.restype = ctypes.c_void_p
COUNTERS = ("CVodeGetNumSteps", "CVodeGetNumRhsEvals", "CVodeGetNumJacEvals",
            "CVodeGetNumLinRhsEvals")
for _name in COUNTERS:
    getattr(sundials_cvode, _name).argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_long)]


@dataclass
class Counts:
    """CVode's counters summed over a run's solver segments (a restart resets them)."""

    steps: int = 0
    rhs: int = 0
    jacobians: int = 0
    rhs_for_jacobians: int = 0
    nan_jacobians: int = 0
    solvers: list = field(default_factory=list, repr=False)

    def collect(self) -> None:
        for solver in self.solvers:
            solver.add_counts(self)
        self.solvers.clear()


def _solver_class(info: FmuInterface, directional: bool, counts: Counts) -> type:
    derivative_vrs = [d.variable.valueReference for d in info.model_description.derivatives]

    class CountingSolver(fmpy.sundials.CVodeSolver):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            counts.solvers.append(self)
            if directional:
                self._use_directional_jacobian(kwargs["get_dx"].__self__)

        def reset(self, time_s):
            self.add_counts(counts)  # CVodeReInit zeroes the counters
            super().reset(time_s)

        def add_counts(self, into: Counts) -> None:
            values = []
            for name in COUNTERS:
                value = ctypes.c_long()
                getattr(sundials_cvode, name)(self.cvode_mem, ctypes.byref(value))
                values.append(value.value)
            into.steps += values[0]
            into.rhs += values[1]
            into.jacobians += values[2]
            into.rhs_for_jacobians += values[3]

        def _use_directional_jacobian(self, fmu) -> None:
            nx = self.nx
            unknowns = (fmi3ValueReference * nx)(*derivative_vrs)
            knowns = [(fmi3ValueReference * 1)(vr) for vr in info.state_vrs]
            one = (fmi3Float64 * 1)(1.0)
            derivative, component = fmu.fmi3GetDirectionalDerivative, fmu.component
            column = ctypes.POINTER(fmi3Float64)

            def jacobian(t, y, fy, matrix, user_data, tmp1, tmp2, tmp3):
                self.set_time(t)
                self.set_x(NV_DATA_S(y), nx)
                data = _dense_data(matrix)  # column-major: column j at data + 8 nx j
                for j in range(nx):
                    derivative(component, unknowns, nx, knowns[j], 1, one, 1,
                               ctypes.cast(data + 8 * nx * j, column), nx)
                values = np.ctypeslib.as_array(ctypes.cast(data, column), (nx * nx,))
                if not np.isfinite(values).all():
                    counts.nan_jacobians += 1
                return 0

            self._jacobian = JacobianFn(jacobian)  # kept alive with the solver
            if _set_jacobian(self.cvode_mem, self._jacobian) != 0:
                raise RuntimeError("CVodeSetJacFn failed")

    return CountingSolver


@contextmanager
def _patched(solver: type) -> Iterator[None]:
    original = fmpy.sundials.CVodeSolver
    fmpy.sundials.CVodeSolver = solver
    try:
        yield
    finally:
        fmpy.sundials.CVodeSolver = original


@dataclass
class Run:
    cpu_s: float
    counts: Counts
    simulation: Simulation | None
    error: str = ""


def run(scenario: Scenario, fmu: Path, directional: bool, repeat: int = 3) -> Run:
    """The best CPU time of ``repeat`` runs and CVode's counters of the last one."""
    info = inspect_fmu(fmu)
    best, counts, simulation, error = float("inf"), Counts(), None, ""
    for _ in range(repeat):
        counts = Counts()
        with _patched(_solver_class(info, directional, counts)):
            started = time.process_time()
            try:
                simulation = co_simulate(scenario, fmu, native_rhs=False)
            except SpindlebenchError as exc:
                error = str(exc).split(": ")[-1][:120]
                simulation = None
            best = min(best, time.process_time() - started)
        counts.collect()
        if error:
            break
    return Run(best, counts, simulation, error)


def report(label: str, scenario: Scenario, fmu: Path) -> list[dict]:
    """Print one scenario's comparison (CPU seconds: the machine is shared) and return it as
    rows for ``bench/results.py record()``."""
    own, directional = run(scenario, fmu, False), run(scenario, fmu, True)
    c = own.counts
    print(f"  {label}: CVode's difference quotients {own.cpu_s:.3f} s CPU ({c.steps} steps, "
          f"{c.rhs} + {c.rhs_for_jacobians} right-hand sides for {c.jacobians} Jacobians)")
    rows = [{"variant": f"{label}: Jacobian by CVode's difference quotients",
             "cpu_s": own.cpu_s, "steps": c.steps, "jacobians": c.jacobians}]
    d = directional.counts
    if directional.error or directional.simulation is None or own.simulation is None:
        print(f"  {label}: FMU directional derivatives FAILED: {directional.error} "
              f"({d.nan_jacobians} of {d.jacobians} Jacobians held NaN)")
        return [*rows, {"variant": f"{label}: Jacobian by the FMU's directional derivatives",
                        "failed": str(directional.error)}]
    drift = np.abs(directional.simulation.outputs["drift_um"]
                   - own.simulation.outputs["drift_um"]).max()
    temps = max(np.abs(directional.simulation.outputs[f"T{i}_C"]
                       - own.simulation.outputs[f"T{i}_C"]).max() for i in range(1, 21))
    print(f"  {label}: FMU directional derivatives {directional.cpu_s:.3f} s CPU "
          f"({own.cpu_s / directional.cpu_s:.2f}x; {d.steps} steps, {d.rhs} right-hand sides, "
          f"{d.jacobians} Jacobians, {d.nan_jacobians} with NaN), max|d drift| {drift:.1e} um, "
          f"max|d T| {temps:.1e} K")
    return [*rows, {"variant": f"{label}: Jacobian by the FMU's directional derivatives",
                    "cpu_s": directional.cpu_s, "steps": d.steps, "jacobians": d.jacobians,
                    "cpu_ratio_to_quotients": directional.cpu_s / own.cpu_s,
                    "max_d_drift_um": float(drift), "max_d_T_K": float(temps)}]
