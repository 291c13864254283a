"""``spindlebench place``: run (or resume) a virtual sensor-placement study and print the best
placements.

The study itself is ``studies.placement.placement_run``; the options every study command shares
are ``commands.arguments``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import TYPE_CHECKING

from spindlebench.commands.arguments import register_study_command

if TYPE_CHECKING:
    from spindlebench.studies.family.family_file import SweepStudy
    from spindlebench.studies.family.population import Member, Population

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "virtual sensor placement: choose m of the model's nodes per method"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``place`` sub-command."""
    register_study_command(
        subparsers, "place",
        help=HELP,
        description="Run (or resume) a virtual sensor-placement study: simulate the study's "
        "experiments, choose sensor sets among the temperature-field nodes with the paper's "
        "fuzzy clustering, greedy forward selection and exhaustive search, score them across "
        "seasons and write placements.csv, plots, schematic drawings and README.md.",
        example="scenarios/studies/placement.toml", load_family=_family, run_one=_run_one,
        population_report=_population_report)


# The study's modules (the runner, pandas, scikit-learn) are imported when the command runs,
# not when it is registered: ``place --help`` stays cheap.
def _family(path: Path) -> SweepStudy:
    from spindlebench.studies.placement.placement_file import load_placement_study

    return load_placement_study(path).family


def _population_report(out: Path, population: Population, members: list[Member],
                       study_path: Path, fmu: Path) -> str:
    from spindlebench.studies.placement.population_report import placement_population_report

    return placement_population_report(out, population, members, study_path, fmu)


def _run_one(args: argparse.Namespace, out: Path, machine: str | None) -> None:
    from spindlebench.studies.placement.placement_run import (
        report_best,
        run_placement,
        search_times,
    )

    started = time.perf_counter()
    outcome = run_placement(args.study, out, workers=args.workers,
                            dask_address=args.dask_address, progress=not args.no_progress,
                            machine=machine)
    found = [p for p in outcome.placements if p.found]
    print(f"{'resumed' if outcome.resumed else 'ran'}: {outcome.stats.total('simulation')} "
          f"simulation(s) in {outcome.stats.seconds:.1f} s; {len(found)} placement(s) found "
          f"in {outcome.search_seconds:.1f} s ({len(outcome.placements) - len(found)} "
          f"skipped); {len(outcome.failures)} failed simulation(s); "
          f"{time.perf_counter() - started:.1f} s in all")
    print(search_times(outcome.placements))
    if outcome.out_dir != out:  # several targets: the first one's best, then the joint sets
        print(f"target {outcome.target} (each target's study is in {out}/<target>/):")
    print(report_best(outcome.table))
    print(f"results: {out / 'README.md'}")
