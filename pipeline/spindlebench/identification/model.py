"""A low-order thermal model identified from a recording: structure, simulation, fit.

**The grey-box network.** ``n`` thermal nodes, node ``i`` with capacity ``C_i`` and
conductance ``G_i`` to the room, heated by the spindle: a heat source ``P_s = g_s (n /
n_ref)^a_s`` per source (the exponent fitted: Palmgren bearing friction gives about 5/3, a
motor's copper loss 2), optional linear sources (a feed column), the room temperature as an
input (a column) or unknown (then constant, absorbed in the offset). The error and every
mapped sensor are linear combinations of the node temperatures plus an offset.

Why the nodes are not chained here: seen through an output that is a *free* linear
combination of node temperatures, every RC network (chain, ladder, any graph with positive
conductances and capacities) is equivalent to its modal decomposition, ``n`` first-order
elements with real, positive time constants ``tau_i`` (the eigenvalues of ``C^-1 L`` of a
symmetric conductance matrix ``L`` are real and positive). The conductances between nodes are
then not identifiable from the error, only the time constants are; fitting the chain would
leave ``2 n - 1`` parameters for ``n`` identifiable ones and give meaningless intervals. So
the fitted parameters are ``tau_i = C_i / G_i`` (bounded, positive) and the exponents; the
node-to-output weights (heat gain times expansion coefficient) are linear and solved exactly
at every step (variable projection: ``least_squares`` sees only ``log tau`` and the
exponents). In each node the room enters with the node's own rate (``dT_i/dt = (T_room -
T_i) / tau_i + P_i / C_i``), which is what makes the unknown room an identifiable input when a
column gives it.

**The transfer-function baseline.** Per heat source a first-order response ``K / (tau s +
1)`` or a second-order one ``K / ((tau_1 s + 1)(tau_2 s + 1))`` (two lags in series, one
gain): the form practitioners fit per heat source.

**Simulation** is the exact zero-order-hold discretisation of each element (``x_{k+1} = phi x_k
+ (1 - phi) u_k``, ``phi = exp(-dt / tau)``, the matrix exponential of a diagonal system),
run by ``scipy.signal.lfilter`` on a uniform grid and step by step otherwise:
a 46 h recording at 15 s (11 115 samples) is simulated in well under a millisecond per element.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import least_squares
from scipy.signal import lfilter

from spindlebench.core.errors import SpindlebenchError

#: Kinds of structure: the grey-box network and the transfer-function forms.
KINDS = ("network", "tf1", "tf2")
#: Bounds of a heat-input exponent (P proportional to n^a).
EXPONENT_BOUNDS = (0.3, 3.0)
#: The shortest time constant, s (and at least two samples).
MIN_TAU_S = 60.0
#: The longest time constant, as a multiple of the training span: slower modes are ramps the
#: data cannot tell from a drift.
MAX_TAU_SPAN = 2.0
#: Successive time constants of a network differ at least by this factor.
MIN_TAU_RATIO = 2.0
#: Relative tolerance on a uniform time grid (else the step-by-step path is used).
UNIFORM_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Structure:
    """What is fitted: the kind, the order and which inputs drive the nodes."""

    kind: str = "network"
    n_nodes: int = 2
    speed_sources: int = 1  # heat sources of the speed, each with its own exponent
    linear_inputs: int = 0  # further heat inputs used as they are (e.g. |feed|)
    ambient: bool = False  # an ambient column drives every node
    initial: bool = False  # each node's initial temperature is fitted (else: at rest)
    exponent: float | None = None  # a fixed exponent for every speed source (None: fitted)
    basis: tuple[float, ...] = ()  # fixed exponents, one speed source each (replaces the above)
    tau_max_s: float = np.inf  # the longest time constant (``fit`` sets it from the data)

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise SpindlebenchError(f"model kind {self.kind!r}: choose one of {', '.join(KINDS)}")
        if self.kind == "network" and not 1 <= self.n_nodes <= 6:
            raise SpindlebenchError(f"n_nodes {self.n_nodes}: must be in [1, 6]")
        if self.speed_sources not in (1, 2):
            raise SpindlebenchError(f"speed_sources {self.speed_sources}: must be 1 or 2")

    @property
    def n_taus(self) -> int:
        if self.kind == "network":
            return self.n_nodes
        return {"tf1": 1, "tf2": 2}[self.kind] * (self.n_sources + self.linear_inputs)

    @property
    def n_sources(self) -> int:
        return len(self.basis) if self.basis else self.speed_sources

    @property
    def n_exponents(self) -> int:
        return 0 if self.exponent is not None or self.basis else self.speed_sources

    def taus_of(self, theta: np.ndarray) -> np.ndarray:
        """Time constants, s. A network's are ordered and at least ``MIN_TAU_RATIO`` apart
        (``theta`` holds the log of the fastest, then the log ratios): two nearly equal modes
        are one mode, and fitted as two they cancel with huge opposite weights."""
        head = np.asarray(theta[:self.n_taus], dtype=float)
        return np.minimum(np.exp(np.cumsum(head) if self.kind == "network" else head),
                          self.tau_max_s)

    def exponents_of(self, theta: np.ndarray) -> np.ndarray:
        """The speed sources' exponents: the fixed basis, the fixed one, or fitted."""
        if self.basis:
            return np.asarray(self.basis, dtype=float)
        if self.exponent is not None:
            return np.full(self.speed_sources, self.exponent)
        return np.asarray(theta[self.n_taus:], dtype=float)

    @property
    def label(self) -> str:
        if self.kind == "network":
            return f"network{self.n_nodes}"
        return self.kind


