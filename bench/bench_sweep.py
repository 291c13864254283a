"""Benchmark: season-sweep throughput on this machine, in-process vs 1 vs 2 worker processes.

Runs the shipped example study (``scenarios/studies/season_sweep.toml``) cut to 2 replicas
and one training run (January), i.e. 48 FMU simulations of 6 h and 14 evaluations of 14
methods, three times from scratch in temporary folders, in the same process: in-process (no
worker processes, the baseline), with 1 worker process and with 2. Prints experiments
(simulations) per second of wall time for the whole sweep, the time a worker spent per
simulation and per evaluation, and the speed-up of 2 workers over 1. The results of every
run are checked to be identical (same seeds, any executor).

Run: .venv/bin/python bench/bench_sweep.py [STUDY.toml]   (a given study runs as it is)
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd
from spindlebench.studies.executor import TaskRunner
from spindlebench.studies.study import load_study
from spindlebench.studies.sweep import Sweep

STUDY = Path(__file__).resolve().parents[1] / "scenarios" / "studies" / "season_sweep.toml"
KEYS = ["replica", "data", "noise", "fault", "train_experiment", "method", "k", "test_experiment"]


def bench_study(folder: Path) -> Path:
    """The example study with 2 replicas and a single training run."""
    text = STUDY.read_text(encoding="utf-8")
    for old, new in (("replicas = 5", "replicas = 2"),
                     ('rule = "each-season"', 'rule = "one"\nmonth = "Jan"')):
        if old not in text:
            raise SystemExit(f"{STUDY} changed: cannot find {old!r}; update the benchmark")
        text = text.replace(old, new)
    path = folder / "bench_sweep.toml"
    path.write_text(text, encoding="utf-8")
    return path


def run(study_path: Path, workers: int) -> tuple[float, object, pd.DataFrame]:
    with tempfile.TemporaryDirectory(prefix="bench-sweep-") as folder:
        sweep = Sweep(load_study(study_path), Path(folder) / "out")
        start = time.perf_counter()
        outcome = sweep.run(TaskRunner(workers=workers, progress=False))
        wall = time.perf_counter() - start
    return wall, outcome.stats, outcome.results.sort_values(KEYS).reset_index(drop=True)


def main() -> int:
    with tempfile.TemporaryDirectory(prefix="bench-sweep-study-") as folder:
        study_path = Path(sys.argv[1]) if len(sys.argv) > 1 else bench_study(Path(folder))
        return measure(study_path)


def measure(study_path: Path) -> int:
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    print(f"season sweep benchmark: {study_path} on {os.cpu_count()} core(s), "
          f"load average before the run {load} (other work on the machine skews the ratio)")
    print(f"{'executor':<22}{'wall s':>9}{'exp/s':>9}{'sim ms':>9}{'eval s':>9}")
    walls: dict[int, float] = {}
    reference = None
    for workers, label in ((0, "in-process (baseline)"), (1, "1 worker process"),
                           (2, "2 worker processes")):
        wall, stats, results = run(study_path, workers)
        walls[workers] = wall
        n_sim = stats.total("simulation")
        per_sim_ms = 1000 * stats.busy_s.get("simulation", 0.0) / max(1, n_sim)
        per_eval_s = stats.busy_s.get("evaluation", 0.0) / max(1, stats.total("evaluation"))
        print(f"{label:<22}{wall:9.2f}{n_sim / wall:9.2f}{per_sim_ms:9.1f}{per_eval_s:9.2f}")
        if reference is None:
            reference = results
        else:
            pd.testing.assert_frame_equal(results, reference)
    print(f"ratio 2 workers / 1 worker: {walls[1] / walls[2]:.2f}x faster "
          f"(ideal 2.00x on 2 free cores); 1 worker / in-process: "
          f"{walls[0] / walls[1]:.2f}x")
    print("results identical across executors: yes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
