"""The array reader (``read_table``, NumPy engine, no pandas) and the DataFrame reader
(``read_recording``, pandas' tokenizer) are one parser: the same values to the last bit, the
same errors, on odd cells, odd files, the examples and the real recording (read in place);
and ``spindlebench evaluate`` runs without importing pandas, with one OpenBLAS thread."""

from __future__ import annotations

import itertools
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, SHARED_RECORDINGS
from spindlebench.formats import recording
from spindlebench.formats.recording import read_recording, read_table
from spindlebench.formats.roles import (
    ColumnRoles,
    detect_dialect,
    read_table_with_roles,
    read_with_roles,
)

REAL = SHARED_RECORDINGS
EXAMPLES = sorted((REPO / "docs" / "examples").rglob("*.csv"))
#: Cells each engine must read as the other does (value or error), in a number column.
CELLS = ["1.5", " 1.5", "1.5 ", "+1.5", "-0", "-0.0", "-0e0", ".5", "5.", "1e5", "1E+05", "1e",
         "e5", "1.2.3", "--1", "", " ", "nan", "NaN", "NAN", " nan ", "-nan", "+NaN", "inf",
         "-inf", "Infinity", "1_0", "0x10", "hot", "True", "1e400", "1,5", "١٢", '"1.5"',
         "1.5\r", "12345678901234567890", "0.1000000000000000055511151231257827",
         "2.2250738585072011e-308", "4.9e-324", "1d5", "NA", "null", "1.5;2"]
GOOD = "time_s,T1,T2\n0,20,21\n60,20.5,21.5\n120,21,22\n"
FILES = {
    "good": GOOD, "no final newline": GOOD.rstrip("\n"), "crlf": GOOD.replace("\n", "\r\n"),
    "cr only": GOOD.replace("\n", "\r"), "bom": "\ufeff" + GOOD,
    "blank line": GOOD.replace("60,", "\n60,"), "blank lines at the end": GOOD + "\n\n",
    "blank line at the end, crlf": GOOD.replace("\n", "\r\n") + "\r\n",
    "space line": GOOD.replace("60,", " \n60,"),
    "short line": GOOD.replace("60,20.5,21.5", "60,20.5"),
    "long line": GOOD.replace("60,20.5,21.5", "60,20.5,21.5,3"),
    "header only": "time_s,T1,T2\n", "header without newline": "time_s,T1,T2",
    "one row": "time_s,T1,T2\n0,1,2\n", "spaces around": GOOD.replace(",", " , "),
    "trailing delimiter": GOOD.replace("\n", ",\n").replace("time_s,T1,T2,", "time_s,T1,T2"),
    "quoted": GOOD.replace("20.5", '"20.5"'), "comment sign": GOOD.replace("60,", "#60,"),
    "non-ASCII note": "time_s,T1,T2,note\n0,20,21,é\n60,20.5,21.5,\n120,21,22,x\n",
    "text column": "time_s,T1,T2,note\n0,20,21,a\n60,20.5,21.5,b\n120,21,22,c\n",
    "empty column": "time_s,T1,T2\n0,20,\n60,20.5,\n120,21,\n",
    "integers with -0 and a gap": "time_s,T1,T2\n0,-0,1\n60,,2\n120,3,4\n",
    "time repeats": GOOD.replace("60,", "0,"), "one column": "time_s\n0\n60\n\n120\n",
    "one column ok": "time_s\n0\n60\n120\n",
}


def outcome(read):
    """(values as bytes, shape) or (error type, message)."""
    try:
        values = read()
    except Exception as exc:
        return type(exc).__name__, str(exc)
    return values.tobytes(), values.shape


def both(path: Path, **options):
    numpy = outcome(lambda: read_table(path, engine="numpy", **options).values)
    pandas = outcome(lambda: read_recording(path, **options).to_numpy())
    return numpy, pandas


@pytest.mark.parametrize("delimiter", [",", ";"])
def test_odd_cells_read_alike(tmp_path, delimiter):
    path = tmp_path / "r.csv"
    differ = []
    for cell, column, allow, columns in itertools.product(
            CELLS, range(3), [False, True], [None, ["T1"]]):
        rows = [["0", "20", "21"], ["60", "20.5", "21.5"], ["120", "21", "22"]]
        rows[1][column] = cell
        path.write_bytes((delimiter.join(["time_s", "T1", "T2"]) + "\n" + "".join(
            delimiter.join(row) + "\n" for row in rows)).encode())
        numpy, pandas = both(path, allow_missing=allow, columns=columns, delimiter=delimiter)
        if numpy != pandas:
            differ.append((cell, column, allow, columns, numpy, pandas))
    assert not differ


def test_decimal_comma_cells_read_alike(tmp_path):
    path = tmp_path / "r.csv"
    for cell, allow in itertools.product(CELLS, [False, True]):
        rows = [["0", "20,5", "21"], ["60", cell, "21,5"], ["120", "21", "22"]]
        path.write_bytes(("time_s;T1;T2\n" + "".join(";".join(r) + "\n" for r in rows)).encode())
        numpy, pandas = both(path, allow_missing=allow, delimiter=";", decimal=",")
        assert numpy == pandas, (cell, allow)


