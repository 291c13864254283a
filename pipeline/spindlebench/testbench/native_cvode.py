"""CVode on the FMU's own C right-hand side: no Python callback inside the solver (issue 26).

FMPy's ``CVodeSolver`` gives SUNDIALS CVode Python callbacks: every right-hand side, and
each of the N_X evaluations of CVode's difference-quotient Jacobian, goes from C through
ctypes into Python and back into the FMU (FMI set time, set the ambient, set the states, get
the derivatives). The SpindleBench FMU exports CVode-compatible C callbacks beside its FMI
functions (``model/fmu_extensions.c``: extra symbols, which FMI allows; its model description
is unchanged): ``sb_cvode_rhs`` does the same work in the same floating-point operations, with
the ambient interpolated in C from a table handed over once (``sb_cvode_table``), and
``sb_cvode_stop`` ends an output point in one call (states, time, inputs, outputs evaluated
once). CVode here is the same library FMPy ships, set up as FMPy sets it up (BDF, dense
linear solver with CVode's own difference-quotient Jacobian, absolute tolerance = nominal ×
relative tolerance, the same step limits), so a run gives the same bytes as the Python
callbacks (tests/testbench/test_native_cvode.py).

An FMU without these symbols (a user's own FMU) or with event indicators (this solver does no
root finding) runs through FMPy's ``CVodeSolver`` as before (``available``).
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from fmpy.fmi3 import FMU3Model, fmi3Float64, fmi3ValueReference
from fmpy.sundials import (
    CV_BDF,
    CV_NORMAL,
    CV_SUCCESS,
    NV_DATA_S,
    SUN_COMM_NULL,
    CVode,
    CVodeCreate,
    CVodeFree,
    CVodeInit,
    CVodeReInit,
    CVodeSetLinearSolver,
    CVodeSetMaxNumSteps,
    CVodeSetMaxStep,
    CVodeSVtolerances,
    CVRhsFn,
    N_VNew_Serial,
    SUNContext,
    SUNContext_Create,
    SUNContext_PushErrHandler,
    SUNDenseMatrix,
    SUNErrHandlerFn,
    SUNLinSol_Dense,
    realtype,
)
from fmpy.sundials.libraries import sundials_core, sundials_cvode, sundials_sunmatrixdense

#: The C callbacks an FMU must export for this solver (``model/fmu_extensions.c``).
SYMBOLS = ("sb_cvode_setup", "sb_cvode_table", "sb_cvode_rhs", "sb_cvode_stop", "sb_cvode_run")
#: CVode's Jacobian: its own difference quotients (one right-hand side per state: the same bytes
#: as FMPy's solver), the FMU's coloured forward derivatives, or coloured difference quotients
#: (one right-hand side per colour).
JACOBIANS = {"cvode": None, "forward": "sb_cvode_jac", "differences": "sb_cvode_jac_dq"}


def _bind(library: Any, name: str, argtypes: list, restype: Any = ctypes.c_int) -> Any:
    function = getattr(library, name)
    function.argtypes, function.restype = argtypes, restype
    return function


_set_user_data = _bind(sundials_cvode, "CVodeSetUserData", [ctypes.c_void_p, ctypes.c_void_p])
_set_stop_time = _bind(sundials_cvode, "CVodeSetStopTime", [ctypes.c_void_p, realtype])
_destroy_vector = _bind(sundials_core, "N_VDestroy", [ctypes.c_void_p], None)
_destroy_matrix = _bind(sundials_core, "SUNMatDestroy", [ctypes.c_void_p], None)
_free_linear_solver = _bind(sundials_core, "SUNLinSolFree", [ctypes.c_void_p])
_free_context = _bind(sundials_core, "SUNContext_Free", [ctypes.POINTER(SUNContext)])
_set_jacobian = _bind(sundials_cvode, "CVodeSetJacFn", [ctypes.c_void_p, ctypes.c_void_p])


def _address(function: Any) -> int:
    return ctypes.cast(function, ctypes.c_void_p).value


#: Handed to the FMU, which has no SUNDIALS of its own: it reads CVode's vectors and dense
#: matrix through the first two, and its loop between output points calls the other three.
_HOST_FUNCTIONS = tuple(_address(f) for f in (
    sundials_core.N_VGetArrayPointer, sundials_sunmatrixdense.SUNDenseMatrix_Data,
    sundials_cvode.CVode, sundials_cvode.CVodeSetStopTime, sundials_cvode.CVodeReInit))

_P = ctypes.c_void_p
_VRS = ctypes.POINTER(fmi3ValueReference)
_VALUES = ctypes.POINTER(fmi3Float64)


def available(fmu: FMU3Model, event_indicators: int) -> bool:
    """Whether ``fmu``'s binary exports the C callbacks and needs no root finding."""
    return event_indicators == 0 and all(hasattr(fmu.dll, name) for name in SYMBOLS)


