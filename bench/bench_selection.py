"""Benchmark: selection over sensors plus all pairwise differences (issue 10's selection rows).

Each size runs in its own child process, so the peak memory (``resource.getrusage`` maxrss,
which only grows) belongs to that size alone:

- ``row-wise``: ``selection.pairs.select_among_pairs`` (Prim's algorithm, each row of R from
  the m x m factor of the raw rises; never forms the candidate matrix or R; NumPy rows up to
  ``pairs.COMPILED_ABOVE`` candidates, the compiled loop above, its cached code loaded before
  the clock starts);
- ``matrix``: the matrix way, R and t(R) (n x n) formed from the candidate matrix
  (``select_sensitive_points`` with the row-wise route switched off), timed in the SAME
  process right after, where its memory allows (8 n^2 bytes per matrix; the 200-sensor set
  took 84 s and 10.4 GB single-threaded and crashed threaded OpenBLAS; 500 sensors would need
  ~125 GB per matrix), so the ratio is one process's; the clusters are checked to agree;
- ``CLI``: ``spindlebench evaluate --differences`` on two 100-sensor and on two 200-sensor
  recordings, wall and CPU time (min and median of ``CLI_RUNS`` runs) and peak memory of
  the whole command (start-up and imports included; ``make bench`` byte-compiles the
  package first, as an install does).

The load average is printed first: on the shared machine wall times follow it, CPU seconds
much less.

Also the fast closure against the paper's max-min squaring (identical results checked).
Absolute times depend on the machine's load; the ratios are what to compare.

Run: .venv/bin/python bench/bench_selection.py  (``make bench`` runs every bench script);
``bench/bench_selection.py --large [--smoke-cpu-s S] [--smoke-only]``: 1 000 sensors timed
and 2 000 run for S CPU seconds (default ``SMOKE_CPU_S``; ``bench/results/
bench_selection_large.json``, rewritten after each row; ``--smoke-only``: only the 2 000 row).
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from results import record

SIZES = [  # (raw sensors, samples, clusters, time today's matrix way too?, goal s, goal MB)
    (100, 1440, 4, True, 1.0, 300),
    (200, 1440, 4, False, 5.0, 500),
    (500, 1440, 4, False, 60.0, 1000),
]
CLOSURE_SIZES = [(20, 360), (40, 720)]


def synthetic_temperatures(n_sensors: int, n_samples: int, seed: int = 0) -> np.ndarray:
    """Warm-up curves with sensor-specific time constants and gains, ambient wander, noise."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, n_samples)[:, None]
    tau = rng.uniform(0.05, 0.8, n_sensors)
    gain = rng.uniform(0.5, 15.0, n_sensors)
    ambient = 20.0 + np.cumsum(rng.normal(0, 0.02, n_samples))[:, None]
    return ambient + gain * (1 - np.exp(-t / tau)) + rng.normal(0, 0.03, (n_samples, n_sensors))


def drift(raw: np.ndarray, seed: int = 1) -> np.ndarray:
    return 3.0 * (raw[:, 0] - raw[:, -1]) + np.random.default_rng(seed).normal(0, 0.3, len(raw))


