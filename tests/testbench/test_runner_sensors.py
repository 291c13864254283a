"""Sensor model: noise, quantisation, probe zeroing, faults, and reproducibility by seed."""

import numpy as np
import pytest
from spindlebench.testbench.scenario import SensorFault, SensorModel
from spindlebench.testbench.sensors import measure, quantise

NAMES = tuple(f"T{i}" for i in range(1, 21))


def truth(n=600):
    time_s = np.arange(n) * 10.0
    temperatures = 20.0 + np.outer(np.linspace(0.0, 5.0, n), np.linspace(1.0, 2.0, 20))
    drift = np.linspace(3.0, 40.0, n)  # absolute drift: the probe only sees its change
    return time_s, temperatures, drift


def test_quantisation_gives_clean_multiples():
    values = quantise(np.array([20.04, 20.05001, 20.26, -0.04]), 0.1)
    np.testing.assert_array_equal(values, [20.0, 20.1, 20.3, -0.0])
    assert repr(float(quantise(np.array([0.3]), 0.1)[0])) == "0.3"
    np.testing.assert_array_equal(quantise(np.array([1.234]), 0.0), [1.234])


def test_noise_has_the_requested_sigma_and_readings_are_quantised():
    time_s, temperatures, drift = truth()
    model = SensorModel(noise_C=0.3, quantum_C=0.1, probe_noise_um=0.5, probe_quantum_um=0.0)
    measured, probe = measure(model, time_s, temperatures, drift, NAMES, seed=1)
    error = measured - temperatures
    assert error.std() == pytest.approx(np.hypot(0.3, 0.1 / np.sqrt(12)), rel=0.05)
    assert abs(error.mean()) < 0.02
    np.testing.assert_allclose(measured * 10, np.round(measured * 10), atol=1e-9)
    assert probe[0] == 0.0  # the probe is zeroed at the first sample
    assert (probe - (drift - drift[0])).std() == pytest.approx(0.5, rel=0.1)


def test_same_seed_same_numbers_other_seed_other_numbers():
    time_s, temperatures, drift = truth()
    model = SensorModel()
    a = measure(model, time_s, temperatures, drift, NAMES, seed=7)
    b = measure(model, time_s, temperatures, drift, NAMES, seed=7)
    c = measure(model, time_s, temperatures, drift, NAMES, seed=8)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert not np.array_equal(a[0], c[0])


def test_noise_free_model_reproduces_the_truth():
    time_s, temperatures, drift = truth()
    model = SensorModel(noise_C=0.0, quantum_C=0.0, probe_noise_um=0.0, probe_quantum_um=0.0)
    measured, probe = measure(model, time_s, temperatures, drift, NAMES, seed=0)
    np.testing.assert_array_equal(measured, temperatures)
    np.testing.assert_allclose(probe, drift - drift[0])


def test_faults_dropout_stuck_offset():
    time_s, temperatures, drift = truth()
    faults = (
        SensorFault("T7", "dropout", 1000.0, 2000.0),
        SensorFault("T13", "stuck", 3000.0, None),
        SensorFault("T2", "stuck", 0.0, 500.0, value_C=18.0),
        SensorFault("T16", "offset", 100.0, 6000.0, offset_C=1.5),
    )
    clean_model = SensorModel(noise_C=0.0, quantum_C=0.0)
    model = SensorModel(noise_C=0.0, quantum_C=0.0, faults=faults)
    clean, _ = measure(clean_model, time_s, temperatures, drift, NAMES, seed=0)
    faulty, _ = measure(model, time_s, temperatures, drift, NAMES, seed=0)

    dropout = (time_s >= 1000) & (time_s < 2000)
    assert np.isnan(faulty[dropout, 6]).all()
    np.testing.assert_array_equal(faulty[~dropout, 6], clean[~dropout, 6])

    stuck = time_s >= 3000
    assert (faulty[stuck, 12] == clean[~stuck, 12][-1]).all()  # last good reading
    assert (faulty[time_s < 500, 1] == 18.0).all()

    offset = time_s >= 100
    np.testing.assert_allclose(faulty[offset, 15] - clean[offset, 15], 1.5)
    np.testing.assert_array_equal(faulty[~offset, 15], clean[~offset, 15])

    untouched = [i for i in range(20) if i not in (1, 6, 12, 15)]
    np.testing.assert_array_equal(faulty[:, untouched], clean[:, untouched])
