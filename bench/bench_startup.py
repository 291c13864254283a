"""Benchmark: what the command line costs before it does anything (issue 26's start-up goals).

CPU seconds (user + system of the child process, ``resource.getrusage(RUSAGE_CHILDREN)``: on
this shared machine the wall time follows the other users' load, the CPU time much less) of
``spindlebench --help``, of every ``spindlebench CMD --help``, of a mistyped command and of a
small ``evaluate`` end to end (two synthetic recordings of 6 sensors and 6 h at one sample a
minute, 2 clusters), each run ``RUNS`` times; the minimum and median are printed against the
goals (``--help`` and a mistyped command <= 0.5 CPU-s, the small ``evaluate`` <= 0.6), with
the load average, and written to ``bench/results/bench_startup.json``.

Run: .venv/bin/python bench/bench_startup.py
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from spindlebench.commands.main import COMMANDS

from results import record

#: Runs of each command line (the minimum is the cost, the median shows the noise).
RUNS = 3
GOALS = {"help_cpu_s": 0.5, "mistyped_cpu_s": 0.5, "small_evaluate_cpu_s": 0.6}


def command() -> list[str]:
    """The console script beside this interpreter, else ``python -m spindlebench``."""
    script = Path(sys.executable).with_name("spindlebench")
    return [str(script)] if script.exists() else [sys.executable, "-m", "spindlebench"]


def child_cpu_s(argv: list[str]) -> tuple[float, int]:
    """CPU seconds and exit status of one run of ``argv`` (output discarded)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    status = subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), status


def small_recordings(folder: Path) -> list[Path]:
    """Two recordings of 6 sensors, 6 h at 60 s: a first-order heating and a drift from it."""
    rng = np.random.default_rng(0)
    paths = []
    for seed, name in enumerate(("train", "test")):
        t = np.arange(361) * 60.0
        tau = np.array([1800.0, 2400.0, 3600.0, 5400.0, 7200.0, 9000.0])
        rise = (2.0 + seed) * (1 - np.exp(-t[:, None] / tau))
        rise += 0.02 * rng.standard_normal((t.size, 6))
        drift = rise @ np.array([3.0, -1.0, 2.0, 0.5, 0.0, 1.0])
        drift += 0.1 * rng.standard_normal(t.size)
        lines = ["time_s," + ",".join(f"T{i + 1}" for i in range(6)) + ",drift_um"]
        for i in range(t.size):
            values = (t[i], *(20.0 + rise[i]), drift[i] - drift[0])
            lines.append(",".join(f"{v:.4f}" for v in values))
        paths.append(folder / f"{name}.csv")
        paths[-1].write_text("\n".join(lines) + "\n", encoding="utf-8")
    return paths


def main() -> int:
    base = command()
    with tempfile.TemporaryDirectory(prefix="bench-startup-") as folder:
        train, test = small_recordings(Path(folder))
        cases = [("spindlebench --help", ["--help"], "help_cpu_s"),
                 *((f"spindlebench {name} --help", [name, "--help"], "help_cpu_s")
                   for name in COMMANDS),
                 ("spindlebench simulat (mistyped)", ["simulat", "x.toml"], "mistyped_cpu_s"),
                 ("spindlebench evaluate (6 sensors, 361 samples, k=2)",
                  ["evaluate", "--train", str(train), "--test", str(test), "--target",
                   "drift_um", "--clusters", "2"], "small_evaluate_cpu_s")]
        load_before = list(os.getloadavg())
        print("start-up benchmark: CPU seconds of the child process, "
              f"{RUNS} runs each; load average {', '.join(f'{v:.1f}' for v in load_before)}")
        print(f"{'command':<56}{'min':>7}{'median':>8}{'goal':>7}  met")
        rows = []
        for label, argv, goal in cases:
            runs = [child_cpu_s(base + argv) for _ in range(RUNS)]
            cpu = [c for c, _ in runs]
            status = runs[0][1]
            met = min(cpu) <= GOALS[goal]
            print(f"{label:<56}{min(cpu):7.2f}{statistics.median(cpu):8.2f}{GOALS[goal]:7.2f}  "
                  f"{'yes' if met else 'NO'}", flush=True)
            rows.append({"command": label, "argv": argv[:1] + ["..."] * (len(argv) > 2),
                         "cpu_s_min": min(cpu), "cpu_s_median": statistics.median(cpu),
                         "runs": RUNS, "exit_status": status, "goal": goal,
                         "goal_cpu_s": GOALS[goal], "met": met})
    path = record("bench_startup", rows, GOALS)
    print(f"load average after {', '.join(f'{v:.1f}' for v in os.getloadavg())}; wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
