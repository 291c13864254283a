"""The fingerprint statistics (issue 9 definitions) on small recordings with known values."""

import math

import numpy as np
import pytest
from spindlebench.core.errors import SpindlebenchError
from spindlebench.studies.fingerprint.statistics import KEYS, final, fingerprint, smooth, t63


def test_smooth_window_shrinks_at_the_edges():
    x = np.arange(11.0)  # w = 3: interior samples are their own mean, the ends average two
    assert smooth(x).tolist() == [0.5, *range(1, 10), 9.5]
    assert final(x) == 9.5  # last max(1, 11 // 20) = 1 sample


def test_ramp_statistics_by_hand():
    t = np.arange(11.0) * 60.0
    ramp = np.arange(11.0)
    stats = fingerprint(t, np.column_stack([ramp, ramp**2]), ramp)
    assert list(stats) == list(KEYS)
    assert stats["best_raw_psi"] == pytest.approx(1.0)
    assert stats["overshoot"] == pytest.approx(1.0)
    assert stats["early_fraction"] == pytest.approx(1.0 / 9.5)  # smooth[1] / final
    # 63.2 % of the smoothed rise 9.5 - 0.5 is reached at smooth = 6.188 -> sample 7
    assert t63(t, ramp) == 420.0


def test_difference_and_pair_beat_single_sensors():
    t = np.linspace(0, 6 * 3600, 361)
    fast = 1 - np.exp(-t / 1800)
    slow = t / t[-1]
    error = 10 * fast - 6 * slow  # rises, levels off, falls back
    stats = fingerprint(t, np.column_stack([fast, slow, 0.5 * slow + 0.1 * fast]), error)
    assert stats["best_raw_psi"] < 0.95
    assert stats["best_diff_psi"] > stats["best_raw_psi"]
    assert stats["best_pair_r2"] == pytest.approx(1.0)
    assert stats["best_single_r2"] == pytest.approx(stats["best_raw_psi"] ** 2)
    assert stats["overshoot"] > 1.03
    assert stats["early_fraction"] > 0.45


def test_t63_ratio_uses_sensors_that_rise():
    t = np.arange(101.0)
    quick = 1 - np.exp(-t / 5)
    sensor_slow = 1 - np.exp(-t / 20)
    flat = 0.05 * sensor_slow  # rises less than 0.1 K: no t63 of its own
    stats = fingerprint(t, np.column_stack([sensor_slow, flat]), quick)
    assert stats["t63_ratio"] == pytest.approx(t63(t, quick) / t63(t, sensor_slow))
    assert t63(t, -sensor_slow) == t63(t, sensor_slow)  # a falling signal reaches it too


def test_constant_sensors_are_left_out_and_bad_shapes_refused():
    t = np.arange(10.0)
    stats = fingerprint(t, np.column_stack([t, np.ones(10)]), 2 * t)
    assert stats["best_raw_psi"] == pytest.approx(1.0)
    assert math.isnan(stats["best_diff_psi"])
    with pytest.raises(SpindlebenchError, match="same number of samples"):
        fingerprint(t, np.ones((9, 2)), t)
    with pytest.raises(SpindlebenchError, match="no temperature column rises"):
        fingerprint(t, np.ones((10, 2)), t)
