"""One benchmark run: the suite's tasks built, every entrant scored, the leaderboard written.

What ``spindlebench benchmark`` does (``commands/benchmark.py`` only reads its options):
the entrants are the suite's methods (unless ``only``), the given labels (a user's class by
import path among them) and the three baselines; they run on every task of the suite (or of
``tasks``) and on the user's recordings; progress goes to stdout, the leaderboard's files to
``out``.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from spindlebench.core import provenance
from spindlebench.core.errors import SpindlebenchError
from spindlebench.formats.recording import DRIFT_COLUMN

DEFAULT_OUT = Path("results") / "benchmark"


@dataclass
class BenchmarkRequest:
    """What to run (the command's options)."""

    suite: str | None = None
    methods: Sequence[str] = ()
    method_params: Sequence[str] = ()
    only: bool = False
    tasks: Sequence[str] | None = None
    recordings: Sequence[Path] | None = None
    target: str = DRIFT_COLUMN
    roles: object = None
    recordings_root: Path | None = None
    out: Path | None = None
    command: str = "spindlebench benchmark"


def entrants(args: BenchmarkRequest, suite_methods: tuple[str, ...]):
    """The method choices to score, checked (one line), in order, without repeats."""
    from spindlebench.selection.registry import with_params

    given = []
    for label in args.methods:
        choice = parse_entrant(label)
        if args.method_params and _user(choice):
            choice = with_params(choice, args.method_params)
        given.append(choice)
    if args.method_params and not any(_user(c) for c in given):
        raise SpindlebenchError("--method-param applies to a --method given by import path "
                                "(package.module:Class); none was given")
    if args.only and not given:
        raise SpindlebenchError("--only: give the entrants with --method")
    chosen = ([] if args.only else [parse_entrant(label) for label in suite_methods]) + given
    out, seen = [], set()
    for choice in chosen:
        if choice.label not in seen:
            seen.add(choice.label)
            out.append(choice)
    return out


def parse_entrant(label: str):
    """A method label (``selection.registry.parse_method``) or a dynamic model
    (``dynamic:NAME``, ``rollout.parse_dynamic``)."""
    from spindlebench.selection.registry import parse_method
    from spindlebench.studies.benchmark.rollout import is_dynamic, parse_dynamic

    return parse_dynamic(label) if is_dynamic(label) else parse_method(label)


def _user(choice) -> bool:
    return bool(getattr(choice, "user_method", None) or getattr(choice, "user_regressor", None))


def run_benchmark(args: BenchmarkRequest) -> list[Path]:
    """Load the suite, build the tasks, score every entrant, write the leaderboard; return the
    files written."""
    from spindlebench.studies.benchmark import benchmark_report as leaderboard
    from spindlebench.studies.benchmark.benchmark_file import load_suite
    from spindlebench.studies.benchmark.rollout import DynamicChoice
    from spindlebench.studies.benchmark.scoring import (
        BASELINES,
        score_baseline,
        score_dynamic,
        score_method,
    )
    from spindlebench.studies.benchmark.tasks import build_tasks, own_task

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
    if out.exists() and not out.is_dir():
        raise SpindlebenchError(f"-o {out}: exists and is not a folder")
    started = time.perf_counter()
    tasks = [task for spec in specs for task in build_tasks(spec)]
    if args.recordings:
        tasks.append(own_task(args.recordings, args.target, args.roles))
    print(f"suite {suite.name} {suite.version} (tasks {suite.tasks_sha256[:12]}): "
          f"{len(tasks)} task(s), {len(choices)} method(s) + {len(BASELINES)} baselines; "
          f"tasks built in {time.perf_counter() - started:.1f} s")
    entries = []
    for task in tasks:
        task_started = time.perf_counter()
        for baseline in BASELINES:
            entries.append(score_baseline(task, baseline, suite.k, suite.seed))
        for choice in choices:
            score = score_dynamic if isinstance(choice, DynamicChoice) else score_method
            entries.append(score(task, choice, suite.k, suite.seed))
        mine = [e for e in entries if e.task == task.name]
        failed = [e.method for e in mine if e.error]
        slowest = max(mine, key=lambda e: e.seconds)
        print(f"  {task.name}: {len(task.folds)} fold(s), "
              f"{time.perf_counter() - task_started:.1f} s (slowest {slowest.method} "
              f"{slowest.seconds:.1f} s)" + (f"; failed: {', '.join(failed)}" if failed else ""))
    command = args.command
    record = {"provenance": provenance.provenance(
        command=command,
        partial=bool(args.tasks),
        entrants={choice.label: choice.to_dict() for choice in choices},
        baselines=list(BASELINES),
        tasks=[{"name": t.name, "kind": t.kind, "description": t.description,
                "target": t.target, "sensors": list(t.sensors),
                "folds": [{"name": f.name, "train": f.train_name, "tests": list(f.tests)}
                          for f in t.folds], **t.provenance} for t in tasks],
        fmu_sha256=_fmu_sha(specs),
    )}
    written = leaderboard.write(out, suite, entries, record, command)
    print(f"done in {time.perf_counter() - started:.1f} s")
    for path in written:
        print(f"wrote {path}")
    return written


def _fmu_sha(specs) -> str | None:
    shas = {spec.content.get("fmu_sha256") for spec in specs if spec.kind == "synthetic"}
    shas.discard(None)
    return next(iter(shas)) if len(shas) == 1 else (sorted(shas) or None)  # type: ignore
