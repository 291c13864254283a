"""``spindlebench fingerprint``: does this testbench look like my machine?

For each recording (synthetic or real) the fingerprint statistics of
:mod:`spindlebench.studies.fingerprint.statistics` (best raw and difference ψ, best single and
pair R², the error's t63 against the sensors', overshoot, early fraction), one row each plus
their median,
printed as a table and written as JSON with provenance (``--json``). With a figure
(``--figure``, or ``--json OUT.json`` → ``OUT.png``) the recordings are drawn next to the
default machine's paper experiments, error and sensor rises normalised to their final values,
and the table gets the default machine's median as a last row; where those experiments come
from is :mod:`spindlebench.studies.fingerprint.reference` (``--reference DIR`` or a cache simulated
once with the committed FMU).

The error column is ``--target``; without it ``drift_um`` when the recording has it, else the
``axial_target`` its JSON sidecar names (``adapt caiviac`` writes one). The time column,
sensors, excluded columns and CSV dialect are the column roles of
:mod:`spindlebench.formats.roles` (``--time-column``, ``--sensors``, ``--exclude``,
``--delimiter``, ``--decimal``): without ``--sensors`` the temperature-looking columns, listed
on stdout with what was skipped and why. The time column is in seconds, drawn in hours.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from spindlebench.commands.arguments import add_target_argument, targets_of
from spindlebench.core import atomic, provenance
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.files import check_output
from spindlebench.core.listflags import expand_folders
from spindlebench.formats.recording import TIME_COLUMN
from spindlebench.formats.roles import (
    ColumnRoles,
    add_role_arguments,
)
from spindlebench.studies.fingerprint.recordings import (
    DEFAULT_TARGET,
    Fingerprinted,
    fingerprint_recording,
    json_stats,
    median_stats,
)
from spindlebench.studies.fingerprint.statistics import KEYS

if TYPE_CHECKING:
    from spindlebench.studies.fingerprint.reference import Reference

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "shape statistics of recordings (does this testbench look like my machine?)"

# --------------------------------------------------------------------------- table


def table(rows: list[tuple[str, dict[str, float]]]) -> str:
    """A fixed-width text table: one line per (label, statistics)."""
    width = max(len("recording"), *(len(label) for label, _ in rows))
    head = f"{'recording':<{width}}  " + "  ".join(f"{key:>14}" for key in KEYS)
    lines = [head]
    for label, stats in rows:
        cells = "  ".join(
            f"{'-':>14}" if not math.isfinite(stats[key]) else f"{stats[key]:>14.3f}"
            for key in KEYS)
        lines.append(f"{label:<{width}}  {cells}")
    return "\n".join(lines)


# --------------------------------------------------------------------------- command line


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``fingerprint`` sub-command."""
    parser = subparsers.add_parser(
        "fingerprint",
        help=HELP,
        description="The fingerprint statistics (best raw/difference psi, best single/pair "
        "R2, t63 ratio, overshoot, early fraction; defined in the "
        "spindlebench.studies.fingerprint.statistics docstring, explained in README) of each "
        "recording and their median, next to the "
        "default machine's paper experiments.",
    )
    parser.add_argument("recordings", nargs="+", type=Path, metavar="RECORDING",
                        help="recording CSV(s), or folders of them (every *.csv inside)")
    add_target_argument(parser, f"error column (default: {DEFAULT_TARGET}, else the "
                        "axial_target of the recording's JSON sidecar)")
    add_role_arguments(parser)
    parser.add_argument("--json", type=Path, metavar="OUT.json", help="write the result here")
    parser.add_argument("--figure", type=Path, metavar="OUT.png",
                        help="write the comparison figure here (default: OUT.png beside "
                        "--json; none without either)")
    parser.add_argument("--machine", metavar="NAME",
                        help="compare with this machine's paper experiments instead of the "
                        "default's (a name from scenarios/machines/ or a .toml file; "
                        "simulated once into fingerprint_reference/NAME/ of the per-user cache, "
                        "~/.cache/spindlebench or $SPINDLEBENCH_CACHE)")
    parser.add_argument("--reference", type=Path, metavar="DIR",
                        help="recordings of the default machine to compare with (default: "
                        "the paper experiments simulated once with the committed FMU into "
                        "fingerprint_reference/ of the per-user cache)")
    parser.set_defaults(func=run)


def recording_files(paths: list[Path]) -> list[Path]:
    """The recordings named: files as given, a folder as its ``*.csv`` in name order."""
    return expand_folders(paths, ".csv", "recording")


