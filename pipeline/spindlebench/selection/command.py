"""``spindlebench evaluate``: select points on one recording, predict the others.

Warnings (dropped constant candidates, tied similarities, samples dropped for missing values
with ``--missing drop-rows``) go to stderr as ``warning:`` lines and into the JSON's
``provenance.warnings``. With ``--sensors`` only the target, ``time_s`` and those sensors are
read and checked; other columns are ignored.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from spindlebench import atomic, provenance
from spindlebench.formats.recording import MissingValueError, read_recording
from spindlebench.listflags import split_list_flag
from spindlebench.names import (
    DEFAULT_METHOD,
    DEFAULT_METHOD_SEED,
    DEFAULT_REGRESSOR,
    DEFAULT_SIMILARITY,
    DEFAULT_WITHIN,
    METHODS,
    REGRESSORS,
    WITHIN,
)
from spindlebench.selection.closure import CLOSURES
from spindlebench.selection.errors import SelectionError
from spindlebench.selection.evaluate import MISSING_MODES, Evaluation, RecordingLike, evaluate
from spindlebench.selection.registry import MethodChoice
from spindlebench.selection.similarity import SIMILARITIES

#: The same hint ``evaluate`` gives when it reads a file itself.
DROP_HINT = "--missing drop-rows drops incomplete samples"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``evaluate`` sub-command."""
    parser = subparsers.add_parser(
        "evaluate",
        help="select temperature-sensitive points on one recording and predict others",
        description="Xu et al. (2023): fuzzy-cluster the candidates of the training recording, "
        "keep per cluster the one most correlated with the target, fit OLS on rises, and "
        "report the RMSE on every test recording. Without --sensors, every numeric column "
        "except the target, time_s, true_* truth, driver/command columns (ambient_C, feed_*, "
        "*_rpm, *_mm_per_min, *_W) and displacement/error channels (*_um) is a sensor.",
    )
    parser.add_argument("--train", required=True, type=Path, help="training recording (CSV)")
    parser.add_argument(
        "--test", required=True, nargs="+", type=Path, help="recording(s) to predict (CSV)"
    )
    parser.add_argument("--target", required=True, help="thermal-error column, e.g. drift_um")
    parser.add_argument(
        "--sensors", nargs="+", metavar="NAME",
        help="sensor columns, space- or comma-separated (--sensors T1 T6 T8 or --sensors "
        "T1,T6,T8); only these, the target and time_s are read and checked, other columns "
        "are ignored (default: see above, every column is checked)",
    )
    parser.add_argument(
        "--clusters", required=True, type=int, metavar="K",
        help="number of clusters k (for a method without clusters: the number of inputs)"
    )
    parser.add_argument("--method", choices=list(METHODS), default=DEFAULT_METHOD,
                        help="selection method (default: the paper's closure; "
                        "'spindlebench methods' lists them)")
    parser.add_argument("--within", choices=list(WITHIN), default=DEFAULT_WITHIN,
                        help="choice inside a cluster (cluster methods only)")
    parser.add_argument("--regressor", choices=list(REGRESSORS), default=DEFAULT_REGRESSOR,
                        help="regression on the selected rises")
    parser.add_argument("--seed", type=int, default=DEFAULT_METHOD_SEED,
                        help="seed of fcm, kmeans and stability (recorded in --json)")
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


def parse_sensor_list(values: str | Sequence[str] | None) -> list[str] | None:
    """``["T1,T6", "T8"]`` or ``"T1,T6, T8"`` -> ``["T1", "T6", "T8"]``; None stays None."""
    return split_list_flag("--sensors", values, what="name", error=SelectionError)


def _read_used(path: Path, columns: list[str], missing: str) -> pd.DataFrame:
    """One recording with only ``columns`` (and time_s) read and checked: with --sensors a
    gap or a note in a column nobody uses must not reject the file."""
    try:
        return read_recording(path, allow_missing=missing == "drop-rows", columns=columns)
    except MissingValueError as exc:
        raise SelectionError(f"{exc}; {DROP_HINT}") from exc


def run(args: argparse.Namespace) -> int:
    """Evaluate, print the summary, write JSON if asked."""
    sensors = parse_sensor_list(args.sensors)
    choice = MethodChoice(args.method, args.within, args.regressor)  # checked before reading
    train: RecordingLike = args.train
    tests: list[RecordingLike] = [str(path) for path in args.test]
    if sensors is not None:  # read and check only the columns used
        train = _read_used(args.train, [args.target, *sensors], args.missing)
        tests = [_read_used(path, [args.target, *sensors], args.missing) for path in args.test]
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
    for message in messages:
        print(f"warning: {message}", file=sys.stderr)
    print(result.summary())
    if text is not None:
        atomic.write_text(args.json, text)
        print(f"wrote {args.json}")
    return 0


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
    try:
        return json.dumps(record, indent=2, allow_nan=False) + "\n"
    except ValueError as exc:
        raise SelectionError(
            f"--json {args.json}: the result holds a value JSON cannot store ({exc}); "
            f"the input values are probably too large"
        ) from exc
