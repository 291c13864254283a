"""``spindlebench adapt``: turn a real data set into canonical recordings."""

from __future__ import annotations

import argparse

from spindlebench.adapters import caiviac

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "convert a real data set into canonical recordings (one per run)"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``adapt`` with one sub-command per data set."""
    parser = subparsers.add_parser(
        "adapt", help=HELP
    )
    datasets = parser.add_subparsers(dest="dataset", required=True, metavar="DATASET")
    cai = datasets.add_parser(
        "caiviac",
        help="CAIVIAC FL_THERMAL 46 h recording: one recording per run of the speed schedule",
        description=caiviac.__doc__.split("\n\n")[0] if caiviac.__doc__ else None,
    )
    cai.add_argument(
        "--source",
        default=None,
        help=f"data.csv of the recording (default: {caiviac.default_source()})",
    )
    cai.add_argument("--out", required=True, help="folder for <run>.csv + <run>.json")
    cai.add_argument(
        "--phase",
        choices=caiviac.PHASES,
        default="heating",
        help="heating: spindle-on part of each run (the paper's analogue, default); "
        "cycle: heating plus the following cool-down",
    )
    cai.set_defaults(func=_run_caiviac)


def _run_caiviac(args: argparse.Namespace) -> int:
    written = caiviac.write_runs(args.out, args.source, phase=args.phase)
    for path in written:
        print(path)
    return 0
