"""Benchmark and check: the FMU's co-simulation interface (``fmi3DoStep``) against CVode.

The paper's experiment 1 (6 h, 1 s communication step, cold start at the 5.3 °C air):

- ``fmi3DoStep`` (SDIRK4 in the FMU, ``testbench.cosim.co_simulate_cs``, tolerance 1e-6),
  inputs held over each step;
- the runner's CVode on model exchange with the same zero-order hold (``inputs = "hold"``),
  at its default relative tolerance (1e-6) and converged (1e-8).

Prints CPU seconds and the largest differences in drift and in every temperature output
(121 outputs, 361 samples); the issue's agreement is 0.01 um and 0.001 K. Then why
``build --cross-check`` uses rtol 1e-10, and how the remaining difference between the two
depends on the step and on the air (``input_timing``).

    PYTHONPATH=pipeline .venv/bin/python bench/bench_cosim.py [--fmu FILE]

Every comparison is also a row of ``bench/results/bench_cosim.json`` (``bench/results.py``).
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np
from spindlebench.testbench import runner
from spindlebench.testbench.cosim import co_simulate_cs
from spindlebench.testbench.scenario import load_scenario

from results import record

ROOT = Path(__file__).resolve().parents[1]


#: The comparisons as rows for ``bench/results/bench_cosim.json``.
ROWS: list[dict] = []
#: The issue's agreement of fmi3DoStep with CVode.
GOALS = {"max_d_drift_um": 0.01, "max_d_T_K": 0.001}


def differences(a: dict, b: dict, what: str = "") -> str:
    """The largest differences of drift and of any temperature between two runs (and a row
    of the results file named ``what``, when given)."""
    temps = [n for n in a if n.endswith("_C") and n in b]
    worst = max(temps, key=lambda n: float(np.max(np.abs(a[n] - b[n]))))
    d_t = float(np.max(np.abs(a[worst] - b[worst])))
    d_drift = float(np.max(np.abs(a["drift_um"] - b["drift_um"])))
    if what:
        ROWS.append({"comparison": what, "max_d_drift_um": d_drift, "max_d_T_K": d_t,
                     "worst_output": worst})
    return f"max|d drift| {d_drift:.2e} um, max|d T| {d_t:.2e} K ({worst})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmu", type=Path, default=runner.DEFAULT_FMU)
    args = parser.parse_args()
    scenario = dataclasses.replace(load_scenario(ROOT / "scenarios/paper/exp1.toml"),
                                   inputs="hold")
    results, cpu = {}, {}
    for rtol in (1e-6, 1e-8, 1e-10):
        runner.RELATIVE_TOLERANCE["hold"] = rtol
        started = time.process_time()
        results[rtol] = runner.co_simulate(scenario, args.fmu).outputs
        cpu[rtol] = time.process_time() - started
    started = time.process_time()
    cs = co_simulate_cs(scenario, args.fmu, tolerance=1e-6).outputs
    cpu_cs = time.process_time() - started
    cs_tight = co_simulate_cs(scenario, args.fmu, tolerance=1e-9).outputs
    print(f"exp1, 6 h, 1 s communication step, {len(cs)} outputs, "
          f"{len(cs['drift_um'])} samples")
    print(f"CVode rtol 1e-6 (runner hold):  {cpu[1e-6]:6.2f} CPU-s")
    print(f"CVode rtol 1e-8 (runner hold):  {cpu[1e-8]:6.2f} CPU-s")
    print(f"fmi3DoStep, tolerance 1e-6:     {cpu_cs:6.2f} CPU-s")
    for label, seconds in (("CVode rtol 1e-6 (runner hold)", cpu[1e-6]),
                           ("CVode rtol 1e-8 (runner hold)", cpu[1e-8]),
                           ("fmi3DoStep, tolerance 1e-6", cpu_cs)):
        ROWS.append({"comparison": f"exp1 6 h: CPU s of {label}", "cpu_s": seconds})
    print("fmi3DoStep vs CVode 1e-8: "
          f"{differences(cs, results[1e-8], 'exp1 6 h: fmi3DoStep 1e-6 vs CVode 1e-8')}")
    print("fmi3DoStep vs CVode 1e-6: "
          f"{differences(cs, results[1e-6], 'exp1 6 h: fmi3DoStep 1e-6 vs CVode 1e-6')}")
    print("CVode 1e-6 vs CVode 1e-8: "
          f"{differences(results[1e-6], results[1e-8], 'exp1 6 h: CVode 1e-6 vs 1e-8')}")
    print("each converged on its own: fmi3DoStep 1e-9 vs 1e-6: "
          f"{differences(cs_tight, cs, 'exp1 6 h: fmi3DoStep 1e-9 vs 1e-6')}; "
          "CVode 1e-10 vs 1e-8: "
          f"{differences(results[1e-10], results[1e-8], 'exp1 6 h: CVode 1e-10 vs 1e-8')}")
    cross_check_reference(args.fmu)
    input_timing(scenario, args.fmu)
    print(f"wrote {record('bench_cosim', ROWS, GOALS)}")


def input_timing(scenario, fmu: Path) -> None:
    """Where the remaining difference comes from: 3 h of exp1 with the season's air at a 1 s
    and a 0.5 s step, and with a constant air, fmi3DoStep (1e-8) against CVode (1e-9)."""
    from spindlebench.testbench.scenario import ConstantAmbient

    base = dataclasses.replace(scenario, duration_s=3 * 3600.0)
    runner.RELATIVE_TOLERANCE["hold"] = 1e-9
    for label, variant in (("season air, 1 s step", base),
                           ("season air, 0.5 s step", dataclasses.replace(base, step_s=0.5)),
                           ("constant air, 1 s step", dataclasses.replace(
                               base, ambient=ConstantAmbient(temperature_C=7.0)))):
        cvode = runner.co_simulate(variant, fmu).outputs
        cs = co_simulate_cs(variant, fmu, tolerance=1e-8).outputs
        print(f"3 h, {label}: fmi3DoStep vs CVode "
              f"{differences(cs, cvode, f'exp1 3 h, {label}: fmi3DoStep 1e-8 vs CVode 1e-9')}")


def cross_check_reference(fmu: Path) -> None:
    """Why ``build --cross-check``'s reference uses rtol 1e-10: FMPy's CVode at 1e-8 and 1e-10
    on the cross-check experiment (exp1's inputs from the FMU's default start)."""
    from fmpy import simulate_fmu
    from spindlebench.testbench.cross_check import REFERENCE_OUTPUTS, experiment_inputs

    inputs, stop_s = experiment_inputs(ROOT / "scenarios/paper/exp1.toml")
    runs = {rtol: simulate_fmu(str(fmu), fmi_type="ModelExchange", stop_time=stop_s,
                               input=inputs, output_interval=1.0, relative_tolerance=rtol,
                               output=list(REFERENCE_OUTPUTS)) for rtol in (1e-8, 1e-10)}
    a, b = ({n: r[n] for n in REFERENCE_OUTPUTS} for r in runs.values())
    print("cross-check experiment, FMPy CVode 1e-8 vs 1e-10: "
          f"{differences(a, b, 'cross-check experiment: FMPy CVode 1e-8 vs 1e-10')}")


if __name__ == "__main__":
    main()
