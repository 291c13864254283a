"""Fingerprint of a thermal-error recording: the shape statistics that tell machines apart.

Real spindles drift fast, level off and fall back while most sensors keep climbing, so no single
sensor follows the error but a difference of a fast and a slow one does; a machine whose error
simply follows the ambient has one sensor that predicts it alone. These few numbers (defined in
issue 9, the JSON keys are the names below) separate the two regimes and compare a synthetic
machine with a real one:

- ``best_raw_psi``: max over sensors of ``|r(dT_j, e)|`` (Pearson); ``best_single_r2`` its square;
- ``best_diff_psi``: max over pairs ``i < j`` of ``|r(dT_i - dT_j, e)|``;
- ``best_pair_r2``: max over pairs of the R² of the OLS fit ``e ~ 1 + dT_i + dT_j``;
- ``t63_ratio``: ``t63(e)`` over the median ``t63`` of the sensors that rise by at least 0.1 K;
- ``t63_fastest_ratio``: ``t63(e)`` over the smallest ``t63`` of those sensors (issue 20: in real
  spindles the error settles before the fastest sensor, 0.44-0.90 of its time, because it is
  driven by the shaft and the rotor, which no sensor touches);
- ``overshoot``: ``max(s * smooth(e)) / |final(e)|`` with ``s = sign(final(e))``;
- ``early_fraction``: ``smooth(e)[floor(0.1 (n - 1))] / final(e)``.

Rises are ``dT = T - T[0]`` and ``e = y - y[0]``; ``smooth`` is a centred moving mean over
``w = max(3, n // 50)`` samples (shrinking at the edges), ``final`` the mean of the smoothed
signal over the last ``max(1, n // 20)`` samples. Sensors whose rise has zero variance are left
out. ``t63(x)`` is the time of the first sample whose smoothed rise reaches 63.2 % of the final
rise; for a falling signal "reaches" is taken in the direction of the rise (the definition read
literally would give the first sample for every falling signal). In ``t63_ratio`` the times are
counted from the first sample, so a recording whose clock does not start at 0 gets the same ratio.
"""

from __future__ import annotations

import math

import numpy as np

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import FINGERPRINT_KEYS

#: The statistics, in the order they are reported (also the JSON keys); named in
#: ``core.names`` because a machine file's fingerprint targets (``machines.variants``) name them.
KEYS = FINGERPRINT_KEYS
RISE_FRACTION = 0.632
#: Sensors rising less than this (K, final minus first smoothed value) have no t63.
MIN_SENSOR_RISE_K = 0.1