def lag(u: np.ndarray, tau_s: float, time_s: np.ndarray, x0: float = 0.0) -> np.ndarray:
    """Zero-order-hold response of ``dx/dt = (u - x) / tau`` sampled at ``time_s``.

    ``u`` is held from one sample to the next; ``x[0] = x0``. Exact for any step.
    """
    u = np.asarray(u, dtype=float)
    steps = np.diff(time_s)
    if steps.size == 0:
        return np.full(1, x0)
    dt = steps[0]
    if np.all(np.abs(steps - dt) <= UNIFORM_TOLERANCE * abs(dt)):
        phi = np.exp(-dt / tau_s)
        out, _ = lfilter([0.0, 1.0 - phi], [1.0, -phi], u, zi=[x0])
        out[0] = x0
        return out
    phis = np.exp(-steps / tau_s)
    out = np.empty(len(u))
    out[0] = x = x0
    for k, phi in enumerate(phis):
        x = phi * x + (1.0 - phi) * u[k]
        out[k + 1] = x
    return out


@dataclass(frozen=True)
class Inputs:
    """The driving signals of one recording on its time axis."""

    time_s: np.ndarray
    speed_rpm: np.ndarray
    linear: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))  # (k, N)
    ambient_C: np.ndarray | None = None  # noqa: N815

    def __len__(self) -> int:
        return len(self.time_s)


def heat_inputs(inputs: Inputs, exponents: np.ndarray, speed_ref: float) -> list[np.ndarray]:
    """Each source's normalised heat input: ``(n / n_ref)^a`` per speed source, then the
    linear inputs as they are."""
    ratio = np.clip(inputs.speed_rpm, 0.0, None) / speed_ref
    # exponent 0: the spindle-on indicator (a loss present whenever it turns), not 1 always
    out = [ratio ** a if a > 0 else (ratio > 0).astype(float) for a in exponents]
    out += list(np.atleast_2d(inputs.linear)) if inputs.linear.size else []
    return out


def design(structure: Structure, theta: np.ndarray, inputs: Inputs, speed_ref: float,
           initial: bool | None = None) -> np.ndarray:
    """The design matrix (N, p) of the linear output weights at nonlinear parameters
    ``theta`` (``log tau`` then exponents); the last column is the constant."""
    taus = structure.taus_of(theta)
    sources = heat_inputs(inputs, structure.exponents_of(theta), speed_ref)
    t = inputs.time_s
    columns: list[np.ndarray] = []
    if structure.kind == "network":
        for tau in taus:
            columns += [lag(u, tau, t) for u in sources]
            if structure.ambient:
                columns.append(lag(inputs.ambient_C - inputs.ambient_C[0], tau, t))
        if structure.initial if initial is None else initial:
            columns += [np.exp(-(t - t[0]) / tau) for tau in taus]
    else:
        per = 1 if structure.kind == "tf1" else 2
        for j, u in enumerate(sources):
            x = u
            for tau in taus[j * per:(j + 1) * per]:
                x = lag(x, tau, t)
            columns.append(x)
    columns.append(np.ones(len(t)))
    return np.column_stack(columns)