def peak_mb() -> float:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def measure(n_sensors: int, n_samples: int, k: int, with_matrix: bool) -> dict:
    """One size, in this (child) process: row-wise first, then today's matrix way."""
    from spindlebench.selection import pairs
    from spindlebench.selection.differences import pairwise_differences
    from spindlebench.selection.pairs import select_among_pairs
    from spindlebench.selection.select import select_sensitive_points

    raw = synthetic_temperatures(n_sensors, n_samples)
    raw = raw - raw[0]
    y = drift(raw)
    if n_sensors * (n_sensors + 1) // 2 > pairs.COMPILED_ABOVE:  # load the compiled kernel
        above, pairs.COMPILED_ABOVE = pairs.COMPILED_ABOVE, 0  # (cached on disk)
        select_among_pairs(raw[:, :4], y, 2)
        pairs.COMPILED_ABOVE = above
    counted = pairs.PRIM_COUNTS.copy()
    start, cpu = time.perf_counter(), time.process_time()
    rows = select_among_pairs(raw, y, k)
    out = {"row_s": time.perf_counter() - start, "row_cpu_s": time.process_time() - cpu,
           "row_peak_MB": peak_mb()}
    if n_sensors * (n_sensors + 1) // 2 > pairs.COMPILED_ABOVE:  # the compiled loop's work
        names = ("visits", "screened_passes", "exact_similarities", "links_replaced")
        out.update({f"prim_{name}": int(count) for name, count
                    in zip(names, pairs.PRIM_COUNTS - counted, strict=True)})
    if with_matrix:
        pairs.ROW_WISE_ABOVE = 10**12  # the matrix way: R and t(R) formed
        start = time.perf_counter()
        matrix = select_sensitive_points(np.hstack([raw, pairwise_differences(raw)]), y, k)
        out["matrix_s"] = time.perf_counter() - start
        out["matrix_peak_MB"] = peak_mb()
        out["same_clusters"] = all(
            np.array_equal(a, b) for a, b in zip(matrix.clusters, rows.clusters, strict=True))
    return out


#: (sensors, samples, clusters, goal CPU-s, goal MB) of the large rows (issue 26): run by
#: ``--large``, written to ``bench/results/bench_selection_large.json``.
LARGE = [(1000, 1440, 4, 60.0, 1000)]
#: The 2 000-sensor case (2 001 000 candidates) only has to run without a crash: it runs for
#: at most this many CPU seconds (Prim's visits are n^2: 16x those of 1 000 sensors).
SMOKE = (2000, 1440, 4)
SMOKE_CPU_S = 600.0


def smoke(n_sensors: int, n_samples: int, k: int, limit_s: float) -> dict:
    """Run the selection in a thread (the compiled loop releases the GIL) and watch it: peak
    memory and CPU seconds until it ends or ``limit_s`` CPU seconds have passed."""
    import threading

    from spindlebench.selection import pairs

    raw = synthetic_temperatures(n_sensors, n_samples)
    raw = raw - raw[0]
    y = drift(raw)
    above, pairs.COMPILED_ABOVE = pairs.COMPILED_ABOVE, 0  # load the compiled kernel
    pairs.select_among_pairs(raw[:, :4], y, 2)
    pairs.COMPILED_ABOVE = above
    outcome: dict = {}

    def work() -> None:
        try:
            outcome["clusters"] = len(pairs.select_among_pairs(raw, y, k).clusters)
        except BaseException as error:  # reported in the row, not hidden
            outcome["error"] = repr(error)

    cpu = time.process_time()
    thread = threading.Thread(target=work, daemon=True)
    thread.start()
    while thread.is_alive() and time.process_time() - cpu < limit_s:
        thread.join(timeout=5.0)
    return {"row": "smoke", "sensors": n_sensors, "candidates": n_sensors * (n_sensors + 1) // 2,
            "cpu_s": time.process_time() - cpu, "peak_MB": peak_mb(),
            "finished": not thread.is_alive(), "cpu_limit_s": limit_s,
            "error": outcome.get("error"), "clusters": outcome.get("clusters")}


def large(smoke_cpu_s: float = SMOKE_CPU_S, timed: bool = True) -> None:
    """The issue-26 rows: 1 000 sensors timed (unless ``timed`` is false), 2 000 run for
    ``smoke_cpu_s`` CPU seconds (none: 0). The file is written after each row."""
    rows: list[dict] = []
    print("load average (1, 5, 15 min): " + ", ".join(f"{v:.1f}" for v in os.getloadavg()))
    for n_sensors, n_samples, k, goal_s, goal_mb in LARGE if timed else ():
        result = child("--measure", str(n_sensors), str(n_samples), str(k), "False")
        n = n_sensors * (n_sensors + 1) // 2
        print(f"{n_sensors} sensors, {n} candidates: {result['row_cpu_s']:.1f} CPU-s "
              f"({result['row_s']:.1f} s wall), {result['row_peak_MB']:.0f} MB "
              f"(goal <= {goal_s:g} CPU-s, {goal_mb} MB)", flush=True)
        rows.append({"row": "selection", "sensors": n_sensors, "candidates": n,
                     "goal_cpu_s": goal_s, "goal_MB": goal_mb,
                     "load_after": list(os.getloadavg()), **result})
        record("bench_selection_large", rows)
    if smoke_cpu_s <= 0:
        return
    result = child("--smoke", *map(str, SMOKE), str(smoke_cpu_s))
    print(f"{SMOKE[0]} sensors: {'finished' if result['finished'] else 'still running'} after "
          f"{result['cpu_s']:.0f} CPU-s, {result['peak_MB']:.0f} MB peak, "
          f"error: {result['error']}", flush=True)
    rows.append({**result, "load_after": list(os.getloadavg())})
    print(f"wrote {record('bench_selection_large', rows)}")


