"""Model-based compensation: a steady-state Kalman filter on an identified model.

The identified network (``model``, fitted to the error *and* the selected sensors, which share
its nodes) predicts every output from the speed programme; what it cannot predict is mostly
the room and other unmeasured heat, which moves the sensors and the error together. The
observer's state is the network's node states plus ``disturbances`` random-walk states whose
effect on each output is the leading principal direction of the training residuals (the
sensors' and the error's misfit, each scaled by its spread): the unknown room identified from
the data. At run time the filter reads the speed and the sensors (never the error) and
predicts the error as its output row of the estimated state.

Noise covariances from the training data: the disturbances' process noise is the variance of
their steps along the training residuals, each sensor's measurement noise the variance its
residual keeps after the disturbances are taken out, and the node states' process noise
``q`` (one scale, proportional to each state's stationary variance) the value of a
log-spaced grid that maximises the innovations' Gaussian likelihood on the training samples.

Why SciPy's ``solve_discrete_are`` and not ``filterpy`` or ``python-control``: a steady-state
gain is one discrete algebraic Riccati equation (what ``control.dlqe`` itself solves with
SciPy/slycot) and ``filterpy`` runs a time-varying filter step by step; neither adds anything
the one SciPy call does not, and neither is pinned here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm, solve_discrete_are

from spindlebench.core.errors import SpindlebenchError
from spindlebench.identification.model import FitResult, Inputs, heat_inputs

#: The grid of the node-state process-noise scale (fraction of a state's variance per step).
Q_GRID = np.logspace(-9, -1, 9)


def discretise(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretisation by one matrix exponential of ``[[A, B], [0, 0]] dt``."""
    n, m = B.shape
    block = np.zeros((n + m, n + m))
    block[:n, :n] = A
    block[:n, n:] = B
    E = expm(block * dt)
    return E[:n, :n], E[:n, n:]


