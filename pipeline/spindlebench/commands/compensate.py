"""``spindlebench compensate STUDY.toml [-o DIR]``: the model in the controller, day after day.

Writes into DIR (default ``results/<study.name>``): ``README.md`` (set-up, the residual per
model, per day), ``days.csv`` (one row per model and day), ``summary.csv``,
``timeseries.csv.gz`` (every sample of the first retraining rule: true drift, prediction,
applied offset, residual), ``compensation.png`` (uncompensated drift, applied offset and
residual over the run) and ``provenance.json``.
"""

from __future__ import annotations

import argparse
from dataclasses import replace

from spindlebench.commands.arguments import add_study_file_arguments, default_results_folder
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.files import check_output
from spindlebench.core.progress import Stages, for_terminal
from spindlebench.studies.compensation.compensation_file import (
    DAY_MODES,
    load_compensation,
)
from spindlebench.studies.family.family_file import check_fmu
from spindlebench.studies.running.store import ResultStore

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
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Load, simulate, write."""
    # pandas, the runner and the models only here: ``compensate --help`` stays cheap
    import pandas as pd

    from spindlebench.studies.compensation.compensation_report import (
        OUTPUT_FILES,
        summary_text,
        write_outputs,
    )
    from spindlebench.studies.compensation.loop import run_loop, simulate_days, summary

    if args.out is not None:  # before the study is read: a device or / is never a folder
        check_output(args.out, "-o", [args.study], folder=True)
    study = load_compensation(args.study)
    if args.days is not None and args.days != study.days:
        study = replace(study, days=args.days)
    fmu = check_fmu(study.family)
    out = args.out if args.out is not None else default_results_folder(args.study, study.name)
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
    return 0
