"""Machine variants: named FMU parameter sets in ``scenarios/machines/<name>.toml``.

One FMU, several machines: a machine file says what machine it is (``description``), which FMU
parameter values make it so (``[parameters]``, on top of the FMU's defaults) and which
fingerprint (``spindlebench.studies.fingerprint.statistics``) its paper experiments were
checked against (``[[targets]]``). ``default`` is the machine every scenario and study uses
when it names none.
A scenario or study picks one with ``machine = "<name>"`` (or a path to a ``.toml`` file),
``simulate``/``sweep``/``place``/``demo`` with ``--machine NAME``.

A target is one statistic of the fingerprint with ``min`` and/or ``max``; ``above = "<other
statistic>"`` makes the bounds apply to the difference ``statistic - other``; ``runs`` names the
paper experiments it is taken over (default all five) and ``each = true`` requires every run to
meet it instead of the median. A run is a paper experiment (``exp1`` … ``exp5``) or any scenario
named by its path under ``scenarios/`` without ``.toml`` (``heating/room20_4000``: a heating test
in a constant room, where the weather cannot help; ``examples/realistic_day``), simulated
noise-free on the machine.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.files import check_input
from spindlebench.core.names import FINGERPRINT_KEYS as KEYS
from spindlebench.core.paths import SCENARIOS_DIR
from spindlebench.core.provenance import sha256_unchanged
from spindlebench.formats.toml import Table, load_toml

MACHINES_DIR: Path = SCENARIOS_DIR / "machines"
DEFAULT_MACHINE = "default"
#: The paper experiments a target is taken over unless it names ``runs``.
PAPER_RUNS = ("exp1", "exp2", "exp3", "exp4", "exp5")


@dataclass(frozen=True)
class Target:
    """One fingerprint statistic the machine's paper experiments must meet."""

    statistic: str
    minimum: float | None = None
    maximum: float | None = None
    above: str | None = None
    runs: tuple[str, ...] = PAPER_RUNS
    each: bool = False

    def describe(self) -> str:
        """``median best_raw_psi <= 0.95``-style text."""
        what = f"{self.statistic} - {self.above}" if self.above else self.statistic
        where = "each of" if self.each else "median of"
        bounds = " and ".join(
            text
            for text in (
                f">= {self.minimum:g}" if self.minimum is not None else "",
                f"<= {self.maximum:g}" if self.maximum is not None else "",
            )
            if text
        )
        return f"{what} {bounds} ({where} {', '.join(self.runs)})"


@dataclass(frozen=True)
class Machine:
    """A machine variant as read from its file."""

    name: str
    description: str
    path: Path
    sha256: str
    parameters: Mapping[str, float] = field(default_factory=dict)
    targets: tuple[Target, ...] = ()

    def provenance(self) -> dict[str, str]:
        """What a recording's or study's provenance says about the machine."""
        return {"name": self.name, "file": self.path.name, "sha256": self.sha256}


def machine_names() -> list[str]:
    """Names of the shipped machines (``scenarios/machines/*.toml``)."""
    return sorted(path.stem for path in MACHINES_DIR.glob("*.toml"))


def machine_path(name: str, source: str | Path | None = None) -> Path:
    """The file of machine ``name``: a shipped name, or a ``.toml`` path (relative to the
    folder of ``source``, the file that names it, when given)."""
    if name.endswith(".toml"):
        path = Path(name)
        if not path.is_absolute() and source is not None:
            path = Path(source).resolve().parent / path
        return path
    if not name or "/" in name or "\\" in name or name.startswith("."):
        raise SpindlebenchError(f"machine {name!r}: a machine is a name from "
                                f"{MACHINES_DIR} or a path to a .toml file")
    path = MACHINES_DIR / f"{name}.toml"
    if not path.is_file():
        known = ", ".join(machine_names()) or "none"
        where = f"{source}: " if source is not None else ""
        raise SpindlebenchError(f"{where}machine {name!r} not found in {MACHINES_DIR} "
                                f"(shipped: {known})")
    return path


