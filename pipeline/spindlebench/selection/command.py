"""``spindlebench evaluate``: select points on one recording, predict the others.

Warnings (dropped constant candidates, tied similarities, samples dropped for missing values
with ``--missing drop-rows``) go to stderr as ``warning:`` lines and into the JSON's
``provenance.warnings``.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

from spindlebench import atomic, provenance
from spindlebench.selection.closure import CLOSURES
from spindlebench.selection.errors import SelectionError
from spindlebench.selection.evaluate import MISSING_MODES, evaluate
from spindlebench.selection.similarity import SIMILARITIES


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
    parser.add_argument("--sensors", help="comma-separated sensor columns (default: see above)")
    parser.add_argument(
        "--clusters", required=True, type=int, metavar="K", help="number of clusters k"
    )
    parser.add_argument(
        "--differences", action="store_true", help="add every pairwise difference A-B"
    )
    parser.add_argument("--similarity", choices=SIMILARITIES, default="abs-pearson")
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


def parse_sensor_list(text: str | None) -> list[str] | None:
    """``"T1,T6, T8"`` -> ``["T1", "T6", "T8"]``; None stays None."""
    if text is None:
        return None
    names = [name.strip() for name in text.split(",")]
    if not all(names):
        raise SelectionError(f"--sensors: empty name in {text!r}")
    return names


def run(args: argparse.Namespace) -> int:
    """Evaluate, print the summary, write JSON if asked."""
    sensors = parse_sensor_list(args.sensors)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = evaluate(
            args.train,
            [str(path) for path in args.test],
            args.target,
            sensors=sensors,
            k=args.clusters,
            differences=args.differences,
            similarity=args.similarity,
            closure=args.closure,
            missing=args.missing,
        )
    messages = [str(item.message) for item in caught]
    for message in messages:
        print(f"warning: {message}", file=sys.stderr)
    print(result.summary())
    if args.json is not None:
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
            warnings=messages,
        )
        atomic.write_text(args.json, json.dumps(record, indent=2, allow_nan=False) + "\n")
        print(f"wrote {args.json}")
    return 0
