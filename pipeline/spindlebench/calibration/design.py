"""``calibrate --design``: which excitation would separate the parameters a recording could not.

For each candidate programme (speed steps, a heating/cool-down cycle, feed only, an ambient
step, short on/off cycles; as long as the recording, at most 8 h) the calibrated model is
simulated with the recording's own channels and noise, and the Fisher information of the
log-factors it would add, ``J^T J`` of the whitened outputs, is added to what the recordings
gave (the inverse of the fitted covariance).
A candidate is ranked by the strongest correlation left among the pairs that came out
correlated (lower is better), then by the mean reduction of the parameters' standard
deviations. It is a local (linearised) prediction at the fitted values.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np

from spindlebench.calibration.mapping import INPUTS
from spindlebench.calibration.problem import Discretisation, Fit, ambient_series, trajectory
from spindlebench.calibration.series import Series
from spindlebench.formats.recording import AMBIENT_COLUMN

#: Candidates last as long as the first recording, at most this long.
MAX_CANDIDATE_HOURS = 8.0
CORRELATED = 0.8
Programme = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


def _programmes(rpm: float, feed: float) -> dict[str, tuple[str, Programme]]:
    """name -> (description, x -> (speed, feed, ambient offset)), x = time / duration."""
    zero = np.zeros_like

    def steps(x):
        return (np.select([x < 0.25, x < 0.5, x < 0.75], [0.5 * rpm, rpm, 1.5 * rpm], 0.0),
                zero(x), zero(x))

    def cycle(x):
        return np.where(x < 0.5, rpm, 0.0), zero(x), zero(x)

    def feed_only(x):
        return zero(x), np.where(x < 0.5, feed, 0.0), zero(x)

    def ambient_step(x):
        return zero(x), zero(x), np.where(x >= 0.125, 5.0, 0.0)

    def on_off(x):
        return np.where((x * 4) % 1 < 0.5, rpm, 0.0), zero(x), zero(x)

    return {
        "speed-steps": (f"{0.5 * rpm:g} / {rpm:g} / {1.5 * rpm:g} rpm, a quarter each, then off",
                        steps),
        "heat-cool": (f"{rpm:g} rpm for half the time, then cool-down", cycle),
        "feed-only": (f"X and Y at {feed:g} mm/min for half the time, spindle off", feed_only),
        "ambient-step": ("machine off, room 5 K warmer after an eighth of the time",
                         ambient_step),
        "on-off": (f"four on/off cycles at {rpm:g} rpm", on_off),
    }


def _candidate(series: Series, ambient_C: float, programme: Programme) -> Series:
    step_s = float(np.median(np.diff(series.time_s)))
    duration_s = min(series.time_s[-1] - series.time_s[0], MAX_CANDIDATE_HOURS * 3600.0)
    time_s = np.arange(0.0, duration_s + step_s / 2, step_s)
    speed, feed, ambient = programme(time_s / duration_s)
    inputs = np.vstack([speed, feed, feed, ambient_C + ambient])
    channels = tuple(replace(c, values=np.full(len(time_s), np.nan)) for c in series.channels)
    return replace(series, name="candidate", time_s=time_s, inputs=inputs, channels=channels,
                   ambient_unknown=False)


def _information(d: Discretisation, candidate: Series, s: np.ndarray) -> np.ndarray:
    """Fisher information of the log-factors from the candidate's channels."""
    ambient0 = float(candidate.inputs[INPUTS.index(AMBIENT_COLUMN), 0])
    z0 = np.full(d.n_x, ambient0)
    states, S = trajectory(d, candidate, z0, s, np.zeros(0))
    names = [c.output for c in candidate.channels]
    n1 = candidate.intervals + 1
    _, Dx, Ds, _ = (np.asarray(v) for v in d.output_derivatives(names).map(n1)(
        states, candidate.inputs, s))
    Dx = Dx.reshape(len(names), n1, d.n_x)
    Ds = Ds.reshape(len(names), n1, len(s))
    information = np.zeros((len(s), len(s)))
    for c, channel in enumerate(candidate.channels):
        J = np.einsum("kx,kxt->kt", Dx[c], S[:, :, : len(s)]) + Ds[c]
        if channel.kind == "error":  # the probe's free offset: only changes carry information
            J = J - J.mean(axis=0)
        information += J.T @ J / channel.noise**2
    return information


def rank_excitations(d: Discretisation, fit: Fit, series_list: Sequence[Series]) -> dict:
    """Candidates ranked by how well they would separate the correlated parameters."""
    series = series_list[0]
    rpm = float(np.max(series.inputs[0])) or 4000.0
    feed = float(np.max(series.inputs[1])) or 1500.0
    ambient_C = float(np.mean(ambient_series(series, fit.knots(0))))
    s = fit.log_factors
    current = np.linalg.pinv(fit.covariance)
    sd_now = fit.sd_ln
    n = len(fit.fit)
    pairs = [(i, j) for i in range(n) for j in range(i) if abs(fit.correlation[i, j]) >= CORRELATED]
    rows = []
    for name, (description, programme) in _programmes(rpm, feed).items():
        added = _information(d, _candidate(series, ambient_C, programme), s)
        covariance = np.linalg.pinv(current + added)
        sd = np.sqrt(np.diag(covariance))
        correlation = covariance / np.outer(sd, sd)
        worst = max((abs(correlation[i, j]) for i, j in pairs), default=0.0)
        rows.append({
            "excitation": name, "description": description,
            "max_abs_correlation_of_pairs": float(worst),
            "pairs": {f"{fit.fit[i]}~{fit.fit[j]}": round(float(correlation[i, j]), 3)
                      for i, j in pairs},
            "sd_reduction": float(np.mean(1 - sd / sd_now)),
        })
    rows.sort(key=lambda r: (r["max_abs_correlation_of_pairs"], -r["sd_reduction"]))
    return {
        "correlated_pairs": {f"{fit.fit[i]}~{fit.fit[j]}": round(float(fit.correlation[i, j]), 3)
                             for i, j in pairs},
        "candidates": rows,
    }


def design_lines(ranking: dict) -> list[str]:
    """The ranking as printed lines."""
    pairs = ranking["correlated_pairs"]
    if not pairs:
        lines = [f"design: no pair of parameters is correlated beyond |r| = {CORRELATED:g}; "
                 "excitations ranked by the mean reduction of the standard deviations"]
    else:
        lines = ["design: correlated now: " + ", ".join(f"{k} {v:+.2f}" for k, v in pairs.items())]
    for rank, row in enumerate(ranking["candidates"], 1):
        worst = row["max_abs_correlation_of_pairs"]
        lines.append(f"  {rank}. {row['excitation']} ({row['description']}): worst |r| "
                     f"{worst:.2f}, sd -{100 * row['sd_reduction']:.0f} %")
    return lines