@pytest.mark.parametrize("name", sorted(FILES))
def test_odd_files_read_alike(tmp_path, name):
    path = tmp_path / "r.csv"
    path.write_bytes(FILES[name].encode())
    for allow, columns in itertools.product([False, True], [None, ["T1"]]):
        numpy, pandas = both(path, allow_missing=allow, columns=columns)
        assert numpy == pandas, (allow, columns)


def test_a_bad_cell_is_named_alike_by_both(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text(GOOD.replace("20.5", "hot"), encoding="utf-8")
    numpy, pandas = both(path)
    assert numpy == pandas
    assert "line 3, column 'T1': non-numeric value 'hot'" in numpy[1]


def recordings() -> list[Path]:
    real = sorted(REAL.rglob("*.csv")) if REAL.is_dir() else []
    return [*EXAMPLES, *real]


@pytest.mark.parametrize("path", recordings(), ids=lambda p: p.name)
def test_examples_and_real_recordings_read_bit_for_bit_alike(path):
    """In place (never copied); each plain file is taken by the NumPy engine itself."""
    delimiter, decimal = detect_dialect(path)
    header = recording.read_header(path, delimiter)
    dialect = recording._Dialect(delimiter, decimal)
    direct = recording._parse_with_numpy(path, header, False, header, dialect)
    assert direct is not None, "NumPy's parser should take this plain file itself"
    table = read_table(path, delimiter=delimiter, decimal=decimal)
    frame = read_recording(path, delimiter=delimiter, decimal=decimal)
    assert table.values.tobytes() == frame.to_numpy().tobytes() == direct.tobytes()
    assert list(table.columns) == list(frame.columns) == table.header
    assert frame.attrs["path"] == table.path == str(path)


def test_real_recording_with_roles_reads_alike():
    if not REAL.is_dir():
        pytest.skip("no real recordings next to the checkout")
    path = next(REAL.rglob("*.csv"))
    roles = ColumnRoles()
    table, choice = read_table_with_roles(path, "ch3_um", roles)
    frame, same = read_with_roles(path, "ch3_um", roles)
    assert choice == same and list(table.columns) == list(frame.columns)
    assert table.values.tobytes() == frame.to_numpy().tobytes()


def test_a_named_time_axis_replaces_time_s_in_a_table(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("time_s,Zeit,T1,dz_um\n0,0,20,0\n1,60,21,1\n2,120,23,3\n", encoding="utf-8")
    roles = ColumnRoles(time_column="Zeit", sensors=("T1",))
    table, _ = read_table_with_roles(path, "dz_um", roles)
    frame, _ = read_with_roles(path, "dz_um", roles)
    assert table.columns == ("time_s", "T1", "dz_um") == tuple(frame.columns)
    assert table["time_s"].tolist() == [0.0, 60.0, 120.0] == frame["time_s"].tolist()


def two_recordings(folder: Path) -> list[str]:
    rng = np.random.default_rng(0)
    for name in ("a", "b"):
        raw = 20 + np.cumsum(rng.normal(0, 0.1, (40, 5)), axis=0)
        drift = 3 * (raw[:, 0] - raw[:, 4]) + rng.normal(0, 0.1, 40)
        lines = ["time_s," + ",".join(f"T{i}" for i in range(1, 6)) + ",drift_um"]
        lines += [f"{60 * t}," + ",".join(map(repr, row)) + f",{d!r}"
                  for t, (row, d) in enumerate(zip(raw.tolist(), drift.tolist(), strict=True))]
        (folder / f"{name}.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return ["evaluate", "--train", str(folder / "a.csv"), "--test", str(folder / "b.csv"),
            "--target", "drift_um", "--clusters", "2", "--differences"]


def run_checked(argv: list[str], check: str, env: dict[str, str] | None = None):
    code = ("import sys; from spindlebench.commands import main as cli; "
            "status = cli.main(sys.argv[1:]); "
            f"{check}; sys.exit(status)")
    return subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True,
                          env=env)


def test_evaluate_command_does_not_import_pandas(tmp_path):
    """pandas' import was half a second of the command's start-up; the plain files of a
    logger or the testbench never need it (nor numpy.ma, another 30 ms)."""
    result = run_checked(two_recordings(tmp_path),
                         "assert 'pandas' not in sys.modules, 'pandas was imported'; "
                         "assert 'numpy.ma' not in sys.modules, 'numpy.ma was imported'")
    assert result.returncode == 0, result.stderr
    assert "RMSE" in result.stdout


@pytest.mark.parametrize("given", [None, "2"])
def test_evaluate_runs_openblas_with_one_thread_unless_told(tmp_path, given):
    """cli.ONE_BLAS_THREAD: OpenBLAS's idle worker threads cost evaluate ~0.15 s of CPU."""
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if given is not None:
        env["OPENBLAS_NUM_THREADS"] = given
    expected = 1 if given is None else min(int(given), os.cpu_count() or 1)
    check = ("import threadpoolctl; threads = {i['num_threads'] for i in "
             "threadpoolctl.threadpool_info() if i['internal_api'] == 'openblas'}; "
             f"assert threads == {{{expected}}}, threads")
    result = run_checked(two_recordings(tmp_path), check, env)
    assert result.returncode == 0, result.stderr
