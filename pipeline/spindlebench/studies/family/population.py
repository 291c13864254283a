"""A population of machines: N variants drawn around a base machine.

One machine is one answer. Whether a conclusion ("differences beat raw sensors") belongs to the
method or to the particular machine it was tried on shows only across many machines of the same
kind, so a study may name a population instead of a list of machine files::

    [axes]
    machines = { population = 30, base = "default", spread = 0.2, seed = 1 }

Each machine multiplies the base machine's physical parameters by independent log-normal
factors ``exp(N(0, spread))``: the heat capacities (J/K), conductances (W/K), heat-transfer
coefficients (W/(m2.K)), heat sources (W) and loss coefficients (W.min/mm) of the FMU, chosen
by their declared unit (geometry, fractions, temperatures and switches stay as they are), and
every result is kept inside the FMU's declared ``min``/``max``. ``spread`` may instead be a
table: ``default`` is the factor's log standard deviation for the parameters chosen by unit,
every other key an ``fnmatch`` pattern of parameter names with its own (``0`` holds a
parameter fixed; a pattern may also spread a unitless parameter such as a friction factor).

Machine ``i`` is drawn from ``numpy.random.default_rng([seed, i])`` alone, so the first ten
machines of a population of 50 are the machines of a population of 10. ``keep = "targets"``
keeps a drawn machine only if it meets the base machine's fingerprint targets (its file's
``[[targets]]``); rejected draws are recorded, not hidden.

Every drawn machine is written as an ordinary machine file (``machines/<name>.toml`` in the
results folder: a user can simulate it again with ``--machine``) and its fingerprint goes into
``population.csv`` beside the reason it was kept or rejected.
"""

from __future__ import annotations

import fnmatch
import hashlib
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from spindlebench.core import atomic
from spindlebench.core.errors import SpindlebenchError
from spindlebench.formats.toml import Table, in_range
from spindlebench.machines.variants import PAPER_RUNS, Machine, load_machine, target_problems

#: Units of the parameters a population spreads by default: what differs between two machines
#: of one type (masses and materials, contacts, films, losses), not their geometry.
SPREAD_UNITS = ("J/K", "W/K", "W/(m2.K)", "W", "W.min/mm")
MAX_POPULATION = 1000
#: Draws tried per wanted machine before ``keep = "targets"`` gives up.
DRAWS_PER_MACHINE = 20
KEEP_RULES = ("all", "targets")
MACHINES_FOLDER = "machines"
TABLE_FILE = "population.csv"


@dataclass(frozen=True)
class Population:
    """``[axes] machines = { population = N, ... }`` as read from a study file."""

    size: int
    base: str
    seed: int
    #: log standard deviation of the factor for the parameters chosen by unit
    default_spread: float
    #: (pattern, log standard deviation), in the order written
    patterns: tuple[tuple[str, float], ...] = ()
    keep: str = "all"
    #: the study file (a relative ``base`` path is relative to its folder)
    source: Path | None = None

    def describe(self) -> str:
        spread = f"log-sd {self.default_spread:g} on {', '.join(SPREAD_UNITS)}"
        if self.patterns:
            spread += "; " + ", ".join(f"{p} {sd:g}" for p, sd in self.patterns)
        kept = "meeting the base machine's fingerprint targets" if self.keep == "targets" \
            else "all kept"
        return (f"{self.size} machines drawn around '{self.base}' (seed {self.seed}; {spread}; "
                f"{kept})")


def read_population(table: Table, source: Path) -> Population:
    """The population inline table (its keys are checked like every study key)."""
    size = table.integer("population", minimum=1, maximum=MAX_POPULATION)
    base = table.string("base", "default")
    seed = table.integer("seed", 0, minimum=0, maximum=2**63 - 1)
    keep = table.string("keep", "all", choices=KEEP_RULES)
    spread_check = in_range(0.0, 1.0)
    patterns: list[tuple[str, float]] = []
    if table.has("spread") and isinstance(table.data["spread"], Mapping):
        spread = table.table("spread")
        default = spread.number("default", 0.0, minimum=0.0, maximum=1.0)
        for name in list(spread.names()):
            if name != "default":
                patterns.append((name, spread.get(name, float, check=spread_check)))
        spread.finish()
    else:
        default = table.number("spread", 0.2, minimum=0.0, maximum=1.0)
    table.finish()
    try:
        load_machine(base, source=source)
    except SpindlebenchError as exc:
        raise table.error("base", str(exc)) from None
    return Population(size=size, base=base, seed=seed, default_spread=default,
                      patterns=tuple(patterns), keep=keep, source=source)


def spread_of(population: Population, name: str, unit: str | None) -> float:
    """The log standard deviation of parameter ``name``'s factor (0: not spread)."""
    for pattern, sd in population.patterns:
        if fnmatch.fnmatchcase(name, pattern):
            return sd
    return population.default_spread if unit in SPREAD_UNITS else 0.0


def check_patterns(population: Population, known: Mapping[str, Any], where: str) -> None:
    """A spread pattern that names no FMU parameter is a typo: one line."""
    for pattern, _ in population.patterns:
        if not any(fnmatch.fnmatchcase(name, pattern) for name in known):
            raise SpindlebenchError(f"{where}: key 'axes.machines.spread.{pattern}': matches no "
                                    "parameter of the FMU")


