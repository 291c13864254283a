"""``spindlebench compensate STUDY.toml -o DIR``: the model in the controller, day after day.

Writes into DIR: ``README.md`` (set-up, the residual per model, per day), ``days.csv`` (one
row per model and day), ``summary.csv``, ``timeseries.csv.gz`` (every sample of the first
retraining rule: true drift, prediction, applied offset, residual), ``compensation.png``
(uncompensated drift, applied offset and residual over the run) and ``provenance.json``.
With ``[axes] machines`` (a list or a population) each machine gets its own folder under DIR
and, for a population, DIR's README counts the machines on which the difference group wins
(``studies.compensation.population_report``), like every study command
(``commands.arguments.run_study_command``).

A study with several ``[study] targets`` (issue 21) is simulated once; each target is
compensated on its own (its models trained on its probe reading, its residual = its true rise
minus its applied offset, in its unit) into ``DIR/<target>/`` (the same files as that target
alone); the joint models (``loop.JointSupports``: each model's candidates chosen on day 1 for
every target at once, as the union of the per-target selections or by a multi-output method,
each target refitted on them) into ``DIR/joint/<target>/``; ``DIR/README.md`` holds every
target's residual side by side, per-target and joint (``compensation_report.targets_readme``).
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

    from spindlebench.core.atomic import write_text
    from spindlebench.formats.recording import DRIFT_COLUMN
    from spindlebench.studies.compensation.compensation_report import (
        OUTPUT_FILES,
        summary_text,
        targets_readme,
        write_outputs,
    )
    from spindlebench.studies.compensation.loop import (
        JointSupports,
        measure_days,
        run_loop,
        simulate_days,
        summary,
    )
    from spindlebench.studies.family.experiments import probe_geometry_m
    from spindlebench.studies.running.store import ResultStore  # pandas

    study = load_compensation(args.study, machine)
    if args.days is not None and args.days != study.days:
        study = replace(study, days=args.days)
    fmu = check_fmu(study.family)
    check_output(out, "-o", [args.study], folder=True)
    if out.exists() and not out.is_dir():
        raise SpindlebenchError(f"{out}: exists and is not a folder")
    stages = Stages("compensate", enabled=for_terminal(getattr(args, "quiet", False)))
    # its own folder only (a sweep's README is not ours to replace), one process at a time
    targets = study.family.targets
    store = ResultStore(out, owned=lambda entry: entry.name in OUTPUT_FILES
                        or (len(targets) > 1 and entry.name in (*targets, "joint")))
    geometry = None if targets == (DRIFT_COLUMN,) else probe_geometry_m(study.family, fmu)
    tables: dict[str, pd.DataFrame] = {}
    joint_tables: dict[str, pd.DataFrame] = {}
    with store.locked():
        truths = simulate_days(study, fmu, progress=stages)
        runs = [(target, out if len(targets) == 1 else out / target, study, None, tables)
                for target in targets]
        if len(targets) > 1:
            stages("joint models: one sensor set per model for every target (day 1)")
            supports = JointSupports(study, {t: measure_days(study, truths, t, geometry)[1]
                                             for t in targets})
            joint = replace(study, models=supports.models)
            runs += [(t, out / "joint" / t, joint, supports, joint_tables) for t in targets]
        for target, where, study_, supports_, into in runs:
            stages(f"training, compensating and scoring the days ({', '.join(study.retrain)})"
                   + ("" if len(targets) == 1 else f" into {where}"))
            outcomes = {rule: run_loop(study_, truths, rule, target, geometry, supports_)
                        for rule in study.retrain}
            days = pd.DataFrame([row for o in outcomes.values() for row in o.days])
            series = pd.concat([part for o in outcomes.values() for part in o.series],
                               ignore_index=True)
            into[target] = summary(study_, days, series)
            if len(targets) == 1:
                stages(f"writing tables, figure and README into {where}")
            write_outputs(study_, args.study, fmu, where, days, series, into[target],
                          outcomes, None if len(targets) == 1 else target)
        if len(targets) > 1:
            write_text(out / "README.md",
                       targets_readme(study, args.study, tables, joint_tables))
    for target, table in tables.items():
        if len(targets) > 1:
            print(f"target {target} (residual in its unit; {out / target}):")
        print(summary_text(table))
    print(f"wrote {out / 'README.md'} and {len(OUTPUT_FILES) - 1} more files"
          + ("" if len(targets) == 1 else " per target") + f"; {stages.seconds:.1f} s in all")
