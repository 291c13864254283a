"""A batch of scenario files: validated whole and ordered before the first run.

A scenario may continue from another of the same batch (``initial.from``), so the batch is
planned first: each scenario loaded once, runs ordered after the run they continue from, and
every FMU-dependent check made, so a mistake in the last file costs nothing.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.testbench.runner import (
    check_scenario,
    inspect_fmu,
)
from spindlebench.testbench.scenario import (
    Scenario,
    load_scenario,
    resolve_initial,
    start_state,
    with_machine,
)


@dataclass(frozen=True)
class BatchPlan:
    """A validated batch: each scenario loaded once, and the order to run them in."""

    order: list[int]  # indices into the batch, each after the run it continues from
    scenarios: list[Scenario]  # loaded, with sibling references resolved to files
    state_from_batch: list[bool]  # whether a run's start state is written by an earlier run
    #: the index of the run each run continues from (None: not a run of this batch)
    producers: list[int | None] = field(default_factory=list)


def plan_batch(files: list[Path], targets: list[Path], machine: str | None = None) -> BatchPlan:
    """Validate a batch and order it so a run comes after the run it continues from.

    ``targets[i]`` is the CSV that ``files[i]`` will be written to. A scenario whose
    ``initial.from`` is the sidecar of another target (by sibling name or by path) runs after
    it; otherwise the given (alphabetical) order is kept. ``machine`` (``--machine``) replaces
    every scenario's machine. A reference that no run of the batch
    writes and that does not exist yet, or a circle of continuations, is one error line naming
    the file and key, before anything is simulated.
    """
    seen: dict[Path, int] = {}
    for i, target in enumerate(targets):
        key = target.resolve()
        if key in seen:
            raise SpindlebenchError(f"{files[i]}: writes {target} like {files[seen[key]]}; "
                                    "rename one of the two scenario files")
        seen[key] = i
    producers = {target.with_suffix(".json").resolve(): i for i, target in enumerate(targets)}
    scenarios = [resolve_initial(with_machine(load_scenario(path), machine), target.parent)
                 for path, target in zip(files, targets, strict=True)]
    after: list[int | None] = []
    for path, scenario in zip(files, scenarios, strict=True):
        source = scenario.initial.from_file
        if scenario.initial.kind != "continue" or source is None:
            after.append(None)
            continue
        producer = producers.get(source.resolve())
        if producer is None and not source.is_file():
            sibling = scenario.initial.from_scenario
            what = (f"no scenario {sibling!r} in this batch and no recording {source}"
                    if sibling is not None else f"no such file {source}")
            raise SpindlebenchError(f"{path}: key 'initial.from': {what} (simulate the "
                                    "previous run first, or together with this one)")
        after.append(producer)
    order: list[int] = []
    state: dict[int, str] = {}  # "open" while its chain is being followed, then "done"

    def visit(i: int, chain: list[int]) -> None:
        if state.get(i) == "done":
            return
        if state.get(i) == "open":
            loop = [*chain[chain.index(i):], i]
            names = " continues from ".join(files[j].stem for j in loop)
            raise SpindlebenchError(f"{files[i]}: key 'initial.from': circular continuation: "
                                    f"{names}")
        state[i] = "open"
        producer = after[i]
        if producer is not None:
            visit(producer, [*chain, i])
        state[i] = "done"
        order.append(i)

    for i in range(len(files)):
        visit(i, [])
    return BatchPlan(order=order, scenarios=scenarios, producers=after,
                     state_from_batch=[producer is not None for producer in after])


def check_batch(plan: BatchPlan, fmu_path: str | Path | None) -> None:
    """Check every scenario of a planned batch against the FMU before any is simulated.

    Parameter names, step count and continue-from sidecars are checked here, so a batch is
    all or nothing. A state that an earlier run of the batch writes can only be checked to
    come from the batch (``plan_batch`` did that).
    """
    fmu = inspect_fmu(DEFAULT_FMU if fmu_path is None else fmu_path)
    for i in plan.order:
        scenario = plan.scenarios[i]
        start = None if plan.state_from_batch[i] else start_state(scenario)
        check_scenario(scenario, fmu, start=start)
