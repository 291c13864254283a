"""Benchmark: season-sweep throughput on this machine, in-process vs 1 vs 2 worker processes.

Runs the shipped example study (``scenarios/studies/season_sweep.toml``) cut to 2 replicas
and one training run (January), i.e. 48 FMU simulations of 6 h and 14 evaluations of 14
methods, three times from scratch in temporary folders, in the same process: in-process (no
worker processes, the baseline), with 1 worker process and with 2. Prints experiments
(simulations) per second of wall time for the whole sweep, the time a worker spent per
simulation and per evaluation, and the speed-up of 2 workers over 1. The results of every
run are checked to be identical (same seeds, any executor).

Then issue 10's goal row: the same example study with 42 replicas, i.e. 24 x 42 = 1 008
experiments (FMU simulations of 6 h, as the study's) and 42 x 7 x 4 = 1 176 evaluations of 14
methods each (in 42 x 7 = 294 jobs: one per replica and condition covers its 4 training runs;
one task per replica holds its 7 jobs), on 2 worker processes, from scratch (goal: <= 3 min on
this machine, results identical to the per-method evaluation, which tests check). It prints
wall seconds, experiments per second, and CPU seconds (this process, which writes every
recording and result, plus the workers' CPU inside their tasks and outside them: start-up,
unpickling the tasks, pickling the results): on the shared machine the wall time holds the
other users' work, the CPU seconds do not.

Run: .venv/bin/python bench/bench_sweep.py [STUDY.toml] [--runs-only | --no-runs]
(a given study runs as it is; --runs-only: only the 1 008-experiment row; --no-runs: without
it)
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd
from spindlebench.studies.family.family_file import load_study
from spindlebench.studies.running.executor import TaskRunner
from spindlebench.studies.sweep.sweep_run import Sweep, write_outputs

from results import record

STUDY = Path(__file__).resolve().parents[1] / "scenarios" / "studies" / "season_sweep.toml"
KEYS = ["replica", "data", "noise", "fault", "train_experiment", "method", "k", "test_experiment"]


#: Replicas of the goal row: 24 experiments x 42 = 1 008 simulations.
GOAL_REPLICAS = 42
GOAL_S = 180.0
#: Issue 26: the whole sweep's CPU (simulations, evaluations, this process) over the
#: simulations' alone (the floor).
GOAL_FLOOR_RATIO = 1.5


def bench_study(folder: Path, replicas: int = 2, one_training_run: bool = True) -> Path:
    """The example study with ``replicas`` replicas (and a single training run)."""
    text = STUDY.read_text(encoding="utf-8")
    edits = [("replicas = 5", f"replicas = {replicas}")]
    if one_training_run:
        edits.append(('rule = "each-season"', 'rule = "one"\nmonth = "Jan"'))
    for old, new in edits:
        if old not in text:
            raise SystemExit(f"{STUDY} changed: cannot find {old!r}; update the benchmark")
        text = text.replace(old, new)
    path = folder / f"bench_sweep_{replicas}.toml"
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
    flags = {arg for arg in sys.argv[1:] if arg.startswith("--")}
    given = [arg for arg in sys.argv[1:] if not arg.startswith("--")]
    rows: list[dict] = []
    with tempfile.TemporaryDirectory(prefix="bench-sweep-study-") as folder:
        if "--runs-only" not in flags:
            rows += measure(Path(given[0]) if given else bench_study(Path(folder)))
        if "--no-runs" not in flags and not given:
            rows.append(goal_row(bench_study(Path(folder), GOAL_REPLICAS, one_training_run=False)))
    goals = {"goal_row_wall_s": GOAL_S, "goal_over_floor": GOAL_FLOOR_RATIO}
    # the goal row alone goes to its own file: the executor rows of bench_sweep.json stay
    name = "bench_sweep_goal" if "--runs-only" in flags else None
    print(f"wrote {record('bench_sweep', rows, goals, name=name)}")
    return 0


def goal_row(study_path: Path) -> dict:
    """The 1 008-experiment season sweep on 2 worker processes, wall and CPU seconds."""
    study = load_study(study_path)
    load_before = list(os.getloadavg())
    load = ", ".join(f"{value:.1f}" for value in load_before)
    with tempfile.TemporaryDirectory(prefix="bench-sweep-goal-") as folder:
        sweep = Sweep(study, Path(folder) / "out")
        runs = len(sweep.family) * study.replicas
        print(f"\n{runs}-experiment season sweep ({len(sweep.family)} experiments x "
              f"{study.replicas} replicas, 6 h each, 2 worker processes), load average before "
              f"{load}")
        start, cpu = time.perf_counter(), time.process_time()
        runner = TaskRunner(workers=2, progress=False)
        outcome = sweep.run(runner)
        run_s, run_cpu = time.perf_counter() - start, time.process_time() - cpu
        write_outputs(sweep, outcome, runner)
        wall, here = time.perf_counter() - start, time.process_time() - cpu
    stats = outcome.stats
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    sim_cpu, eval_cpu = stats.cpu_s.get("simulation", 0.0), stats.cpu_s.get("evaluation", 0.0)
    # the workers' CPU between their tasks (imports, unpickling the jobs, pickling results)
    outside = stats.outside_cpu_s
    total = here + sim_cpu + eval_cpu + outside
    print(f"wall {wall:.0f} s (simulate + evaluate {run_s:.0f} s, tables/plots/README "
          f"{wall - run_s:.0f} s) = {runs / wall:.2f} experiments/s; goal <= {GOAL_S:.0f} s: "
          f"{'holds' if wall <= GOAL_S else 'NOT met'} in wall time; load average after {load}")
    print(f"CPU seconds: {total:.0f} = workers' simulations {sim_cpu:.0f} "
          f"({1000 * sim_cpu / max(1, stats.total('simulation')):.0f} ms each) + evaluations "
          f"{eval_cpu:.0f} ({1000 * eval_cpu / max(1, outcome.evaluated):.0f} ms per replica x "
          f"condition x training run, {outcome.evaluated} in {stats.total('evaluation')} tasks) "
          f"+ the workers outside their tasks {outside:.0f} (start-up, unpickling tasks, "
          f"pickling results) + this process {here:.0f} (recordings written and read back, "
          f"results, of which tables/plots/README {here - run_cpu:.0f})")
    ratio = total / sim_cpu if sim_cpu else float("nan")
    print(f"simulation floor {sim_cpu:.1f} CPU-s (the workers' simulations alone): the sweep "
          f"costs {ratio:.2f}x it (goal <= {GOAL_FLOOR_RATIO}x: evaluations + this process "
          f"<= half the simulations' CPU): {'holds' if ratio <= GOAL_FLOOR_RATIO else 'NOT met'}")
    print(f"on 2 cores of our own that is >= {max(here, total / 2):.0f} s of wall time "
          f"(CPU seconds / 2, or this process's serial part if larger): the goal "
          f"{'holds' if max(here, total / 2) <= GOAL_S else 'is NOT met'} on an idle machine")
    return {"row": "goal", "experiments": runs, "workers": 2, "wall_s": wall,
            "run_wall_s": run_s, "outputs_wall_s": wall - run_s, "cpu_s": total,
            "simulation_cpu_s": sim_cpu, "evaluation_cpu_s": eval_cpu,
            "workers_outside_tasks_cpu_s": outside,
            "coordinator_cpu_s": here, "outputs_cpu_s": here - run_cpu,
            "evaluations": outcome.evaluated, "goal_wall_s": GOAL_S,
            "floor_cpu_s": sim_cpu, "over_floor": ratio, "goal_over_floor": GOAL_FLOOR_RATIO,
            "load_before": load_before, "load_after": list(os.getloadavg())}


def measure(study_path: Path) -> list[dict]:
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    print(f"season sweep benchmark: {study_path} on {os.cpu_count()} core(s), "
          f"load average before the run {load} (other work on the machine skews the ratio)")
    print(f"{'executor':<22}{'wall s':>9}{'exp/s':>9}{'sim ms':>9}{'eval s':>9}")
    walls: dict[int, float] = {}
    rows: list[dict] = []
    reference = None
    for workers, label in ((0, "in-process (baseline)"), (1, "1 worker process"),
                           (2, "2 worker processes")):
        wall, stats, results = run(study_path, workers)
        walls[workers] = wall
        n_sim = stats.total("simulation")
        per_sim_ms = 1000 * stats.busy_s.get("simulation", 0.0) / max(1, n_sim)
        per_eval_s = stats.busy_s.get("evaluation", 0.0) / max(1, stats.total("evaluation"))
        print(f"{label:<22}{wall:9.2f}{n_sim / wall:9.2f}{per_sim_ms:9.1f}{per_eval_s:9.2f}")
        rows.append({"row": "executor", "executor": label, "workers": workers, "wall_s": wall,
                     "simulations": n_sim, "experiments_per_s": n_sim / wall,
                     "ms_per_simulation": per_sim_ms, "s_per_evaluation_job": per_eval_s})
        if reference is None:
            reference = results
        else:
            pd.testing.assert_frame_equal(results, reference)
    print(f"ratio 2 workers / 1 worker: {walls[1] / walls[2]:.2f}x faster "
          f"(ideal 2.00x on 2 free cores); 1 worker / in-process: "
          f"{walls[0] / walls[1]:.2f}x")
    print("results identical across executors: yes")
    return rows


if __name__ == "__main__":
    sys.exit(main())