@dataclass
class FitResult:
    """A fitted structure: parameters, linear weights, their intervals and the fit."""

    structure: Structure
    theta: np.ndarray  # log tau, then exponents (if fitted)
    weights: np.ndarray  # (p, outputs)
    speed_ref: float
    theta_se: np.ndarray
    weights_se: np.ndarray
    theta_cov: np.ndarray
    rmse: np.ndarray  # per output, on the weighted samples
    cost: float
    evaluations: int
    status: str
    starts: int
    outputs: tuple[str, ...] = ()

    @property
    def taus_s(self) -> np.ndarray:
        return self.structure.taus_of(self.theta)

    @property
    def exponents(self) -> np.ndarray:
        return self.structure.exponents_of(self.theta)

    def predict(self, inputs: Inputs, initial: bool = False) -> np.ndarray:
        """Outputs (N, outputs) of the model on ``inputs``; from rest unless ``initial``
        (the fitted initial state belongs to the training recording only)."""
        X = design(self.structure, self.theta, inputs, self.speed_ref,
                   initial=initial and self.structure.initial)
        weights = self.weights if X.shape[1] == self.weights.shape[0] else \
            _drop_initial(self.structure, self.weights)
        return X @ weights

    def predict_all(self, inputs: Inputs | list[Inputs]) -> np.ndarray:
        """``predict`` of one recording or of several, stacked."""
        if isinstance(inputs, Inputs):
            return self.predict(inputs)
        return np.vstack([self.predict(part) for part in inputs])

    def tau_interval95(self) -> np.ndarray:
        """(n_taus, 2) 95 % intervals of the time constants (normal on log tau)."""
        n = self.structure.n_taus
        log_tau = np.log(self.taus_s)
        if self.structure.kind == "network":  # log tau = cumulative sum of theta's head
            L = np.tril(np.ones((n, n)))
            se = np.sqrt(np.clip(np.diag(L @ self.theta_cov[:n, :n] @ L.T), 0.0, None))
        else:
            se = self.theta_se[:n]
        return np.column_stack([np.exp(log_tau - 1.96 * se), np.exp(log_tau + 1.96 * se)])

    def to_dict(self) -> dict:
        s = self.structure
        out = {
            "kind": s.kind, "label": s.label, "n_nodes": s.n_nodes if s.kind == "network" else None,
            "speed_sources": s.speed_sources, "linear_inputs": s.linear_inputs,
            "ambient_input": s.ambient, "initial_state_fitted": s.initial,
            "speed_ref_rpm": self.speed_ref,
            "tau_s": self.taus_s.tolist(),
            "tau_s_interval95": self.tau_interval95().tolist(),
            "exponents": self.exponents.tolist(),
            "exponent_fixed": s.n_exponents == 0,
            "exponents_se": self.theta_se[s.n_taus:].tolist(),
            "outputs": list(self.outputs),
            "weights": self.weights.T.tolist(),
            "weights_se": self.weights_se.T.tolist(),
            "rmse": self.rmse.tolist(),
            "evaluations": self.evaluations, "status": self.status, "starts": self.starts,
        }
        return out


def _drop_initial(structure: Structure, weights: np.ndarray) -> np.ndarray:
    """The weights without the initial-state columns (they sit just before the constant)."""
    n = structure.n_taus
    keep = np.r_[0:weights.shape[0] - 1 - n, weights.shape[0] - 1]
    return weights[keep]


def effective_fraction(residuals: np.ndarray) -> float:
    """``(1 - rho) / (1 + rho)`` of the lag-1 autocorrelation ``rho`` of the residuals: the
    fraction of the samples that count as independent (model-error residuals of a slow
    thermal signal are strongly correlated; white-noise intervals would be far too narrow)."""
    r = residuals - residuals.mean()
    denominator = float(r @ r)
    if denominator <= 0 or len(r) < 3:
        return 1.0
    rho = float(np.clip(r[1:] @ r[:-1] / denominator, 0.0, 0.999))
    return (1.0 - rho) / (1.0 + rho)


def stacked_design(structure: Structure, theta: np.ndarray, inputs: Inputs | list[Inputs],
                   speed_ref: float) -> np.ndarray:
    """``design`` of one recording, or of several stacked (each simulated from its own
    first sample)."""
    if isinstance(inputs, Inputs):
        return design(structure, theta, inputs, speed_ref)
    return np.vstack([design(structure, theta, part, speed_ref) for part in inputs])


def concatenated(inputs: Inputs | list[Inputs]) -> Inputs:
    """Several recordings' inputs end to end (for the bounds and the reference speed)."""
    if isinstance(inputs, Inputs):
        return inputs
    return Inputs(np.concatenate([p.time_s for p in inputs]),
                  np.concatenate([p.speed_rpm for p in inputs]))