@dataclass
class Plan:
    """A run's stops for ``NativeCVode.run``: the step indices ``stops`` where CVode stops,
    ``ends`` (the end of each one's segment), ``jumps`` (per step: restart CVode there),
    the input matrix (one row per step) and the output matrix (one row per output point,
    ``every`` steps apart), as the C loop reads and writes them."""

    stops: np.ndarray
    ends: np.ndarray
    jumps: np.ndarray
    step_s: float
    every: int
    inputs: np.ndarray
    samples: np.ndarray
    input_vrs: Any = field(init=False)
    output_vrs: Any = field(init=False)
    n_in: int = 0
    n_out: int = 0
    input_vr_list: tuple[int, ...] = ()
    output_vr_list: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        self.stops = np.ascontiguousarray(self.stops, dtype=np.int64)
        self.ends = np.ascontiguousarray(self.ends, dtype=np.int64)
        self.jumps = np.ascontiguousarray(self.jumps, dtype=np.uint8)
        for name in ("inputs", "samples"):
            array = getattr(self, name)
            if array.dtype != np.float64 or not array.flags.c_contiguous:
                raise ValueError(f"Plan.{name} must be a C-contiguous float64 matrix")
        self.n_in, self.n_out = len(self.input_vr_list), len(self.output_vr_list)
        if self.inputs.shape[1] != self.n_in or self.samples.shape[1] != self.n_out:
            raise ValueError("Plan: the matrices' columns and the value references differ")
        last = int(self.stops.max(initial=0))  # the C loop reads and writes these rows
        if (self.ends.shape != self.stops.shape or self.every < 1 or self.jumps.size <= last
                or self.inputs.shape[0] <= last or self.samples.shape[0] <= last // self.every):
            raise ValueError("Plan: stops beyond the input, jump or output rows")
        self.input_vrs = (fmi3ValueReference * self.n_in)(*self.input_vr_list)
        self.output_vrs = (fmi3ValueReference * self.n_out)(*self.output_vr_list)


class NativeCVode:
    """CVode (BDF, dense) on the FMU's C right-hand side, for one instantiated FMU.

    ``table`` is ``(value reference, values, step_s)``: that input at ``t = k * step_s``,
    interpolated linearly in C at the solver's time (None: no input changes inside a
    segment). Start it after ``fmi3EnterContinuousTimeMode``; ``free`` it before the instance.
    """

    def __init__(self, fmu: FMU3Model, nx: int, *, start_time: float, relative_tolerance: float,
                 max_step: float, max_num_steps: int,
                 table: tuple[int, np.ndarray, float] | None = None, jacobian: str = "cvode"):
        self.fmu, self.nx, self.component = fmu, nx, fmu.component
        self.context = self.x = self.abstol = self.mem = self.matrix = None
        self.linear_solver = None
        self.error = "CVode failed"
        try:
            self._start(start_time, relative_tolerance, max_step, max_num_steps, table, jacobian)
        except BaseException:
            self.free()  # what was allocated before the failure
            raise

    def _start(self, start_time: float, relative_tolerance: float, max_step: float,
               max_num_steps: int, table: tuple[int, np.ndarray, float] | None,
               jacobian: str) -> None:
        fmu, nx = self.fmu, self.nx
        dll = fmu.dll
        self._stop = _bind(dll, "sb_cvode_stop", [_P, realtype, _P, _VRS, ctypes.c_size_t,
                                                  _P, _VRS, ctypes.c_size_t, _P])
        setup = _bind(dll, "sb_cvode_setup", [_P] * 6)
        if setup(self.component, *_HOST_FUNCTIONS):
            raise RuntimeError("sb_cvode_setup failed (out of memory)")
        set_table = _bind(dll, "sb_cvode_table", [_P, fmi3ValueReference, _P, ctypes.c_size_t,
                                                  ctypes.c_double])
        if table is not None:
            vr, values, step_s = table
            values = np.ascontiguousarray(values, dtype=np.float64)
            if set_table(self.component, vr, values.ctypes.data, values.size, step_s):
                raise RuntimeError("sb_cvode_table refused the input table")
        else:
            set_table(self.component, 0, None, 0, 1.0)
        self.context = SUNContext()
        self._check(SUNContext_Create(SUN_COMM_NULL, ctypes.byref(self.context)),
                    "SUNContext_Create")
        self.x = N_VNew_Serial(nx, self.context)
        self.abstol = N_VNew_Serial(nx, self.context)
        fmu.getContinuousStates(NV_DATA_S(self.x), nx)
        fmu.getNominalsOfContinuousStates(NV_DATA_S(self.abstol), nx)
        np.ctypeslib.as_array(NV_DATA_S(self.abstol), (nx,))[:] *= relative_tolerance
        self.mem = CVodeCreate(CV_BDF, self.context)
        # the C function itself: CVode calls the FMU's code directly
        self._rhs = CVRhsFn(ctypes.cast(dll.sb_cvode_rhs, ctypes.c_void_p).value)
        self._errors = SUNErrHandlerFn(self._on_error)  # kept alive with the solver
        self._check(CVodeInit(self.mem, self._rhs, start_time, self.x), "CVodeInit")
        self._check(_set_user_data(self.mem, self.component), "CVodeSetUserData")
        self._check(CVodeSVtolerances(self.mem, relative_tolerance, self.abstol),
                    "CVodeSVtolerances")
        self.matrix = SUNDenseMatrix(nx, nx, self.context)
        self.linear_solver = SUNLinSol_Dense(self.x, self.matrix, self.context)
        self._check(CVodeSetLinearSolver(self.mem, self.linear_solver, self.matrix),
                    "CVodeSetLinearSolver")
        if JACOBIANS[jacobian] is not None:
            if not hasattr(dll, JACOBIANS[jacobian]):
                raise RuntimeError(f"the FMU's binary has no {JACOBIANS[jacobian]} (jacobian "
                                   f"{jacobian!r}); rebuild it with `spindlebench build`")
            self._check(_set_jacobian(self.mem, _address(getattr(dll, JACOBIANS[jacobian]))),
                        "CVodeSetJacFn")
        self._check(CVodeSetMaxStep(self.mem, max_step), "CVodeSetMaxStep")
        self._check(CVodeSetMaxNumSteps(self.mem, max_num_steps), "CVodeSetMaxNumSteps")
        self._check(SUNContext_PushErrHandler(self.context, self._errors, None),
                    "SUNContext_PushErrHandler")
        self._t = realtype(0.0)
        self._t_ref = ctypes.byref(self._t)
        self._run = _bind(dll, "sb_cvode_run", [_P] * 6 + [
            ctypes.c_size_t, ctypes.c_size_t, ctypes.c_double, ctypes.c_longlong, _P,
            ctypes.c_size_t, _P, _P, ctypes.c_size_t, _P, _P, _P, _P])
        self._done, self._flag = ctypes.c_size_t(), ctypes.c_int()
        self._refs = (ctypes.byref(self._done), ctypes.byref(self._flag), self._t_ref)

    def _on_error(self, line: int, function: bytes, file: bytes, message: bytes, code: int,
                  user_data: Any, context: Any) -> None:
        self.error = (f"CVode error (code {code}) in function {function.decode()}: "
                      f"{message.decode()}")

    @staticmethod
    def _check(flag: int, what: str) -> None:
        if flag != CV_SUCCESS:
            raise RuntimeError(f"{what} failed (flag {flag})")

    def advance(self, t_next: float, stop_time: float) -> float:
        """Integrate to ``t_next``, never past ``stop_time``; the time CVode reached."""
        _set_stop_time(self.mem, stop_time)
        if CVode(self.mem, t_next, self.x, self._t_ref, CV_NORMAL) < 0:
            raise RuntimeError(self.error)
        return self._t.value

    def stop(self, t: float, input_vrs: Any, n_in: int, inputs: int, output_vrs: Any,
             n_out: int, outputs: int | None) -> None:
        """The FMU at ``t``: CVode's states, the inputs at address ``inputs`` and, with an
        address ``outputs``, the outputs evaluated once and written there."""
        status = self._stop(self.component, t, self.x, input_vrs, n_in, inputs, output_vrs,
                            n_out, outputs)
        if status != 0:
            raise RuntimeError(f"sb_cvode_stop at t={t:g} s returned FMI status {status}")

    def run(self, plan: Plan, first: int, count: int) -> int:
        """Stops ``first`` .. ``first + count - 1`` of ``plan`` in the FMU's C loop (CVode to
        each, never past its segment's end, then ``stop``, outputs at output points, restarts
        at jumps); the number of stops done. A failure raises, naming the time and what
        failed."""
        if not 0 <= first <= first + count <= plan.stops.size:
            raise ValueError(f"stops {first}..{first + count - 1} outside the plan's "
                             f"{plan.stops.size}")
        code = self._run(self.component, self.mem, self.x, plan.stops.ctypes.data,
                         plan.ends.ctypes.data, plan.jumps.ctypes.data, first, count,
                         plan.step_s, plan.every, plan.input_vrs, plan.n_in,
                         plan.inputs.ctypes.data, plan.output_vrs, plan.n_out,
                         plan.samples.ctypes.data, *self._refs)
        if code == 0:
            return self._done.value
        t = (first + self._done.value, self._t.value)
        if code == 1:
            raise RuntimeError(self.error)
        if code == 2:
            raise RuntimeError(f"CVode stopped at t={t[1]:g} s instead of "
                               f"{plan.stops[t[0]] * plan.step_s:g} s")
        what = {3: "setting the stop's states and inputs or reading its outputs (FMI status",
                4: "CVodeReInit (flag", -1: "the FMU's C loop is not set up (flag"}
        raise RuntimeError(f"{what.get(code, f'code {code} (flag')} {self._flag.value}) at "
                           f"t={plan.stops[t[0]] * plan.step_s:g} s")

    def reset(self, t: float) -> None:
        """Restart CVode at ``t`` from the states of the last stop (an input jump)."""
        self._check(CVodeReInit(self.mem, t, self.x), "CVodeReInit")

    def free(self) -> None:
        """Release CVode and its vectors (the FMU instance stays the caller's)."""
        if self.mem is not None:
            CVodeFree(ctypes.byref(ctypes.c_void_p(self.mem)))
            self.mem = None
        for pointer, release in ((self.linear_solver, _free_linear_solver),
                                 (self.matrix, _destroy_matrix), (self.x, _destroy_vector),
                                 (self.abstol, _destroy_vector)):
            if pointer is not None:
                release(pointer)
        self.linear_solver = self.matrix = self.x = self.abstol = None
        if self.context is not None:
            _free_context(ctypes.byref(self.context))
            self.context = None
