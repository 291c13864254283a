"""formats.table_csv writes a study table with exactly the bytes of pandas' to_csv."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from spindlebench.formats.table_csv import _column_texts, table_bytes, write_table


def _pandas(frame: pd.DataFrame, path) -> bytes:
    frame.to_csv(path, index=False, lineterminator="\n")
    return path.read_bytes()


def _results_like(rows: int = 40) -> pd.DataFrame:
    rng = np.random.default_rng(3)
    rmse = rng.lognormal(0, 1, rows)
    rmse[::7] = np.nan
    return pd.DataFrame({
        "replica": np.arange(rows) % 3 + 1,
        "big": np.array([-2**63, 2**63 - 1, 0, -1] * (rows // 4), dtype=np.int64),
        "data": pd.Series(["measured", "noise-free"] * (rows // 2), dtype="str"),
        "method": ["six_diff", "oracle", "ridge", "all_raw"] * (rows // 4),
        "k": pd.array([2, None, 3, -2**63 + 1] * (rows // 4), dtype="Int64"),
        "k_full": pd.array([2**62, 0, -7, 10] * (rows // 4), dtype="Int64"),
        "rmse_um": rmse,
        "test_speed_rpm": [2000.0, 4000.0] * (rows // 2),
        "selected": ["T1;T18", "all 20 sensors, fitted", 'a "quoted" name', ""] * (rows // 4),
        "error": [None, "simulation failed: ValueError: x, y", "", np.nan] * (rows // 4),
        "holds": [True, False] * (rows // 2),
        "edge": [0.0, -0.0, 1e-5, 1e16, np.inf, -np.inf, 5e-324, 0.1 + 0.2] * (rows // 8),
    })


def test_a_results_like_table_takes_the_fast_path_and_gives_pandas_bytes(tmp_path):
    frame = _results_like()
    assert _column_texts(frame) is not None
    write_table(tmp_path / "fast.csv", frame)
    assert (tmp_path / "fast.csv").read_bytes() == _pandas(frame, tmp_path / "pandas.csv")


@pytest.mark.parametrize("frame", [
    pd.DataFrame({"a,b": [1.0], 'c"': ["x"]}),  # names that need quoting
    pd.DataFrame({"a": ["line\nbreak", "x"], "b": [1, 2]}),  # a line break: pandas writes it
    pd.DataFrame({"a": ["x\rcarriage", "y"], "b": [1, 2]}),
    pd.DataFrame({"a": [1.0, np.nan]}),  # one column
    pd.DataFrame({"a": [], "b": []}),  # no rows
    pd.DataFrame({"a": [1.5, 2.5], "b": pd.to_datetime(["2024-01-01", "2024-01-02"])}),
    pd.DataFrame({"a": [1, 2], "b": [True, None]}),  # object column of bools
    pd.DataFrame({"a": np.array([1, 2], dtype=np.int32), "b": [0.5, 1.5]}),
    pd.DataFrame({"a": np.array([1.5, 2.5], dtype=np.float32), "b": ["x", "y"]}),
    pd.DataFrame({"a": [np.nan, np.nan], "b": [None, None]}),
    pd.DataFrame({"a": pd.array(["NA", None, "", "None", "x, y", np.nan, 'q"'], dtype="str"),
                  "b": pd.array([None, "nan", "", None, "y", "z", "N/A"], dtype="str"),
                  "c": pd.array([None] * 7, dtype="str"), "d": range(7)}),  # missing text
    pd.DataFrame({"a": pd.array(["ok", None, "line\nbreak"], dtype="str"), "b": [1, 2, 3]}),
])
def test_edge_cases_and_fallbacks_give_pandas_bytes(tmp_path, frame):
    write_table(tmp_path / "fast.csv", frame)
    assert (tmp_path / "fast.csv").read_bytes() == _pandas(frame, tmp_path / "pandas.csv")


@pytest.mark.parametrize("frame", [
    _results_like(),  # column by column
    pd.DataFrame({"a": [0.5, 1e-5, np.nan], "b": [1e16, -0.0, 2.0]}),  # row by row
    pd.DataFrame({"a": [1.0, np.nan]}),  # pandas writes it: nothing returned
])
def test_write_table_returns_the_bytes_it_wrote(tmp_path, frame):
    """The store and the recording writer hash what write_table returns instead of reading
    the file back: it must be the file's bytes, or None where pandas wrote them."""
    data = write_table(tmp_path / "t.csv", frame)
    assert data == table_bytes(frame)
    if data is not None:
        assert data == (tmp_path / "t.csv").read_bytes() == _pandas(frame, tmp_path / "p.csv")
    else:
        assert _column_texts(frame) is None