def draw_parameters(population: Population, base: Machine, known: Mapping[str, Any],
                    index: int) -> dict[str, float]:
    """Machine ``index``'s parameter values: the base machine's, each spread parameter times
    its own log-normal factor, kept within the FMU's declared bounds.

    ``known`` is the FMU's parameters (name → FMPy model variable). Names are walked in sorted
    order, so the same FMU, seed and index always give the same machine."""
    rng = np.random.default_rng([population.seed, index])
    values = dict(base.parameters)
    for name in sorted(known):
        variable = known[name]
        sd = spread_of(population, name, getattr(variable, "unit", None))
        if sd <= 0.0:
            continue
        start = values.get(name, _number(variable.start))
        if start is None or not start > 0.0:
            continue  # a zero (a switched-off path) stays off; a sign is not a spread
        value = start * math.exp(rng.normal(0.0, sd))
        low, high = _number(variable.min), _number(variable.max)
        if low is not None:
            value = max(value, low)
        if high is not None:
            value = min(value, high)
        values[name] = float(value)
    return values


def _number(text: Any) -> float | None:
    return None if text is None else float(text)


def machine_name(population: Population, base: Machine, index: int) -> str:
    return f"{base.name}-p{index:03d}"


def machine_file_text(population: Population, base: Machine, name: str, index: int,
                      parameters: Mapping[str, float], study: str) -> str:
    """A drawn machine as a machine file (``spindlebench.machines`` reads it like any other).

    Every value is written with ``repr``, which reads back to the same float, so the file
    and not the drawing code is what every later simulation uses."""
    lines = [
        f"# Drawn by spindlebench for the study {study}: machine {index} of the population",
        f"# {population.describe()}.",
        f"# Base machine file: {base.path.name} (sha256 {base.sha256}).",
        f"name = {json.dumps(name)}",
        f"description = {json.dumps(f'Machine {index} of a population around {base.name}.')}",
        "",
        "[parameters]",
    ]
    lines += [f"{key} = {float(parameters[key])!r}" for key in sorted(parameters)]
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class Member:
    """One drawn machine: its file, whether it was kept, and why not."""

    index: int
    name: str
    path: Path
    kept: bool
    problems: tuple[str, ...]
    fingerprint: Mapping[str, float]


def draw_population(population: Population, known: Mapping[str, Any], fmu: Path,
                    out: Path, study: str) -> list[Member]:
    """Draw, fingerprint and write the machines of ``population`` into ``out/machines/``
    (draw after draw until ``size`` machines are kept), and ``out/population.csv``.

    Rewriting on resume gives the same bytes (the draw is seeded), so a resumed study reads
    machine files identical to the first run's."""
    from spindlebench.studies.fingerprint import machine_check as check

    base = load_machine(population.base, source=population.source)
    check_patterns(population, known, str(population.source))
    members: list[Member] = []
    kept = 0
    limit = population.size * (DRAWS_PER_MACHINE if population.keep == "targets" else 1)
    index = 0
    while kept < population.size and index < limit:
        index += 1
        name = machine_name(population, base, index)
        parameters = draw_parameters(population, base, known, index)
        path = out / MACHINES_FOLDER / f"{name}.toml"
        text = machine_file_text(population, base, name, index, parameters, study)
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            path.parent.mkdir(parents=True, exist_ok=True)
            atomic.write_text(path, text)
        machine = load_machine(str(path))
        checked = Machine(name=machine.name, description=machine.description,
                          path=machine.path, sha256=machine.sha256,
                          parameters=machine.parameters, targets=base.targets)
        if population.keep == "targets":  # every run the base machine's targets name
            fingerprints = check.machine_fingerprints(checked, fmu)
            problems = tuple(target_problems(checked, fingerprints))
        else:
            fingerprints, problems = check.paper_fingerprints(machine, fmu), ()
        member_kept = not problems
        kept += member_kept
        paper = [fingerprints[run] for run in PAPER_RUNS]
        summary = {key: float(np.median([f[key] for f in paper])) for key in paper[0]}
        members.append(Member(index=index, name=name, path=path, kept=member_kept,
                              problems=problems, fingerprint=summary))
    if kept < population.size:
        raise SpindlebenchError(
            f"{population.source}: key 'axes.machines': only {kept} of {index} drawn machines "
            f"met the targets of '{population.base}' (wanted {population.size}); lower "
            "'spread' or use keep = \"all\"")
    _write_table(out / TABLE_FILE, members, base)
    return members


def _write_table(path: Path, members: list[Member], base: Machine) -> None:
    keys = list(members[0].fingerprint) if members else []
    rows = ["index,machine,kept,why_rejected," + ",".join(f"median_{k}" for k in keys)]
    for m in members:
        why = "; ".join(m.problems).replace(",", ";").replace("\n", " ")
        rows.append(f"{m.index},{m.name},{str(m.kept).lower()},{why},"
                    + ",".join(repr(m.fingerprint[k]) for k in keys))
    atomic.write_text(path, "\n".join(rows) + "\n")


def population_sha256(members: list[Member]) -> str:
    """One hash of every kept machine file (for the population's provenance)."""
    digest = hashlib.sha256()
    for m in members:
        if m.kept:
            digest.update(m.path.read_bytes())
    return digest.hexdigest()


def draw_population_of(study, out: Path) -> list[Member]:
    """The population of ``study`` (a ``SweepStudy`` with ``population`` set), drawn into
    ``out`` against its FMU's declared parameters."""
    from spindlebench.testbench.runner import inspect_fmu

    return draw_population(study.population, inspect_fmu(study.fmu).parameters, study.fmu,
                           out, study.name)