def kalman_gain(A: np.ndarray, H: np.ndarray, Q: np.ndarray, R: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """Steady-state Kalman gain ``K`` (filtered form) and prior covariance ``P`` of
    ``x' = A x + w`` (cov Q), ``y = H x + v`` (cov R): ``P`` solves the filter DARE."""
    P = solve_discrete_are(A.T, H.T, Q, R)
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    return K, P


def network_state_space(fitted: FitResult) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """Continuous ``A``, ``B`` of the fitted network's node states (one per design column
    except the constant): every state is a lag ``dz/dt = (u - z) / tau`` of one source.
    Returns A, B (states x sources) and each state's source index."""
    s = fitted.structure
    if s.kind != "network" or s.initial or s.ambient:
        raise SpindlebenchError("the observer needs a network model driven by the speed "
                                "(no ambient column, no fitted initial state)")
    n_sources = s.n_sources + s.linear_inputs
    taus = fitted.taus_s
    source = [j for _ in taus for j in range(n_sources)]
    rates = np.repeat(1.0 / taus, n_sources)
    A = np.diag(-rates)
    B = np.zeros((len(rates), n_sources))
    B[np.arange(len(rates)), source] = rates
    return A, B, source


@dataclass
class SteadyStateObserver:
    """The filter's matrices and what it was tuned to (see the module docstring)."""

    Ad: np.ndarray
    Bd: np.ndarray
    H: np.ndarray  # sensors x states
    sensor_offset: np.ndarray
    error_row: np.ndarray
    error_offset: float
    K: np.ndarray
    q: float
    log_likelihood: float
    fitted: FitResult
    dt: float

    def run(self, inputs: Inputs, sensors: np.ndarray) -> np.ndarray:
        """Predicted error at each sample from the speed and the sensors (N, k)."""
        return filter_states(self, inputs, sensors)[0]


def _sources(fitted: FitResult, inputs: Inputs) -> np.ndarray:
    return np.column_stack(heat_inputs(inputs, fitted.exponents, fitted.speed_ref))


def filter_states(obs: SteadyStateObserver, inputs: Inputs, sensors: np.ndarray,
                  return_states: bool = False) -> tuple[np.ndarray, ...]:
    """(error predictions, innovations[, filtered states]) of the steady-state filter over a
    recording."""
    steps = np.diff(inputs.time_s)
    if steps.size and np.max(np.abs(steps - obs.dt)) > 1e-6 * obs.dt:
        raise SpindlebenchError(f"the observer needs the training sample step ({obs.dt:g} s) "
                                "throughout the recording")
    U = _sources(obs.fitted, inputs)
    Y = np.asarray(sensors, dtype=float) - obs.sensor_offset
    n = obs.Ad.shape[0]
    x = np.zeros(n)
    errors = np.empty(len(U))
    innovations = np.empty_like(Y)
    states = np.empty((len(U), n)) if return_states else None
    Ad, Bd, H, K, c = obs.Ad, obs.Bd, obs.H, obs.K, obs.error_row
    for k in range(len(U)):
        nu = Y[k] - H @ x
        if np.all(np.isfinite(nu)):
            x = x + K @ nu
        else:
            nu = np.where(np.isfinite(nu), nu, 0.0)
        innovations[k] = nu
        errors[k] = c @ x
        if states is not None:
            states[k] = x
        x = Ad @ x + Bd @ U[k]
    if states is not None:
        return errors + obs.error_offset, innovations, states
    return errors + obs.error_offset, innovations


def build_observer(fitted: FitResult, inputs: Inputs, outputs: np.ndarray, mask: np.ndarray,
                   disturbances: int = 1, q_grid: np.ndarray = Q_GRID,
                   refit_readout: bool = True) -> SteadyStateObserver:
    """The observer of a network ``fitted`` to ``outputs`` (N, 1 + k: the error, then the
    sensors) on the training samples ``mask``; noise covariances from those samples."""
    A, B, _ = network_state_space(fitted)
    dt = float(np.median(np.diff(inputs.time_s)))
    Ad_nodes, Bd_nodes = discretise(A, B, dt)
    weights = fitted.weights  # (states + 1, outputs); last row the constant
    W, offsets = weights[:-1], weights[-1]
    predicted = fitted.predict(inputs)
    resid = (outputs - predicted)[mask]
    resid = resid[np.all(np.isfinite(resid), axis=1)]
    spread = resid.std(axis=0)
    spread[spread == 0] = 1.0
    Z = (resid - resid.mean(axis=0)) / spread
    _, _, Vt = np.linalg.svd(Z, full_matrices=False)
    r = int(np.clip(disturbances, 0, Z.shape[1] - 1))
    loadings = (Vt[:r].T * spread[:, None]) if r else np.zeros((Z.shape[1], 0))  # outputs x r
    scores = np.linalg.lstsq(loadings[1:], (resid - resid.mean(axis=0))[:, 1:].T,
                             rcond=None)[0].T if r else np.zeros((len(resid), 0))
    q_dist = np.var(np.diff(scores, axis=0), axis=0) if r else np.zeros(0)
    sensor_resid = (resid - resid.mean(axis=0))[:, 1:] - scores @ loadings[1:].T
    R = np.diag(np.maximum(np.var(sensor_resid, axis=0), 1e-6))
    n_nodes = Ad_nodes.shape[0]
    Ad = np.eye(n_nodes + r)
    Ad[:n_nodes, :n_nodes] = Ad_nodes
    Bd = np.vstack([Bd_nodes, np.zeros((r, Bd_nodes.shape[1]))])
    H = np.hstack([W[:, 1:].T, loadings[1:]])
    error_row = np.r_[W[:, 0], loadings[0]]
    states = np.column_stack(heat_inputs(inputs, fitted.exponents, fitted.speed_ref))
    node_var = np.var(_node_trajectories(Ad_nodes, Bd_nodes, states[mask]), axis=0) + 1e-12
    phi2 = np.diag(Ad_nodes) ** 2
    best = None
    for q in q_grid:
        Q = np.diag(np.r_[q * node_var * (1 - phi2), np.maximum(q_dist, 1e-12)])
        try:
            K, P = kalman_gain(Ad, H, Q, R)
        except np.linalg.LinAlgError:  # no stabilising solution at this scale: next one
            continue
        obs = SteadyStateObserver(Ad, Bd, H, offsets[1:], error_row, float(offsets[0]), K,
                                  float(q), float("nan"), fitted, dt)
        _, nu = filter_states(obs, inputs, outputs[:, 1:])
        S = H @ P @ H.T + R
        _, logdet = np.linalg.slogdet(S)
        nu = nu[mask]
        ll = -0.5 * (len(nu) * logdet + np.einsum("ij,jk,ik->", nu, np.linalg.inv(S), nu))
        if best is None or ll > best.log_likelihood:
            obs.log_likelihood = float(ll)
            best = obs
    if best is None:
        raise ObserverError(
            f"observer: no process-noise scale in {q_grid[0]:g} .. {q_grid[-1]:g} gives a "
            f"steady-state Kalman filter for {n_nodes} node(s) and {r} disturbance(s) (the "
            "Riccati equation has eigenvalues on the unit circle: a disturbance the sensors "
            "cannot see); use fewer disturbances or train on more cycles")
    if refit_readout:
        _refit_readout(best, inputs, outputs, mask)
    return best


class ObserverError(SpindlebenchError):
    """No steady-state filter exists for a structure on these training data."""


def _refit_readout(obs: SteadyStateObserver, inputs: Inputs, outputs: np.ndarray,
                   mask: np.ndarray) -> None:
    """The error's row of the filtered state by least squares on the training samples.

    The network's error row was fitted to the speed-driven part of the error; what the
    filter adds from the sensors (the disturbances, the node states moved by them) reaches
    the error with weights only the training error itself can tell. Few weights (states + 1),
    so this is far stiffer than a regression on every sensor.
    """
    states = filter_states(obs, inputs, outputs[:, 1:], return_states=True)[2]
    ok = mask & np.isfinite(outputs[:, 0])
    A = np.column_stack([states[ok], np.ones(int(ok.sum()))])
    coef, *_ = np.linalg.lstsq(A, outputs[ok, 0], rcond=None)
    obs.error_row = coef[:-1]
    obs.error_offset = float(coef[-1])


def _node_trajectories(Ad: np.ndarray, Bd: np.ndarray, U: np.ndarray) -> np.ndarray:
    x = np.zeros(Ad.shape[0])
    out = np.empty((len(U), Ad.shape[0]))
    a = np.diag(Ad)
    for k in range(len(U)):
        out[k] = x
        x = a * x + Bd @ U[k]
    return out
