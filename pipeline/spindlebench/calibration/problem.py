"""Calibration as a weighted nonlinear least-squares problem on the model's own equations.

The equations are ``model.equations.explicit_ode`` (what the FMU contains), integrated with
the implicit trapezoidal rule (A-stable, second order) on the recording's sample grid, inputs
held over each interval as in the co-simulation. The network is stiff (probes react in
seconds, the floor in a day), so an explicit method would need steps far below the 60 s
sampling; one Newton-solved implicit step per sample is cheap because the network is nearly
linear.

Unknowns ``theta``: the log-factors ``s`` of the fitted parameters (shared by all recordings),
and per recording a uniform shift of the initial state, the knots of an unknown ambient and the
offset of the error probe (a probe's zero is arbitrary). The initial state is the network's
steady state at rest with every node a sensor sees held at its first reading ("interpolated
from its neighbours" through the model's own conductances) plus that shift. Residuals are
measured minus modelled, divided by each channel's noise; weak priors complete them.

Solver: Gauss-Newton with a trust region and bounds (SciPy ``least_squares``, 'trf'), with the
exact Jacobian from forward sensitivities of every step (``S' = -A^-1 (B S + C)``, CasADi
derivatives of the step). ``method="ipopt"`` solves the same problem with IPOPT on the full
discretisation instead (``calibration.ipopt``); ``bench/bench_calibration.py`` compares them.

Uncertainty: the Gauss-Newton covariance ``(J^T J)^-1`` of all unknowns (priors included). When
the fit is worse than the stated noise (reduced chi-square above 1, as on any real machine) the
data's noise is inflated by the reduced chi-square (the priors' is not), so the intervals
reflect the misfit actually seen and an unseen parameter keeps its prior interval.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import casadi as ca
import numpy as np
import scipy.linalg
import scipy.optimize
from threadpoolctl import threadpool_limits

from spindlebench.calibration.fitset import PRIOR_SD_LN, log_bounds
from spindlebench.calibration.mapping import INPUTS
from spindlebench.calibration.series import Series
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import KELVIN_OFFSET
from spindlebench.formats.recording import AMBIENT_COLUMN, TIME_COLUMN, node_output
from spindlebench.model.equations import ExplicitOde

#: Prior sd (K) of the uniform shift of the initial state.
INITIAL_SD_K = 3.0
#: Prior sd (K) of an unknown ambient's level, and of its change from one knot to the next.
AMBIENT_LEVEL_SD_K = 10.0
AMBIENT_STEP_SD_K = 1.0
NEWTON_TOL_K = 1e-7
MAX_CHORD_ITERATIONS = 30
#: Newton iterations (Jacobian refreshed each time) when the chord iterations fail.
MAX_NEWTON_ITERATIONS = 30
#: (n / n_ref)^(2/3) has an infinite partial at n = 0, which numeric AD multiplies by a zero
#: seed into NaN: a standing spindle is given as this speed (no heat to speak of).
MIN_SPEED_RPM = 1e-3
AMBIENT = INPUTS.index(AMBIENT_COLUMN)


class _Dense:
    """A CasADi function evaluated into preallocated NumPy arrays (``Function.buffer``):
    converting DM results costs more than evaluating the step itself."""

    def __init__(self, function: ca.Function) -> None:
        self.buffer, self.trigger = function.buffer()
        self.args = [np.zeros(function.numel_in(i)) for i in range(function.n_in())]
        for i, arg in enumerate(self.args):
            self.buffer.set_arg(i, memoryview(arg))
        self.shapes = [function.size_out(i) for i in range(function.n_out())]
        self.results = [np.zeros(function.numel_out(i)) for i in range(function.n_out())]
        for i, res in enumerate(self.results):
            self.buffer.set_res(i, memoryview(res))

    def __call__(self, *args: np.ndarray | float) -> list[np.ndarray]:
        for target, value in zip(self.args, args, strict=True):
            # CasADi reads a matrix argument column-major
            target[:] = value if np.ndim(value) < 2 else np.ravel(value, order="F")
        self.trigger()
        # CasADi stores column-major
        return [r.reshape(shape[1], shape[0]).T for r, shape in zip(self.results, self.shapes,
                                                                     strict=True)]


def _lu_factor(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """LU factors of ``A`` by LAPACK's ``getrf`` directly: SciPy's ``lu_factor`` wraps it in
    checks and conversions that cost as much as factorising the 105 x 105 step Jacobian, once
    per step of every evaluation. A singular factor is kept (``lu_solve`` then gives inf/NaN,
    which the step's convergence test rejects), as ``lu_factor`` only warns of it."""
    lu, piv, info = _GETRF(A)
    if info < 0:
        raise ValueError(f"getrf: illegal argument {-info}")
    return lu, piv


def _lu_solve(lu: tuple[np.ndarray, np.ndarray], b: np.ndarray) -> np.ndarray:
    """``A^-1 b`` from ``_lu_factor(A)`` (LAPACK's ``getrs``)."""
    x, info = _GETRS(lu[0], lu[1], b)
    if info < 0:
        raise ValueError(f"getrs: illegal argument {-info}")
    return x


_GETRF, _GETRS = scipy.linalg.lapack.get_lapack_funcs(("getrf", "getrs"), dtype=np.float64)


@dataclass
class Discretisation:
    """The trapezoidal step and the output map of an ODE, with the fitted parameters as
    log-factors on ``base`` (the parameter values calibration starts from)."""

    ode: ExplicitOde
    fit: list[str]
    base: np.ndarray  # every tunable parameter, ode order
    #: Fitted name -> parameters moved by the same log-factor (a tie: one unknown for several
    #: parameters the data cannot separate, ``calibration.identifiability``).
    ties: dict[str, tuple[str, ...]] = field(default_factory=dict)
    step: ca.Function = field(init=False)
    outputs: ca.Function = field(init=False)

    def __post_init__(self) -> None:
        n_x, n_u = len(self.ode.states), len(self.ode.inputs)
        if self.ode.inputs != list(INPUTS):
            raise SpindlebenchError(f"model inputs {self.ode.inputs} are not {list(INPUTS)}")
        index = {name: i for i, name in enumerate(self.ode.parameters)}
        self.fit_index = [index[name] for name in self.fit]
        z0, z1 = ca.SX.sym("z0", n_x), ca.SX.sym("z1", n_x)
        u, h = ca.SX.sym("u", n_u), ca.SX.sym("h")
        s = ca.SX.sym("s", len(self.fit))
        p = ca.SX(ca.DM(self.base))
        for k, i in enumerate(self.fit_index):
            p[i] = self.base[i] * ca.exp(s[k])
            for other in self.ties.get(self.fit[k], ()):
                p[index[other]] = self.base[index[other]] * ca.exp(s[k])
        u_model = ca.vertcat(ca.fmax(ca.fabs(u[0]), MIN_SPEED_RPM), u[1:])
        f0, y0 = self.ode.ode(z0 + KELVIN_OFFSET, u_model, p)
        f1 = self.ode.ode(z1 + KELVIN_OFFSET, u_model, p)[0]
        residual = z1 - z0 - h / 2 * (f0 + f1)
        self.step = ca.Function("step", [z0, z1, u, h, s], [residual])
        dense = ca.densify
        # one call per step: the residual and every Jacobian at the predicted next state;
        # then chord iterations on the residual alone (the network is nearly linear)
        self._jacobians = _Dense(ca.Function(
            "jacobians", [z0, z1, u, h, s],
            [dense(residual), dense(ca.jacobian(residual, z1)),
             dense(ca.jacobian(residual, z0)), dense(ca.jacobian(residual, s)),
             dense(ca.jacobian(residual, u[AMBIENT]))]))
        self._residual = _Dense(ca.Function("residual", [z0, z1, u, h, s], [dense(residual)]))
        self._rest = _Dense(ca.Function("rest", [z0, u, s],
                                        [dense(f0), dense(ca.jacobian(f0, z0))]))
        self.outputs = ca.Function("outputs", [z0, u, s], [y0])
        self.output_index = {name: i for i, name in enumerate(self.ode.outputs)}
        self._u, self._z, self._s, self._y = u, z0, s, y0
        self._sampled: dict[tuple[tuple[str, ...], int], tuple[_Dense, np.ndarray]] = {}

    def output_derivatives(self, names: Sequence[str]) -> ca.Function:
        """``(x, u, s) -> (y, dy/dx, dy/ds, dy/d ambient)`` for the outputs ``names``."""
        y = ca.vertcat(*[self._y[self.output_index[n]] for n in names])
        return ca.Function("output_derivatives", [self._z, self._u, self._s],
                           [y, ca.jacobian(y, self._z), ca.jacobian(y, self._s),
                            ca.jacobian(y, self._u[AMBIENT])])

    def sampled_outputs(self, names: Sequence[str], samples: int) -> tuple[_Dense, np.ndarray]:
        """``(X (n_x, N), U (4, N), s) -> (Y, dY/dx[:, columns], dY/ds, dY/d ambient)`` at
        ``samples`` samples at once, dense into reused buffers, and ``columns``: the states
        any of the outputs ``names`` depends on (structurally). A sensor reads one state and
        the drift a third of them, so the products with the state sensitivities only need
        those columns. Built once per (names, samples) and kept: a calibration evaluates it
        once per model evaluation."""
        key = (tuple(names), samples)
        if key not in self._sampled:
            y = ca.vertcat(*[self._y[self.output_index[n]] for n in names])
            dy_dz = ca.jacobian(y, self._z)
            columns = np.array(sorted(set(dy_dz.sparsity().get_col())), dtype=int)
            dense = ca.densify
            function = ca.Function(
                "sampled_outputs", [self._z, self._u, self._s],
                [dense(y), dense(dy_dz[:, columns.tolist()]), dense(ca.jacobian(y, self._s)),
                 dense(ca.jacobian(y, self._u[AMBIENT]))])
            # s is the same at every sample: a non-repeated input of the map
            self._sampled[key] = (_Dense(function.map("sampled", "serial", samples, [2], [])),
                                  columns)
        return self._sampled[key]

    def log_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of the log-factors: the factor range of ``fitset``, narrowed to the FMU's
        declared min/max of each parameter (a calibrated machine must load in the FMU)."""
        lo_s, hi_s = log_bounds()
        lower, upper = np.full(len(self.fit), lo_s), np.full(len(self.fit), hi_s)
        for k, (name, i) in enumerate(zip(self.fit, self.fit_index, strict=True)):
            minimum, maximum = self.ode.bounds.get(name, (None, None))
            if minimum is not None and minimum > 0:
                lower[k] = max(lower[k], np.log(minimum / self.base[i]))
            if maximum is not None:
                upper[k] = min(upper[k], np.log(maximum / self.base[i]))
        if np.any(lower > 0) or np.any(upper < 0):
            bad = self.fit[int(np.flatnonzero((lower > 0) | (upper < 0))[0])]
            raise SpindlebenchError(f"{bad}: the start value is outside the FMU's declared "
                                    "min/max")
        return lower, upper

    @property
    def n_x(self) -> int:
        return len(self.ode.states)

    def parameters(self, s: np.ndarray) -> dict[str, float]:
        """Fitted parameter values for log-factors ``s`` (and those tied to them)."""
        index = {name: i for i, name in enumerate(self.ode.parameters)}
        values = {}
        for k, (name, i) in enumerate(zip(self.fit, self.fit_index, strict=True)):
            values[name] = float(self.base[i] * np.exp(s[k]))
            for other in self.ties.get(name, ()):
                values[other] = float(self.base[index[other]] * np.exp(s[k]))
        return values

    def sensed_states(self, outputs: Sequence[str]) -> dict[int, str]:
        """State index -> the mapped output that reads it (node outputs, sensor probes)."""
        sensed = {}
        for i, state in enumerate(self.ode.states):
            stem = state.removesuffix("_T")
            candidates = (node_output(stem),
                          stem.removeprefix("sensor_").removesuffix("_body") + "_C")
            for output in candidates:
                if output in outputs:
                    sensed[i] = output
        return sensed

    def initial_guess(self, series: Series, s: np.ndarray, ambient_C: float) -> np.ndarray:
        """Initial state (degC): every sensed state at its first reading, every other node
        interpolated between them and the ambient through the network's own conductances
        (the linear network's steady state without heat sources). A machine at rest at the
        ambient is uniform; a warm sensor warms the nodes near it."""
        first = series.first_temperatures()
        sensed = {i: first[o] for i, o in self.sensed_states(list(first)).items()}
        z = np.full(self.n_x, ambient_C)
        fixed = np.zeros(self.n_x, bool)
        for i, value in sensed.items():
            z[i], fixed[i] = value, True
        free = ~fixed
        if free.any() and fixed.any():
            _, A = self._rest(np.full(self.n_x, ambient_C), [0.0, 0.0, 0.0, ambient_C], s)
            delta = z[fixed] - ambient_C
            z[free] = ambient_C - np.linalg.solve(A[np.ix_(free, free)],
                                                  A[np.ix_(free, fixed)] @ delta)
        return z


@dataclass(frozen=True)
class Layout:
    """Where each unknown sits in ``theta``: the log-factors first, then per recording the
    initial-state shift, the ambient knots and the error offset."""

    n_s: int
    blocks: tuple[tuple[slice, slice, slice], ...]  # per recording: shift, knots, offset

    @classmethod
    def of(cls, d: Discretisation, series_list: Sequence[Series]) -> Layout:
        start, blocks = len(d.fit), []
        for series in series_list:
            n_k = series.ambient_basis().shape[1] if series.ambient_unknown else 0
            n_c = 1 if any(c.kind == "error" for c in series.channels) else 0
            shift = slice(start, start + 1)
            knots = slice(shift.stop, shift.stop + n_k)
            offset = slice(knots.stop, knots.stop + n_c)
            blocks.append((shift, knots, offset))
            start = offset.stop
        return cls(len(d.fit), tuple(blocks))

    @property
    def size(self) -> int:
        return self.blocks[-1][2].stop if self.blocks else self.n_s

    def start(self, series_list: Sequence[Series]) -> np.ndarray:
        """Start values: unchanged parameters, no shift, the guessed ambient."""
        theta = np.zeros(self.size)
        for series, (_, knots, _) in zip(series_list, self.blocks, strict=True):
            theta[knots] = series.ambient_guess()
        return theta

    def prior_residuals(self, series_list: Sequence[Series], theta: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray]:
        """Whitened prior residuals and their (constant) Jacobian."""
        rows: list[np.ndarray] = []
        values: list[float] = []

        def add(weights: dict[int, float], value: float) -> None:
            row = np.zeros(self.size)
            for j, w in weights.items():
                row[j] = w
            rows.append(row)
            values.append(value)

        for k in range(self.n_s):
            add({k: 1 / PRIOR_SD_LN}, theta[k] / PRIOR_SD_LN)
        for series, (shift, knots, _) in zip(series_list, self.blocks, strict=True):
            add({shift.start: 1 / INITIAL_SD_K}, theta[shift.start] / INITIAL_SD_K)
            if knots.stop > knots.start:
                j0 = knots.start
                add({j0: 1 / AMBIENT_LEVEL_SD_K},
                    (theta[j0] - series.ambient_guess()) / AMBIENT_LEVEL_SD_K)
                for j in range(j0 + 1, knots.stop):
                    add({j: 1 / AMBIENT_STEP_SD_K, j - 1: -1 / AMBIENT_STEP_SD_K},
                        (theta[j] - theta[j - 1]) / AMBIENT_STEP_SD_K)
        return np.array(values), np.array(rows)


def ambient_series(series: Series, knots: np.ndarray) -> np.ndarray:
    """The ambient (degC) at every sample: measured or constant, or from the estimated knots."""
    if series.ambient_unknown:
        return series.ambient_basis() @ knots
    return series.inputs[AMBIENT]


def initial_state(d: Discretisation, series: Series, s: np.ndarray, shift: float,
                  knots: np.ndarray) -> np.ndarray:
    """The initial state for log-factors ``s``, a uniform ``shift`` and ambient ``knots``."""
    return d.initial_guess(series, s, float(ambient_series(series, knots)[0])) + shift


def trajectory(d: Discretisation, series: Series, z0: np.ndarray, s: np.ndarray,
               knots: np.ndarray, sensitivities: bool = True
               ) -> tuple[np.ndarray, np.ndarray | None]:
    """States (n_x, N + 1) from ``z0``, and their sensitivities (N + 1, n_x, n_s + 1 + n_k) to
    the log-factors, the uniform initial shift and the ambient knots.

    One implicit trapezoidal step after the other, each solved by chord iterations with the
    Jacobian at the predicted (linearly extrapolated) state: the network is nearly linear, so
    two or three residual evaluations converge. The sensitivities use the same Jacobians,
    ``S' = -A^-1 (B S + [C, 0, a b_k])``; taking them at the predictor instead of the solution
    changes them by about 1e-4 relative (viscosity is the only nonlinearity), far below what
    the covariance is good for, and saves a factorisation and two Jacobian evaluations per
    step. The sensitivity of the initial state to ``s`` (through the interpolation of the
    unsensed nodes) is neglected: the shift absorbs most of it.
    """
    n, n_x, n_s = series.intervals, d.n_x, len(d.fit)
    inputs = series.inputs.copy()
    inputs[AMBIENT] = ambient_series(series, knots)
    basis = series.ambient_basis() if series.ambient_unknown else np.zeros((n + 1, 0))
    n_k = basis.shape[1]
    h = np.diff(series.time_s)
    states = np.empty((n_x, n + 1))
    states[:, 0] = z0
    S = None
    if sensitivities:
        S = np.zeros((n + 1, n_x, n_s + 1 + n_k))
        S[0, :, n_s] = 1.0
    for k in range(n):
        z = states[:, k]
        z1 = z.copy() if k == 0 else 2 * z - states[:, k - 1]
        u = inputs[:, k]
        r, A, B, C, a = d._jacobians(z, z1, u, h[k], s)
        lu = _lu_factor(A)
        for _ in range(MAX_CHORD_ITERATIONS):
            dz = _lu_solve(lu, r.ravel())
            z1 = z1 - dz
            if np.max(np.abs(dz)) < NEWTON_TOL_K:
                break
            (r,) = d._residual(z, z1, u, h[k], s)
        else:
            z1, lu, (A, B, C, a) = _newton_step(d, series, k, z, u, h[k], s)
        states[:, k + 1] = z1
        if S is not None:
            rhs = B @ S[k]
            rhs[:, :n_s] += C
            if n_k:
                rhs[:, n_s + 1:] += a @ basis[k][None, :]
            S[k + 1] = -_lu_solve(lu, rhs)
    return states, S


def _newton_step(d: Discretisation, series: Series, k: int, z: np.ndarray, u: np.ndarray,
                 h: float, s: np.ndarray) -> tuple[np.ndarray, tuple, tuple]:
    """Step ``k`` by Newton's method, the Jacobian refreshed at every iterate, from the last
    state: the fallback when the chord iterations (Jacobian at the predictor) do not converge.
    That happens where the predictor is far off, e.g. at a speed switched on at a speed the
    fit never saw (the friction's viscosity makes the heat input depend on the oil's
    temperature); a fit's trial point or a prediction over new runs must not abort for it.
    Returns the state, the factorised Jacobian and the partial derivatives at the solution."""
    z1 = z.copy()
    for _ in range(MAX_NEWTON_ITERATIONS):
        r, A, B, C, a = d._jacobians(z, z1, u, h, s)
        lu = _lu_factor(A)
        dz = _lu_solve(lu, r.ravel())
        z1 = z1 - dz
        if not np.all(np.isfinite(z1)):
            break
        if np.max(np.abs(dz)) < NEWTON_TOL_K:
            _, A, B, C, a = d._jacobians(z, z1, u, h, s)
            return z1, _lu_factor(A), (A, B, C, a)
    raise StepFailedError(f"{series.path}: the step at time_s = {series.time_s[k]:g} did not "
                          "converge")


#: A log-factor within this of its bound counts as at the bound (a factor 1.01).
AT_BOUND_LN = 0.01


def at_bound(d: Discretisation, s: np.ndarray) -> list[str]:
    """The fitted parameters whose log-factor in ``s`` sits at a bound of its range
    (``Discretisation.log_bounds``): there the fit compensates for what the model's structure
    cannot do rather than measuring the parameter (``calibration.identifiability``)."""
    lower, upper = d.log_bounds()
    return [name for name, v, lo, hi in zip(d.fit, s, lower, upper, strict=True)
            if v - lo < AT_BOUND_LN or hi - v < AT_BOUND_LN]


@dataclass
class Evaluation:
    """Residuals (whitened: data, then priors) and their Jacobian at one ``theta``."""

    residuals: np.ndarray
    jacobian: np.ndarray | None
    n_data: int
    models: list[list[np.ndarray]]  # per recording, per channel: modelled values at all samples
    initial_states: list[np.ndarray]
    #: Per recording, the state (degC) at its last sample: where a continuation starts.
    end_states: list[np.ndarray] = field(default_factory=list)


def evaluate(d: Discretisation, series_list: Sequence[Series], layout: Layout,
             theta: np.ndarray, jacobian: bool = True) -> Evaluation:
    """Whitened residuals measured-vs-model and priors, and their Jacobian in ``theta``."""
    n_s = layout.n_s
    s = theta[:n_s]
    parts, jac_parts, models, initial_states, end_states = [], [], [], [], []
    for series, (shift, knots, offset) in zip(series_list, layout.blocks, strict=True):
        z0 = initial_state(d, series, s, theta[shift][0], theta[knots])
        initial_states.append(z0)
        states, S = trajectory(d, series, z0, s, theta[knots], jacobian)
        end_states.append(states[:, -1].copy())
        inputs = series.inputs.copy()
        inputs[AMBIENT] = ambient_series(series, theta[knots])
        names = [c.output for c in series.channels]
        n1 = series.intervals + 1
        outputs, columns = d.sampled_outputs(names, n1)
        Y, Dx, Ds, Da = outputs(states, inputs, s)
        Dx = Dx.reshape(len(names), n1, len(columns))  # column blocks per sample
        Ds = Ds.reshape(len(names), n1, n_s)
        if jacobian:
            S_used = S[:, columns, :]  # (n1, columns, n_s + 1 + n_k), gathered once
        basis = series.ambient_basis() if series.ambient_unknown else np.zeros((n1, 0))
        recording_models = []
        for c, channel in enumerate(series.channels):
            model = Y[c].copy()
            if channel.kind == "error":
                model += theta[offset][0]
            recording_models.append(model)
            valid = np.flatnonzero(np.isfinite(channel.values))
            parts.append((model[valid] - channel.values[valid]) / channel.noise)
            if not jacobian:
                continue
            block = np.zeros((len(valid), layout.size))
            local = np.einsum("kx,kxt->kt", Dx[c, valid], S_used[valid])
            local[:, :n_s] += Ds[c, valid]
            if basis.shape[1]:
                local[:, n_s + 1:] += Da[c, valid][:, None] * basis[valid]
            block[:, :n_s] = local[:, :n_s]
            block[:, shift] = local[:, n_s:n_s + 1]
            block[:, knots] = local[:, n_s + 1:]
            if channel.kind == "error":
                block[:, offset] = 1.0
            jac_parts.append(block / channel.noise)
        models.append(recording_models)
    data = np.concatenate(parts)
    prior, prior_jac = layout.prior_residuals(series_list, theta)
    return Evaluation(
        residuals=np.concatenate([data, prior]),
        jacobian=np.vstack([*jac_parts, prior_jac]) if jacobian else None,
        n_data=data.size, models=models, initial_states=initial_states,
        end_states=end_states,
    )


@dataclass
class Fit:
    """The result of a calibration (see ``report`` for what is written from it)."""

    fit: list[str]
    start_values: dict[str, float]
    theta: np.ndarray
    layout: Layout
    covariance: np.ndarray  # of the log-factors
    correlation: np.ndarray
    chi2_reduced: float
    channel_rmse: list[dict]
    trajectories: list[dict]
    evaluations: int
    status: str
    seconds: float
    method: str
    initial_states: list[np.ndarray]
    #: Per recording, the fitted state (degC, ``state_names`` order) at its last sample.
    end_states: list[np.ndarray] = field(default_factory=list)
    #: The model's state names (``ode.states``: the FMU's), the order of the states above.
    state_names: list[str] = field(default_factory=list)
    #: The fitted parameters whose estimate sits at a bound of its range (``at_bound``).
    at_bound: list[str] = field(default_factory=list)

    @property
    def log_factors(self) -> np.ndarray:
        return self.theta[: self.layout.n_s]

    @property
    def values(self) -> dict[str, float]:
        return {name: self.start_values[name] * float(np.exp(s))
                for name, s in zip(self.fit, self.log_factors, strict=True)}

    @property
    def sd_ln(self) -> np.ndarray:
        return np.sqrt(np.diag(self.covariance))

    def interval95(self) -> dict[str, tuple[float, float]]:
        return {name: (self.start_values[name] * float(np.exp(s - 1.96 * e)),
                       self.start_values[name] * float(np.exp(s + 1.96 * e)))
                for name, s, e in zip(self.fit, self.log_factors, self.sd_ln, strict=True)}

    def knots(self, recording: int) -> np.ndarray:
        return self.theta[self.layout.blocks[recording][1]]


class StepFailedError(SpindlebenchError):
    """A model step did not converge at some parameter values."""


def _gauss_newton(d, series_list, layout, theta0, max_iter, verbose, progress=False):
    """Bounded Gauss-Newton with a trust region (SciPy's ``least_squares``, 'trf');
    ``progress``: a bar of model evaluations (at most ``max_iter``) with the cost.

    A trial point whose integration fails (a step that does not converge near a bound) is
    rejected, not the fit: its residuals are returned as infinite, on which 'trf' shrinks
    the trust region to a quarter of the step and tries again. Only a failure at the start
    values is an error. The count of rejected points is in the returned message.
    """
    from spindlebench.core.progress import bar as progress_bar

    cache: dict[bytes, Evaluation] = {}
    rejected = [0]
    size = [0]
    shown = progress_bar(max_iter, "calibrate", "evaluations", progress)

    def at(theta: np.ndarray) -> Evaluation:
        key = theta.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = evaluate(d, series_list, layout, theta)
            if shown is not None:
                r = cache[key].residuals
                shown.set_postfix_str(f"cost {0.5 * float(r @ r):.4g}", refresh=False)
                shown.update(1)
        return cache[key]

    lower = np.full(layout.size, -np.inf)
    upper = np.full(layout.size, np.inf)
    lower[: layout.n_s], upper[: layout.n_s] = d.log_bounds()
    def residuals(theta: np.ndarray) -> np.ndarray:
        try:
            values = at(theta).residuals
        except StepFailedError:
            if not size[0]:
                raise
            rejected[0] += 1
            return np.full(size[0], np.inf)
        size[0] = len(values)
        return values

    try:
        result = scipy.optimize.least_squares(
            residuals, theta0, jac=lambda t: at(t).jacobian,
            bounds=(lower, upper), method="trf", x_scale="jac", max_nfev=max_iter,
            xtol=1e-8, ftol=1e-7, gtol=1e-8, verbose=2 if verbose else 0,
        )
    finally:
        if shown is not None:
            shown.close()
    message = str(result.message)
    if rejected[0]:
        message += f" ({rejected[0]} trial point(s) rejected: the model step failed there)"
    return result.x, int(result.nfev), message


def calibrate(d: Discretisation, series_list: Sequence[Series], *, method: str = "gauss-newton",
              max_iter: int = 50, verbose: bool = False, progress: bool = False) -> Fit:
    """Fit ``d.fit`` (and initial states, unknown ambients, probe offsets) to the recordings;
    ``progress``: a bar of the Gauss-Newton's model evaluations on stderr."""
    with threadpool_limits(1):  # 94 x 94 solves: threads only contend (and see docs: SIGSEGV)
        return _calibrate(d, series_list, method, max_iter, verbose, progress)


def _calibrate(d, series_list, method, max_iter, verbose, progress=False) -> Fit:
    started = time.perf_counter()
    layout = Layout.of(d, series_list)
    theta0 = layout.start(series_list)
    if method == "gauss-newton":
        theta, evaluations, status = _gauss_newton(d, series_list, layout, theta0, max_iter,
                                                    verbose, progress)
    elif method == "ipopt":
        from spindlebench.calibration.ipopt import solve_ipopt

        theta, evaluations, status = solve_ipopt(d, series_list, layout, theta0, max_iter,
                                                 verbose)
    else:
        raise SpindlebenchError(f"unknown calibration method {method!r}")
    final = evaluate(d, series_list, layout, theta)
    r = final.residuals[: final.n_data]
    J = final.jacobian
    dof = max(final.n_data - layout.size, 1)
    chi2_reduced = float(r @ r / dof)
    # the data's noise is inflated by the misfit, the priors stay what they are: a parameter
    # the data do not see keeps its prior interval instead of one blown up by the misfit
    J_data, J_prior = J[: final.n_data], J[final.n_data:]
    information = J_data.T @ J_data / max(1.0, chi2_reduced) + J_prior.T @ J_prior
    covariance_all = np.linalg.pinv(information)
    covariance = covariance_all[: layout.n_s, : layout.n_s]
    sd = np.sqrt(np.diag(covariance))
    correlation = covariance / np.outer(sd, sd)

    channel_rmse, trajectories = [], []
    for i, series in enumerate(series_list):
        curves = {"recording": series.name, TIME_COLUMN: series.time_s,
                  AMBIENT_COLUMN: ambient_series(series, theta[layout.blocks[i][1]]),
                  "channels": []}
        for channel, model in zip(series.channels, final.models[i], strict=True):
            valid = np.isfinite(channel.values)
            error = channel.values[valid] - model[valid]
            channel_rmse.append({
                "recording": series.name, "column": channel.column, "output": channel.output,
                "kind": channel.kind, "noise": channel.noise,
                "rmse": float(np.sqrt(np.mean(error**2))), "bias": float(np.mean(error)),
            })
            curves["channels"].append({"column": channel.column, "output": channel.output,
                                       "kind": channel.kind, "measured": channel.values,
                                       "model": model})
        trajectories.append(curves)
    return Fit(
        fit=list(d.fit),
        start_values={n: float(d.base[i]) for n, i in zip(d.fit, d.fit_index, strict=True)},
        theta=theta, layout=layout, covariance=covariance, correlation=correlation,
        chi2_reduced=chi2_reduced, channel_rmse=channel_rmse, trajectories=trajectories,
        evaluations=evaluations, status=status, seconds=time.perf_counter() - started,
        method=method, initial_states=final.initial_states, end_states=final.end_states,
        state_names=list(d.ode.states), at_bound=at_bound(d, theta[: layout.n_s]),
    )
