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
import time
import warnings
from collections.abc import Sequence
from typing import NoReturn

from spindlebench import __version__
from spindlebench.core import interrupts
from spindlebench.core.console import one_line, print_warning
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import OVERWRITE_SHIPPED_FLAG, allow_shipped

#: Each sub-command and its one-line help, for the top-level help and "did you mean" without
#: importing any command module: importing all of them (SciPy, scikit-learn, matplotlib,
#: CasADi, dask ...) cost ``spindlebench --help`` 5.8 CPU-s. The home of each line is the
#: command module's ``HELP`` (what its ``register`` passes as ``help=``); this is a copy,
#: because reading it lazily would mean importing the module (the cost this avoids) or
#: parsing its source (not there in a bytecode-only install).
#: ``tests/commands/test_cli_commands.py`` fails when a line differs from its module's ``HELP``.
COMMAND_HELP: dict[str, str] = {
    "adapt": "convert a real data set into canonical recordings (one per run)",
    "benchmark": "score methods on a fixed, versioned task suite; write a leaderboard",
    "build": "build the FMU from the Modelica model (models/ -> fmus/)",
    "calibrate": "fit the model to recordings of a real machine; write a machine file",
    "compensate": "run the trained model in a simulated controller over many days",
    "demo": "main job: build the FMU, simulate the paper's experiments, run the comparisons",
    "evaluate": "select temperature-sensitive points on one recording and predict others",
    "export-ssp": "write an SSP file: the FMU, a machine's parameter set and a scenario's inputs",
    "fingerprint": "shape statistics of recordings (does this testbench look like my machine?)",
    "identify": "identify a low-order thermal model (and observer) from recordings",
    "iso230-3": "run an ISO 230-3 thermal test and write its report",
    "methods": "list the selection methods, choices inside clusters and regressors",
    "paper": "rerun the paper's comparison (3 sensor groups x 2/3/4 clusters) on recordings",
    "place": "virtual sensor placement: choose m of the model's nodes per method",
    "plot": "draw recording(s): temperatures by machine part, thermal error, inputs",
    "simulate": "co-simulate scenario(s) with the FMU into recording(s)",
    "sweep": "season stress test: run a study of experiments and score the methods",
}

#: Each sub-command and the module that registers it. ``spindlebench CMD ...`` imports only
#: CMD's module (~20 s of 22 s for a 100-sensor ``evaluate`` on a busy machine went to
#: importing all of them); ``--help`` and unknown names import none (``COMMAND_HELP``).
COMMANDS: dict[str, str] = {
    name: f"spindlebench.commands.{name.replace('-', '_')}" for name in COMMAND_HELP
}
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
    """The argument parser with every sub-command registered (imports every command module),
    or only ``command`` (a key of ``COMMANDS``)."""
    parser, subparsers = _top_level_parser()
    modules = COMMAND_MODULES if command is None else (COMMANDS[command],)
    for module_name in modules:
        importlib.import_module(module_name).register(subparsers)
    parser.commands = dict(subparsers.choices)
    for subparser in parser.commands.values():  # one flag, the same on every sub-command
        subparser.add_argument(OVERWRITE_SHIPPED_FLAG, action="store_true",
                               help="allow this command to replace a file shipped with "
                               "spindlebench (the committed FMU, models/, scenarios/)")
    return parser


def static_parser() -> _OneLineErrorParser:
    """The top-level parser with each sub-command's name and help from ``COMMAND_HELP`` but
    none of its options: enough for ``spindlebench --help``, ``--version`` and a mistyped
    name, without importing a command module."""
    parser, subparsers = _top_level_parser()
    for name, line in COMMAND_HELP.items():
        subparsers.add_parser(name, help=line, add_help=False)
    parser.commands = dict(subparsers.choices)
    return parser


def _top_level_parser() -> tuple[_OneLineErrorParser, argparse._SubParsersAction]:
    parser = _OneLineErrorParser(
        prog="spindlebench",
        description="Modelica/FMU testbench and temperature-sensitive point selection "
        "for machine-tool thermal error.",
    )
    parser.add_argument("--version", action="version", version=f"spindlebench {__version__}")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    return parser, subparsers


def _first_word(argv: list[str]) -> str | None:
    """The first word that is not an option: the sub-command's place (the top level has no
    option that takes a value)."""
    return next((word for word in argv if not word.startswith("-")), None)


def _refuse_unknown_command(parser: _OneLineErrorParser, argv: list[str]) -> None:
    """A first word that is no sub-command: one ``error:`` line with the closest name."""
    first = _first_word(argv)
    if first is not None and first not in COMMANDS:
        from spindlebench.formats.toml import did_you_mean

        parser.error(f"unknown command '{first}'{did_you_mean(first, list(COMMANDS))}")


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
    started = time.perf_counter()  # a command's summary reports its wall time from here
    interrupts.install()
    try:
        argv = list(sys.argv[1:] if argv is None else argv)
        command = argv[0] if argv and argv[0] in COMMANDS else None
        if command in ONE_BLAS_THREAD and "numpy" not in sys.modules:
            os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
        if command is None:  # --help, --version, a mistyped name: no command module
            parser = static_parser()
            _refuse_unknown_command(parser, argv)
            command = _first_word(argv)  # '--flag CMD ...': CMD's parser tells what is wrong
            if command is None:
                parse_args(parser, argv)  # prints the help or the version, or a usage error
        args = parse_args(build_parser(command), argv)  # imports commands: Ctrl-C can land here
        args.started_s = started
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
