"""The same calibration as one sparse NLP for IPOPT (``calibrate --method ipopt``).

Simultaneous (full-discretisation) formulation: every state at every sample is a decision
variable, the trapezoidal steps are equality constraints, the objective is half the sum of the
squared whitened residuals and priors of ``problem.evaluate``. IPOPT gets exact sparse
derivatives from CasADi. It is kept as the reference against which the default reduced-space
Gauss-Newton is measured (``bench/bench_calibration.py``). The initial state's interpolation
is taken at the start values here (the reduced-space method updates it with the parameters).
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca
import numpy as np

from spindlebench.calibration.fitset import PRIOR_SD_LN
from spindlebench.calibration.mapping import INPUTS
from spindlebench.calibration.problem import (
    AMBIENT_LEVEL_SD_K,
    AMBIENT_STEP_SD_K,
    INITIAL_SD_K,
    Discretisation,
    Layout,
    initial_state,
    trajectory,
)
from spindlebench.calibration.series import Series
from spindlebench.formats.recording import AMBIENT_COLUMN


def _recording_terms(d: Discretisation, series: Series, s: ca.MX, tag: str,
                     guess: np.ndarray):
    """Symbols (shift, knots, offset), states, constraints, residuals and priors of one
    recording; the initial state is ``guess`` (fixed) plus the uniform shift."""
    n = series.intervals
    shift = ca.MX.sym(f"shift_{tag}", 1)
    z0 = ca.DM(guess) + shift
    Z = ca.MX.sym(f"Z_{tag}", d.n_x, n)
    basis = series.ambient_basis() if series.ambient_unknown else None
    knots = ca.MX.sym(f"a_{tag}", basis.shape[1] if basis is not None else 0)
    offset = ca.MX.sym(f"c_{tag}", 1 if any(c.kind == "error" for c in series.channels) else 0)
    U = ca.MX(ca.DM(np.nan_to_num(series.inputs)))
    if basis is not None:
        U[INPUTS.index(AMBIENT_COLUMN), :] = ca.mtimes(ca.DM(basis), knots).T
    states = ca.horzcat(z0, Z)
    h = ca.DM(np.diff(series.time_s)).T
    G = d.step.map(n)(states[:, :-1], states[:, 1:], U[:, :-1], h, s)
    Y = d.outputs.map(n + 1)(states, U, s)
    residuals = []
    for channel in series.channels:
        valid = np.flatnonzero(np.isfinite(channel.values))
        model = Y[d.output_index[channel.output], valid.tolist()]
        if channel.kind == "error":
            model = model + offset
        residuals.append((model.T - ca.DM(channel.values[valid])) / channel.noise)
    priors = [shift / INITIAL_SD_K]
    if basis is not None:
        priors.append((knots[0] - series.ambient_guess()) / AMBIENT_LEVEL_SD_K)
        if knots.numel() > 1:
            priors.append((knots[1:] - knots[:-1]) / AMBIENT_STEP_SD_K)
    return (shift, knots, offset), Z, ca.vec(G), ca.vertcat(*residuals), ca.vertcat(*priors)


def solve_ipopt(d: Discretisation, series_list: Sequence[Series], layout: Layout,
                theta0: np.ndarray, max_iter: int, verbose: bool
                ) -> tuple[np.ndarray, int, str]:
    """IPOPT on the full discretisation, started from the states simulated at ``theta0``."""
    s = ca.MX.sym("s", layout.n_s)
    free, dependent, constraints, residuals, priors = [s], [], [], [], [s / PRIOR_SD_LN]
    start_states = []
    for i, series in enumerate(series_list):
        shift, knots, _ = layout.blocks[i]
        z0 = initial_state(d, series, theta0[: layout.n_s], 0.0, theta0[knots])
        symbols, Z, G, r, prior = _recording_terms(d, series, s, str(i), z0)
        free += list(symbols)
        dependent.append(ca.vec(Z))
        constraints.append(G)
        residuals.append(r)
        priors.append(prior)
        states, _ = trajectory(d, series, z0 + theta0[shift][0], theta0[: layout.n_s],
                               theta0[knots], sensitivities=False)
        start_states.append(states[:, 1:].T.ravel())  # vec() is column-major: sample by sample
    w = ca.vertcat(*free, *dependent)
    objective = 0.5 * (ca.sumsqr(ca.vertcat(*residuals)) + ca.sumsqr(ca.vertcat(*priors)))
    n_free = layout.size
    lbw = np.full(w.numel(), -np.inf)
    ubw = np.full(w.numel(), np.inf)
    lbw[: layout.n_s], ubw[: layout.n_s] = d.log_bounds()
    solver = ca.nlpsol("calibration", "ipopt", {"x": w, "f": objective,
                                                "g": ca.vertcat(*constraints)}, {
        "ipopt.print_level": 5 if verbose else 0, "print_time": False, "ipopt.sb": "yes",
        "ipopt.max_iter": max_iter, "ipopt.tol": 1e-8,
    })
    solution = solver(x0=np.concatenate([theta0, *start_states]), lbx=lbw, ubx=ubw,
                      lbg=0.0, ubg=0.0)
    stats = solver.stats()
    theta = np.asarray(solution["x"]).ravel()[:n_free]
    return theta, int(stats.get("iter_count", -1)), str(stats.get("return_status"))