def smooth(x: np.ndarray) -> np.ndarray:
    """Centred moving mean over ``max(3, n // 50)`` samples, the window shrinking at the edges."""
    x = np.asarray(x, dtype=float)
    n = x.size
    half = max(3, n // 50) // 2
    cumulative = np.concatenate(([0.0], np.cumsum(x)))
    index = np.arange(n)
    lo = np.maximum(0, index - half)
    hi = np.minimum(n - 1, index + half) + 1
    return (cumulative[hi] - cumulative[lo]) / (hi - lo)


def final(x: np.ndarray) -> float:
    """Mean of ``smooth(x)`` over the last ``max(1, n // 20)`` samples."""
    smoothed = smooth(x)
    return float(smoothed[-max(1, smoothed.size // 20):].mean())


def t63(time_s: np.ndarray, x: np.ndarray) -> float:
    """Time of the first sample whose smoothed rise reaches 63.2 % of the final rise."""
    smoothed = smooth(x)
    rise = final(x) - smoothed[0]
    if rise == 0.0:
        return math.nan
    direction = math.copysign(1.0, rise)
    reached = np.flatnonzero(direction * (smoothed - smoothed[0]) >= RISE_FRACTION * abs(rise))
    return float(np.asarray(time_s, dtype=float)[reached[0]]) if reached.size else math.nan


def _correlations(columns: np.ndarray, target: np.ndarray) -> np.ndarray:
    """|Pearson r| of every column of ``columns`` (n x k) with ``target``."""
    a = columns - columns.mean(axis=0)
    b = target - target.mean()
    denominator = np.sqrt((a * a).sum(axis=0) * (b * b).sum())
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.abs(a.T @ b) / denominator
    return np.where(denominator > 0, r, 0.0)


def _best_pair_r2(gram: np.ndarray, cross: np.ndarray, total: float) -> float:
    """Largest R² of ``e ~ 1 + dT_i + dT_j`` over all pairs (closed form on centred data:
    ``gram`` = AᵀA and ``cross`` = Aᵀb of the centred rises A and error b, ``total`` = bᵀb)."""
    if total == 0.0:
        return math.nan
    best = 0.0
    m = gram.shape[0]
    for i in range(m):
        for j in range(i + 1, m):
            g = gram[np.ix_([i, j], [i, j])]
            c = cross[[i, j]]
            coef, *_ = np.linalg.lstsq(g, c, rcond=None)
            best = max(best, float(coef @ c) / total)
    return min(best, 1.0)


def _best_diff_psi(gram: np.ndarray, cross: np.ndarray, total: float) -> float:
    """Largest ``|r(dT_i - dT_j, e)|`` over pairs ``i < j``, from the m x m Gram matrix.

    On centred data, cov(a_i - a_j, b) = c_i - c_j and var(a_i - a_j) = G_ii + G_jj - 2 G_ij,
    so no n x m(m-1)/2 matrix of differences is formed (it took ~5 KB per sample for 20
    sensors: 5 GB for 10^6 samples). A difference without variance of its own (two equal
    sensors, up to rounding) has r = 0, as a constant column has."""
    if total == 0.0:
        return 0.0
    diagonal = np.diag(gram)
    upper = np.triu_indices(gram.shape[0], 1)
    variance = (diagonal[:, None] + diagonal[None, :] - 2.0 * gram)[upper]
    scale = (diagonal[:, None] + diagonal[None, :])[upper]
    numerator = np.abs(cross[:, None] - cross[None, :])[upper]
    usable = variance > 1e-12 * scale
    r = numerator[usable] / np.sqrt(variance[usable] * total)
    return min(float(r.max()), 1.0) if r.size else 0.0


def fingerprint(time_s: np.ndarray, temps_2d: np.ndarray, error: np.ndarray) -> dict[str, float]:
    """The fingerprint statistics of one recording (keys :data:`KEYS`).

    ``time_s`` (n), ``temps_2d`` (n x m temperatures in any offset unit), ``error`` (n, the
    thermal error in any length unit).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(100.0)
    >>> temps = np.column_stack([1 - np.exp(-t / 10), t / 100])
    >>> stats = fingerprint(t, temps, 1 - np.exp(-t / 10))
    >>> round(stats["best_raw_psi"], 6)
    1.0
    """
    time_s = np.asarray(time_s, dtype=float)
    temps = np.asarray(temps_2d, dtype=float)
    y = np.asarray(error, dtype=float)
    if temps.ndim == 1:
        temps = temps[:, None]
    n = time_s.size
    if temps.ndim != 2 or temps.shape[0] != n or y.shape != (n,):
        raise SpindlebenchError(
            f"fingerprint: time ({n}), temperatures {temps.shape} and error {y.shape} must have "
            "the same number of samples"
        )
    if n < 3:
        raise SpindlebenchError(f"fingerprint: needs at least 3 samples, got {n}")
    if not (np.isfinite(time_s).all() and np.isfinite(temps).all() and np.isfinite(y).all()):
        raise SpindlebenchError("fingerprint: time, temperatures and error must be finite")
    rises = temps - temps[0]
    rises = rises[:, rises.var(axis=0) > 0]
    e = y - y[0]
    m = rises.shape[1]
    if m == 0:
        raise SpindlebenchError("fingerprint: no temperature column rises (all constant)")
    raw = _correlations(rises, e)
    best_raw = float(raw.max())
    if m > 1:
        centred = rises - rises.mean(axis=0)
        b = e - e.mean()
        gram, cross, total = centred.T @ centred, centred.T @ b, float(b @ b)
        del centred
        best_diff = _best_diff_psi(gram, cross, total)
        best_pair = _best_pair_r2(gram, cross, total)
    else:
        best_diff = best_pair = math.nan
    elapsed = time_s - time_s[0]  # a ratio of t63s is one of durations, wherever the clock began
    sensor_t63 = [
        t63(elapsed, rises[:, j])
        for j in range(m)
        if abs(final(rises[:, j]) - smooth(rises[:, j])[0]) >= MIN_SENSOR_RISE_K
    ]
    sensor_t63 = [value for value in sensor_t63 if math.isfinite(value)]
    error_t63 = t63(elapsed, e)
    median_t63 = float(np.median(sensor_t63)) if sensor_t63 else math.nan
    t63_ratio = error_t63 / median_t63 if median_t63 > 0 else math.nan
    fastest_t63 = min(sensor_t63) if sensor_t63 else math.nan
    t63_fastest_ratio = error_t63 / fastest_t63 if fastest_t63 > 0 else math.nan
    smoothed = smooth(e)
    final_e = final(e)
    if final_e == 0.0:
        overshoot = early = math.nan
    else:
        sign = math.copysign(1.0, final_e)
        overshoot = float((sign * smoothed).max()) / abs(final_e)
        early = float(smoothed[math.floor(0.1 * (n - 1))]) / final_e
    return {
        "best_raw_psi": best_raw,
        "best_single_r2": best_raw**2,
        "best_diff_psi": best_diff,
        "best_pair_r2": best_pair,
        "t63_ratio": float(t63_ratio),
        "t63_fastest_ratio": float(t63_fastest_ratio),
        "overshoot": overshoot,
        "early_fraction": early,
    }
