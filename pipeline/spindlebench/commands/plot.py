"""``spindlebench plot``: recordings → one figure (temperatures by part, error, inputs).

Works on any recording (synthetic, ``spindlebench adapt`` output, another logger's CSV): the
time column, sensors, excluded columns and CSV dialect are the column roles of
``formats.roles`` (``--time-column``, ``--sensors``, ``--exclude``, ``--delimiter``,
``--decimal``); without ``--sensors`` the temperature-looking columns are drawn and the
command prints which it took and skipped. A recording without a time column is refused. A
copy of the target is not refused here (nothing is fitted; the plot shows it). The figure
itself is ``testbench.overview.recordings_figure``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.files import check_output
from spindlebench.formats.recording import DRIFT_COLUMN, true_column
from spindlebench.formats.roles import (
    ColumnRoles,
    add_role_arguments,
    read_with_roles,
    require_time,
)

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "draw recording(s): temperatures by machine part, thermal error, inputs"


def input_columns() -> tuple[str, ...]:
    """Columns drawn besides the sensors and the error when a recording has them."""
    from spindlebench.testbench.overview import AMBIENT_DRIVER, FEEDS, SPEED

    return (SPEED, *FEEDS, AMBIENT_DRIVER, true_column(DRIFT_COLUMN))


def default_output(recordings: list[Path]) -> Path:
    """One recording → ``<recording>.png`` beside it; several need ``-o``."""
    if len(recordings) > 1:
        raise SpindlebenchError(f"plot: {len(recordings)} recordings go into one figure; "
                                "name it with -o FIG.png")
    return recordings[0].with_suffix(".png")


#: Longest ``--title``: matplotlib lays out a 100 000-character title for minutes.
MAX_TITLE = 300


def run(args: argparse.Namespace) -> int:
    """Read every recording (refusing bad ones in one line), draw, write atomically."""
    # matplotlib only here: ``plot --help`` stays cheap
    from spindlebench.testbench.overview import recordings_figure, save_figure

    recordings = [Path(p) for p in args.recordings]
    out = Path(args.output) if args.output else default_output(recordings)
    if out.suffix.lower() != ".png":
        raise SpindlebenchError(f"-o {out}: the figure is written as PNG; name it *.png")
    if out.is_dir():
        raise SpindlebenchError(f"-o {out}: is a directory; give a file name FIG.png")
    check_output(out, "-o", recordings)
    if args.title is not None and len(args.title) > MAX_TITLE:
        raise SpindlebenchError(f"--title: {len(args.title):,} characters; a figure title has "
                                f"at most {MAX_TITLE}")
    roles = ColumnRoles.from_args(args)
    frames, sensors = [], []
    for path in recordings:
        frame, choice = read_with_roles(path, args.target, roles, allow_missing=True,
                                        extra=input_columns())
        require_time(choice, str(path), "a plot over time")
        if choice.by_rule:
            print(choice.report(str(path)))
        frames.append(frame)
        sensors.append(choice.sensors)
    titles = [path.stem for path in recordings]
    save_figure(recordings_figure(frames, titles, rises=args.rises, target=args.target,
                                  suptitle=args.title, sensors=sensors), out)
    print(out)
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``plot`` sub-command."""
    parser = subparsers.add_parser(
        "plot",
        help=HELP,
        description="Draw one or more recordings side by side: the sensor temperatures "
        "grouped by machine part (one colour family per part, each line named at its end), "
        "the thermal error and the inputs (spindle speed, feeds, ambient), over hours.",
    )
    parser.add_argument("recordings", nargs="+", metavar="RECORDING",
                        help="recording .csv file(s), one column of panels each")
    parser.add_argument("-o", "--output", metavar="FIG.png", default=None,
                        help="figure to write (default for one recording: RECORDING.png "
                        "beside it)")
    parser.add_argument("--rises", action="store_true",
                        help="temperatures as rises since the first sample (default: °C)")
    parser.add_argument("--target", default=DRIFT_COLUMN,
                        help="thermal-error column (default: drift_um; e.g. ch3_um)")
    parser.add_argument("--title", default=None, help="title above the figure")
    add_role_arguments(parser, copies=False)
    parser.set_defaults(func=run)
