"""The recording writer's fast path writes exactly the bytes of pandas' ``to_csv``."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from conftest import QUICK
from spindlebench.formats.recording import write_csv
from spindlebench.paths import DEFAULT_FMU
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
