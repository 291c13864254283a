"""``spindlebench benchmark [SUITE] [--method LABEL|module:Class ...] [-o DIR]``.

Runs every entrant (the suite's methods, the ones given with ``--method``, and the three
baselines) on every task of the suite (``benchmarks/<suite>.toml``; ``default`` unless
named), plus the user's own recordings as one more task (``--recordings``), and writes the
leaderboard (``benchmark.leaderboard``). A method given by import path
(``mypkg.sel:MySel``) runs exactly as a built-in does (``selection.user_methods``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from spindlebench import provenance
from spindlebench.errors import SpindlebenchError

DEFAULT_OUT = Path("results") / "benchmark"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``benchmark`` sub-command."""
    parser = subparsers.add_parser(
        "benchmark", help="score methods on a fixed, versioned task suite; write a leaderboard",
        description="Every method of the suite (and --method ones: built-in labels or your "
        "own scikit-learn selector/regressor/pipeline by import path) plus three baselines "
        "(constant training mean, replay of the training run's error, OLS on all sensors) on "
        "every task of benchmarks/SUITE.toml (synthetic families simulated with the FMU, the "
        "CAIVIAC runs with fixed folds) and on --recordings. Writes leaderboard.md/.csv/.json/"
        ".png and folds.csv.")
    parser.add_argument("suite", nargs="?", default=None,
                        help="suite name in benchmarks/ or a .toml path (default: default)")
    parser.add_argument("--method", action="append", default=[], metavar="LABEL",
                        help="an entrant: a method label (kmeans+grey+ridge) or your class by "
                        "import path (mypkg.sel:MySel, all-candidates+mypkg.reg:MyReg); repeat "
                        "for more")
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
    parser.add_argument("--target", default="drift_um",
                        help="target column of --recordings (default drift_um)")
    from spindlebench.formats.columns import add_role_arguments

    add_role_arguments(parser)  # how --recordings are read: as evaluate reads them
    parser.add_argument("--recordings-root", type=Path, default=None, metavar="DIR",
                        help="folder of the real recordings (default: ../shared/recordings "
                        "beside the checkout)")
    parser.add_argument("-o", "--out", type=Path, default=None, metavar="DIR",
                        help=f"output folder (default: {DEFAULT_OUT}/SUITE)")
    parser.add_argument("--doc", type=Path, default=None, metavar="FILE.md",
                        help="also write the leaderboard's tables between the '<!-- "
                        "leaderboard: start -->' and '<!-- leaderboard: end -->' lines of "
                        "FILE.md (docs/benchmark.md)")
    parser.set_defaults(func=run)


def entrants(args: argparse.Namespace, suite_methods: tuple[str, ...]):
    """The method choices to score, checked (one line), in order, without repeats."""
    from spindlebench.selection.registry import parse_method, with_params

    given = []
    for label in args.method:
        choice = parse_method(label)
        if args.method_param and (choice.user_method or choice.user_regressor):
            choice = with_params(choice, args.method_param)
        given.append(choice)
    if args.method_param and not any(c.user_method or c.user_regressor for c in given):
        raise SpindlebenchError("--method-param applies to a --method given by import path "
                                "(package.module:Class); none was given")
    if args.only and not given:
        raise SpindlebenchError("--only: give the entrants with --method")
    chosen = ([] if args.only else [parse_method(label) for label in suite_methods]) + given
    out, seen = [], set()
    for choice in chosen:
        if choice.label not in seen:
            seen.add(choice.label)
            out.append(choice)
    return out


def run(args: argparse.Namespace) -> int:
    """Load the suite, build the tasks, score every entrant, write the leaderboard."""
    from spindlebench.benchmark import leaderboard
    from spindlebench.benchmark.scoring import BASELINES, score_baseline, score_method
    from spindlebench.benchmark.suite import load_suite
    from spindlebench.benchmark.tasks import build_tasks, own_task

    suite = load_suite(args.suite, args.recordings_root)
    choices = entrants(args, suite.methods)
    specs = list(suite.tasks)
    if args.tasks:
        unknown = [name for name in args.tasks if name not in {t.name for t in specs}]
        if unknown:
            raise SpindlebenchError(f"--tasks: {', '.join(unknown)} not in suite {suite.name} "
                                    f"({', '.join(t.name for t in specs)})")
        specs = [t for t in specs if t.name in args.tasks]
    out = args.out if args.out is not None else DEFAULT_OUT / suite.name
    if args.doc is not None:  # checked before the work, not after it
        if not args.doc.is_file():
            raise SpindlebenchError(f"--doc {args.doc}: no such file")
        text = args.doc.read_text(encoding="utf-8")
        if leaderboard.DOC_START not in text or leaderboard.DOC_END not in text:
            raise SpindlebenchError(f"--doc {args.doc}: has no '{leaderboard.DOC_START}' / "
                                    f"'{leaderboard.DOC_END}' lines to put the leaderboard "
                                    "between")
    if out.exists() and not out.is_dir():
        raise SpindlebenchError(f"-o {out}: exists and is not a folder")
    started = time.perf_counter()
    tasks = [task for spec in specs for task in build_tasks(spec)]
    if args.recordings:
        from spindlebench.formats.columns import ColumnRoles

        tasks.append(own_task(args.recordings, args.target, ColumnRoles.from_args(args)))
    print(f"suite {suite.name} {suite.version} (tasks {suite.tasks_sha256[:12]}): "
          f"{len(tasks)} task(s), {len(choices)} method(s) + {len(BASELINES)} baselines; "
          f"tasks built in {time.perf_counter() - started:.1f} s")
    entries = []
    for task in tasks:
        task_started = time.perf_counter()
        for baseline in BASELINES:
            entries.append(score_baseline(task, baseline, suite.k, suite.seed))
        for choice in choices:
            entries.append(score_method(task, choice, suite.k, suite.seed))
        mine = [e for e in entries if e.task == task.name]
        failed = [e.method for e in mine if e.error]
        slowest = max(mine, key=lambda e: e.seconds)
        print(f"  {task.name}: {len(task.folds)} fold(s), "
              f"{time.perf_counter() - task_started:.1f} s (slowest {slowest.method} "
              f"{slowest.seconds:.1f} s)" + (f"; failed: {', '.join(failed)}" if failed else ""))
    command = "spindlebench " + " ".join(sys.argv[1:]) if sys.argv[1:2] == ["benchmark"] \
        else "spindlebench benchmark"
    record = {"provenance": provenance.provenance(
        command="benchmark",
        partial=bool(args.tasks),
        entrants={choice.label: choice.to_dict() for choice in choices},
        baselines=list(BASELINES),
        tasks=[{"name": t.name, "kind": t.kind, "description": t.description,
                "target": t.target, "sensors": list(t.sensors),
                "folds": [{"name": f.name, "train": f.train_name, "tests": list(f.tests)}
                          for f in t.folds], **t.provenance} for t in tasks],
        fmu_sha256=_fmu_sha(specs),
    )}
    written = leaderboard.write(out, suite, entries, record, command, args.doc)
    print(f"done in {time.perf_counter() - started:.1f} s")
    for path in written:
        print(f"wrote {path}")
    return 0


def _fmu_sha(specs) -> str | None:
    shas = {spec.content.get("fmu_sha256") for spec in specs if spec.kind == "synthetic"}
    shas.discard(None)
    return next(iter(shas)) if len(shas) == 1 else (sorted(shas) or None)  # type: ignore
