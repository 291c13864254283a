"""The sub-command table of the CLI: ``spindlebench CMD`` imports only CMD's module."""

import ast
import importlib
import os
import subprocess
import sys

import pytest
from conftest import REPO
from spindlebench.commands import main as cli

PIPELINE = REPO / "pipeline"


def test_every_module_registers_exactly_the_commands_the_table_names():
    for module in cli.COMMAND_MODULES:
        parser = cli._OneLineErrorParser(prog="spindlebench")
        subparsers = parser.add_subparsers(dest="command")
        importlib.import_module(module).register(subparsers)
        assert sorted(subparsers.choices) == sorted(
            name for name, owner in cli.COMMANDS.items() if owner == module), module


def test_one_command_parser_parses_like_the_full_one(tmp_path):
    argv = ["evaluate", "--train", "a.csv", "--test", "b.csv", "--target", "drift_um",
            "--clusters", "2"]
    alone = cli.parse_args(cli.build_parser("evaluate"), argv)
    full = cli.parse_args(cli.build_parser(), argv)
    assert list(cli.build_parser("evaluate").commands) == ["evaluate"]
    assert vars(alone) == vars(full)


def test_the_static_help_table_is_each_command_modules_help():
    """``COMMAND_HELP`` is a copy of each module's ``HELP`` (the line its ``register`` passes
    as ``help=``): the top-level help must not drift from the module."""
    assert set(cli.COMMAND_HELP) == set(cli.COMMANDS)
    for name, module in cli.COMMANDS.items():
        assert cli.COMMAND_HELP[name] == importlib.import_module(module).HELP, name
    parser = cli.build_parser()
    registered = {action.dest: action.help for action in parser._subparsers._group_actions[0]
                  ._choices_actions}
    assert registered == cli.COMMAND_HELP


def test_a_mistyped_command_gets_the_closest_name(capsys):
    with pytest.raises(SystemExit) as stop:
        cli.main(["simulat", "x.toml"])
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0
    assert "unknown command 'simulat'" in err and "did you mean 'simulate'?" in err
    with pytest.raises(SystemExit):
        cli.main(["zzzzzz"])
    assert "did you mean" not in capsys.readouterr().err


def test_a_flag_before_the_command_is_still_the_top_levels_mistake(capsys):
    with pytest.raises(SystemExit) as stop:
        cli.main(["--frobnicate", "methods"])
    assert stop.value.code == 2
    assert "unrecognized arguments: --frobnicate" in capsys.readouterr().err


_IMPORTED_COMMANDS = """
import sys
from spindlebench.commands import main as cli
try:
    cli.main({argv!r})
except SystemExit:
    pass
heavy = ("pandas", "matplotlib", "scipy", "sklearn", "casadi", "fmpy", "dask")
print(sorted(m for m in sys.modules
             if (m.startswith("spindlebench.commands.") and m != "spindlebench.commands.main")
             or m.split(".")[0] in heavy))
"""


def _imported(argv: list[str]) -> list[str]:
    code = _IMPORTED_COMMANDS.format(argv=argv)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env=dict(os.environ, PYTHONPATH=str(PIPELINE)))
    return ast.literal_eval(out.stdout.strip().splitlines()[-1])


def test_top_level_help_and_a_mistyped_command_import_no_command_module():
    assert _imported(["--help"]) == []
    assert _imported(["evalute"]) == []


def test_a_commands_help_imports_only_that_command():
    imported = _imported(["sweep", "--help"])
    commands = [m for m in imported if m.startswith("spindlebench.commands.")]
    assert set(commands) <= {"spindlebench.commands.sweep", "spindlebench.commands.arguments"}


@pytest.mark.parametrize("name", sorted(cli.COMMANDS))
def test_no_commands_help_imports_a_heavy_library(name):
    """The parser of every command needs numpy at most: ``compensate --help`` imported pandas
    through a module-level ``ResultStore`` import (0.2 -> 1 CPU-s; only ``sweep --help`` was
    checked then)."""
    heavy = sorted({m.split(".")[0] for m in _imported([name, "--help"])
                    if not m.startswith("spindlebench.")})
    assert heavy == [], f"{name} --help imports {heavy}"
