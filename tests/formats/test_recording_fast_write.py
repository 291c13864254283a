"""The recording writer's fast path writes exactly the bytes of pandas' ``to_csv``."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from conftest import QUICK
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.formats.recording import (
    TRUTH_COLUMNS,
    read_back,
    read_recording,
    write_csv,
    write_recording,
)
from spindlebench.testbench.scenario import load_scenario
from spindlebench.testbench.simulate import record


def _pandas(frame: pd.DataFrame, path, float_format=None) -> bytes:
    frame.to_csv(path, index=False, float_format=float_format, lineterminator="\n")
    return path.read_bytes()


def test_a_simulated_recording_is_written_as_pandas_writes_it(tmp_path):
    scenario = tmp_path / "quick.toml"
    scenario.write_text(QUICK, encoding="utf-8")
    frame, _ = record(load_scenario(scenario), DEFAULT_FMU)
    assert frame.shape[1] > 100 and (frame.dtypes == np.float64).all()
    write_csv(tmp_path / "fast.csv", frame)
    assert (tmp_path / "fast.csv").read_bytes() == _pandas(frame, tmp_path / "pandas.csv")


@pytest.mark.parametrize("frame", [
    pd.DataFrame({"a": [0.0, -0.0, 1e-5, 1e-4, 9.999e15, 1e16, 1.5e300, 5e-324, np.nan,
                        np.inf, -np.inf, 123456789.123, 0.1 + 0.2, -2.5e-7],
                  "b": [np.nan] * 14, "c": np.linspace(-1, 1, 14) ** 3}),
    pd.DataFrame({"a": [np.nan], "b": [np.nan]}),  # a row of empty fields
    pd.DataFrame({"a": [1.0, np.nan]}),  # one column: pandas quotes an empty row
    pd.DataFrame({"a,b": [1.0], "c": [2.0]}),  # a name that needs quoting
    pd.DataFrame({"a": [1, 2], "b": [0.5, 1.5]}),  # not all float
])
def test_edge_values_and_fallbacks_give_pandas_bytes(tmp_path, frame):
    write_csv(tmp_path / "fast.csv", frame)
    assert (tmp_path / "fast.csv").read_bytes() == _pandas(frame, tmp_path / "pandas.csv")
    write_csv(tmp_path / "six.csv", frame, "%.6f")
    assert (tmp_path / "six.csv").read_bytes() == _pandas(frame, tmp_path / "p6.csv", "%.6f")


def _same_bits(a: pd.DataFrame, b: pd.DataFrame) -> None:
    assert list(a.columns) == list(b.columns) and a.index.equals(b.index)
    assert (a.dtypes == np.float64).all() and (b.dtypes == np.float64).all()
    assert np.array_equal(a.to_numpy().view(np.int64), b.to_numpy().view(np.int64))
    assert a.attrs["path"] == b.attrs["path"] and a.attrs["header"] == b.attrs["header"]


def test_read_back_is_what_the_written_recording_reads_back_bit_for_bit(tmp_path):
    scenario = tmp_path / "quick.toml"
    scenario.write_text(QUICK, encoding="utf-8")
    frame, sidecar = record(load_scenario(scenario), DEFAULT_FMU)
    path = write_recording(tmp_path / "run.csv", frame, sidecar)
    for columns in (TRUTH_COLUMNS, list(frame.columns)):
        kept = read_back(path, frame, columns)
        _same_bits(kept, read_recording(path).loc[:, list(columns)].copy())


def test_read_back_edge_values_are_the_bits_pandas_parses(tmp_path):
    rng = np.random.default_rng(7)
    edge = [0.0, -0.0, 1e-5, 1e-4, 9.999e15, 1e16, 1.5e300, 5e-324, 2.2250738585072014e-308,
            123456789.123, 0.1 + 0.2, -2.5e-7, 1 / 3, 2.0 ** 53 + 2, -1.7976931348623157e308]
    random = np.concatenate([rng.normal(20, 5, 3000), rng.normal(0, 1e-3, 3000),
                             10 ** rng.uniform(-300, 300, 3000) * rng.choice([-1, 1], 3000),
                             rng.integers(0, 2 ** 63, 3000).view(np.float64)])
    random = random[np.isfinite(random)]
    values = np.concatenate([edge, random])
    frame = pd.DataFrame({"time_s": np.arange(len(values), dtype=float), "a": values,
                          "b": values[::-1].copy()})
    path = write_recording(tmp_path / "edge.csv", frame, {})
    _same_bits(read_back(path, frame, ["time_s", "a", "b"]), read_recording(path))


@pytest.mark.parametrize("change", ["nan", "inf", "time", "int", "one row", "spaces"])
def test_read_back_declines_where_the_file_would_not_read_as_written(tmp_path, change):
    frame = pd.DataFrame({"time_s": [0.0, 1.0, 2.0], "a": [1.0, 2.0, 3.0]})
    if change == "nan":
        frame.loc[1, "a"] = np.nan
    elif change == "inf":
        frame.loc[1, "a"] = np.inf
    elif change == "time":
        frame.loc[2, "time_s"] = 1.0
    elif change == "int":
        frame["a"] = [1, 2, 3]
    elif change == "one row":
        frame = frame.iloc[:1]
    else:
        frame = frame.rename(columns={"a": " a"})
    assert read_back(tmp_path / "x.csv", frame, ["time_s"]) is None
