"""``spindlebench evaluate``: select points on one recording, predict the others.

Warnings (dropped constant candidates, tied similarities, samples dropped for missing values
with ``--missing drop-rows``) go to stderr as ``warning:`` lines and into the JSON's
``provenance.warnings``. The column roles (time column, sensors, excluded columns, CSV
dialect) are ``spindlebench.formats.roles``'; only the target, the time column and the
sensors are read and checked, other columns are ignored.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from spindlebench.commands.arguments import add_target_argument, joint_of, targets_of
from spindlebench.core import atomic, provenance
from spindlebench.core.files import check_output
from spindlebench.core.names import DEFAULT_SIMILARITY, MISSING_MODES
from spindlebench.formats.recording import MissingValueError, RecordingTable, read_header
from spindlebench.formats.roles import (
    ColumnRoles,
    RoleChoice,
    add_role_arguments,
    choose,
    detect_dialect,
    read_table_with_roles,
    refuse_target_copies,
)
from spindlebench.selection.closure import CLOSURES
from spindlebench.selection.dynamic import driver_columns, is_dynamic
from spindlebench.selection.errors import SelectionError
from spindlebench.selection.evaluate import (
    Evaluation,
    check_same_sensors,
    evaluate,
)

if TYPE_CHECKING:
    from collections.abc import Sequence

    from spindlebench.selection.evaluate import RecordingLike
    from spindlebench.selection.registry import MethodChoice
from spindlebench.selection.registry import add_method_arguments, choice_from_args
from spindlebench.selection.similarity import SIMILARITIES

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "select temperature-sensitive points on one recording and predict others"

#: The same hint ``evaluate`` gives when it reads a file itself.
DROP_HINT = "--missing drop-rows drops incomplete samples"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``evaluate`` sub-command."""
    parser = subparsers.add_parser(
        "evaluate",
        help=HELP,
        description="Xu et al. (2023): fuzzy-cluster the candidates of the training recording, "
        "keep per cluster the one most correlated with the target, fit OLS on rises, and "
        "report the RMSE on every test recording. Without --sensors, the columns that look "
        "like temperatures (T3, t3_C, '... [degC]', '... °C', Temp...) are the sensors; the "
        "command prints which it took and which it skipped and why. Only the target, the "
        "time column and the sensors are read and checked.",
    )
    parser.add_argument("--train", required=True, type=Path, help="training recording (CSV)")
    parser.add_argument(
        "--test", required=True, nargs="+", type=Path, help="recording(s) to predict (CSV)"
    )
    add_target_argument(parser, "thermal-error column, e.g. drift_um", required=True,
                        joint=True)
    add_role_arguments(parser)
    parser.add_argument(
        "--clusters", required=True, type=int, metavar="K",
        help="number of clusters k (for a method without clusters: the number of inputs)"
    )
    add_method_arguments(parser)
    parser.add_argument(
        "--differences", action="store_true", help="add every pairwise difference A-B"
    )
    parser.add_argument("--similarity", choices=SIMILARITIES, default=DEFAULT_SIMILARITY)
    parser.add_argument(
        "--closure", choices=CLOSURES, default="fast", help="closure algorithm (same result)"
    )
    parser.add_argument(
        "--missing",
        choices=MISSING_MODES,
        default="error",
        help="missing (empty/NaN) values: a one-line error (default), or drop the samples "
        "where the target or a used sensor is missing, with a warning (rises then start at "
        "the first complete sample; nothing is filled in)",
    )
    parser.add_argument("--json", type=Path, metavar="OUT.json", help="write the result here")
    parser.set_defaults(func=run)


def _read_used(path: Path, target: str, roles: ColumnRoles,
               missing: str, others: Sequence[str] = (),
               drivers: Sequence[str] = ()) -> tuple[RecordingTable, RoleChoice]:
    """One recording with only the target (and the ``others`` of several targets, and the
    ``drivers`` a dynamic regressor reads, issue 22), time and
    sensor columns read and checked: a gap or a note in a column nobody uses must not reject
    the file. As arrays: the command never imports pandas (half a second of its start-up)
    unless a file needs its parser."""
    if others:  # each target must be in the file and none may be a sensor or the time axis
        header = read_header(path, detect_dialect(path, roles.delimiter, roles.decimal,
                                                  roles.encoding)[0], roles.encoding)
        for other in others:
            choose(header, other, roles, str(path))
    try:
        table, taken = read_table_with_roles(path, target, roles,
                                             allow_missing=missing == "drop-rows",
                                             extra=(*others, *drivers))
    except MissingValueError as exc:
        raise SelectionError(f"{exc}; {DROP_HINT}") from exc
    overlap = [other for other in others if other in taken.sensors]
    if overlap:
        raise SelectionError(f"recording {path}: target {overlap[0]!r} is also a sensor")
    return table, taken


#: Most candidate columns (sensors, with --differences their pairwise differences too):
#: 200 sensors with --differences are 20 100; each candidate is a column of the recording's
#: length in memory, so 5 000 sensors' 12.5 million would not finish.
MAX_CANDIDATES = 50_000


