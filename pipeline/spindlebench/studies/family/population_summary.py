"""What every population report shares: "on how many machines" in words, how its README and
provenance are written.

A study kind (sweep, placement, compensation) reads its own per-machine outputs and decides,
machine by machine, whether a conclusion holds there; how that count is written and what the
population's ``provenance.json`` records is the same for all of them, so it lives here once.
"""

from __future__ import annotations

import json
from pathlib import Path

from spindlebench.core import atomic
from spindlebench.core.provenance import package_versions, sha256_file
from spindlebench.studies.family.population import Member, Population, population_sha256


def on_machines(count: int, total: int) -> str:
    """``"11 of 30 machines (37 %)"``; ``"none"`` when no machine was shown."""
    return f"{count} of {total} machines ({100.0 * count / total:.0f} %)" if total else "none"


def write_population_provenance(out: Path, population: Population, members: list[Member],
                                study_path: Path, fmu: Path) -> None:
    """``out/provenance.json`` of a population run: the study, the FMU, the population's
    description and seed, and one hash of every kept machine file."""
    record = {"study": str(study_path), "study_sha256": sha256_file(study_path),
              "fmu_sha256": sha256_file(fmu), "population": population.describe(),
              "seed": population.seed, "machines_sha256": population_sha256(members),
              "package_versions": package_versions()}
    atomic.write_text(out / "provenance.json", json.dumps(record, indent=2) + "\n")


def write_population_readme(out: Path, lines: list[str], population: Population,
                            members: list[Member], study_path: Path, fmu: Path) -> str:
    """Write a population report's ``README.md`` (``lines``) and its ``provenance.json``
    into ``out``; return the README text."""
    text = "\n".join(lines) + "\n"
    atomic.write_text(out / "README.md", text)
    write_population_provenance(out, population, members, study_path, fmu)
    return text
