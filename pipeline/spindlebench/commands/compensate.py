"""``spindlebench compensate STUDY.toml -o DIR``: the model in the controller, day after day.

Writes into DIR: ``README.md`` (set-up, the residual per model, per day), ``days.csv`` (one
row per model and day), ``summary.csv``, ``timeseries.csv.gz`` (every sample of the first
retraining rule: true drift, prediction, applied offset, residual), ``compensation.png``
(uncompensated drift, applied offset and residual over the run) and ``provenance.json``.
With ``[axes] machines`` (a list or a population) each machine gets its own folder under DIR
and, for a population, DIR's README counts the machines on which the difference group wins
(``studies.compensation.population_report``), like every study command
(``commands.arguments.run_study_command``).
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from spindlebench.commands.arguments import add_study_file_arguments, run_study_command
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.files import check_output
from spindlebench.core.progress import Stages, for_terminal
from spindlebench.machines.variants import add_machine_argument
from spindlebench.studies.compensation.compensation_file import (
    DAY_MODES,
    load_compensation,
)
from spindlebench.studies.family.family_file import check_fmu
from spindlebench.studies.running.store import ResultStore

if TYPE_CHECKING:
    from spindlebench.studies.family.family_file import SweepStudy
    from spindlebench.studies.family.population import Member, Population

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "run the trained model in a simulated controller over many days"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``compensate`` sub-command."""
    parser = subparsers.add_parser(
        "compensate", help=HELP,
        description="Train each model of the study's [compensate] table on day 1, then "
        "simulate every other day of the study family with the model in the controller "
        "(update interval, rate limit, dead band); report the residual (true drift minus "
        "applied offset) per day, the fraction of time within the tolerance, the effect of "
        "a sensor fault after training and of the retraining rule.")
    add_study_file_arguments(parser, "scenarios/studies/compensate_month.toml, with a "
                             "[compensate] table")
    parser.add_argument("--days", choices=DAY_MODES, default=None,
                        help="override [compensate] days: 'continuous' (one machine, the "
                        "state carried from day to day) or 'cold-starts' (every day on its "
                        "own)")
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no step lines on stderr")
    add_machine_argument(parser, "machine variant of every day",
                         "the study's [study] machine or [axes] machines, else 'default'")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """One compensation run per machine of the study (``run_study_command``)."""
    return run_study_command(args, load_family=_family, run_one=_run_one,
                             population_report=_population_report)


def _family(path: Path) -> SweepStudy:
    return load_compensation(path).family


def _population_report(out: Path, population: Population, members: list[Member],
                       study_path: Path, fmu: Path) -> str:
    from spindlebench.studies.compensation.population_report import (
        compensation_population_report,
    )

    return compensation_population_report(out, population, members, study_path, fmu)


def _run_one(args: argparse.Namespace, out: Path, machine: str | None) -> None:
    """Load, simulate, write one machine's compensation into ``out``."""
    # pandas, the runner and the models only here: ``compensate --help`` stays cheap
    import pandas as pd

    from spindlebench.studies.compensation.compensation_report import (
        OUTPUT_FILES,
        summary_text,
        write_outputs,
    )
    from spindlebench.studies.compensation.loop import run_loop, simulate_days, summary

    study = load_compensation(args.study, machine)
    if args.days is not None and args.days != study.days:
        study = replace(study, days=args.days)
    fmu = check_fmu(study.family)
    check_output(out, "-o", [args.study], folder=True)
    if out.exists() and not out.is_dir():
        raise SpindlebenchError(f"{out}: exists and is not a folder")
    stages = Stages("compensate", enabled=for_terminal(getattr(args, "quiet", False)))
    # its own folder only (a sweep's README is not ours to replace), one process at a time
    store = ResultStore(out, owned=lambda entry: entry.name in OUTPUT_FILES)
    with store.locked():
        truths = simulate_days(study, fmu, progress=stages)
        stages(f"training, compensating and scoring the days ({', '.join(study.retrain)})")
        outcomes = {rule: run_loop(study, truths, rule) for rule in study.retrain}
        days = pd.DataFrame([row for o in outcomes.values() for row in o.days])
        series = pd.concat([part for o in outcomes.values() for part in o.series],
                           ignore_index=True)
        table = summary(study, days, series)
        stages(f"writing tables, figure and README into {out}")
        write_outputs(study, args.study, fmu, out, days, series, table, outcomes)
    print(summary_text(table))
    print(f"wrote {out / 'README.md'} and {len(OUTPUT_FILES) - 1} more files; "
          f"{stages.seconds:.1f} s in all")
