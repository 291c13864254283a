"""Benchmark: one warm state saved and forked into 20 scenarios, against 20 soaks (issue 24).

Twenty runs of the paper's experiment 1 at 20 spindle speeds (1 000 to 4 800 rpm), each
starting from the same soak history (``initial.kind = "soak"``: ``--days`` idle days of the
run's season cycle; the speed is not part of the soak, so all twenty share one):

A. each run soaks itself: the soak cache is emptied before every run, so each simulates its
   ``--days`` of history, then the run;
B. the soak is simulated once; its end is saved as an FMU state (``fmi3GetFMUState`` +
   ``fmi3SerializeFMUState``, ``testbench.soak.soak_start``) and restored into every run
   (``fmi3DeserializeFMUState`` + ``fmi3SetFMUState``).

Prints the CPU seconds (``time.process_time``, this process only) of A and B, their ratio,
the load average, and whether the twenty recordings of A and B are the same bytes (they must
be: the restored state is exactly the soak's end), and writes them to
``bench/results/bench_warm_start.json`` (``bench/results.py``).

    PYTHONPATH=pipeline .venv/bin/python bench/bench_warm_start.py [--days 7] [--hours 1]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import tempfile
import time
from pathlib import Path

import numpy as np
from spindlebench.testbench import soak
from spindlebench.testbench.runner import DEFAULT_FMU, co_simulate
from spindlebench.testbench.scenario import ConstantSpeed, InitialState, load_scenario
from spindlebench.testbench.simulate import run_start_with_state

from results import record

ROOT = Path(__file__).resolve().parents[1]
SPEEDS_RPM = tuple(range(1000, 5000, 200))  # 20 scenarios


def scenarios(days: int, hours: float) -> list:
    base = load_scenario(ROOT / "scenarios" / "paper" / "exp1.toml")
    base = dataclasses.replace(base, duration_s=hours * 3600.0,
                               initial=InitialState(kind="soak", days=days))
    return [dataclasses.replace(base, name=f"exp1 {rpm} rpm", speed=ConstantSpeed(rpm=rpm))
            for rpm in SPEEDS_RPM]


def run_all(runs: list, fmu: Path, fresh_soak_each: bool) -> tuple[float, list[bytes]]:
    """CPU seconds and the output bytes of every run."""
    outputs = []
    with tempfile.TemporaryDirectory(prefix="bench-soak-") as folder:
        os.environ[soak.CACHE_ENV] = folder
        soak._memory.clear()
        soak._memory_fmu_state.clear()
        started = time.process_time()
        for index, scenario in enumerate(runs):
            if fresh_soak_each:
                soak._memory.clear()
                soak._memory_fmu_state.clear()
                os.environ[soak.CACHE_ENV] = str(Path(folder) / str(index))
            start, warm = run_start_with_state(scenario, fmu)
            result = co_simulate(scenario, fmu, start=start, start_fmu_state=warm)
            outputs.append(b"".join(np.ascontiguousarray(v).tobytes()
                                    for v in result.outputs.values()))
        return time.process_time() - started, outputs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=int, default=7, help="soak days (default 7)")
    parser.add_argument("--hours", type=float, default=1.0, help="hours per run (default 1)")
    parser.add_argument("--fmu", type=Path, default=DEFAULT_FMU)
    args = parser.parse_args()
    runs = scenarios(args.days, args.hours)
    co_simulate(runs[0], args.fmu, start=run_start_with_state(runs[0], args.fmu)[0])  # warm-up
    load_before = os.getloadavg()[0]
    cpu_a, out_a = run_all(runs, args.fmu, fresh_soak_each=True)
    cpu_b, out_b = run_all(runs, args.fmu, fresh_soak_each=False)
    load_after = os.getloadavg()[0]
    same = sum(a == b for a, b in zip(out_a, out_b, strict=True))
    print(f"{len(runs)} runs of {args.hours:g} h after a {args.days}-day soak "
          f"(load average {load_before:.2f} -> {load_after:.2f})")
    print(f"A. 20 soaks:                      {cpu_a:7.2f} CPU-s")
    print(f"B. 1 soak, saved state restored:  {cpu_b:7.2f} CPU-s")
    print(f"ratio A/B {cpu_a / cpu_b:.2f}; recordings identical in bytes: {same} of {len(runs)}")
    common = {"runs": len(runs), "hours_per_run": args.hours, "soak_days": args.days}
    rows = [{"way": "A. every run soaks itself", **common, "cpu_s": cpu_a},
            {"way": "B. one soak, saved FMU state restored", **common, "cpu_s": cpu_b,
             "ratio_A_over_B": cpu_a / cpu_b, "identical_recordings": same}]
    print(f"wrote {record('bench_warm_start', rows)}")


if __name__ == "__main__":
    main()