def fit(structure: Structure, inputs: Inputs | list[Inputs], outputs: np.ndarray,
        weight: np.ndarray | None = None,
        scales: np.ndarray | None = None, seed: int = 0, starts: int = 4,
        speed_ref: float | None = None, output_names: tuple[str, ...] = (),
        max_nfev: int = 200) -> FitResult:
    """Fit ``structure`` to ``outputs`` (N, m) on the samples where ``weight`` > 0.

    Variable projection: for each trial of the nonlinear parameters the output weights are the
    weighted linear least-squares solution, so ``least_squares`` (trust-region reflective,
    bounds on ``log tau`` and the exponents) sees only ``n_taus + n_exponents`` parameters.
    ``starts`` starting points (the first: time constants spread log-evenly; the others drawn
    from ``numpy.random.default_rng(seed)``): the same seed gives the same fit. ``scales``
    (m,) divides each output's residual (its noise or range), so outputs in K and um weigh
    alike. Intervals: the reduced Jacobian's Gauss-Newton covariance, with the residual
    variance inflated by the residuals' lag-1 autocorrelation (``effective_fraction``).
    """
    outputs = np.asarray(outputs, dtype=float)
    if outputs.ndim == 1:
        outputs = outputs[:, None]
    n_samples, m = outputs.shape
    weight = np.ones(n_samples) if weight is None else np.asarray(weight, dtype=float)
    use = (weight > 0) & np.all(np.isfinite(outputs), axis=1)
    if use.sum() < 10:
        raise SpindlebenchError(f"identification: {int(use.sum())} usable samples; need >= 10")
    scales = np.ones(m) if scales is None else np.asarray(scales, dtype=float)
    whole = concatenated(inputs)
    if speed_ref is None:
        speed_ref = float(np.max(whole.speed_rpm[use])) if use.any() else 0.0
    if not speed_ref > 0:
        raise SpindlebenchError("identification: the spindle never turns in the training "
                                "samples; the speed programme gives no heat input to fit")
    parts = [inputs] if isinstance(inputs, Inputs) else list(inputs)
    span = max(float(p.time_s[-1] - p.time_s[0]) for p in parts)
    dt = float(np.median(np.concatenate([np.diff(p.time_s) for p in parts])))
    tau_lo = max(MIN_TAU_S, 2.0 * dt)
    tau_hi = max(MAX_TAU_SPAN * span, 10.0 * tau_lo)
    structure = replace(structure, tau_max_s=tau_hi)
    n_taus, n_exp = structure.n_taus, structure.n_exponents
    lower = np.r_[np.full(n_taus, np.log(tau_lo)), np.full(n_exp, EXPONENT_BOUNDS[0])]
    upper = np.r_[np.full(n_taus, np.log(tau_hi)), np.full(n_exp, EXPONENT_BOUNDS[1])]
    network = structure.kind == "network"
    if network and n_taus > 1:  # log ratios of successive time constants
        lower[1:n_taus] = np.log(MIN_TAU_RATIO)
        upper[1:n_taus] = max(np.log(tau_hi / tau_lo), np.log(MIN_TAU_RATIO) + 1.0)
    sw = np.sqrt(weight[use])
    Y = outputs[use] / scales * sw[:, None]

    def solve(theta):
        X = stacked_design(structure, theta, inputs, speed_ref)[use] * sw[:, None]
        coef, *_ = np.linalg.lstsq(X, Y, rcond=None)
        return X, coef

    def residual(theta):
        X, coef = solve(theta)
        return (X @ coef - Y).ravel(order="F")

    rng = np.random.default_rng(seed)
    best = None
    evaluations = 0
    for start in range(max(1, starts)):
        if start == 0:
            log_taus = np.linspace(np.log(tau_lo) + 1.0, np.log(tau_hi) - 1.0, n_taus + 2)[1:-1] \
                if n_taus > 1 else np.array([0.5 * (np.log(tau_lo) + np.log(tau_hi))])
            exps = np.full(n_exp, 1.5)
        else:
            log_taus = np.sort(rng.uniform(np.log(tau_lo), np.log(tau_hi), n_taus))
            exps = rng.uniform(0.8, 2.5, n_exp)
        head = np.r_[log_taus[0], np.maximum(np.diff(log_taus), np.log(MIN_TAU_RATIO) + 0.1)] \
            if network else log_taus
        theta0 = np.clip(np.r_[head, exps], lower + 1e-9, upper - 1e-9)
        result = least_squares(residual, theta0, bounds=(lower, upper), method="trf",
                               x_scale="jac", max_nfev=max_nfev)
        evaluations += result.nfev
        if best is None or result.cost < best.cost - 1e-12 * abs(best.cost):
            best = result
    theta = best.x
    X, coef = solve(theta)
    resid = (X @ coef - Y)
    dof = max(1, resid.size - theta.size - coef.size)
    fraction = float(np.mean([effective_fraction(resid[:, j]) for j in range(m)]))
    sigma2 = float(np.sum(resid ** 2) / dof) / fraction
    J = best.jac
    theta_cov = sigma2 * np.linalg.pinv(J.T @ J)
    theta_se = np.sqrt(np.clip(np.diag(theta_cov), 0.0, None))
    xtx_inv = np.linalg.pinv(X.T @ X)
    per_output = np.array([np.sum(resid[:, j] ** 2) / max(1, len(resid) - X.shape[1])
                           / effective_fraction(resid[:, j]) for j in range(m)])
    weights_se = np.sqrt(np.outer(np.clip(np.diag(xtx_inv), 0, None), per_output)) * scales
    weights = coef * scales
    rmse = np.sqrt(np.mean((resid / sw[:, None]) ** 2, axis=0)) * scales
    status = "converged" if best.status > 0 else "evaluation limit"
    return FitResult(structure, theta, weights, speed_ref, theta_se, weights_se, theta_cov, rmse,
                     float(best.cost), evaluations, status, max(1, starts), tuple(output_names))


