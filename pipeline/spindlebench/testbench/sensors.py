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

All randomness comes from one ``numpy.random.Generator`` seeded by the scenario's seed, drawn in
a fixed order (temperatures, then probe), so a seed always gives the same recording.
"""

from __future__ import annotations

import numpy as np

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


def measure(
    model: SensorModel,
    time_s: np.ndarray,
    true_temperatures_C: np.ndarray,
    true_drift_um: np.ndarray,
    sensor_names: tuple[str, ...],
    seed: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Measured temperatures ``(n, len(sensor_names))`` and measured drift ``(n,)``."""
    rng = np.random.default_rng(seed)
    n, m = true_temperatures_C.shape
    temperature_noise = rng.standard_normal((n, m)) * model.noise_C
    probe_noise = rng.standard_normal(n) * model.probe_noise_um

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