def load_machine(name: str = DEFAULT_MACHINE, source: str | Path | None = None) -> Machine:
    """Read and check a machine file by name or path (see the module docstring)."""
    return _load(machine_path(name, source).resolve())


@functools.lru_cache(maxsize=32)
def _load_cached(path: Path, sha256: str) -> Machine:
    top = Table(load_toml(path, "machine"), path)
    name = top.string("name", path.stem)
    description = top.string("description")
    parameters_table = top.table("parameters", required=False)
    parameters = {key: parameters_table.number(key) for key in sorted(parameters_table.names())}
    parameters_table.finish()
    targets = tuple(_read_target(t) for t in top.tables("targets", []))
    top.finish()
    return Machine(name=name, description=description, path=path, sha256=sha256,
                   parameters=parameters, targets=targets)


def _load(path: Path) -> Machine:
    check_input(path, "machine file (.toml)")  # before the hash reads a FIFO forever
    if not path.is_file():
        raise SpindlebenchError(f"{path}: machine file not found")
    return _load_cached(path, sha256_unchanged(path))  # re-read only when changed


def _read_target(t: Table) -> Target:
    statistic = t.string("statistic", choices=KEYS)
    above = t.get("above", str, None, check=lambda v: None if v in KEYS else
                  f"must be one of {', '.join(KEYS)}, got {v!r}")
    minimum = t.number("min", None)
    maximum = t.number("max", None)
    if minimum is None and maximum is None:
        raise t.error("statistic", "a target needs min and/or max")
    runs = tuple(t.get_list("runs", str, list(PAPER_RUNS), check=_run_problem))
    each = t.get("each", bool, False)
    t.finish()
    return Target(statistic=statistic, minimum=minimum, maximum=maximum, above=above,
                  runs=runs, each=each)


def run_scenario_path(run: str) -> Path:
    """The scenario file of a target's run: ``exp1`` … ``exp5`` are the paper's, any other
    name is a path under ``scenarios/`` without ``.toml``."""
    return SCENARIOS_DIR / ("paper" if run in PAPER_RUNS else "") / f"{run}.toml"


def _run_problem(run: str) -> str | None:
    if run in PAPER_RUNS:
        return None
    if "\\" in run or run.startswith(("/", ".")) or ".." in run.split("/"):
        return f"must be one of {', '.join(PAPER_RUNS)} or a scenario under scenarios/, got {run!r}"
    if not run_scenario_path(run).is_file():
        return (f"must be one of {', '.join(PAPER_RUNS)} or a scenario under scenarios/ "
                f"(no {run}.toml there), got {run!r}")
    return None


def target_runs(machine: Machine) -> tuple[str, ...]:
    """Every run a target of ``machine`` is taken over, in order of first mention."""
    return tuple(dict.fromkeys(run for target in machine.targets for run in target.runs))


def target_problems(machine: Machine,
                    fingerprints: Mapping[str, Mapping[str, float]]) -> list[str]:
    """Targets of ``machine`` that ``fingerprints`` (run name → statistics) do not meet."""
    problems = []
    for target in machine.targets:
        values = []
        for run in target.runs:
            stats = fingerprints[run]
            value = stats[target.statistic]
            values.append(value - stats[target.above] if target.above else value)
        checked = values if target.each else [float(np.median(values))]
        for value in checked:
            low = target.minimum is not None and not value >= target.minimum
            high = target.maximum is not None and not value <= target.maximum
            if low or high:
                problems.append(f"{machine.name}: {target.describe()}: got {value:.3f}")
                break
    return problems


def add_machine_argument(parser, what: str, default_text: str,
                         default: str | None = None) -> None:
    """``--machine NAME``: a machine variant, by name (``scenarios/machines/NAME.toml``) or
    as a .toml file, the same argument on every command that simulates (``demo``,
    ``simulate``, the studies, ``calibrate``); ``what`` says what it is used for there."""
    parser.add_argument("--machine", default=default, metavar="NAME",
                        help=f"{what}: a name from scenarios/machines/ or a .toml file "
                        f"(default: {default_text})")
