"""Benchmark: the FMU co-simulation runner (continuous inputs vs the 1 s hold) and solve_ivp.

Simulates the paper's experiment 1 (6 h, 1 s communication grid) in this process:

0. the runner with continuous-time inputs (the default): the ambient evaluated at the
   solver's time, CVode stopped only at output points and input jumps; its ratio to (1) is
   issue 10's goal (>= 10x, outputs within 0.01 um / 0.01 K);
1. the runner with ``inputs = "hold"`` (today's way until issue 10): FMPy, the compiled FMU,
   inputs held over each step, CVode stopped at every communication point;
2. the same co-simulation done with SciPy: ``solve_ivp`` called for every communication step,
   on a Python function that evaluates the same equations
   (``spindlebench.model.equations.explicit_ode``, a CasADi function);
3. for scale, not a co-simulation: one ``solve_ivp`` call over the whole run with the held
   inputs looked up inside the right-hand side; it strides over the communication points, so it
   only shows what the 21 600 input exchanges cost.

Prints wall time per simulated hour and the ratios, plus the largest difference in drift and
sensor temperatures against the runner, so a fast but wrong variant cannot look good.

Last, issue 10's question whether the Jacobian from the FMU's directional derivatives pays
(``bench/jacobian_variant.py``): CPU seconds of the default runner with CVode's own
difference quotients against the same run with the FMU's Jacobian, on experiment 1 and on
the start/stop example (the spindle standing still).

With ``--baseline-fmu OLD.fmu`` (issue 26, the FMU's hot loop): CPU seconds of the default
runner on OLD and on ``--fmu`` (best of 5, same process), their ratio and whether the outputs
are the same bytes; e.g. the FMU of the commit before the value-reference table
(``git show b91ff71:fmus/SpindleBench.fmu > /tmp/old.fmu``). Also the co-simulation
interface (``fmi3DoStep``, ``testbench.cosim``) on the same experiment, with its difference
to the runner's hold.

Every row (and the build comparison) is also written to ``bench/results/bench_simulation.json``
(``bench/results.py``), which the speed page shows.

    .venv/bin/python bench/bench_simulation.py [--scenario FILE] [--fmu FILE] [--method LSODA]
        [--baseline-fmu OLD.fmu]
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import jacobian_variant  # bench/, beside this script
import numpy as np
from scipy.integrate import solve_ivp
from spindlebench.testbench.drivers import INPUT_NAMES, drive
from spindlebench.testbench.runner import (
    DEFAULT_FMU,
    RELATIVE_TOLERANCE,
    FmuInterface,
    co_simulate,
    inspect_fmu,
)
from spindlebench.testbench.scenario import Scenario, load_scenario

from results import record

ROOT = Path(__file__).resolve().parents[1]
ABSOLUTE_TOLERANCE_K = 1e-6
#: Issue 10's goal: continuous inputs at least this much faster than the 1 s hold.
GOALS = {"continuous_speed_up_over_hold": 10.0, "max_d_drift_um": 0.01, "max_d_T_K": 0.01}


def fmu_segments(info: FmuInterface) -> int | None:
    """Segments per large part the FMU was built with (its build writes them in the description)."""
    found = re.search(r"(\d+) segments per large part", info.model_description.description or "")
    return int(found.group(1)) if found else None


class Equations:
    """The model's explicit ODE as Python callables, with the run's inputs and parameters."""

    def __init__(self, scenario: Scenario, info: FmuInterface, parameters: Mapping[str, float]):
        from spindlebench.model.equations import explicit_ode

        segments = fmu_segments(info)
        model = (explicit_ode(ROOT / "models") if segments is None
                 else explicit_ode(ROOT / "models", segments=segments))
        if set(model.states) != set(info.state_names):
            raise SystemExit(f"models/ (segments={model.segments}) and {info.path.name} have "
                             "different states: rebuild the FMU (spindlebench build) first")
        self.model = model
        self.p = model.parameter_vector(**parameters)  # the same values the FMU was given
        signals = drive(scenario)
        columns = [INPUT_NAMES.index(name) for name in model.inputs]
        self.held = np.ascontiguousarray(signals.matrix[:, columns])
        self.sample_rows = np.arange(0, scenario.n_steps + 1, scenario.steps_per_sample)
        self.scenario = scenario

    def rhs_with(self, u: np.ndarray) -> Callable[[float, np.ndarray], np.ndarray]:
        ode, p = self.model.ode, self.p
        return lambda _t, x: np.asarray(ode(x, u, p)[0]).ravel()

    def outputs(self, states: np.ndarray) -> dict[str, np.ndarray]:
        """Model outputs at the sample times, from states sampled there (one row each)."""
        ode, p = self.model.ode, self.p
        y = np.column_stack([np.asarray(ode(x, self.held[row], p)[1]).ravel()
                             for x, row in zip(states, self.sample_rows, strict=True)])
        return {name: y[j] for j, name in enumerate(self.model.outputs)}


def stepped_solve_ivp(eq: Equations, x0: np.ndarray, method: str) -> np.ndarray:
    """The co-simulation loop in SciPy: one solve_ivp call per communication step."""
    scenario = eq.scenario
    h, every = scenario.step_s, scenario.steps_per_sample
    states = [x0]
    x = x0
    for k in range(scenario.n_steps):
        solution = solve_ivp(eq.rhs_with(eq.held[k]), (k * h, (k + 1) * h), x, method=method,
                             rtol=RELATIVE_TOLERANCE["hold"], atol=ABSOLUTE_TOLERANCE_K)
        if not solution.success:
            raise RuntimeError(f"solve_ivp failed at t={k * h:g} s: {solution.message}")
        x = solution.y[:, -1]
        if (k + 1) % every == 0:
            states.append(x)
    return np.array(states)


def one_call_solve_ivp(eq: Equations, x0: np.ndarray, method: str) -> np.ndarray:
    """One solve_ivp call over the whole run, held inputs looked up by time in the RHS."""
    scenario = eq.scenario
    ode, p, held = eq.model.ode, eq.p, eq.held
    h, last = scenario.step_s, len(held) - 1

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        return np.asarray(ode(x, held[min(int(t / h + 1e-9), last)], p)[0]).ravel()

    solution = solve_ivp(rhs, (0.0, scenario.duration_s), x0, method=method,
                         t_eval=eq.sample_rows * h, rtol=RELATIVE_TOLERANCE["hold"],
                         atol=ABSOLUTE_TOLERANCE_K)
    if not solution.success:
        raise RuntimeError(f"solve_ivp failed: {solution.message}")
    return solution.y.T


def timed(function: Callable[..., Any], *args: Any) -> tuple[float, Any]:
    started = time.perf_counter()
    result = function(*args)
    return time.perf_counter() - started, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", type=Path, default=ROOT / "scenarios/paper/exp1.toml")
    parser.add_argument("--fmu", type=Path, default=DEFAULT_FMU)
    parser.add_argument("--method", default="LSODA",
                        help="solve_ivp method (LSODA was the fastest on this model; BDF, RK45 …)")
    parser.add_argument("--baseline-fmu", type=Path, default=None,
                        help="an older FMU build: CPU ratio of the default runner on it and on "
                             "--fmu, and whether their outputs are the same bytes")
    args = parser.parse_args()
    rows: list[dict] = []
    if args.baseline_fmu is not None:
        rows.append(compare_builds(load_scenario(args.scenario), args.baseline_fmu, args.fmu))
    scenario = dataclasses.replace(load_scenario(args.scenario), inputs="hold")
    hours = scenario.duration_s / 3600.0
    info = inspect_fmu(args.fmu)
    print(f"{scenario.path.name}: {hours:g} h at a {scenario.step_s:g} s communication step "
          f"({scenario.n_steps} steps); {args.fmu.name}: {len(info.state_names)} states, "
          f"{len(info.output_names)} outputs; solve_ivp method {args.method}, rtol "
          f"{RELATIVE_TOLERANCE['hold']:g}")

    runner_s, simulation = timed(co_simulate, scenario, args.fmu)
    continuous = dataclasses.replace(scenario, inputs="continuous")
    continuous_s, smooth = timed(co_simulate, continuous, args.fmu)
    drift = np.abs(smooth.outputs["drift_um"] - simulation.outputs["drift_um"]).max()
    temps = max(np.abs(smooth.outputs[f"T{i}_C"] - simulation.outputs[f"T{i}_C"]).max()
                for i in range(1, 21))
    eq = Equations(scenario, info, simulation.parameters)
    x0 = np.array([simulation.initial_state_K[name] for name in eq.model.states])
    stepped_s, stepped = timed(stepped_solve_ivp, eq, x0, args.method)
    single_s, single = timed(one_call_solve_ivp, eq, x0, args.method)

    def report(label: str, seconds: float, states: np.ndarray | None) -> None:
        line = f"{label:<46} {seconds:8.3f} s = {seconds / hours:7.3f} s/sim h"
        row = {"variant": label, "wall_s": seconds, "s_per_simulated_h": seconds / hours}
        if states is not None:
            other = eq.outputs(states)
            drift = np.abs(simulation.outputs["drift_um"] - other["drift_um"]).max()
            temps = max(np.abs(simulation.outputs[f"T{i}_C"] - other[f"T{i}_C"]).max()
                        for i in range(1, 21))
            line += (f"  {seconds / runner_s:6.2f}x the runner's time, "
                     f"max|d drift| {drift:.1e} um, max|d T| {temps:.1e} K")
            row.update({"ratio_to_hold": seconds / runner_s, "max_d_drift_um": float(drift),
                        "max_d_T_K": float(temps)})
        rows.append(row)
        print(line)

    print(f"{'runner, continuous inputs (default)':<46} {continuous_s:8.3f} s = "
          f"{continuous_s / hours:7.3f} s/sim h  {runner_s / continuous_s:6.1f}x faster than "
          f"the 1 s hold ({smooth.solver['solver_stops']} vs {simulation.solver['solver_stops']}"
          f" CVode stops), max|d drift| {drift:.1e} um, max|d T| {temps:.1e} K")
    rows.append({"variant": "runner, continuous inputs (default)", "wall_s": continuous_s,
                 "s_per_simulated_h": continuous_s / hours,
                 "ratio_to_hold": continuous_s / runner_s, "max_d_drift_um": float(drift),
                 "max_d_T_K": float(temps), "solver_stops": smooth.solver["solver_stops"]})
    report("runner, 1 s hold: FMPy + CVode on the FMU", runner_s, None)
    report("solve_ivp per communication step (same job)", stepped_s, stepped)
    report("solve_ivp in one call (not a co-simulation)", single_s, single)
    print(f"speed-up of the runner over solve_ivp doing the same co-simulation: "
          f"{stepped_s / runner_s:.1f}x")
    from spindlebench.testbench.cosim import co_simulate_cs

    cs_s, cs = timed(co_simulate_cs, scenario, args.fmu)
    drift = np.abs(cs.outputs["drift_um"] - simulation.outputs["drift_um"]).max()
    temps = max(np.abs(cs.outputs[n] - simulation.outputs[n]).max()
                for n in cs.outputs if n.endswith("_C") and n in simulation.outputs)
    print(f"{'fmi3DoStep (SDIRK4 in the FMU), 1 s steps':<46} {cs_s:8.3f} s = "
          f"{cs_s / hours:7.3f} s/sim h  {cs_s / runner_s:6.2f}x the runner's time, "
          f"max|d drift| {drift:.1e} um, max|d T| {temps:.1e} K (all temperature outputs)")
    rows.append({"variant": "fmi3DoStep (SDIRK4 in the FMU), 1 s steps", "wall_s": cs_s,
                 "s_per_simulated_h": cs_s / hours, "ratio_to_hold": cs_s / runner_s,
                 "max_d_drift_um": float(drift), "max_d_T_K": float(temps)})
    print("Jacobian from the FMU's directional derivatives instead of CVode's difference "
          "quotients (continuous inputs, best of 3, CPU seconds):")
    rows += jacobian_variant.report(args.scenario.name, continuous, args.fmu)
    stops = load_scenario(ROOT / "scenarios/examples/start_stop_cycles.toml")
    rows += jacobian_variant.report(stops.path.name, stops, args.fmu)
    print(f"wrote {record('bench_simulation', rows, GOALS)}")


def compare_builds(scenario: Scenario, baseline: Path, fmu: Path) -> dict:
    """CPU seconds (best of 5) of the default runner on two FMU builds, and equal bytes (also
    returned as a row)."""
    def best(path: Path) -> tuple[float, Any]:
        times, result = [], None
        for _ in range(5):
            started = time.process_time()
            result = co_simulate(scenario, path)
            times.append(time.process_time() - started)
        return min(times), result

    best(fmu), best(baseline)  # load both binaries first
    old_s, old = best(baseline)
    new_s, new = best(fmu)
    same = all(old.outputs[n].tobytes() == new.outputs[n].tobytes() for n in old.outputs)
    print(f"runner (default inputs) on {baseline}: {old_s * 1e3:.1f} CPU-ms, on {fmu}: "
          f"{new_s * 1e3:.1f} CPU-ms, ratio {old_s / new_s:.2f}; outputs identical in bytes: "
          f"{same} ({len(old.outputs)} outputs)")
    return {"variant": f"runner (default inputs) on {baseline.name} against {fmu.name}",
            "cpu_s": new_s, "baseline_cpu_s": old_s, "identical_outputs": same}


if __name__ == "__main__":
    main()