def run(args: argparse.Namespace) -> int:
    """Evaluate, print the summary, write JSON if asked."""
    if args.clusters < 1:
        raise SelectionError(f"--clusters: must be at least 1, got {args.clusters}")
    if args.json is not None and args.json.is_dir():
        raise SelectionError(f"--json {args.json}: is a directory; give a file OUT.json")
    if args.json is not None:
        check_output(args.json, "--json", [args.train, *args.test])
    targets = targets_of(args)
    joint = joint_of(args)
    args.target, others = targets[0], targets[1:]  # one target: as before, to the byte
    roles = ColumnRoles.from_args(args)
    choice = choice_from_args(args)  # checked before reading
    # a dynamic regressor (issue 22) reads the speed programme (and the room) too
    drivers = driver_columns(choice.regressor)[1:] if is_dynamic(choice.regressor) else ()
    train, taken = _read_used(args.train, args.target, roles, args.missing, others, drivers)
    sensors = taken.sensors
    n = len(sensors) * (len(sensors) + 1) // 2 if args.differences else len(sensors)
    if n > MAX_CANDIDATES:  # 5 000 sensors with --differences: 12.5 million columns
        raise SelectionError(f"recording {args.train}: {len(sensors)} sensors give {n:,} "
                             f"candidates{' with --differences' if args.differences else ''}, "
                             f"more than the {MAX_CANDIDATES:,} evaluate can score; choose "
                             "fewer with --sensors or --exclude")
    for target in targets:
        refuse_target_copies(train, target, taken.sensors, str(args.train),
                             roles.allow_target_copy)
    if args.clusters > n:
        raise SelectionError(f"--clusters {args.clusters}: larger than the number of candidates "
                             f"({n}) of recording {args.train} (sensors, and their differences "
                             "with --differences)")
    same = dataclasses.replace(roles, sensors=tuple(sensors), exclude=())  # the train's columns
    tests: list[RecordingLike] = []
    for path in args.test:
        if taken.by_rule:  # the rule must find the same sensors in every file
            theirs = choose(read_header(path, detect_dialect(path, roles.delimiter)[0]),
                            args.target, roles, str(path)).sensors
            check_same_sensors(str(path), theirs, sensors, str(args.train))
        tests.append(_read_used(path, args.target, same, args.missing, others, drivers)[0])
    if others:
        return _run_targets(args, targets, joint, train, tests, taken, sensors, choice)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = evaluate(
            train,
            tests,
            args.target,
            sensors=sensors,
            k=args.clusters,
            differences=args.differences,
            similarity=args.similarity,
            closure=args.closure,
            missing=args.missing,
            method=choice,
            seed=args.seed,
        )
    messages = [str(item.message) for item in caught]
    text = None if args.json is None else _json_text(result, args, messages)
    return _finish(args, messages, taken, result, text)


def _run_targets(args: argparse.Namespace, targets: list[str], joint: Sequence[str],
                 train: RecordingTable, tests: list[RecordingLike], taken: RoleChoice,
                 sensors: list[str], choice: MethodChoice) -> int:
    """Several targets: each on its own, then the joint selections; the comparison table."""
    from spindlebench.selection.evaluate import load_recordings
    from spindlebench.selection.multi_target import evaluate_targets

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        train_recording, test_recordings = load_recordings(train, tests, args.missing)
        result = evaluate_targets(train_recording, test_recordings, targets, sensors=sensors,
                                  k=args.clusters, differences=args.differences,
                                  similarity=args.similarity, closure=args.closure,
                                  missing=args.missing, method=choice, seed=args.seed,
                                  joint=joint)
    messages = list(dict.fromkeys(str(item.message) for item in caught))
    text = None
    if args.json is not None:
        record = result.to_dict()
        record["provenance"] = provenance.provenance(
            command="evaluate", train=provenance.file_entry(args.train),
            tests=[provenance.file_entry(path) for path in args.test], targets=targets,
            joint=list(result.joint), sensors=sensors, clusters=args.clusters,
            differences=args.differences, similarity=args.similarity, closure=args.closure,
            missing=args.missing, method=choice.to_dict(), seed=args.seed, warnings=messages)
        text = _dumps(record, args)
    return _finish(args, messages, taken, result, text)


def _finish(args: argparse.Namespace, messages: Sequence[str], taken: RoleChoice, result,
            text: str | None) -> int:
    """The end of every evaluate: its warnings, the roles taken, the summary, the JSON."""
    for message in messages:
        print(f"warning: {message}", file=sys.stderr)
    print(taken.report())
    print(result.summary())
    if text is not None:
        atomic.write_text(args.json, text)
        print(f"wrote {args.json}")
    return 0


def _dumps(record: dict, args: argparse.Namespace) -> str:
    """``record`` as JSON; a value JSON cannot hold is one error line."""
    try:
        return json.dumps(record, indent=2, allow_nan=False) + "\n"
    except ValueError as exc:
        raise SelectionError(
            f"--json {args.json}: the result holds a value JSON cannot store ({exc}); "
            f"the input values are probably too large"
        ) from exc


def _json_text(result: Evaluation, args: argparse.Namespace, messages: list[str]) -> str:
    """The --json document, made before anything is printed so that a value JSON cannot
    hold (inf, NaN) is one error line, not a traceback after the summary."""
    record = result.to_dict()
    record["provenance"] = provenance.provenance(
        command="evaluate",
        train=provenance.file_entry(args.train),
        tests=[provenance.file_entry(path) for path in args.test],
        target=args.target,
        sensors=result.sensors,
        clusters=args.clusters,
        differences=args.differences,
        similarity=args.similarity,
        closure=args.closure,
        missing=args.missing,
        method=result.method.to_dict(),
        seed=args.seed,
        warnings=messages,
    )
    return _dumps(record, args)
