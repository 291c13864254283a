"""The ``spindlebench`` command line: one sub-command per job, each in its own module.

Sub-command NAME lives in ``spindlebench/commands/NAME.py`` (``COMMANDS``), which exposes
``register(subparsers)``, which adds its
sub-command and sets ``func`` on the parser's defaults to a callable taking the parsed args and
returning an exit status.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import warnings
from collections.abc import Sequence
from typing import NoReturn

from spindlebench import __version__
from spindlebench.core import interrupts
from spindlebench.core.console import one_line, print_warning
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import OVERWRITE_SHIPPED_FLAG, allow_shipped

#: Each sub-command and the module that registers it. ``spindlebench CMD ...`` imports only
#: CMD's module: importing all of them (SciPy, scikit-learn, matplotlib, CasADi, dask ...)
#: took most of a short command's time (~20 s of 22 s for a 100-sensor ``evaluate`` on a
#: busy machine). ``--help`` and unknown names still import them all.
COMMANDS: dict[str, str] = {
    name: f"spindlebench.commands.{name.replace('-', '_')}"
    for name in ("adapt", "benchmark", "build", "calibrate", "compensate", "demo", "evaluate",
                 "fingerprint", "identify", "iso230-3", "methods", "paper", "place", "plot",
                 "simulate", "sweep")
}
COMMANDS["export-ssp"] = "spindlebench.commands.export_ssp"  # a name that is no module name
COMMAND_MODULES: tuple[str, ...] = tuple(sorted(set(COMMANDS.values())))

#: Sub-commands that run OpenBLAS with one thread: their large products are single-threaded
#: already (threadpoolctl) and the rest is small, so the library's worker threads only cost
#: their start-up and spin-waiting: ~0.15 s of CPU of a 0.8 s ``evaluate --differences`` on
#: 100 sensors (its output and --json are the same bytes either way, tested). Set before
#: numpy is first imported (later it has no effect), unless the user chose a number.
ONE_BLAS_THREAD: tuple[str, ...] = ("evaluate", "benchmark")


class _OneLineErrorParser(argparse.ArgumentParser):
    """argparse, but a usage mistake is one ``error:`` line (status 2) like every other error;
    sub-command parsers inherit the class. ``commands`` maps each sub-command to its parser
    (filled by ``build_parser``)."""

    commands: dict[str, argparse.ArgumentParser]

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"error: {self.prog}: {message} (see '{self.prog} --help')\n")


def build_parser(command: str | None = None) -> _OneLineErrorParser:
    """The argument parser with every sub-command registered, or only ``command`` (a key of
    ``COMMANDS``)."""
    parser = _OneLineErrorParser(
        prog="spindlebench",
        description="Modelica/FMU testbench and temperature-sensitive point selection "
        "for machine-tool thermal error.",
    )
    parser.add_argument("--version", action="version", version=f"spindlebench {__version__}")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    modules = COMMAND_MODULES if command is None else (COMMANDS[command],)
    for module_name in modules:
        importlib.import_module(module_name).register(subparsers)
    parser.commands = dict(subparsers.choices)
    for subparser in parser.commands.values():  # one flag, the same on every sub-command
        subparser.add_argument(OVERWRITE_SHIPPED_FLAG, action="store_true",
                               help="allow this command to replace a file shipped with "
                               "spindlebench (the committed FMU, models/, scenarios/)")
    return parser


def parse_args(parser: _OneLineErrorParser, argv: Sequence[str] | None) -> argparse.Namespace:
    """``parser.parse_args``, but arguments left over after a sub-command are reported by that
    sub-command's parser, so the hint names ``spindlebench <cmd> --help`` (its flags), not the
    top-level help that does not list them."""
    argv = list(sys.argv[1:] if argv is None else argv)
    args, extras = parser.parse_known_args(argv)
    if extras:
        command = getattr(args, "command", None)
        after = argv[argv.index(command) + 1:] if command in argv else []
        subparser = parser.commands.get(command) if command else None
        if subparser is None or any(extra not in after for extra in extras):
            subparser = parser  # something before the sub-command: the top level's mistake
        subparser.error(f"unrecognized arguments: {' '.join(extras)}")
    return args


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point: run a sub-command; user errors become one ``error:`` line and status 2,
    warnings one ``warning:`` line each."""
    own_process = argv is None  # the console script, not a caller in its own process
    interrupts.install()
    try:
        argv = list(sys.argv[1:] if argv is None else argv)
        command = argv[0] if argv and argv[0] in COMMANDS else None
        if command in ONE_BLAS_THREAD and "numpy" not in sys.modules:
            os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
        args = parse_args(build_parser(command), argv)  # imports commands: Ctrl-C can land here
    except KeyboardInterrupt as exc:
        status = _interrupted(exc)
    else:
        with warnings.catch_warnings():
            warnings.showwarning = print_warning
            status = _run(args)
    if own_process and status == interrupts.EXIT_STATUS:
        interrupts.ignore_further()  # the process is ending: a second Ctrl-C must not kill it
    return status


def _interrupted(exc: KeyboardInterrupt) -> int:
    interrupts.ending()
    name = exc.args[0] if isinstance(exc, interrupts.Interrupted) else "SIGINT"
    print(f"error: interrupted by {name}; the unfinished output was not written",
          file=sys.stderr)
    return interrupts.EXIT_STATUS


def _run(args: argparse.Namespace) -> int:
    try:
        if getattr(args, "overwrite_shipped", False):
            with allow_shipped():
                return int(args.func(args) or 0)
        return int(args.func(args) or 0)
    except SpindlebenchError as exc:
        print(f"error: {one_line(str(exc))}", file=sys.stderr)
        return 2
    except OSError as exc:  # the environment refused a file: unwritable folder, full disk, ...
        name = exc.filename2 or exc.filename  # a failed rename names its target second
        where = f"{name}: " if name else ""
        print(f"error: {one_line(f'{where}{exc.strerror or exc}')}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:  # Ctrl-C or SIGTERM (spindlebench.core.interrupts)
        return _interrupted(exc)


if __name__ == "__main__":
    sys.exit(main())
