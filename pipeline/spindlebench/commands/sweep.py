"""``spindlebench sweep``: run (or resume) a season sweep and print what it did.

The sweep itself is ``studies.sweep.sweep_run``; the options every study command shares are
``commands.arguments``.
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
HELP = "season stress test: run a study of experiments and score the methods"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``sweep`` sub-command."""
    register_study_command(
        subparsers, "sweep",
        help=HELP,
        description="Run (or resume) a season sweep: simulate every experiment of STUDY.toml "
        "on every replica, train each selection method on the training experiment(s), score "
        "it on the others, and write results.csv, a summary, box plots and README.md.",
        example="scenarios/studies/season_sweep.toml", load_family=_load_study, run_one=_run_one,
        population_report=_population_report)


# The study's modules (the runner, pandas, scikit-learn) are imported when the command runs,
# not when it is registered: ``sweep --help`` stays cheap.
def _load_study(path: Path) -> SweepStudy:
    from spindlebench.studies.family.family_file import load_study

    return load_study(path)


def _population_report(out: Path, population: Population, members: list[Member],
                       study_path: Path, fmu: Path) -> str:
    from spindlebench.studies.sweep.population_report import sweep_population_report

    return sweep_population_report(out, population, members, study_path, fmu)


def _run_one(args: argparse.Namespace, out: Path, machine: str | None) -> None:
    from spindlebench.studies.sweep.sweep_run import run_sweep

    # "in all": from the command's start (set by commands.main, before the imports and the
    # study's checks) to the last file written, the wait the user sees
    started = getattr(args, "started_s", None)
    started = time.perf_counter() if started is None else started
    outcome = run_sweep(args.study, out, workers=args.workers,
                        dask_address=args.dask_address, progress=not args.no_progress,
                        machine=machine)
    results = outcome.results
    failed = int((results["error"] != "").sum()) if len(results) else 0
    stats = outcome.stats
    print(f"{'resumed: ' if outcome.resumed else ''}ran {stats.total('simulation')} "
          f"simulation(s) and {outcome.evaluated} evaluation(s) in "
          f"{stats.seconds:.1f} s (skipped {outcome.skipped['simulation']} done simulation(s), "
          f"{outcome.skipped['evaluation']} done evaluation(s)); {len(results)} result rows, "
          f"{failed} with errors; {time.perf_counter() - started:.1f} s in all")
    if outcome.study_dir is not None:  # several targets: the counts above are the first's
        print(f"target {outcome.out_dir.name} above; each target's sweep is in "
              f"{outcome.study_dir}/<target>/")
    print(f"results: {(outcome.study_dir or outcome.out_dir) / 'README.md'}")
