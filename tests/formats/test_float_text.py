"""formats.float_text writes every float64 as Python's ``repr`` does (a NaN as nothing)."""

from __future__ import annotations

import numpy as np
import orjson
import pytest
from spindlebench.formats.float_text import _odd, csv_rows, float_cells, orjson_writes_repr

#: Values where a shortest-digits writer can go wrong: zeros and signs, NaN and infinities,
#: where ``repr`` switches to an exponent (1e-05, 1e+16), the smallest subnormal and normal,
#: the largest double, powers of 2 (an uneven rounding interval), exact halves, sums that
#: need 17 digits, and integers beyond 2^53.
AWKWARD = [
    0.0, -0.0, np.nan, np.inf, -np.inf, 1e-05, 1e-4, 0.00012, 9.999e-05, 1e16, 1e15,
    9999999999999998.0, 0.1 + 0.2, 5e-324, 1.5e-323, 2.2250738585072014e-308,
    2.225073858507201e-308, 1.7976931348623157e308, 1.0, -1.0, 120.0, 0.5, 0.125, 2.75,
    1e22, 1e23, 1e-7, -2.5e-7, 1e100, 1e-100, 1.2345e-300, 2.0 ** 53, 2.0 ** 53 + 2,
    2.0 ** 60, 2.0 ** -1022, 2.0 ** -1074 * 3, 123456789012345680.0, 4.35, 1 / 3,
]


def _repr_rows(values: np.ndarray) -> bytes:
    return "".join(",".join(repr(v) if v == v else "" for v in row) + "\n"
                   for row in values.tolist()).encode()


def _repr_cells(values: np.ndarray) -> list[str]:
    return [repr(v) if v == v else "" for v in values.tolist()]


def test_awkward_values_are_written_as_repr_writes_them():
    values = np.array(AWKWARD)
    assert float_cells(values) == _repr_cells(values)
    assert float_cells(np.array([np.nan, 1e-13, 2.0])) == ["", "1e-13", "2.0"]
    assert csv_rows(values[:, None]) == _repr_rows(values[:, None])
    assert csv_rows(values.reshape(1, -1)) == _repr_rows(values.reshape(1, -1))


@pytest.mark.parametrize("family", ["bits", "uniform", "integers", "dyadic", "short decimals",
                                    "powers", "neighbours of powers", "subnormals"])
def test_many_values_of_each_family_are_written_as_repr_writes_them(family):
    rng = np.random.default_rng(26)
    n = 20_000
    if family == "bits":
        values = rng.integers(0, 2 ** 64, n, dtype=np.uint64).view(np.float64)
    elif family == "uniform":
        values = rng.uniform(-1, 1, n) * 10.0 ** rng.integers(-30, 30, n)
    elif family == "integers":
        values = rng.integers(-2 ** 62, 2 ** 62, n).astype(float) // 10.0 ** rng.integers(
            0, 18, n)
    elif family == "dyadic":
        values = rng.integers(-10 ** 6, 10 ** 6, n) / 2.0 ** rng.integers(0, 40, n)
    elif family == "short decimals":
        values = np.array([float(f"{rng.integers(0, 10 ** int(d))}e{rng.integers(-40, 40)}")
                           for d in rng.integers(1, 17, n)])
    elif family == "powers":
        values = np.array([2.0 ** e for e in range(-1074, 1024)]
                          + [float(f"1e{e}") for e in range(-323, 309)])
    elif family == "neighbours of powers":
        powers = np.array([2.0 ** e for e in range(-1073, 1023)]
                          + [float(f"1e{e}") for e in range(-322, 308)])
        values = np.concatenate([np.nextafter(powers, np.inf), np.nextafter(powers, -np.inf)])
    else:
        values = rng.integers(1, 2 ** 52, n, dtype=np.uint64).view(np.float64)
    assert float_cells(values) == _repr_cells(values)
    values = values[: len(values) // 10 * 10].reshape(-1, 10)
    assert csv_rows(values) == _repr_rows(values)


def test_no_rows_is_no_text():
    assert csv_rows(np.empty((0, 3))) == b""
    assert float_cells(np.empty(0)) == []


def test_values_outside_the_positional_range_spread_over_rows_and_columns():
    """A simulated recording has a ~1e-13 column in every row among positional values."""
    rng = np.random.default_rng(26)
    values = rng.uniform(10.0, 30.0, (60, 13))
    values[:, 4] = rng.uniform(-1e-12, 1e-12, 60)
    values.flat[rng.choice(values.size, len(AWKWARD), replace=False)] = AWKWARD
    assert csv_rows(values) == _repr_rows(values)


def test_orjson_text_is_taken_only_where_it_is_repr_and_a_heat_flow_column_is_not_odd():
    """``orjson_writes_repr`` (and ``_odd``, its array form) trust orjson's text outside
    1e-10 <= |x| < 1e-4: there it must be ``repr``'s, scalar and array alike, at every power
    of 2 and 10, their neighbours and random bit patterns; a recording's ~1e-13 W column and
    large values are then written by orjson (``repr`` of each was most of a write)."""
    powers = np.array([2.0 ** e for e in range(-1074, 1024)]
                      + [float(f"1e{e}") for e in range(-323, 309)])
    bits = np.random.default_rng(26).integers(0, 2 ** 64, 50_000, dtype=np.uint64).view(
        np.float64)
    values = np.concatenate([powers, np.nextafter(powers, np.inf),
                             np.nextafter(powers, -np.inf), bits])
    values = np.concatenate([values, -values])
    values = values[np.isfinite(values)]
    trusted = ~_odd(values)
    assert trusted.tolist() == [orjson_writes_repr(v) for v in values.tolist()]
    texts = orjson.dumps(values[trusted], option=orjson.OPT_SERIALIZE_NUMPY)[1:-1].split(b",")
    assert [t.decode() for t in texts] == [repr(v) for v in values[trusted].tolist()]
    assert all(orjson.dumps(v).decode() == repr(v) for v in values[trusted][::7].tolist())
    assert not _odd(np.array([1e-13, -3.2e-12, 1e16, 1e300, 0.0, 1e-4])).any()
    assert _odd(np.array([1e-5, 9.99e-5, 2.5e-7, 1e-10, np.nan, np.inf, -np.inf])).all()