def run_starts(time_s: np.ndarray, speed_rpm: np.ndarray) -> list[int]:
    """Sample indices where the spindle switches on (0 -> > 0): the cycles of a programme."""
    on = np.asarray(speed_rpm) > 0
    return [int(i) + 1 for i in np.flatnonzero(~on[:-1] & on[1:])]


def blocks(time_s: np.ndarray, speed_rpm: np.ndarray, mask: np.ndarray,
           min_blocks: int = 3) -> list[np.ndarray]:
    """Contiguous blocks of the training samples ``mask`` for leave-one-block-out: one per
    heating/cooling cycle (cut at every switch-on), or ``min_blocks`` equal parts if the
    training samples hold fewer cycles."""
    index = np.flatnonzero(mask)
    cuts = [i for i in run_starts(time_s, speed_rpm) if index[0] < i <= index[-1]]
    parts = [p for p in np.split(index, np.searchsorted(index, cuts)) if p.size]
    # an idle stretch before the first switch-on is no cycle: part of the first one
    while len(parts) > 1 and parts[0].size < 0.25 * np.median([p.size for p in parts]):
        parts[:2] = [np.concatenate(parts[:2])]
    if len(parts) < min_blocks:
        parts = [p for p in np.array_split(index, min_blocks) if p.size]
    return parts


def rezeroed_rmse(predicted: np.ndarray, measured: np.ndarray) -> float:
    """RMSE of the change since the block's first sample (a probe zeroed at a run's start)."""
    ok = np.isfinite(measured)
    first = int(np.flatnonzero(ok)[0])
    p = predicted[ok] - predicted[first]
    y = measured[ok] - measured[first]
    return float(np.sqrt(np.mean((p - y) ** 2)))


def select_order(candidates: list[Structure], inputs: Inputs | list[Inputs],
                 outputs: np.ndarray,
                 mask: np.ndarray, seed: int = 0, starts: int = 2,
                 scales: np.ndarray | None = None) -> tuple[Structure, list[dict]]:
    """The candidate with the lowest mean held-out error, leave-one-block-out.

    Each block (``blocks``: a heating/cooling cycle of the training samples) is left out in
    turn: the structure is fitted on the other blocks (simulated through the whole recording,
    so the state carries over) and scored on the left-out block by the RMSE of the first
    output's change since the block's start (``rezeroed_rmse``, the validation protocol). The
    lowest mean wins; a higher order must beat a lower one by more than 2 % to be chosen.
    """
    if isinstance(inputs, Inputs):
        parts = blocks(inputs.time_s, inputs.speed_rpm, mask)
    else:  # several recordings: leave one recording out
        edges = np.cumsum([0] + [len(p) for p in inputs])
        parts = [np.flatnonzero(mask[a:b]) + a for a, b in itertools.pairwise(edges)]
        parts = [p for p in parts if p.size]
    rows = []
    y = np.asarray(outputs, dtype=float)
    y0 = y[:, 0] if y.ndim == 2 else y
    for structure in candidates:
        scores = []
        for part in parts:
            weight = mask.astype(float).copy()
            weight[part] = 0.0
            result = fit(structure, inputs, outputs, weight, scales=scales, seed=seed,
                         starts=starts)
            predicted = result.predict_all(inputs)[:, 0]
            scores.append(rezeroed_rmse(predicted[part], y0[part]))
        rows.append({"structure": structure.label, "held_out_rmse": scores,
                     "mean": float(np.mean(scores))})
    best = 0
    for i in range(1, len(rows)):
        if rows[i]["mean"] < 0.98 * rows[best]["mean"]:
            best = i
    return candidates[best], rows
