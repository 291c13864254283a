"""``measure`` keeps a run's draws for the next measurement with its seed (issue 26): every
reading is the one a fresh generator gives, for each noise kind, a wandering probe, faults,
repeated and interleaved measurements, and runs too long to keep."""

import numpy as np
import pytest
from spindlebench.testbench import sensors
from spindlebench.testbench.scenario import SensorFault, SensorModel
from spindlebench.testbench.sensors import coloured_noise, measure, probe_drift_um, quantise

NAMES = tuple(f"T{i}" for i in range(1, 21))


def truth(n):
    time_s = np.arange(n) * 120.0
    temperatures = 20.0 + np.outer(np.linspace(0.0, 5.0, n), np.linspace(1.0, 2.0, 20))
    return time_s, temperatures, np.linspace(3.0, 40.0, n)


def measure_afresh(model, time_s, temperatures, drift, seed):
    """``measure`` as it was: one new generator per call, drawn in the documented order
    (its faults left to ``measure`` itself, checked with the fault-free readings)."""
    rng = np.random.default_rng(seed)
    n, m = temperatures.shape
    noise = coloured_noise(model, rng.standard_normal((n, m)), time_s)
    probe = rng.standard_normal(n) * model.probe_noise_um + probe_drift_um(model, rng, time_s)
    probe = drift + probe
    return (quantise(temperatures + noise, model.quantum_C),
            quantise(probe - probe[0], model.probe_quantum_um))


MODELS = [
    SensorModel(noise_C=0.05, quantum_C=0.1, probe_noise_um=0.3, probe_quantum_um=0.1),
    SensorModel(noise_C=0.2, quantum_C=0.0, noise_kind="ar1", noise_lag1=0.86),
    SensorModel(noise_C=0.2, noise_kind="random_walk", probe_drift_um_per_sqrt_h=0.4,
                probe_drift_rate_um_per_h=0.1),
]


@pytest.mark.parametrize("n", [181, sensors._CACHED_DRAWS // 20 + 1])
def test_kept_draws_give_the_readings_of_a_fresh_generator(n):
    time_s, temperatures, drift = truth(n)
    sensors._draws.cache_clear()
    for _ in range(2):  # the second round measures from the kept draws
        for seed in (11, 12):
            for model in MODELS:
                measured, probe = measure(model, time_s, temperatures.copy(), drift, NAMES,
                                          seed)
                expected, expected_probe = measure_afresh(model, time_s, temperatures, drift,
                                                          seed)
                np.testing.assert_array_equal(measured, expected)
                np.testing.assert_array_equal(probe, expected_probe)
    kept = sensors._draws.cache_info()
    assert (kept.currsize, kept.hits) == ((2, 10) if n == 181 else (0, 0))


def test_faults_do_not_change_the_kept_draws():
    time_s, temperatures, drift = truth(181)
    faults = (SensorFault("T7", "dropout", 1000.0, 2000.0),
              SensorFault("T13", "stuck", 3000.0, None),
              SensorFault("T16", "offset", 100.0, 6000.0, offset_C=1.5))
    healthy = SensorModel(noise_C=0.05, quantum_C=0.1)
    before, _ = measure(healthy, time_s, temperatures, drift, NAMES, 5)
    faulty, _ = measure(SensorModel(noise_C=0.05, quantum_C=0.1, faults=faults), time_s,
                        temperatures, drift, NAMES, 5)
    after, _ = measure(healthy, time_s, temperatures, drift, NAMES, 5)
    np.testing.assert_array_equal(before, after)
    assert np.isnan(faulty[:, 6]).any() and not np.isnan(after).any()
    np.testing.assert_array_equal(after, measure_afresh(healthy, time_s, temperatures,
                                                        drift, 5)[0])
