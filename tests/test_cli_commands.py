"""The sub-command table of the CLI: ``spindlebench CMD`` imports only CMD's module."""

import importlib

from spindlebench.commands import main as cli


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