def reference_label(args: argparse.Namespace) -> str:
    """What the reference is called in the table, the figure and the JSON."""
    if args.reference is not None:
        return f"reference {args.reference}"
    return "default machine" if args.machine is None else f"machine {args.machine}"


def run(args: argparse.Namespace) -> int:
    """Fingerprint every recording, print the table, write JSON and figure if asked."""
    # the reference simulates (FMPy, pandas, SciPy): only here, not for ``fingerprint --help``
    from spindlebench.studies.fingerprint.reference import (
        REFERENCE_TARGET,
        cached_reference,
        explicit_reference,
    )

    targets = targets_of(args)
    args.target = targets[0] if targets else None  # one target: as before, to the byte
    args.targets = targets
    roles = ColumnRoles.from_args(args)
    for out, suffix in ((args.json, ".json"), (args.figure, ".png")):
        if out is not None and out.suffix.lower() != suffix:
            raise SpindlebenchError(f"{out}: must be a {suffix} file")
        if out is not None and out.is_dir():
            raise SpindlebenchError(f"{out}: is a directory")
    args.recordings = recording_files(args.recordings)
    for out, flag in ((args.json, "--json"), (args.figure, "--figure")):
        if out is not None:
            check_output(out, flag, args.recordings)
    results = []
    for path in args.recordings:
        for target in targets or [None]:
            result, choice = fingerprint_recording(path, target, roles)
            results.append(result)
        if choice.by_rule:
            print(choice.report(str(path)))
    figure = args.figure or (args.json.with_suffix(".png") if args.json else None)
    reference: Reference | None = None
    ref_results: list[Fingerprinted] = []
    if args.machine is not None and args.reference is not None:
        raise SpindlebenchError("--machine and --reference: give one (--reference is a folder "
                                "of recordings, --machine simulates its paper experiments)")
    label = reference_label(args)
    if figure is not None or args.reference is not None or args.machine is not None:
        reference = (explicit_reference(args.reference) if args.reference is not None
                     else cached_reference(machine=args.machine))
        ref_results = [fingerprint_recording(path, REFERENCE_TARGET)[0]
                       for path in reference.recordings]
    several = targets is not None and len(targets) > 1
    if several:  # a row per recording and target, a median per target
        medians = {t: median_stats([r.stats for r in results if r.target == t])
                   for t in targets}
        rows = [(f"{item.path} [{item.target}]", item.stats) for item in results]
        rows += [(f"median [{t}]", medians[t]) for t in targets]
        median: Any = medians
    else:
        median = median_stats([item.stats for item in results])
        rows = [(str(item.path), item.stats) for item in results]
        rows.append(("median", median))
    ref_median = None
    if ref_results:
        ref_median = median_stats([item.stats for item in ref_results])
        rows.append((f"{label} (median)", ref_median))
    text = None
    if args.json is not None:
        text = _json_text(results, median, reference, ref_results, ref_median, figure, args,
                          roles)
    if figure is not None:
        from spindlebench.studies.fingerprint.figure import write_figure
        write_figure(figure, results, ref_results, f"{label}, paper experiments"
                     if args.reference is None else label)
    print(table(rows))
    if text is not None:
        atomic.write_text(args.json, text)
        print(f"wrote {args.json}")
    if figure is not None:
        print(f"wrote {figure}")
    return 0


def _json_text(results: list[Fingerprinted], median: dict[str, float],
               reference: Reference | None, ref_results: list[Fingerprinted],
               ref_median: dict[str, float] | None, figure: Path | None,
               args: argparse.Namespace, roles: ColumnRoles) -> str:
    several = args.targets is not None and len(args.targets) > 1
    record: dict[str, Any] = {
        **({"targets": args.targets} if several else {}),
        "recordings": [item.row() for item in results],
        "median": ({t: json_stats(m) for t, m in median.items()} if several
                   else json_stats(median)),
    }
    if reference is not None and ref_median is not None:
        record["reference"] = {
            "label": reference_label(args),
            "recordings": [item.row() for item in ref_results],
            "median": json_stats(ref_median),
        }
    record["figure"] = None if figure is None else str(figure)
    record["provenance"] = provenance.provenance(
        command="fingerprint",
        recordings=[provenance.file_entry(path) for path in args.recordings],
        target=args.targets if several else args.target,
        time_column=roles.time_column or TIME_COLUMN,
        sensors=None if roles.sensors is None else list(roles.sensors),
        exclude=list(roles.exclude),
        allow_target_copy=roles.allow_target_copy,
        reference=None if reference is None else {
            **reference.source,
            "files": [provenance.file_entry(path) for path in reference.recordings]},
    )
    return json.dumps(record, indent=2, allow_nan=False) + "\n"
