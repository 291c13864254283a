"""Benchmark: peak memory of ``spindlebench fingerprint`` on long recordings (issue 28).

The fingerprint's best difference ψ used to form the n x m(m-1)/2 matrix of every pairwise
difference (about 5 KB per sample for 20 sensors: 5 GB for 10^6 samples); it now works on the
m x m Gram matrix of the rises. Each row here runs in its own child process so that its peak
resident memory (``getrusage`` maxrss of that child, from ``os.wait4``) is its own:

- ``CLI``: the whole command (start-up, imports, reading the CSV, the statistics) on a
  synthetic recording of ``rows`` samples x ``sensors`` sensors, written once to a temporary
  folder;
- ``function``: ``spindlebench.studies.fingerprint.statistics.fingerprint`` alone on arrays
  of that size (the arrays' own 8 x rows x (sensors + 2) bytes included).

Goal (issue 28): 10^6 rows x 20 sensors in <= 1 GB. The rows are written to
``bench/results/bench_fingerprint.json`` (``bench/results.py``), which the speed page shows.

Run: .venv/bin/python bench/bench_fingerprint.py [ROWS ...]   (default: 100000 1000000)
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from results import record

SENSORS = 20
GOAL_MB = 1024.0

FUNCTION_CHILD = """
import sys, numpy as np
from spindlebench.studies.fingerprint.statistics import fingerprint
rows, sensors = int(sys.argv[1]), int(sys.argv[2])
rng = np.random.default_rng(0)
t = np.arange(rows, dtype=float)
temps = 20.0 + np.cumsum(rng.normal(scale=1e-3, size=(rows, sensors)), axis=0)
e = temps[:, 0] - 0.5 * temps[:, 1]
print(fingerprint(t, temps, e)["best_diff_psi"])
"""


def recording(folder: Path, rows: int, sensors: int) -> Path:
    """A synthetic recording: slow random-walk temperatures, an error from two of them."""
    rng = np.random.default_rng(1)
    temps = 20.0 + np.cumsum(rng.normal(scale=1e-3, size=(rows, sensors)), axis=0)
    frame = pd.DataFrame(temps, columns=[f"T{i + 1}" for i in range(sensors)])
    frame.insert(0, "drift_um", 3.0 * (temps[:, 0] - temps[:, 1]) + rng.normal(
        scale=0.05, size=rows))
    frame.insert(0, "time_s", np.arange(rows, dtype=float) * 10.0)
    path = folder / f"long_{rows}.csv"
    frame.to_csv(path, index=False, float_format="%.5f")
    return path


def peak_of(argv: list[str]) -> tuple[float, float, str]:
    """(wall s, peak MB, last stdout line) of a child process."""
    started = time.perf_counter()
    child = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    _, status, usage = os.wait4(child.pid, 0)
    wall = time.perf_counter() - started
    out, err = child.stdout.read(), child.stderr.read()
    child.returncode = os.waitstatus_to_exitcode(status)
    if child.returncode != 0:
        raise SystemExit(f"{' '.join(argv[:4])}...: exit {child.returncode}: {err.strip()}")
    return wall, usage.ru_maxrss / 1024.0, (out.strip().splitlines() or [""])[-1]


def main(sizes: list[int]) -> None:
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; "
          f"{SENSORS} sensors; goal <= {GOAL_MB:.0f} MB at 10^6 rows")
    print(f"{'rows':>9} {'what':>9} {'wall s':>7} {'peak MB':>8}  result")
    table = []
    with tempfile.TemporaryDirectory() as scratch:
        for rows in sizes:
            path = recording(Path(scratch), rows, SENSORS)
            for what, argv in (
                    ("CLI", [sys.executable, "-m", "spindlebench", "fingerprint", str(path),
                             "--target", "drift_um"]),
                    ("function", [sys.executable, "-c", FUNCTION_CHILD, str(rows),
                                  str(SENSORS)])):
                wall, peak, last = peak_of(argv)
                print(f"{rows:>9} {what:>9} {wall:>7.1f} {peak:>8.0f}  {last[:60]}")
                table.append({"rows": rows, "sensors": SENSORS, "what": what,
                              "wall_s": wall, "peak_MB": peak,
                              "best_diff_psi": _number(last)})
            path.unlink()
    print(f"wrote {record('bench_fingerprint', table, {'peak_MB_at_1e6_rows': GOAL_MB})}")


def _number(text: str) -> float | None:
    """The child's last line as a number (the best difference's ψ), None if it is not one."""
    try:
        return float(text)
    except ValueError:
        return None


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [100_000, 1_000_000])