def child(*args: str) -> dict:
    result = subprocess.run([sys.executable, __file__, *args], capture_output=True, text=True,
                            check=True)
    return json.loads(result.stdout.strip().splitlines()[-1])


def write_recording(path: Path, raw: np.ndarray, y: np.ndarray) -> None:
    import pandas as pd

    frame = pd.DataFrame(raw, columns=[f"T{i + 1}_C" for i in range(raw.shape[1])])
    frame.insert(0, "time_s", np.arange(len(raw)) * 60.0)
    frame["drift_um"] = y - y[0]
    frame.to_csv(path, index=False)


#: Runs of the CLI command: on the shared machine one run's wall time follows the load.
CLI_RUNS = 5
#: (sensors, goal s, goal MB) of the command-line rows: issue 10's CLI goals.
CLI_GOALS = [(100, 1, 300), (200, 5, 500)]


def cli_run(n_sensors: int = 100, n_samples: int = 1440,
            runs: int = CLI_RUNS) -> list[tuple[float, float, float]]:
    """(wall s, CPU s, peak MB) of each of ``runs`` runs of ``spindlebench evaluate
    --differences`` on two recordings."""
    with tempfile.TemporaryDirectory() as folder:
        paths = []
        for seed in (0, 1):
            raw = synthetic_temperatures(n_sensors, n_samples, seed)
            paths.append(Path(folder, f"run{seed}.csv"))
            write_recording(paths[-1], raw, drift(raw - raw[0], seed))
        command = [str(Path(sys.executable).with_name("spindlebench")), "evaluate",
                   "--train", str(paths[0]), "--test", str(paths[1]),
                   "--target", "drift_um", "--clusters", "4", "--differences"]
        subprocess.run(command, capture_output=True, check=True)  # warm the disk caches
        measured = []
        for _ in range(runs):
            result = subprocess.run([sys.executable, "-c", _TIMED_RUN, *command],
                                    capture_output=True, text=True, check=True)
            seconds, status, cpu, peak, errors = json.loads(result.stdout)
            if status != 0:
                raise SystemExit(f"CLI failed: {errors}")
            measured.append((seconds, cpu, peak))
        return measured


#: Starts the command from a small process and reports its wall, status, CPU and peak RSS:
#: a child's ru_maxrss counts the memory of the process it was forked from (Python forks
#: with vfork), so started from this one it would include the bench's own ~90 MB.
_TIMED_RUN = """
import json, os, subprocess, sys, time
start = time.perf_counter()
process = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
_, status, usage = os.wait4(process.pid, 0)
seconds = time.perf_counter() - start
print(json.dumps([seconds, status, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024,
                  process.stderr.read().decode()]))
"""


def closure_rows() -> None:
    from spindlebench.selection.closure import closure_by_squaring, closure_minimax
    from spindlebench.selection.differences import pairwise_differences
    from spindlebench.selection.similarity import similarity_matrix

    print(f"{'closure':>10} {'candidates':>12} {'fast':>9} {'squaring':>9} {'ratio':>7}")
    for n_sensors, n_samples in CLOSURE_SIZES:
        raw = synthetic_temperatures(n_sensors, n_samples)
        R = similarity_matrix(np.hstack([raw, pairwise_differences(raw)]))
        start = time.perf_counter()
        fast = closure_minimax(R)
        t_fast = time.perf_counter() - start
        start = time.perf_counter()
        reference = closure_by_squaring(R)
        t_ref = time.perf_counter() - start
        if not np.array_equal(fast, reference):
            raise SystemExit("fast closure differs from the squaring reference")
        print(f"{'':>10} {R.shape[0]:>12} {t_fast:8.3f}s {t_ref:8.3f}s {t_ref / t_fast:6.0f}x",
              flush=True)


