"""Benchmark (issue 26): CPU milliseconds of the runner per 6 h paper experiment, FMPy's
Python callbacks against the FMU's C right-hand side, in the same process.

For each scenario and input mode, the same ``co_simulate`` call three ways, interleaved so that
a change of load hits all of them alike (best and median of ``--repeat`` runs of each, CPU
time of this process: the machine is shared):

- ``python``: FMPy's ``CVodeSolver`` with Python callbacks (``native_rhs=False``: what every
  FMU without the C callbacks gets, and the runner before issue 26);
- ``c``: the default, CVode on the FMU's C right-hand side with its loop between output points
  in C (``testbench.native_cvode``); its outputs must be the same bytes as ``python``'s;
- ``c+forward`` and ``c+differences``: the same with the FMU's Jacobian instead of CVode's
  difference quotients (one right-hand side per state): coloured forward derivatives
  (``sb_cvode_jac``) or coloured difference quotients (``sb_cvode_jac_dq``, one right-hand side
  per colour); their largest output difference to ``c`` is printed.

The goal row is exp1 with continuous inputs (the default): ≤ 25 CPU-ms. Writes
``bench/results/bench_runner.json`` (``bench/results.py``).

    .venv/bin/python bench/bench_runner.py [--fmu FILE] [--repeat 15]
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time
from pathlib import Path

import numpy as np
from spindlebench.testbench import runner
from spindlebench.testbench.runner import DEFAULT_FMU, co_simulate
from spindlebench.testbench.scenario import load_scenario

from results import record  # bench/, beside this script

ROOT = Path(__file__).resolve().parents[1]
GOAL_CPU_MS = 25.0
#: (scenario, input mode, runs per variant: the hold's 21 600 stops take a second or more)
CASES = (("scenarios/paper/exp1.toml", "continuous", None),
         ("scenarios/examples/start_stop_cycles.toml", "continuous", None),
         ("scenarios/paper/exp1.toml", "hold", 3))
VARIANTS = ("python", "c", "c+forward", "c+differences")


def run(scenario, fmu: Path, variant: str):
    runner.NATIVE_JACOBIAN = variant.split("+")[1] if "+" in variant else "cvode"
    try:
        started = time.process_time()
        simulation = co_simulate(scenario, fmu, native_rhs=variant != "python")
        return time.process_time() - started, simulation
    finally:
        runner.NATIVE_JACOBIAN = "cvode"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmu", type=Path, default=DEFAULT_FMU)
    parser.add_argument("--repeat", type=int, default=15)
    args = parser.parse_args()
    rows = []
    for path, mode, repeat in CASES:
        scenario = dataclasses.replace(load_scenario(ROOT / path), inputs=mode)
        repeat = repeat or args.repeat
        times: dict[str, list[float]] = {v: [] for v in VARIANTS}
        last = {}
        for variant in VARIANTS:  # load the binary, unpack the FMU: not what is measured
            run(scenario, args.fmu, variant)
        for _ in range(repeat):
            for variant in VARIANTS:
                seconds, last[variant] = run(scenario, args.fmu, variant)
                times[variant].append(seconds)
        python, c = last["python"], last["c"]
        same = all(python.outputs[n].tobytes() == c.outputs[n].tobytes() for n in python.outputs)
        gap = {v: max(float(np.max(np.abs(last[v].outputs[n] - c.outputs[n])))
                      for n in c.outputs if n.endswith(("_C", "_um")))
               for v in ("c+forward", "c+differences")}
        best = {v: min(t) * 1e3 for v, t in times.items()}
        median = {v: statistics.median(t) * 1e3 for v, t in times.items()}
        goal = path.endswith("exp1.toml") and mode == "continuous"
        label = f"{Path(path).stem} ({scenario.duration_s / 3600:g} h, {mode})"
        verdict = "met" if best["c"] <= GOAL_CPU_MS else "NOT met"
        print(f"{label}: Python callbacks {best['python']:.1f} CPU-ms (median "
              f"{median['python']:.1f}), C right-hand side {best['c']:.1f} ({median['c']:.1f}), "
              f"{best['python'] / best['c']:.2f}x, same bytes: {same}; with the FMU's forward "
              f"Jacobian {best['c+forward']:.1f} ({median['c+forward']:.1f}, within "
              f"{gap['c+forward']:.1e} K/um), coloured differences {best['c+differences']:.1f} "
              f"({median['c+differences']:.1f}, within {gap['c+differences']:.1e})"
              + (f"; goal <= {GOAL_CPU_MS:g} CPU-ms: {verdict}" if goal else ""))
        rows.append({
            "scenario": path, "inputs": mode, "duration_s": scenario.duration_s, "runs": repeat,
            "solver_stops": c.solver["solver_stops"],
            **{f"{v.replace('+', '_')}_cpu_ms_min": best[v] for v in VARIANTS},
            **{f"{v.replace('+', '_')}_cpu_ms_median": median[v] for v in VARIANTS},
            "speed_up": best["python"] / best["c"], "same_bytes": same,
            **{f"{v.replace('+', '_')}_max_abs_difference": g for v, g in gap.items()},
            **({"goal_cpu_ms": GOAL_CPU_MS, "met": best["c"] <= GOAL_CPU_MS} if goal else {}),
        })
    print(f"wrote {record('bench_runner', rows, {'exp1_continuous_cpu_ms': GOAL_CPU_MS})}")


if __name__ == "__main__":
    main()
