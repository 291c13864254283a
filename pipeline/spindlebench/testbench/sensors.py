"""The virtual data logger: true temperatures and drift → what the instruments record.

Temperatures get white Gaussian noise and the logger's quantisation (0.1 °C by default, like
the PT100/thermocouple loggers of thermal-error experiments). The displacement probe gets its
own noise and resolution and is zeroed at the first sample, as an eddy-current probe is set to
zero before the run. Faults make a sensor misbehave over a time window:

- ``dropout``: the logger records nothing → NaN (an empty CSV field). We chose NaN over holding
  the last value because a held value is indistinguishable from a stuck sensor and would hide
  the gap from the analysis; a consumer must decide how to treat missing data.
- ``stuck``: the reading freezes at ``value_C`` or, if not given, at the last good reading.
- ``offset``: a constant bias (a loose sensor, a calibration error).

Real logger residuals are not white: in the CAIVIAC recording the lag-1 autocorrelation is
about 0.86 for the temperatures and 0.985 for the displacement. ``noise_kind = "ar1"`` makes
each channel's noise an AR(1) process with that lag-1 coefficient (same stationary sigma as the
white noise); ``"random_walk"`` lets it wander (1 sigma ``noise_C`` after one hour). The probe's
zero can drift slowly: a random walk (``probe_drift_um_per_sqrt_h``) plus a constant creep
(``probe_drift_rate_um_per_h``), both zero at the first sample like the probe itself.

All randomness comes from one ``numpy.random.Generator`` seeded by the scenario's seed, drawn in
a fixed order (temperatures, then probe noise, then probe drift when there is one), so a seed
always gives the same recording, and white noise without drift is what it always was.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from scipy.signal import lfilter

from spindlebench.testbench.scenario import SensorFault, SensorModel


def quantise(values: np.ndarray, quantum: float) -> np.ndarray:
    """Round to the instrument's resolution; ``quantum = 0`` leaves values as they are.

    The second rounding removes binary noise (``0.30000000000000004``) so CSV text is short
    and stable.
    """
    if quantum <= 0:
        return values
    return np.round(np.round(values / quantum) * quantum, 10)


def _window(fault: SensorFault, time_s: np.ndarray) -> np.ndarray:
    """Samples a fault affects: from ``start_s`` up to (excluding) ``end_s``, or to the end."""
    window = time_s >= fault.start_s
    if fault.end_s is not None:
        window &= time_s < fault.end_s
    return window


def _sample_step_s(time_s: np.ndarray) -> float:
    return float(time_s[1] - time_s[0]) if time_s.size > 1 else 0.0


def coloured_noise(model: SensorModel, shocks: np.ndarray, time_s: np.ndarray) -> np.ndarray:
    """Noise (°C) of each channel from standard-normal ``shocks`` (n × m), per ``noise_kind``.

    ``ar1``: ``x[0] = sd ε[0]``, ``x[k] = φ x[k-1] + sqrt(1 - φ²) sd ε[k]`` (stationary, sd =
    ``noise_C``, φ = ``noise_lag1``). ``random_walk``: the cumulative sum of increments with
    sd ``noise_C · sqrt(Δt / 1 h)``, starting at ``noise_C · sqrt(Δt / 1 h) · ε[0]``.
    """
    if model.noise_kind == "white":
        return shocks * model.noise_C
    if model.noise_kind == "ar1":
        phi = model.noise_lag1
        scaled = shocks * model.noise_C
        scaled[1:] *= np.sqrt(1.0 - phi * phi)
        return lfilter([1.0], [1.0, -phi], scaled, axis=0)
    step = model.noise_C * np.sqrt(_sample_step_s(time_s) / 3600.0)
    return np.cumsum(shocks * step, axis=0)


def probe_drift_um(model: SensorModel, rng: np.random.Generator | None,
                   time_s: np.ndarray) -> np.ndarray:
    """The probe zero's slow drift (µm), 0 at the first sample; draws only if it wanders
    (``rng`` may be None where it does not)."""
    drift = model.probe_drift_rate_um_per_h * (time_s - time_s[0]) / 3600.0
    if model.probe_drift_um_per_sqrt_h > 0.0:
        steps = np.sqrt(np.diff(time_s) / 3600.0) * model.probe_drift_um_per_sqrt_h
        walk = np.concatenate(([0.0], np.cumsum(rng.standard_normal(steps.size) * steps)))
        drift = drift + walk
    return drift


#: Up to this many temperature draws (samples x sensors) a run's draws are kept for the next
#: measurement with its seed (``_draws``): a sweep's run is 181 x 20.
_CACHED_DRAWS = 50_000


def _drawn(seed: int, n: int, m: int) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """The standard-normal draws of ``measure`` in their order (temperatures (n, m), then the
    probe's (n)), read-only, and the generator's state after them (for the probe drift's)."""
    rng = np.random.default_rng(seed)
    temperature, probe = rng.standard_normal((n, m)), rng.standard_normal(n)
    temperature.setflags(write=False)
    probe.setflags(write=False)
    return temperature, probe, rng.bit_generator.state


@functools.lru_cache(maxsize=64)
def _draws(seed: int, n: int, m: int) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """``_drawn``, kept for the next measurement with the same seed and shape: a sweep
    measures each run's truth once per condition with one seed (common random numbers), and
    the draws and the generator made for them were half of ``measure``'s time (issue 26).
    64 runs of at most ``_CACHED_DRAWS`` draws: at most 26 MB."""
    return _drawn(seed, n, m)


def _generator_at(state: dict[str, Any]) -> np.random.Generator:
    """A generator continuing from ``state`` (a ``default_rng``'s, PCG64), as that one would."""
    bits = np.random.PCG64()
    bits.state = state
    return np.random.Generator(bits)


def measure(
    model: SensorModel,
    time_s: np.ndarray,
    true_temperatures_C: np.ndarray,
    true_drift_um: np.ndarray,
    sensor_names: tuple[str, ...],
    seed: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Measured temperatures ``(n, len(sensor_names))`` and measured drift ``(n,)``."""
    n, m = true_temperatures_C.shape
    temperature_shocks, probe_shocks, state = _draws(seed, n, m) if n * m <= _CACHED_DRAWS \
        else _drawn(seed, n, m)
    temperature_noise = coloured_noise(model, temperature_shocks, time_s)
    probe_noise = probe_shocks * model.probe_noise_um
    wanders = model.probe_drift_um_per_sqrt_h > 0.0
    probe_noise = probe_noise + probe_drift_um(model, _generator_at(state) if wanders else None,
                                               time_s)

    raw = true_temperatures_C + temperature_noise
    for fault in model.faults:
        if fault.kind == "offset":
            column = sensor_names.index(fault.sensor)
            raw[_window(fault, time_s), column] += fault.offset_C
    measured = quantise(raw, model.quantum_C)
    for fault in model.faults:
        column = sensor_names.index(fault.sensor)
        window = _window(fault, time_s)
        if not window.any():
            continue
        if fault.kind == "dropout":
            measured[window, column] = np.nan
        elif fault.kind == "stuck":
            if fault.value_C is not None:
                frozen = fault.value_C
            else:
                first = int(np.argmax(window))
                frozen = measured[first - 1, column] if first > 0 else measured[0, column]
            measured[window, column] = frozen

    probe = true_drift_um + probe_noise
    drift = quantise(probe - probe[0], model.probe_quantum_um)
    return measured, drift


#: The radial probes of the five-probe set-up, each measured like the axial probe.
RADIAL_PROBES = ("probe_X1_um", "probe_X2_um", "probe_Y1_um", "probe_Y2_um")


def measure_probes(
    model: SensorModel,
    time_s: np.ndarray,
    truth: dict[str, np.ndarray],
    probe_l_m: float,
    probe_end_offset_m: float,
    measured_drift_um: np.ndarray,
    seed: int,
) -> dict[str, np.ndarray]:
    """The five-probe channels as recorded: each radial probe with the axial probe's noise,
    drift and resolution, zeroed at the first sample; the Z probe is the measured
    ``drift_um``; the end-face drifts and the tilts follow from the radial probes as an
    evaluation would compute them (extrapolated over ``probe_end_offset_m``, divided by l).

    Its own generator (seeded by ``seed`` and the probe's index) leaves the draws of
    ``measure`` and hence every older recording unchanged."""
    readings: dict[str, np.ndarray] = {}
    for index, name in enumerate(RADIAL_PROBES):
        rng = np.random.default_rng([seed, 230, index])
        noise = rng.standard_normal(time_s.size) * model.probe_noise_um
        probe = truth[name] + noise + probe_drift_um(model, rng, time_s)
        readings[name] = quantise(probe - probe[0], model.probe_quantum_um)
    readings["probe_Z_um"] = measured_drift_um
    x1, x2 = readings["probe_X1_um"], readings["probe_X2_um"]
    y1, y2 = readings["probe_Y1_um"], readings["probe_Y2_um"]
    reach = probe_end_offset_m / probe_l_m
    readings["drift_x_um"] = x2 - (x1 - x2) * reach
    readings["drift_y_um"] = y2 - (y1 - y2) * reach
    readings["tilt_a_urad"] = (y1 - y2) / probe_l_m
    readings["tilt_b_urad"] = (x1 - x2) / probe_l_m
    return readings