def main() -> None:
    rows: list[dict] = []
    print("load average (1, 5, 15 min): " + ", ".join(f"{v:.1f}" for v in os.getloadavg()))
    print("selection, sensors + all pairwise differences (row-wise vs the matrix way)")
    print(f"{'sensors':>7} {'candidates':>10} {'row-wise':>9} {'(cpu)':>8} {'peak':>8} "
          f"{'goal':>16} {'matrix':>9} {'peak':>8} {'ratio':>7}")
    for n_sensors, n_samples, k, with_matrix, goal_s, goal_mb in SIZES:
        result = child("--measure", str(n_sensors), str(n_samples), str(k), str(with_matrix))
        n = n_sensors * (n_sensors + 1) // 2
        if with_matrix:
            if not result["same_clusters"]:
                raise SystemExit(f"{n_sensors} sensors: row-wise clusters differ from the matrix")
            old = f"{result['matrix_s']:8.2f}s {result['matrix_peak_MB']:6.0f}MB " \
                  f"{result['matrix_s'] / result['row_s']:6.1f}x"
        else:
            old = f"not run: R alone is {8 * n * n / 1e9:.0f} GB"
        goal = f"<= {goal_s:g} s, {goal_mb} MB"
        print(f"{n_sensors:>7} {n:>10} {result['row_s']:8.2f}s {result['row_cpu_s']:7.2f}s "
              f"{result['row_peak_MB']:6.0f}MB {goal:>16} {old}", flush=True)
        rows.append({"row": "selection", "sensors": n_sensors, "candidates": n,
                     "goal_s": goal_s, "goal_MB": goal_mb, **result})
    for n_sensors, goal_s, goal_mb in CLI_GOALS:
        runs = cli_run(n_sensors)
        wall, cpu, peak = ([run[i] for run in runs] for i in range(3))
        print(f"CLI `spindlebench evaluate --differences`, {n_sensors} sensors + "
              f"{n_sensors * (n_sensors - 1) // 2} differences, 1440 samples, {len(runs)} runs: "
              f"{min(wall):.2f} s wall min, {statistics.median(wall):.2f} median "
              f"({min(cpu):.2f} / {statistics.median(cpu):.2f} s CPU), {max(peak):.0f} MB peak "
              f"(goal <= {goal_s:g} s, <= {goal_mb} MB)", flush=True)
        rows.append({"row": "cli", "sensors": n_sensors, "runs": len(runs),
                     "wall_s_min": min(wall), "wall_s_median": statistics.median(wall),
                     "cpu_s_min": min(cpu), "cpu_s_median": statistics.median(cpu),
                     "peak_MB": max(peak), "goal_s": goal_s, "goal_MB": goal_mb})
    closure_rows()
    print(f"wrote {record('bench_selection', rows)}")


if __name__ == "__main__":
    if sys.argv[1:2] == ["--large"]:
        options = sys.argv[2:]
        limit = float(options[options.index("--smoke-cpu-s") + 1]) \
            if "--smoke-cpu-s" in options else SMOKE_CPU_S
        large(limit, timed="--smoke-only" not in options)
    elif sys.argv[1:2] == ["--smoke"]:
        m, samples, k, limit = sys.argv[2:6]
        print(json.dumps(smoke(int(m), int(samples), int(k), float(limit))), flush=True)
        os._exit(0)  # a selection still running in its thread is not waited for
    elif sys.argv[1:2] == ["--measure"]:
        m, samples, k, with_matrix = sys.argv[2:6]
        print(json.dumps(measure(int(m), int(samples), int(k), with_matrix == "True")))
    else:
        main()
