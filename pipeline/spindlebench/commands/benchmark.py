"""``spindlebench benchmark [SUITE] [--method LABEL|module:Class ...] [-o DIR]``.

Runs every entrant (the suite's methods, the ones given with ``--method``, and the three
baselines) on every task of the suite (``benchmarks/<suite>.toml``; ``default`` unless
named), plus the user's own recordings as one more task (``--recordings``), and writes the
leaderboard (``studies.benchmark``: ``benchmark_run`` runs it, ``benchmark_report`` writes it). A
method given by import path (``mypkg.sel:MySel``) runs exactly as a built-in does
(``selection.user_methods``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from spindlebench.formats.recording import DRIFT_COLUMN
from spindlebench.studies.benchmark.benchmark_run import DEFAULT_OUT

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "score methods on a fixed, versioned task suite; write a leaderboard"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``benchmark`` sub-command."""
    parser = subparsers.add_parser(
        "benchmark", help=HELP,
        description="Every method of the suite (and --method ones: built-in labels or your "
        "own scikit-learn selector/regressor/pipeline by import path) plus three baselines "
        "(constant training mean, replay of the training run's error, OLS on all sensors) on "
        "every task of benchmarks/SUITE.toml (synthetic families simulated with the FMU, the "
        "CAIVIAC runs with fixed folds) and on --recordings. Writes leaderboard.md/.csv/.json/"
        ".png and folds.csv.")
    parser.add_argument("suite", nargs="?", default=None,
                        help="suite name in benchmarks/ or a .toml path (default: default)")
    parser.add_argument("--method", action="append", default=[], metavar="LABEL",
                        help="an entrant: a method label (kmeans+grey+ridge), your class by "
                        "import path (mypkg.sel:MySel, all-candidates+mypkg.reg:MyReg), or an "
                        "identified dynamic model (dynamic:tf1, dynamic:network, "
                        "dynamic:observer); repeat for more")
    parser.add_argument("--method-param", action="append", default=[], metavar="NAME=VALUE",
                        help="a parameter of every --method given by import path")
    parser.add_argument("--only", action="store_true",
                        help="enter only the --method entrants (and the baselines), not the "
                        "suite's methods")
    parser.add_argument("--tasks", nargs="+", metavar="NAME",
                        help="run only these suite tasks (a synthetic entry's name runs all "
                        "of its machine x condition tasks)")
    parser.add_argument("--recordings", nargs="+", type=Path, metavar="CSV",
                        help="your own recordings as one more task (each trains in turn, the "
                        "others are predicted)")
    parser.add_argument("--target", default=DRIFT_COLUMN,
                        help="target column of --recordings (default drift_um)")
    from spindlebench.formats.roles import add_role_arguments

    add_role_arguments(parser)  # how --recordings are read: as evaluate reads them
    parser.add_argument("--recordings-root", type=Path, default=None, metavar="DIR",
                        help="folder of the real recordings (default: ../shared/recordings "
                        "beside the checkout)")
    parser.add_argument("-o", "--out", type=Path, default=None, metavar="DIR",
                        help=f"output folder (default: {DEFAULT_OUT}/SUITE)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """The options as a ``BenchmarkRequest``, then ``benchmark_run.run_benchmark``."""
    from spindlebench.formats.roles import ColumnRoles
    from spindlebench.studies.benchmark.benchmark_run import BenchmarkRequest, run_benchmark

    command = "spindlebench " + " ".join(sys.argv[1:]) if sys.argv[1:2] == ["benchmark"] \
        else "spindlebench benchmark"
    run_benchmark(BenchmarkRequest(
        suite=args.suite, methods=args.method, method_params=args.method_param,
        only=args.only, tasks=args.tasks, recordings=args.recordings, target=args.target,
        roles=ColumnRoles.from_args(args), recordings_root=args.recordings_root,
        out=args.out, command=command))
    return 0
